#pragma once
// Every bake parameter in one place: its default, unit, valid range and meaning. The same table
// parses --config files (unknown keys and out-of-range values are errors naming the JSON path)
// and prints --dump-config, so the reference cannot drift from the code.

#include <nlohmann/json.hpp>
#include <string>

#include "drape/bake/importer.h"
#include "drape/formats/status.h"

namespace drape::bake {

struct BakeConfig {
  ImportOptions import;
};

// Reads a JSON config file over the defaults in `config`. `path` names the file in messages.
Status LoadBakeConfig(const std::string& path, BakeConfig* config);
Status ApplyBakeConfig(const nlohmann::json& json, const std::string& source, BakeConfig* config);

// {"section.key": {"default", "unit", "range", "description"}, ...}
nlohmann::json BakeConfigReference();
// The values in effect, as a config file would spell them.
nlohmann::json BakeConfigToJson(const BakeConfig& config);

}  // namespace drape::bake

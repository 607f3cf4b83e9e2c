#pragma once
// Reading a JSON document (a bake config, a scene) from its bytes, strictly: a key given twice
// in one object and a number no double can hold are refused with the JSON path where they stand,
// and nothing escapes as an exception. nlohmann::json on its own keeps the last of two equal
// keys silently and throws out_of_range on 1e400.

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "drape/formats/status.h"

namespace drape::bake {

// `text` parsed into *out. Errors are kInvalidArgument, one line starting with `source`:
// "<source>: /maps/resolution: appears twice in its object", "<source>: /maps/resolution: the
// number 1e400 is beyond what a double holds", "<source>: not valid JSON: <where and why>".
Status ParseJsonText(std::string_view text, const std::string& source, nlohmann::json* out);

// The whole file at `path` through ParseJsonText (source: the path). `what` names the file in
// the message when it cannot be read ("config", "scene").
Status ReadJsonFile(const std::string& path, const std::string& what, nlohmann::json* out);

}  // namespace drape::bake

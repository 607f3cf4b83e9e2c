// libFuzzer target: drape-bake's config entry point (ParseBakeConfig, what --config's bytes go
// through) on arbitrary bytes: a status, never a crash and never an escaped exception; an
// accepted config round-trips through BakeConfigToJson unchanged.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <string_view>

#include "drape/bake/bake_config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    drape::bake::BakeConfig config;
    const drape::Status status = drape::bake::ParseBakeConfig(text, "fuzz.json", &config);
    if (!status.ok()) {
      if (status.message().rfind("fuzz.json: ", 0) != 0) std::abort();  // names the file
      return 0;
    }
    drape::bake::BakeConfig again;
    const std::string dumped = drape::bake::BakeConfigToJson(config).dump();
    if (!drape::bake::ParseBakeConfig(dumped, "again", &again).ok()) std::abort();
    if (drape::bake::BakeConfigToJson(again) != drape::bake::BakeConfigToJson(config)) std::abort();
  } catch (...) {
    std::abort();  // an exception escaping the entry point is a crash of the tool
  }
  return 0;
}

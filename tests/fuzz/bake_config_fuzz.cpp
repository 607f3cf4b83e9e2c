// libFuzzer target: the bake config parser on arbitrary text: a status, never a crash; an
// accepted config round-trips through BakeConfigToJson unchanged.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "drape/bake/bake_config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const nlohmann::json parsed = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (parsed.is_discarded()) return 0;
  drape::bake::BakeConfig config;
  if (!drape::bake::ApplyBakeConfig(parsed, "fuzz.json", &config).ok()) return 0;
  drape::bake::BakeConfig again;
  if (!drape::bake::ApplyBakeConfig(drape::bake::BakeConfigToJson(config), "again", &again).ok())
    std::abort();
  if (drape::bake::BakeConfigToJson(again) != drape::bake::BakeConfigToJson(config)) std::abort();
  return 0;
}

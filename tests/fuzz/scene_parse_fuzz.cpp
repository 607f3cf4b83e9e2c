// libFuzzer target: the scene parser on arbitrary text, then the bake config it implies: a
// status, never a crash; every refusal names the scene file.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "drape/bake/bake_config.h"
#include "drape/bake/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const nlohmann::json parsed = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (parsed.is_discarded()) return 0;
  drape::bake::Scene scene;
  const drape::Status status = drape::bake::ParseScene(parsed, "fuzz.json", "/nonexistent", &scene);
  if (!status.ok()) {
    if (status.message().find("fuzz.json") == std::string::npos) std::abort();
    return 0;
  }
  drape::bake::BakeConfig config;
  (void)drape::bake::ApplySceneToBakeConfig(scene, &config);
  return 0;
}

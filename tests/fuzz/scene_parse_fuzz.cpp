// libFuzzer target: drape-sim's scene entry point (ParseSceneText, what the scene file's bytes
// go through), then the bake config it implies, on arbitrary bytes: a status, never a crash and
// never an escaped exception; every refusal names the scene file.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <string_view>

#include "drape/bake/bake_config.h"
#include "drape/bake/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    drape::bake::Scene scene;
    const drape::Status status =
        drape::bake::ParseSceneText(text, "fuzz.json", "/nonexistent", &scene);
    if (!status.ok()) {
      if (status.message().find("fuzz.json") == std::string::npos) std::abort();
      return 0;
    }
    drape::bake::BakeConfig config;
    (void)drape::bake::ApplySceneToBakeConfig(scene, &config);
  } catch (...) {
    std::abort();  // an exception escaping the entry point is a crash of the tool
  }
  return 0;
}

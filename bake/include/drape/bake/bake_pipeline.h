#pragma once
// The whole bake: import, then every collider stage the config enables, into one asset plus a
// JSON report (what was built, what was left out and why, timings per stage).

#include <nlohmann/json.hpp>
#include <string>

#include "drape/bake/bake_config.h"
#include "drape/bake/scene.h"
#include "drape/formats/character_asset.h"
#include "drape/formats/status.h"

namespace drape::bake {

struct BakeResult {
  CharacterAsset asset;
  nlohmann::json report;
  // Every file the bake read besides its config and scene files: the model and what it names
  // (buffers, materials, textures), then the scene's garment meshes. For build-system
  // dependency files (drape-bake --depfile).
  std::vector<std::string> input_files;
};

// preview_dir: where preview pictures go (must exist), or empty for none. scene: when given, the
// colliders and map poses the scene's garments cannot reach over what it plays are left out, and
// the report says which and why ("model only what a scene needs").
Status BakeCharacter(const std::string& input, const BakeConfig& config, BakeResult* result,
                     const std::string& preview_dir = "", const Scene* scene = nullptr);

}  // namespace drape::bake

#pragma once
// drape-sim's bake cache: the character's .drape for a scene, baked only when the cached one is
// missing or stale. The cache is DIR/character.drape plus DIR/character.bake.json, which holds
// the key it was baked under: a hash of the character file's bytes, the effective bake
// configuration (defaults + the scene's /bake overrides + the collider kinds and clip the scene
// needs, as drape-bake --config would spell them) and the file format version. Any difference
// rebakes.

#include <nlohmann/json.hpp>
#include <string>

#include "drape/bake/scene.h"
#include "drape/formats/character_asset.h"
#include "drape/formats/status.h"

namespace drape::sim {

struct SceneAsset {
  CharacterAsset asset;
  std::string path;       // the .drape in use
  bool baked = false;     // baked by this call (else read: cached, or named by the scene)
  std::string reason;     // why it was baked, or "cached" / "named by the scene"
  double bake_ms = 0.0;   // wall time of the bake (0 when not baked)
  nlohmann::json report;  // the bake report (baked only)
};

// A scene naming a .drape reads it; otherwise the cache in `directory` (which must exist) is
// reused or rebaked. Errors name the file and the reason.
Status LoadOrBakeAsset(const bake::Scene& scene, const std::string& directory, SceneAsset* out);

// 64-bit FNV-1a of a file's bytes, as 16 hex digits.
Status HashFile(const std::string& path, std::string* hex);

}  // namespace drape::sim

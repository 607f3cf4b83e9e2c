#include "characters.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"
#include "options.h"

namespace drape::bench {
namespace {

// The height (metres, along +Y) of the character's rest pose: the skinned body that every
// measurement uses (SplitRegions skins the same pose). The bind-pose mesh can differ from it by
// the armature's scale.
float RestHeight(const CharacterSpec& spec, const bake::Character& character) {
  SkeletonPose pose;
  std::vector<Float3> rest(character.mesh.vertex_count());
  if (!pose.Init(character.skeleton).ok()) Fail(spec.label + ": cannot pose its skeleton");
  pose.SetRest();
  if (!SkinMesh(character.mesh, pose.skinning(), rest).ok()) {
    Fail(spec.label + ": cannot skin its rest pose");
  }
  return HeightOf(rest);
}

}  // namespace

std::vector<CharacterSpec> ResolveCharacters(const std::vector<std::string>& requested) {
  const std::string shared = std::string(DRAPE_SHARED_DIR) + "/assets/characters/";
  const CharacterSpec builtin{
      "mannequin", std::string(DRAPE_SOURCE_DIR) + "/samples/mannequin/mannequin.gltf", true};
  // Humans are held to the targets (--check, the report's target table); the others are
  // measured and reported.
  const CharacterSpec shared_characters[] = {
      {"CesiumMan", shared + "CesiumMan/CesiumMan.glb", true},
      {"RiggedFigure", shared + "RiggedFigure/RiggedFigure.glb", true},
      {"RobotExpressive", shared + "RobotExpressive/RobotExpressive.glb", true},
      {"Animated_Human", shared + "QuaterniusAnimatedHuman/Animated_Human.fbx", true},
      {"RiggedSimple", shared + "RiggedSimple/RiggedSimple.gltf", false},
      {"Fox", shared + "Fox/Fox.glb", false},
      {"Spider", shared + "QuaterniusSpider/Spider.fbx", false},
  };
  std::vector<CharacterSpec> out;
  for (const std::string& r : requested) {
    if (r == "builtin") {
      out.push_back(builtin);
    } else if (r == "all") {
      out.push_back(builtin);
      for (const CharacterSpec& c : shared_characters) {
        if (std::filesystem::exists(c.path)) {
          out.push_back(c);
        } else {
          std::printf("skipping %s: shared asset absent (%s)\n", c.label.c_str(), c.path.c_str());
        }
      }
    } else {
      if (!std::filesystem::exists(r)) Fail(r + ": no such file");
      out.push_back({std::filesystem::path(r).stem().string(), r, true});
    }
  }
  return out;
}

float HeightOf(const std::vector<Float3>& body) {
  float lo = 1e30f, hi = -1e30f;
  for (const Float3& p : body) lo = std::min(lo, p.y), hi = std::max(hi, p.y);
  return hi - lo;
}

bake::ImportOptions ImportFor(const CharacterSpec& spec, bake::Character* character,
                              std::string* note) {
  bake::ImportOptions import;
  Status s = bake::ImportCharacter(spec.path, import, character);
  if (!s.ok()) Fail(spec.path + ": " + s.message());
  const float height = RestHeight(spec, *character);
  if (spec.human && height > kTallestHuman) {
    import.unit_scale = double(character->info.unit_scale) * 1.75 / double(height);
    s = bake::ImportCharacter(spec.path, import, character);
    if (!s.ok()) Fail(spec.path + ": " + s.message());
    *note = "its rest pose is " + std::to_string(height) + " m tall; measured rescaled to 1.75 m";
  }
  return import;
}

}  // namespace drape::bench

// ParseScene, LoadScene and ApplySceneToBakeConfig: a scene file through its schema
// (scene_schema.cpp), then the rules that span its objects.

#include <filesystem>
#include <fstream>

#include "config/json_document.h"
#include "drape/bake/scene.h"
#include "scene/scene_frames.h"
#include "scene/scene_messages.h"
#include "scene/scene_schema.h"

namespace drape::bake {

using namespace detail;
using nlohmann::json;

Status ParseScene(const json& value, const std::string& source, const std::string& directory,
                  Scene* scene) {
  Scene result;
  result.source = source;
  result.directory = directory;
  if (!value.is_object())
    return Invalid(source + ": the scene must be a JSON object, not " + JsonTypeName(value));
  const JsonDocument document{source, directory};
  const JsonAt root(value, "", document);
  DRAPE_RETURN_IF_ERROR(SceneSchema().Read(root, &result));

  // Baked maps of a static scene are of the rest pose (drape-bake's pose without a clip).
  if (result.use_maps && result.maps_source == MapSource::kBaked && result.animation.clip.empty() &&
      result.animation.pose == ScenePose::kBind) {
    return root.Member("animation")
        .Member("pose")
        .Error("baked maps are of the rest pose: use \"rest\", a clip, or rendered maps");
  }
  const SceneAnimation& anim = result.animation;
  if (result.use_maps && result.maps_source == MapSource::kBaked &&
      (!anim.blend_clip.empty() || anim.perturb_degrees > 0.f)) {
    return root.Member("collision")
        .Member("maps_source")
        .Error(
            "baked maps hold the clip's own poses: a blend or a perturbation needs "
            "\"rendered\" maps");
  }
  if (result.animation.clip.empty() && result.animation.duration < 0.f)
    result.animation.duration = 1.f;  // a static scene: one second unless told
  if (result.animation.duration > 0.f)
    result.frame_count = FrameCountFor(result.animation.duration, result.dt);
  *scene = std::move(result);
  return Status::Ok();
}

Status LoadScene(const std::string& path, Scene* scene) {
  json parsed;
  if (Status s = ReadJsonFile(path, "scene", &parsed); !s.ok()) return s;
  const std::string directory = std::filesystem::path(path).parent_path().string();
  return ParseScene(parsed, path, directory, scene);
}

Status ParseSceneText(std::string_view text, const std::string& source,
                      const std::string& directory, Scene* scene) {
  json parsed;
  if (Status s = ParseJsonText(text, source, &parsed); !s.ok()) return s;
  return ParseScene(parsed, source, directory, scene);
}

Status ApplySceneToBakeConfig(const Scene& scene, BakeConfig* config) {
  BakeConfig result = *config;
  if (!scene.bake.empty()) {
    const JsonDocument document{scene.source, scene.directory};
    DRAPE_RETURN_IF_ERROR(ReadBakeOverrides(JsonAt(scene.bake, "/bake", document), &result));
  }
  result.maps_enabled = scene.use_maps;
  result.hulls_enabled = scene.use_hulls;
  result.spheres_enabled = scene.use_spheres;
  result.capsules_enabled = scene.use_capsules;
  // Baked maps of the poses the scene plays: its clip (at maps.clip_rate), or the rest pose.
  // Rendered maps need the rest pose's alone (their texel size, epsilon and grid).
  result.maps_clip = scene.use_maps && scene.maps_source == MapSource::kBaked ? scene.animation.clip
                                                                              : std::string();
  result.maps_clip_origin = scene.source + ": /animation/clip";
  *config = result;
  return Status::Ok();
}

}  // namespace drape::bake

#pragma once
// drape-sim's pictures of one frame: the body, the garments and (on request) the colliders'
// outlines, on a floor, framed once for the whole scene.

#include <cstdint>
#include <utility>
#include <vector>

#include "drape/bake/scene.h"
#include "drape/formats/character_asset.h"
#include "renderer.h"
#include "simulation.h"

namespace drape::sim {

class FrameRenderer {
 public:
  static constexpr int kSupersample = 2;

  // Frames the camera on the body over the whole scene (eight poses of the clip, or the static
  // pose) and on the garments at their start. The scene and the asset must outlive the renderer.
  Status Frame(const bake::Scene& scene, const CharacterAsset& asset, int32_t clip,
               const SceneSimulation& sim);
  // The frame's picture: output.width x output.height RGB bytes.
  std::vector<uint8_t> Render(const SceneSimulation& sim);

 private:
  void DrawColliders(const SceneSimulation& sim, Canvas* canvas);

  const bake::Scene* scene_ = nullptr;
  const CharacterAsset* asset_ = nullptr;
  Camera camera_;
  Light light_;
  float floor_y_ = 0.f, floor_x_ = 0.f, floor_z_ = 0.f;
  std::vector<std::vector<std::pair<Float3, Float3>>> hull_edges_;  // per hull of the set
  std::vector<Float3> body_;
};

}  // namespace drape::sim

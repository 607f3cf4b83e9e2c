#pragma once
// The scene's engine colliders (/collision/shapes) posed for each frame into a ShapeColliderSet.

#include <cstdint>
#include <span>
#include <vector>

#include "drape/bake/scene.h"
#include "drape/formats/skeleton_data.h"
#include "drape/formats/status.h"
#include "drape/runtime/shape_collider_set.h"

namespace drape::sim {

class SceneShapes {
 public:
  // Resolves the shapes' joints against the skeleton and their frames at the rest pose
  // (rest_skinning). Errors name the scene path of the shape. Allocates.
  Status Init(const bake::Scene& scene, const SkeletonData& skeleton,
              std::span<const Mat34> rest_skinning);
  bool empty() const { return shapes_.empty(); }
  // Fills `set` with every shape at the frame's start and end poses (no allocation once the set
  // was reserved by Init's caller for size() shapes).
  Status Pose(std::span<const Mat34> skinning_start, std::span<const Mat34> skinning_end,
              ShapeColliderSet* set) const;
  uint32_t size() const { return static_cast<uint32_t>(shapes_.size()); }

 private:
  struct Posed {
    const bake::SceneShape* shape = nullptr;
    int32_t joint = -1;       // -1: fixed in the world
    Mat34 local;              // shape frame -> world at the rest pose
    Mat34 inverse_rest;       // inverse of the joint's rest skinning matrix
    float half_length = 0.f;  // capsule, metres
  };
  std::vector<Posed> shapes_;
};

}  // namespace drape::sim

#pragma once
// Per-bone local maps at run time (drape/formats/body_map_data.h, BoneMapSet): each bone's part
// of the body as front/back maps baked once in a view frame fixed to the bone, posed by the
// skinning matrices, so the collider follows any pose the engine drives without rendering. How
// it works and what it costs: docs/ALGORITHMS.md §7.10, docs/PERFORMANCE.md.
//
//   BoneMapCollider bones;
//   bones.Build(asset.bone_maps, asset.skeleton.joint_count());            // once: allocates
//   bones.SetPose(skinning_at_step_start, skinning_at_step_end);           // per step
//   bones.CollideBatch(previous, positions, velocities, flags, params);    // per step
//
// A motion p0 -> p1 is tested in each bone whose posed bounds it reaches, p0 mapped by the start
// pose and p1 by the end pose (the motion relative to the moving bone); the earliest contact
// wins. The blended skin near a joint is in the parts of both bones, each taking it as rigid:
// that is the method's error where a joint bends (docs/PERFORMANCE.md measures it).

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "drape/formats/body_map_data.h"
#include "drape/formats/status.h"
#include "drape/formats/types.h"
#include "drape/runtime/body_map_collider.h"
#include "drape/runtime/collision_types.h"

namespace drape {

class BoneMapCollider {
 public:
  // Validates and decodes every bone's maps (allocates); joint indices must be < joint_count.
  // Posed in the bind pose until SetPose. On error the collider is empty and the message names
  // the bone map and the reason.
  Status Build(const BoneMapSet& maps, uint32_t joint_count,
               DepthSampling sampling = DepthSampling::kNearest);

  // The pose at the start and the end of the step (SkeletonPose::skinning(), one per joint).
  // No allocation. A matrix that is not finite or not invertible is kInvalidArgument naming the
  // joint, and leaves the previous pose.
  Status SetPose(std::span<const Mat34> skinning_start, std::span<const Mat34> skinning_end);

  bool IsInside(Float3 p) const;  // at the end pose
  // The earliest contact over the bones the motion reaches (see above); a motion starting
  // inside takes the nearest exit among the bones holding it. Non-finite input: no contact,
  // kCollisionInvalidInput.
  ContactQuery Query(Float3 p0, Float3 p1) const;
  // Query and the response per particle, in place; up to two passes over the bones (a particle
  // pushed out of one part into its neighbour leaves that one too). No allocation; identical
  // bits at any thread count. Spans of one size, params finite.
  Status CollideBatch(std::span<const Float3> previous, std::span<Float3> positions,
                      std::span<Float3> velocities, std::span<uint8_t> flags,
                      const ResponseParams& params, uint32_t* contact_count = nullptr) const;

  bool empty() const { return bones_.empty(); }
  size_t size() const { return bones_.size(); }
  uint32_t joint(size_t bone) const { return bones_[bone].joint; }
  const BodyMapCollider& maps(size_t bone) const { return bones_[bone].maps; }
  size_t memory_bytes() const;

 private:
  struct Bone {
    uint32_t joint = 0;
    Mat34 view_from_bind;
    BodyMapCollider maps;
  };
  struct PosedBone {  // 172 bytes
    Mat34 view_from_world_start, view_from_world_end;
    Mat34 world_from_view_end;
    Float3 lo, hi;    // world box of the maps' bounds over the step, metres
    float scale_end;  // world metres per view-frame metre at the end pose (a depth's scale)
  };
  ContactQuery QueryBone(size_t bone, Float3 p0, Float3 p1) const;
  uint8_t CollideOne(Float3 from, Float3* position, Float3* velocity,
                     const ResponseParams& params) const;

  std::vector<Bone> bones_;
  std::vector<PosedBone> posed_;
  uint32_t joint_count_ = 0;
};

}  // namespace drape

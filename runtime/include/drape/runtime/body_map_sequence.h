#pragma once
// The baked body-map poses of one clip (or the bind pose alone), answered for any time.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "drape/formats/body_map_data.h"
#include "drape/formats/status.h"
#include "drape/runtime/body_map_collider.h"

namespace drape {

// How a sequence answers times between its baked poses.
//  kNearest: the baked pose nearest in time (ties: the earlier one).
//  kBracket: the two poses around the time blended per texel into a caller-owned scratch collider
//    when they share one grid: z interpolated where both poses are valid, the nearer pose's slab,
//    normals and gaps elsewhere. Different grids or layer counts, a time on or outside the baked
//    keys, or no scratch: nearest.
enum class PoseBlend : uint8_t { kNearest = 0, kBracket = 1 };

class BodyMapSequence {
 public:
  // One clip's poses, sorted by non-decreasing finite time, all with the same clip index; at least
  // one. The first pose that fails to build is returned in the message and leaves it empty.
  Status Build(std::span<const BodyMapPose> poses, DepthSampling sampling = DepthSampling::kNearest,
               PoseBlend blend = PoseBlend::kNearest);

  // The collider for `time` (seconds, clamped to the baked range). With kBracket and a scratch,
  // the answer may be *scratch, refilled by this call (its first fill allocates, later fills of
  // the same grid size do not; O(texels)). Not thread-safe on the same scratch.
  const BodyMapCollider& At(float time, BodyMapCollider* scratch = nullptr) const;

  size_t size() const { return poses_.size(); }
  const BodyMapCollider& pose(size_t index) const { return poses_[index]; }
  PoseBlend blend() const { return blend_; }
  size_t memory_bytes() const;
  // BodyMapCollider::LimitInstructionSet on every pose (a caller's scratch keeps its own).
  void LimitInstructionSet(InstructionSet widest) {
    for (BodyMapCollider& pose : poses_) pose.LimitInstructionSet(widest);
  }

 private:
  // The gaps of the blend of a and b at weight w (of b) into *out, whose slabs are blended.
  static void BlendGaps(const BodyMapCollider& a, const BodyMapCollider& b, float w,
                        BodyMapCollider* out);

  std::vector<BodyMapCollider> poses_;
  PoseBlend blend_ = PoseBlend::kNearest;
  BodyMapCollider empty_;
};

}  // namespace drape

#pragma once
// A pose of one skeleton: local transforms -> joint world matrices -> skinning matrices.
// Init allocates; every other call works in the buffers it made (no allocation per frame).

#include <span>
#include <string_view>
#include <vector>

#include "drape/formats/clip_data.h"
#include "drape/formats/skeleton_data.h"
#include "drape/formats/status.h"
#include "drape/formats/types.h"

namespace drape {

class SkeletonPose {
 public:
  // Keeps a reference to `skeleton`, which must outlive the pose. Starts in the rest pose.
  Status Init(const SkeletonData& skeleton);

  // Samples the clip at `time` seconds (clamped to [0, duration], or wrapped when `loop`),
  // interpolating the two neighbouring keys (nlerp on the shorter arc for rotations).
  Status SampleClip(const ClipData& clip, float time, bool loop);
  // The rest pose as authored (often not the bind pose).
  void SetRest();
  // The bind pose: world(j) = inverse(inverse_bind[j]), so every skinning matrix is identity.
  void SetBind();
  // The engine path: joint world matrices in the asset frame, one per joint, from the caller.
  Status SetJointWorldMatrices(std::span<const Mat34> world);
  // Local transforms (parent space) from the caller, one per joint: an engine's animation graph,
  // IK, or a clip edited on top. Non-finite values are refused naming the joint.
  Status SetLocalTransforms(std::span<const Transform> local);
  // Moves this pose's local transforms toward `other`'s (a pose of the same skeleton) by
  // `weight` in [0, 1]: translations and scales lerped, rotations nlerped on the shorter arc
  // (a blend of two clips: sample each into a pose, blend one with the other). Both poses' local
  // transforms come from SetRest, SampleClip or SetLocalTransforms (not the matrix paths).
  Status BlendWith(const SkeletonPose& other, float weight);

  uint32_t joint_count() const { return static_cast<uint32_t>(world_.size()); }
  std::span<const Transform> local() const { return local_; }
  std::span<const Mat34> world() const { return world_; }
  // world(j) * inverse_bind(j): maps the bind-pose asset frame to this pose.
  std::span<const Mat34> skinning() const { return skinning_; }

 private:
  void UpdateFromLocal();
  void UpdateSkinning();

  const SkeletonData* skeleton_ = nullptr;
  std::vector<Transform> local_;
  std::vector<Mat34> world_;
  std::vector<Mat34> skinning_;
};

// Index of the joint with this name, or -1.
int32_t FindJoint(const SkeletonData& skeleton, std::string_view name);

}  // namespace drape

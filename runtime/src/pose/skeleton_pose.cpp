#include "drape/runtime/skeleton_pose.h"

#include <cmath>
#include <string>

#include "drape/runtime/math.h"

namespace drape {

Status SkeletonPose::Init(const SkeletonData& skeleton) {
  const size_t n = skeleton.parents.size();
  if (skeleton.rest_local.size() != n || skeleton.inverse_bind.size() != n) {
    return Status(StatusCode::kInvalidArgument, "skeleton arrays have different lengths");
  }
  // Hand-built skeletons skip the file validator: parents must precede their children.
  for (size_t j = 0; j < n; ++j) {
    if (skeleton.parents[j] < -1 || skeleton.parents[j] >= static_cast<int32_t>(j)) {
      return Status(StatusCode::kInvalidArgument, "skeleton parent of joint " + std::to_string(j) +
                                                      " is " + std::to_string(skeleton.parents[j]) +
                                                      ", not -1 or an earlier joint");
    }
  }
  skeleton_ = &skeleton;
  local_.assign(n, Transform{});
  world_.assign(n, Mat34{});
  skinning_.assign(n, Mat34{});
  SetRest();
  return Status::Ok();
}

void SkeletonPose::SetRest() {
  for (size_t j = 0; j < local_.size(); ++j) local_[j] = skeleton_->rest_local[j];
  UpdateFromLocal();
}

void SkeletonPose::SetBind() {
  for (size_t j = 0; j < world_.size(); ++j) {
    if (!InverseAffine(skeleton_->inverse_bind[j], &world_[j])) world_[j] = Mat34{};
  }
  UpdateSkinning();
}

Status SkeletonPose::SampleClip(const ClipData& clip, float time, bool loop) {
  const size_t joints = world_.size();
  if (clip.frame_count == 0 || clip.keys.size() != static_cast<size_t>(clip.frame_count) * joints) {
    return Status(StatusCode::kInvalidArgument,
                  "clip '" + clip.name + "' does not match the skeleton");
  }
  if (!std::isfinite(time)) return Status(StatusCode::kInvalidArgument, "clip time is not finite");
  if (!(clip.sample_rate > 0.f && std::isfinite(clip.sample_rate)) || !(clip.duration >= 0.f)) {
    return Status(StatusCode::kInvalidArgument,
                  "clip '" + clip.name + "' has a bad rate or duration");
  }
  if (loop && clip.duration > 0.f) {
    time = std::fmod(time, clip.duration);
    if (time < 0.f) time += clip.duration;
  }
  time = std::fmin(std::fmax(time, 0.f), clip.duration);
  const float position = time * clip.sample_rate;
  const uint32_t last = clip.frame_count - 1;
  uint32_t frame = static_cast<uint32_t>(std::floor(position));
  if (frame > last) frame = last;
  const uint32_t next = frame < last ? frame + 1 : last;
  // The last frame sits at the duration, which may be closer than one sample period.
  const float frame_time = static_cast<float>(frame) / clip.sample_rate;
  const float next_time = std::fmin(static_cast<float>(next) / clip.sample_rate, clip.duration);
  const float span = next_time - frame_time;
  const float alpha = span > 0.f ? std::fmin(std::fmax((time - frame_time) / span, 0.f), 1.f) : 0.f;
  const Transform* a = &clip.keys[static_cast<size_t>(frame) * joints];
  const Transform* b = &clip.keys[static_cast<size_t>(next) * joints];
  for (size_t j = 0; j < joints; ++j) local_[j] = Interpolate(a[j], b[j], alpha);
  UpdateFromLocal();
  return Status::Ok();
}

Status SkeletonPose::SetJointWorldMatrices(std::span<const Mat34> world) {
  if (world.size() != world_.size()) {
    return Status(StatusCode::kInvalidArgument, "expected " + std::to_string(world_.size()) +
                                                    " joint matrices, got " +
                                                    std::to_string(world.size()));
  }
  for (size_t j = 0; j < world.size(); ++j) {
    for (float v : world[j].m) {
      if (!std::isfinite(v)) {
        return Status(StatusCode::kInvalidArgument,
                      "joint matrix " + std::to_string(j) + " is not finite");
      }
    }
    world_[j] = world[j];
  }
  UpdateSkinning();
  return Status::Ok();
}

Status SkeletonPose::SetLocalTransforms(std::span<const Transform> local) {
  if (local.size() != local_.size()) {
    return Status(StatusCode::kInvalidArgument, "expected " + std::to_string(local_.size()) +
                                                    " local transforms, got " +
                                                    std::to_string(local.size()));
  }
  for (size_t j = 0; j < local.size(); ++j) {
    const Transform& t = local[j];
    const bool finite = IsFinite(t.translation) && IsFinite(t.scale) &&
                        std::isfinite(t.rotation.x) && std::isfinite(t.rotation.y) &&
                        std::isfinite(t.rotation.z) && std::isfinite(t.rotation.w);
    if (!finite) {
      return Status(StatusCode::kInvalidArgument,
                    "local transform " + std::to_string(j) + " is not finite");
    }
  }
  for (size_t j = 0; j < local.size(); ++j) local_[j] = local[j];
  UpdateFromLocal();
  return Status::Ok();
}

Status SkeletonPose::BlendWith(const SkeletonPose& other, float weight) {
  if (other.skeleton_ != skeleton_ || other.local_.size() != local_.size()) {
    return Status(StatusCode::kInvalidArgument, "BlendWith: a pose of another skeleton");
  }
  if (!(weight >= 0.f && weight <= 1.f)) {
    return Status(StatusCode::kInvalidArgument, "BlendWith: weight is not in [0, 1]");
  }
  for (size_t j = 0; j < local_.size(); ++j) {
    local_[j] = Interpolate(local_[j], other.local_[j], weight);
  }
  UpdateFromLocal();
  return Status::Ok();
}

void SkeletonPose::UpdateFromLocal() {
  for (size_t j = 0; j < local_.size(); ++j) {
    const Mat34 local = ToMatrix(local_[j]);
    const int32_t parent = skeleton_->parents[j];
    world_[j] = parent < 0 ? local : Multiply(world_[parent], local);
  }
  UpdateSkinning();
}

void SkeletonPose::UpdateSkinning() {
  for (size_t j = 0; j < world_.size(); ++j) {
    skinning_[j] = Multiply(world_[j], skeleton_->inverse_bind[j]);
  }
}

int32_t FindJoint(const SkeletonData& skeleton, std::string_view name) {
  for (size_t j = 0; j < skeleton.joint_names.size(); ++j) {
    if (skeleton.joint_names[j] == name) return static_cast<int32_t>(j);
  }
  return -1;
}

}  // namespace drape

// ScenePoser: the pose a scene plays at a time (its clip or static pose, a blend with a second
// clip, fixed random joint rotations on top), and the perturbation itself.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "config/clip_lookup.h"
#include "drape/bake/scene.h"
#include "drape/runtime/math.h"
#include "scene/scene_messages.h"

namespace drape::bake {
namespace {

// splitmix64: the same numbers on every machine and standard library.
uint64_t NextRandom(uint64_t* state) {
  uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

double Uniform(uint64_t* state, double lo, double hi) {  // [lo, hi)
  return lo + (hi - lo) * static_cast<double>(NextRandom(state) >> 11) * 0x1.0p-53;
}

}  // namespace

void PerturbJointRotations(std::span<Transform> local, float max_degrees, uint32_t seed) {
  if (!(max_degrees > 0.f)) return;
  uint64_t state = seed;
  constexpr double kPi = 3.14159265358979323846;
  for (Transform& t : local) {
    // A uniform axis: a point in the unit ball, by rejection, normalised.
    double axis[3] = {0.0, 0.0, 1.0}, length = 0.0;
    for (int tries = 0; tries < 64; ++tries) {
      for (double& c : axis) c = Uniform(&state, -1.0, 1.0);
      length = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
      if (length > 1e-3 && length <= 1.0) break;
    }
    const double angle = Uniform(&state, -1.0, 1.0) * max_degrees * kPi / 180.0;
    const double s = std::sin(0.5 * angle) / std::max(length, 1e-3);
    const Quat turn{static_cast<float>(axis[0] * s), static_cast<float>(axis[1] * s),
                    static_cast<float>(axis[2] * s), static_cast<float>(std::cos(0.5 * angle))};
    t.rotation = Normalize(Multiply(t.rotation, turn));
  }
}

Status ScenePoser::Init(const Scene& scene, const CharacterAsset& asset, int32_t clip) {
  scene_ = &scene;
  asset_ = &asset;
  clip_ = clip;
  blend_clip_ = -1;
  DRAPE_RETURN_IF_ERROR(blend_pose_.Init(asset.skeleton));
  local_.assign(asset.skeleton.joint_count(), Transform{});
  const SceneAnimation& anim = scene.animation;
  if (!anim.blend_clip.empty() && clip >= 0) {
    DRAPE_RETURN_IF_ERROR(detail::FindClipNamed(asset.clips, anim.blend_clip,
                                                scene.source + ": /animation/blend_clip",
                                                scene.character, &blend_clip_));
  }
  return Status::Ok();
}

Status ScenePoser::Pose(float time, SkeletonPose* pose) {
  const SceneAnimation& anim = scene_->animation;
  if (clip_ >= 0) {
    DRAPE_RETURN_IF_ERROR(
        pose->SampleClip(asset_->clips[static_cast<size_t>(clip_)], time, anim.loop));
    if (blend_clip_ >= 0) {
      DRAPE_RETURN_IF_ERROR(
          blend_pose_.SampleClip(asset_->clips[static_cast<size_t>(blend_clip_)], time, anim.loop));
      DRAPE_RETURN_IF_ERROR(pose->BlendWith(blend_pose_, anim.blend_weight));
    }
  } else if (anim.pose == ScenePose::kRest) {
    pose->SetRest();
  } else {
    pose->SetBind();
    return Status::Ok();  // matrices only: nothing local to perturb
  }
  if (anim.perturb_degrees > 0.f) {
    const std::span<const Transform> current = pose->local();
    std::copy(current.begin(), current.end(), local_.begin());
    PerturbJointRotations(local_, anim.perturb_degrees, anim.perturb_seed);
    DRAPE_RETURN_IF_ERROR(pose->SetLocalTransforms(local_));
  }
  return Status::Ok();
}

}  // namespace drape::bake

// ClothSolver's constraints beyond the springs: long-range tethers, and a skinned garment's
// targets, max distance and backstop (docs/ALGORITHMS.md §10.7).
#include <cmath>
#include <limits>

#include "cloth/cloth_setup.h"
#include "cloth/cloth_solver_internal.h"
#include "drape/runtime/cloth_solver.h"
#include "drape/runtime/math.h"
#include "tasks/parallel_for.h"

namespace drape {

using detail::kParticleGrain;
using detail::ParallelFor;

// Skinned garments: each skinned target's position at the frame's start and end, and its normal
// where it has a backstop.
void ClothSolver::ComputeSkinnedTargets(const ClothFrame& frame) {
  const Cloth& cloth = *cloth_;
  const int64_t count = static_cast<int64_t>(skin_targets_.size());
  if (count == 0) return;
  const ClothSkinWeights* skin = cloth.skin().data();
  const Float3* rest = cloth.skin_bind_positions().data();
  const Float3* normal = cloth.rest_normals().data();
  const float* backstop = cloth.backstops().data();
  const Mat34* s0 = frame.skinning_start.data();
  const Mat34* s1 = frame.skinning_end.data();
  ParallelFor(count, kParticleGrain, [&](int64_t k) {
    const uint32_t i = skin_targets_[k];
    skin_start_[k] = detail::SkinPoint(skin[i], s0, rest[i]);
    skin_end_[k] = detail::SkinPoint(skin[i], s1, rest[i]);
    // Only a backstop needs the normal (a kinematic particle is placed exactly).
    if (k < skin_kinematic_count_ || !(backstop[i] < std::numeric_limits<float>::infinity()))
      return;
    skin_normal_start_[k] = detail::SkinVector(skin[i], s0, normal[i]);
    skin_normal_end_[k] = detail::SkinVector(skin[i], s1, normal[i]);
  });
}

// Each tethered particle is pulled back onto the sphere of its tether's length around its anchor
// (a kinematic particle, already placed): writes its own particle only.
void ClothSolver::ApplyTethers(ClothState* state, const Substep& sub) {
  const int64_t count = static_cast<int64_t>(cloth_->tethers().size());
  if (!settings_.tethers || count == 0) return;
  const ClothTether* tethers = cloth_->tethers().data();
  Float3* x = state->positions.data();
  Float3* v = state->velocities.data();
  const bool euler = settings_.integrator == ClothIntegrator::kExplicitEuler;
  const float inv_h = 1.f / sub.h;
  ParallelFor(count, kParticleGrain, [&](int64_t k) {
    const ClothTether& t = tethers[k];
    const Float3 anchor = x[t.anchor];
    const Float3 d = x[t.particle] - anchor;
    const float squared = Dot(d, d);
    if (!(squared > t.length * t.length)) return;
    const Float3 moved = anchor + d * (t.length / std::sqrt(squared));
    if (euler) v[t.particle] += (moved - x[t.particle]) * inv_h;  // Verlet re-derives it
    x[t.particle] = moved;
  });
}

// Skinned garments: a particle farther than its max distance from its skinned position is pulled
// onto that sphere; one behind its backstop plane (backstop metres behind the skinned position
// along the skinned normal) is pushed onto the plane.
void ClothSolver::ApplySkinConstraints(ClothState* state, const Substep& sub) {
  const int64_t begin = skin_kinematic_count_, end = static_cast<int64_t>(skin_targets_.size());
  if (begin == end) return;
  const float* max_distance = cloth_->max_distances().data();
  const float* backstop = cloth_->backstops().data();
  Float3* x = state->positions.data();
  Float3* v = state->velocities.data();
  const bool euler = settings_.integrator == ClothIntegrator::kExplicitEuler;
  const float inv_h = 1.f / sub.h;
  const float s = sub.s1;
  ParallelFor(end - begin, kParticleGrain, [&](int64_t offset) {
    const int64_t k = begin + offset;
    const uint32_t i = skin_targets_[k];
    const Float3 target = skin_start_[k] * (1.f - s) + skin_end_[k] * s;
    Float3 p = x[i];
    const float limit = max_distance[i];
    const Float3 d = p - target;
    const float squared = Dot(d, d);
    if (squared > limit * limit) p = target + d * (limit / std::sqrt(squared));
    if (backstop[i] < std::numeric_limits<float>::infinity()) {
      const Float3 n =
          NormalizeOr(skin_normal_start_[k] * (1.f - s) + skin_normal_end_[k] * s, Float3{});
      const float behind = -backstop[i] - Dot(p - target, n);
      if (behind > 0.f) p += n * behind;
    }
    if (euler) v[i] += (p - x[i]) * inv_h;
    x[i] = p;
  });
}

}  // namespace drape

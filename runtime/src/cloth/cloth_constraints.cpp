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

namespace {

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

// A tethered particle farther than its tether's length from its anchor is pulled onto that
// sphere. True when it moved.
inline bool TetherLimit(Float3 anchor, float length, Float3* x) {
  const Float3 d = *x - anchor;
  const float squared = Dot(d, d);
  if (!(squared > length * length)) return false;
  *x = anchor + d * (length / std::sqrt(squared));
  return true;
}

inline Float3 ToFloat3(const internal::Particle4& p) { return Float3{p.x, p.y, p.z}; }

}  // namespace

// Which tether and skinned target (if any) constrain each particle: Cloth builds at most one
// tether per particle (to its nearest held one), and a particle is one skinned target at most.
void ClothSolver::IndexConstraints() {
  const size_t n = cloth_->particle_count();
  tether_of_.assign(n, kNone);
  const std::span<const ClothTether> tethers = cloth_->tethers();
  for (uint32_t k = 0; k < tethers.size(); ++k) tether_of_[tethers[k].particle] = k;
  skin_target_of_.assign(n, kNone);
  for (uint32_t k = skin_kinematic_count_; k < skin_targets_.size(); ++k)
    skin_target_of_[skin_targets_[k]] = k;
}

// A skinned garment's particle, skinned target k, at x at the substep's end fraction s: farther
// than its max distance from its skinned position it is pulled onto that sphere; behind its
// backstop plane (backstop metres behind the skinned position along the skinned normal) it is
// pushed onto the plane.
Float3 ClothSolver::SkinLimit(uint32_t k, Float3 x, float s) const {
  const uint32_t i = skin_targets_[k];
  const Float3 target = skin_start_[k] * (1.f - s) + skin_end_[k] * s;
  const float limit = cloth_->max_distances()[i];
  const float backstop = cloth_->backstops()[i];
  const Float3 d = x - target;
  const float squared = Dot(d, d);
  if (squared > limit * limit) x = target + d * (limit / std::sqrt(squared));
  if (backstop < std::numeric_limits<float>::infinity()) {
    const Float3 n =
        NormalizeOr(skin_normal_start_[k] * (1.f - s) + skin_normal_end_[k] * s, Float3{});
    const float behind = -backstop - Dot(x - target, n);
    if (behind > 0.f) x += n * behind;
  }
  return x;
}

// After the springs: each particle's tether (its anchor is kinematic, already placed), then its
// skinned target's limits, one particle at a time (each writes only its own). Verlet: from the
// spring solver's copy, which goes back to the state here with the re-estimated velocities, in
// the same pass. Explicit Euler: on the state, each correction also added to the velocity, then
// the kinematic particles' velocities.
void ClothSolver::ConstrainAndUpdateVelocities(ClothState* state, const Substep& sub) {
  const int64_t n = static_cast<int64_t>(state->positions.size());
  const ClothTether* tethers = cloth_->tethers().data();
  const uint32_t* tether_of = tether_of_.data();
  const uint32_t* skin_target_of = skin_target_of_.data();
  const bool tether = settings_.tethers && !cloth_->tethers().empty();
  const bool skin = skin_targets_.size() > skin_kinematic_count_;
  Float3* x = state->positions.data();
  const Float3* x_start = state->previous_positions.data();
  Float3* v = state->velocities.data();
  const float inv_h = 1.f / sub.h;
  const float s = sub.s1;
  if (settings_.integrator == ClothIntegrator::kVerlet) {
    const internal::Particle4* p = solver_positions_.data();
    ParallelFor(n, kParticleGrain, [&](int64_t i) {
      Float3 xi = ToFloat3(p[i]);
      if (tether && tether_of[i] != kNone) {
        const ClothTether& t = tethers[tether_of[i]];
        TetherLimit(ToFloat3(p[t.anchor]), t.length, &xi);
      }
      if (skin && skin_target_of[i] != kNone) xi = SkinLimit(skin_target_of[i], xi, s);
      x[i] = xi;
      v[i] = (xi - x_start[i]) * inv_h;
    });
    return;
  }
  if (tether || skin) {
    ParallelFor(n, kParticleGrain, [&](int64_t i) {
      if (tether && tether_of[i] != kNone) {
        const ClothTether& t = tethers[tether_of[i]];
        Float3 moved = x[i];
        if (TetherLimit(x[t.anchor], t.length, &moved)) {
          v[i] += (moved - x[i]) * inv_h;
          x[i] = moved;
        }
      }
      if (skin && skin_target_of[i] != kNone) {
        const Float3 limited = SkinLimit(skin_target_of[i], x[i], s);
        v[i] += (limited - x[i]) * inv_h;
        x[i] = limited;
      }
    });
  }
  const uint32_t* kinematic = cloth_->kinematic_particles().data();
  const int64_t count = static_cast<int64_t>(cloth_->kinematic_particles().size());
  ParallelFor(count, kParticleGrain, [&](int64_t k) {
    const uint32_t i = kinematic[k];
    v[i] = (x[i] - x_start[i]) * inv_h;
  });
}

}  // namespace drape

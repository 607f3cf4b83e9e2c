// ClothSolver's bookkeeping stages: the kinematic particles restored after the colliders, the
// finite checks, the contact count and the stretch measure, and the backup restored after a
// blow-up.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>

#include "cloth/cloth_solver_internal.h"
#include "drape/runtime/cloth_solver.h"
#include "drape/runtime/math.h"
#include "tasks/parallel_for.h"

namespace drape {

using detail::AnyNonFinite;
using detail::kNoParticle;
using detail::kParticleGrain;
using detail::ParallelRanges;

namespace {
constexpr int64_t kSpringGrain = 4096;  // springs per chunk of the stretch measure
}  // namespace

void ClothSolver::RestoreKinematic(ClothState* state) {
  if (!restore_kinematic_) return;
  restore_kinematic_ = false;
  const std::span<const uint32_t> kinematic = cloth_->kinematic_particles();
  for (size_t k = 0; k < kinematic.size(); ++k) {
    const uint32_t i = kinematic[k];
    state->positions[i] = kinematic_positions_[k];
    state->velocities[i] = kinematic_velocities_[k];
    flags_[i] = 0;
    body_map_flags_[i] = 0;
    shape_flags_[i] = 0;
  }
}

// Only once a check has found one (an error message names it): a plain scan in order.
uint32_t ClothSolver::FirstNonFinite(const ClothState& state) const {
  for (size_t i = 0; i < state.positions.size(); ++i)
    if (!IsFinite(state.positions[i]) || !IsFinite(state.velocities[i]))
      return static_cast<uint32_t>(i);
  return kNoParticle;
}

// One pass over the particles for the substep's bookkeeping: the other colliders' flags merged,
// the contacts counted and (check_finite) whether any position or velocity is not finite.
uint32_t ClothSolver::CountContacts(const ClothState& state, bool check_finite,
                                    bool* any_non_finite) {
  const Float3* x = state.positions.data();
  const Float3* v = state.velocities.data();
  uint8_t* flags = flags_.data();
  const uint8_t* body_map = body_map_flags_.data();
  const uint8_t* shapes = shape_flags_.data();
  const bool merge_body_map = (merge_flags_ & 1) != 0, merge_shapes = (merge_flags_ & 2) != 0;
  const int64_t n = static_cast<int64_t>(flags_.size());
  detail::ChunkSum contacts, bad_chunks;
  ParallelRanges(n, kParticleGrain, [&](int64_t begin, int64_t end) {
    uint32_t count = 0;
    for (int64_t i = begin; i < end; ++i) {
      if (merge_body_map) flags[i] = static_cast<uint8_t>(flags[i] | body_map[i]);
      if (merge_shapes) flags[i] = static_cast<uint8_t>(flags[i] | shapes[i]);
      count += flags[i] & kCollisionContact;
    }
    contacts.Add(count);
    if (check_finite && AnyNonFinite(x, v, begin, end)) bad_chunks.Add(1);
  });
  *any_non_finite = bad_chunks.total() != 0;
  return contacts.total();
}

// After Integrate: the previous positions are the substep's start unless the root's motion
// carried the particles (CheckInputAndBackUp or BeginSubstep then copied them first).
void ClothSolver::RestoreBackup(ClothState* state) {
  const size_t bytes = state->positions.size() * sizeof(Float3);
  if (positions_backed_up_)
    std::memcpy(state->previous_positions.data(), backup_positions_.data(), bytes);
  std::memcpy(state->positions.data(), state->previous_positions.data(), bytes);
  std::memcpy(state->velocities.data(), backup_velocities_.data(), bytes);
  restore_kinematic_ = false;
}

ClothSolver::StretchFigures ClothSolver::MeasureStretch(const ClothState& state) const {
  if (measured_springs_.empty()) return {};
  const MeasuredSpring* springs = measured_springs_.data();
  const Float3* x = state.positions.data();
  // A spring counts as overstretched beyond the strain limit by more than the limit pass's
  // rounding (which leaves a spring it shortened within a few ulps of the limit): L^2 > (R (1 +
  // limit))^2 (1 + 1e-4), the limit 10 % when the strain limit is off.
  const bool limited = settings_.max_stretch < std::numeric_limits<float>::infinity();
  const float allowed = 1.f + (limited ? settings_.max_stretch : 0.1f);
  const float over_factor = allowed * allowed * (1.f + 1e-4f);
  // Float max is exact and order-independent: each chunk's max, then the max of those. A chunk
  // skips the square root and division for springs clearly below its running max (L^2 < R^2 (1 +
  // max)^2 (1 - 1e-5): a margin far above the rounding of the test), so the result is
  // the exact max however the springs are chunked. A spring of length 0 has stretch -1. The count
  // is an integer sum over the chunks.
  std::atomic<float> max_stretch{-1.f};
  detail::ChunkSum overstretched;
  ParallelRanges(static_cast<int64_t>(measured_springs_.size()), kSpringGrain,
                 [&](int64_t begin, int64_t end) {
                   float chunk_max = -1.f;
                   float skip_factor = 0.f;  // (1 + chunk_max)^2 (1 - 1e-5)
                   uint32_t chunk_over = 0;
                   for (int64_t k = begin; k < end; ++k) {
                     const MeasuredSpring& s = springs[k];
                     const Float3 d = x[s.b] - x[s.a];
                     const float length_squared = Dot(d, d);
                     const float rest_squared = s.rest_length * s.rest_length;
                     chunk_over += length_squared > rest_squared * over_factor ? 1u : 0u;
                     if (length_squared < rest_squared * skip_factor) continue;
                     chunk_max =
                         std::max(chunk_max, std::sqrt(length_squared) / s.rest_length - 1.f);
                     skip_factor = (1.f + chunk_max) * (1.f + chunk_max) * (1.f - 1e-5f);
                   }
                   overstretched.Add(chunk_over);
                   float seen = max_stretch.load(std::memory_order_relaxed);
                   while (chunk_max > seen && !max_stretch.compare_exchange_weak(seen, chunk_max)) {
                   }
                 });
  return {max_stretch.load(), overstretched.total()};
}

}  // namespace drape

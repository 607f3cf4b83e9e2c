// ClothSolver's stages that move the whole cloth with the character: inertia relative to the
// root (the carried share of its motion, the centrifugal term's inputs), teleport and reset
// (docs/ALGORITHMS.md §10.5).
#include <algorithm>
#include <cmath>

#include "cloth/cloth_setup.h"
#include "cloth/cloth_solver_internal.h"
#include "common/rigid_transform.h"
#include "drape/runtime/cloth_solver.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"
#include "tasks/parallel_for.h"

namespace drape {

using detail::Finite;
using detail::InvalidArgument;

// The root's world rotation and position at the frame's start and end; the carried share of its
// motion is applied per substep by CarryWithRoot, the centrifugal push in Integrate.
ClothSolver::RootMotion ClothSolver::ComputeRootMotion(const ClothFrame& frame) const {
  RootMotion root;
  const float carry_linear = 1.f - settings_.linear_inertia;
  const float carry_angular = 1.f - settings_.angular_inertia;
  if (settings_.root_joint < 0 || (carry_linear == 0.f && carry_angular == 0.f)) return root;
  const size_t r = static_cast<size_t>(settings_.root_joint);
  root.carry = true;
  root.pivot0 = TransformPoint(frame.skinning_start[r], settings_.root_bind_position);
  root.pivot1 = TransformPoint(frame.skinning_end[r], settings_.root_bind_position);
  const detail::QuatD q0 = detail::RotationOf(frame.skinning_start[r]);
  const detail::QuatD q1 = detail::RotationOf(frame.skinning_end[r]);
  detail::QuatD rel = detail::NormalizeQ(detail::Mul(q1, detail::Conjugate(q0)));
  if (rel.w < 0.0) rel = {-rel.x, -rel.y, -rel.z, -rel.w};  // the short way round
  root.rotation = {static_cast<float>(rel.x), static_cast<float>(rel.y), static_cast<float>(rel.z),
                   static_cast<float>(rel.w)};
  const double sin_half = std::sqrt(rel.x * rel.x + rel.y * rel.y + rel.z * rel.z);
  if (sin_half > 1e-12) {
    const double rate = 2.0 * std::atan2(sin_half, rel.w) / (sin_half * frame.dt);  // rad/s
    root.omega = {static_cast<float>(rel.x * rate), static_cast<float>(rel.y * rate),
                  static_cast<float>(rel.z * rate)};
  }
  root.centrifugal = carry_angular > 0.f && settings_.centrifugal_inertia > 0.f && sin_half > 1e-12;
  return root;
}

// The carried share of the root's motion over the substep, which BeginSubstep applies to every
// particle (and its velocity): a rotation by (1 - angular_inertia) of the root's turn about its
// position, then (1 - linear_inertia) of its translation.
Mat34 ClothSolver::CarriedMotion(const RootMotion& root, const Substep& sub) const {
  const float carry_linear = 1.f - settings_.linear_inertia;
  const float carry_angular = 1.f - settings_.angular_inertia;
  const Quat identity;
  const Quat r0 = Nlerp(identity, root.rotation, sub.s0);
  const Quat r1 = Nlerp(identity, root.rotation, sub.s1);
  const Quat turn = Nlerp(identity, Multiply(r1, Quat{-r0.x, -r0.y, -r0.z, r0.w}), carry_angular);
  const Float3 pivot = Lerp(root.pivot0, root.pivot1, sub.s0);
  const Float3 shift = (Lerp(root.pivot0, root.pivot1, sub.s1) - pivot) * carry_linear;
  Transform t;
  t.rotation = turn;
  Mat34 m = ToMatrix(t);
  const Float3 moved = TransformVector(m, pivot);
  m.m[3] = pivot.x - moved.x + shift.x;
  m.m[7] = pivot.y - moved.y + shift.y;
  m.m[11] = pivot.z - moved.z + shift.z;
  return m;
}

// ---- Teleport and reset ------------------------------------------------------------------------

Status ClothSolver::Teleport(ClothState* state, const Mat34& transform) const {
  if (cloth_ == nullptr) return InvalidArgument("Teleport: Init was not called");
  if (!state->Matches(*cloth_))
    return InvalidArgument("Teleport: the state does not match the cloth (call ClothState::Reset)");
  if (!Finite(transform)) return InvalidArgument("Teleport: the transform is not finite");
  // Rigid: orthonormal columns within 1e-3 (a scale would change the rest lengths' meaning).
  for (int a = 0; a < 3; ++a) {
    for (int b = a; b < 3; ++b) {
      const float dot = transform.m[a] * transform.m[b] + transform.m[4 + a] * transform.m[4 + b] +
                        transform.m[8 + a] * transform.m[8 + b];
      if (!(std::abs(dot - (a == b ? 1.f : 0.f)) <= 1e-3f))
        return InvalidArgument(
            "Teleport: the transform is not rigid (a rotation and a translation)");
    }
  }
  detail::ParallelFor(
      static_cast<int64_t>(state->positions.size()), detail::kParticleGrain, [&](int64_t i) {
        state->positions[i] = TransformPoint(transform, state->positions[i]);
        state->previous_positions[i] = TransformPoint(transform, state->previous_positions[i]);
        state->velocities[i] = TransformVector(transform, state->velocities[i]);
      });
  return Status::Ok();
}

Status ClothSolver::Reset(ClothState* state, const ClothColliders& colliders,
                          std::span<const Mat34> skinning) {
  if (cloth_ == nullptr) return InvalidArgument("Reset: Init was not called");
  if (!state->Matches(*cloth_)) state->Reset(*cloth_);
  ClothFrame frame;
  frame.skinning_start = skinning;
  frame.skinning_end = skinning;
  if (Status s = ValidateFrame(*state, colliders, frame); !s.ok()) return s;
  const Cloth& cloth = *cloth_;
  const std::span<const Float3> rest = cloth.rest_positions();
  const int32_t root = settings_.root_joint;
  for (size_t i = 0; i < rest.size(); ++i) {
    Float3 p = root >= 0 ? TransformPoint(skinning[static_cast<size_t>(root)], rest[i]) : rest[i];
    if (cloth.skinned())
      p = detail::SkinPoint(cloth.skin()[i], skinning.data(), cloth.skin_bind_positions()[i]);
    state->positions[i] = p;
  }
  for (const ClothAttachment& a : cloth.attachments())
    state->positions[a.particle] =
        TransformPoint(skinning[static_cast<size_t>(a.joint)], a.bind_position);
  state->previous_positions = state->positions;
  std::fill(state->velocities.begin(), state->velocities.end(), Float3{});
  // Whatever the pose puts inside a collider is pushed out (segments of length 0: the colliders'
  // started-inside response).
  if (colliders.hulls != nullptr) {
    if (Status s = colliders.hulls->SetPose(skinning, skinning); !s.ok()) return s;
  }
  Substep sub;
  sub.h = frame.dt;
  ClothStepStats stats;
  if (Status s = Collide(state, colliders, sub, &stats); !s.ok()) return s;
  RestoreKinematic(state);
  state->previous_positions = state->positions;
  std::fill(state->velocities.begin(), state->velocities.end(), Float3{});
  return Status::Ok();
}

}  // namespace drape

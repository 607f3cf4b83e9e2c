// HullColliderSet's motion within a step: the colliders' poses at the start and end of a step,
// their screw interpolation between them (docs/ALGORITHMS.md §8.1), and the transforms and swept
// spheres of the selected substep.
#include <algorithm>
#include <cmath>
#include <string>

#include "common/rigid_transform.h"
#include "drape/runtime/hull_collider_set.h"
#include "hull/plane_kernels.h"

namespace drape {
namespace {

using namespace detail;

constexpr double kScrewMinAngle = 1e-4;  // radians; below: pivot about the OBB centre

// world -> OBB frame: p_obb[k] = axes[k] . (to_collider(p) - center).
Mat34 ObbFromWorld(const RigidD& collider_to_world, Float3 center, const Float3 axes[3]) {
  RigidD inv;
  inv.rotation = Conjugate(collider_to_world.rotation);
  inv.translation = Rotate(inv.rotation, collider_to_world.translation) * -1.0;
  Mat34 m;
  const Vec3D c = ToD(center);
  // Columns of the world->collider rotation applied to the basis vectors.
  const Vec3D ex = Rotate(inv.rotation, {1, 0, 0}), ey = Rotate(inv.rotation, {0, 1, 0}),
              ez = Rotate(inv.rotation, {0, 0, 1});
  for (int k = 0; k < 3; ++k) {
    const Vec3D a = ToD(axes[k]);
    m.m[4 * k + 0] = static_cast<float>(DotD(a, ex));
    m.m[4 * k + 1] = static_cast<float>(DotD(a, ey));
    m.m[4 * k + 2] = static_cast<float>(DotD(a, ez));
    m.m[4 * k + 3] = static_cast<float>(DotD(a, inv.translation - c));
  }
  return m;
}

}  // namespace

Status HullColliderSet::SetPose(std::span<const Mat34> skinning_start,
                                std::span<const Mat34> skinning_end) {
  if (skinning_start.size() < joint_count_ || skinning_end.size() < joint_count_)
    return Status(StatusCode::kInvalidArgument,
                  "HullColliderSet::SetPose: fewer skinning matrices than the " +
                      std::to_string(joint_count_) + " joints");
  for (uint32_t j = 0; j < joint_count_; ++j)
    if (!IsFinite(skinning_start[j]) || !IsFinite(skinning_end[j]))
      return Status(StatusCode::kInvalidArgument,
                    "HullColliderSet::SetPose: skinning matrix of joint " + std::to_string(j) +
                        " is not finite");
  selection_current_ = false;  // the motions change below
  const uint32_t hull_total = static_cast<uint32_t>(hulls_.size());
  for (uint32_t k = 0; k < motions_.size(); ++k) {
    Motion& m = motions_[k];
    RigidD w0, w1;
    Vec3D local_center;  // the bounding-sphere centre in the collider's frame
    if (k < hull_total) {
      const HullRecord& h = hulls_[k];
      const Mat34 m0 = Multiply(skinning_start[h.joint], h.bind_frame);
      const Mat34 m1 = Multiply(skinning_end[h.joint], h.bind_frame);
      w0 = {RotationOf(m0), {m0.m[3], m0.m[7], m0.m[11]}};
      w1 = {RotationOf(m1), {m1.m[3], m1.m[7], m1.m[11]}};
      local_center = ToD(h.obb_center);
    } else {
      const SphereRecord& s = spheres_[k - hull_total];
      w0.translation = ToD(TransformPoint(skinning_start[s.joint], s.center));
      w1.translation = ToD(TransformPoint(skinning_end[s.joint], s.center));
    }
    // Keep the quaternions in one hemisphere so the relative rotation is the short one.
    if (w0.rotation.x * w1.rotation.x + w0.rotation.y * w1.rotation.y +
            w0.rotation.z * w1.rotation.z + w0.rotation.w * w1.rotation.w <
        0.0)
      w1.rotation = {-w1.rotation.x, -w1.rotation.y, -w1.rotation.z, -w1.rotation.w};
    m.rotation0 = {static_cast<float>(w0.rotation.x), static_cast<float>(w0.rotation.y),
                   static_cast<float>(w0.rotation.z), static_cast<float>(w0.rotation.w)};
    m.translation0 = ToF(w0.translation);
    const Vec3D c0 = Apply(w0, local_center), c1 = Apply(w1, local_center);
    m.center0 = ToF(c0);
    m.center1 = ToF(c1);
    // Relative motion D = W1 W0^-1 = (Rd, td).
    QuatD rel = NormalizeQ(Mul(w1.rotation, Conjugate(w0.rotation)));
    if (rel.w < 0.0) rel = {-rel.x, -rel.y, -rel.z, -rel.w};
    const Vec3D td = w1.translation - Rotate(rel, w0.translation);
    const double sin_half = std::sqrt(rel.x * rel.x + rel.y * rel.y + rel.z * rel.z);
    const double angle = 2.0 * std::atan2(sin_half, rel.w);
    Vec3D pivot = c0, shift = c1 - c0;
    if (angle > kScrewMinAngle) {
      const Vec3D axis = Vec3D{rel.x, rel.y, rel.z} * (1.0 / sin_half);
      const Vec3D t_perp = td - axis * DotD(td, axis);
      const double cot_half = rel.w / sin_half;
      const Vec3D q = (t_perp + CrossD(axis, t_perp) * cot_half) * 0.5;
      pivot = q + axis * DotD(c0 - q, axis);  // the screw-axis point nearest the centre
      shift = Rotate(rel, pivot) + td - pivot;
    }
    m.relative = {static_cast<float>(rel.x), static_cast<float>(rel.y), static_cast<float>(rel.z),
                  static_cast<float>(rel.w)};
    m.pivot = ToF(pivot);
    m.shift = ToF(shift);
    Float3 center;
    float radius;
    ComputeSweep(k, 0.f, 1.f, &center, &radius);
    full_x_[k] = center.x;
    full_y_[k] = center.y;
    full_z_[k] = center.z;
    full_r_[k] = radius;
  }
  return SelectSubstep(0.f, 1.f);
}

// Collider frame -> world at fraction s, in double (see the header: screw interpolation).
Mat34 HullColliderSet::ColliderWorldAt(uint32_t collider, float s) const {
  const Motion& m = motions_[collider];
  const QuatD q0{m.rotation0.x, m.rotation0.y, m.rotation0.z, m.rotation0.w};
  const QuatD rel{m.relative.x, m.relative.y, m.relative.z, m.relative.w};
  const double sd = s;
  const QuatD rs = NormalizeQ({sd * rel.x, sd * rel.y, sd * rel.z, (1.0 - sd) + sd * rel.w});
  RigidD w;
  w.rotation = NormalizeQ(Mul(rs, q0));
  const Vec3D pivot = ToD(m.pivot);
  w.translation = Rotate(rs, ToD(m.translation0) - pivot) + pivot + ToD(m.shift) * sd;
  return ToMat34(w);
}

void HullColliderSet::ComputeFrames(uint32_t collider, float s0, float s1, ActiveFrames* f) const {
  const Motion& m = motions_[collider];
  const uint32_t hull_total = static_cast<uint32_t>(hulls_.size());
  const QuatD q0{m.rotation0.x, m.rotation0.y, m.rotation0.z, m.rotation0.w};
  const QuatD rel{m.relative.x, m.relative.y, m.relative.z, m.relative.w};
  auto rigid_at = [&](double s) {
    const QuatD rs = NormalizeQ({s * rel.x, s * rel.y, s * rel.z, (1.0 - s) + s * rel.w});
    RigidD w;
    w.rotation = NormalizeQ(Mul(rs, q0));
    const Vec3D pivot = ToD(m.pivot);
    w.translation = Rotate(rs, ToD(m.translation0) - pivot) + pivot + ToD(m.shift) * s;
    return w;
  };
  if (collider < hull_total) {
    const HullRecord& h = hulls_[collider];
    const RigidD w0 = rigid_at(s0), w1 = rigid_at(s1);
    f->to_local_start = InverseToMat34(w0);
    f->to_local_end = InverseToMat34(w1);
    f->to_obb_start = ObbFromWorld(w0, h.obb_center, h.obb_axes);
    f->to_obb_end = ObbFromWorld(w1, h.obb_center, h.obb_axes);
    f->to_world_end = ToMat34(w1);
  } else {
    const Float3 c0 = Lerp(m.center0, m.center1, s0), c1 = Lerp(m.center0, m.center1, s1);
    f->to_local_start = TranslationMatrix(-c0);
    f->to_local_end = TranslationMatrix(-c1);
    f->to_obb_start = f->to_local_start;
    f->to_obb_end = f->to_local_end;
    f->to_world_end = TranslationMatrix(c1);
  }
}

void HullColliderSet::ComputeSweep(uint32_t collider, float s0, float s1, Float3* center,
                                   float* radius) const {
  const Motion& m = motions_[collider];
  const uint32_t hull_total = static_cast<uint32_t>(hulls_.size());
  Vec3D c0, c1;
  double base;
  if (collider < hull_total) {
    const HullRecord& h = hulls_[collider];
    const Mat34 w0 = ColliderWorldAt(collider, s0), w1 = ColliderWorldAt(collider, s1);
    c0 = ToD(TransformPoint(w0, h.obb_center));
    c1 = ToD(TransformPoint(w1, h.obb_center));
    base = h.bound_radius;
  } else {
    c0 = ToD(Lerp(m.center0, m.center1, s0));
    c1 = ToD(Lerp(m.center0, m.center1, s1));
    base = spheres_[collider - hull_total].radius;
  }
  // The centre moves on an arc about the screw axis (angle <= pi) plus a shift along it: the
  // arc stays within the ball on its chord, the shift within half its length of the middle.
  const Vec3D chord = c1 - c0;
  const double sin_half =
      std::sqrt(double(m.relative.x) * m.relative.x + double(m.relative.y) * m.relative.y +
                double(m.relative.z) * m.relative.z);
  double sweep = 0.5 * LengthD(chord);
  if (collider < hull_total && sin_half > 0.0) {
    const Vec3D axis = Vec3D{m.relative.x, m.relative.y, m.relative.z} * (1.0 / sin_half);
    const double along = DotD(chord, axis);
    sweep = 0.5 * LengthD(chord - axis * along) + 0.5 * std::fabs(along);
  }
  const Vec3D mid = (c0 + c1) * 0.5;
  const double magnitude = LengthD(mid) + base + sweep;
  *center = ToF(mid);
  *radius = static_cast<float>((base + sweep) * (1.0 + 1e-5) + 1e-6 + 4e-7 * magnitude);
}

Status HullColliderSet::SelectSubstep(float s0, float s1) {
  if (!(s0 >= 0.f && s0 <= s1 && s1 <= 1.f))
    return Status(StatusCode::kInvalidArgument,
                  "HullColliderSet::SelectSubstep: fractions are not 0 <= s0 <= s1 <= 1");
  // Already selected for this pose (a solver's single substep, which SetPose selected).
  if (selection_current_ && s0 == active_s0_ && s1 == active_s1_) return Status::Ok();
  active_s0_ = s0;
  active_s1_ = s1;
  for (uint32_t k = 0; k < motions_.size(); ++k) {
    ComputeFrames(k, s0, s1, &active_[k]);
    if (k < obb_start_.size()) {
      obb_start_[k] = active_[k].to_obb_start;
      obb_end_[k] = active_[k].to_obb_end;
    }
    Float3 center;
    float radius;
    ComputeSweep(k, s0, s1, &center, &radius);
    sweep_x_[k] = center.x;
    sweep_y_[k] = center.y;
    sweep_z_[k] = center.z;
    sweep_r_[k] = radius;
  }
  // The union sphere, in double: centre the middle of the spheres' box, radius the farthest
  // sphere surface, grown by 1e-4 relative and 1e-4 of the magnitude (far above the ~1e-6
  // relative rounding of the float tests).
  if (collider_count_ > 0) {
    Vec3D lo{kPadCenter, kPadCenter, kPadCenter}, hi{-kPadCenter, -kPadCenter, -kPadCenter};
    for (uint32_t k = 0; k < collider_count_; ++k) {
      lo = {std::min(lo.x, double(sweep_x_[k]) - sweep_r_[k]),
            std::min(lo.y, double(sweep_y_[k]) - sweep_r_[k]),
            std::min(lo.z, double(sweep_z_[k]) - sweep_r_[k])};
      hi = {std::max(hi.x, double(sweep_x_[k]) + sweep_r_[k]),
            std::max(hi.y, double(sweep_y_[k]) + sweep_r_[k]),
            std::max(hi.z, double(sweep_z_[k]) + sweep_r_[k])};
    }
    const Vec3D center = (lo + hi) * 0.5;
    double radius = 0.0;
    for (uint32_t k = 0; k < collider_count_; ++k)
      radius = std::max(
          radius, LengthD(Vec3D{sweep_x_[k], sweep_y_[k], sweep_z_[k]} - center) + sweep_r_[k]);
    sweep_union_center_ = ToF(center);
    sweep_union_radius_ =
        static_cast<float>(radius * (1.0 + 1e-4) + 1e-4 * (LengthD(center) + radius) + 1e-6);
  }
  selection_current_ = true;
  return Status::Ok();
}

Mat34 HullColliderSet::HullWorldTransform(uint32_t hull, float s) const {
  return ColliderWorldAt(hull, s);
}

Float3 HullColliderSet::SphereCenter(uint32_t sphere, float s) const {
  const Motion& m = motions_[hulls_.size() + sphere];
  return Lerp(m.center0, m.center1, s);
}

}  // namespace drape

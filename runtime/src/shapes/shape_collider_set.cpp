// ShapeColliderSet: the engine's shapes validated and copied by the Add calls, posed over each
// substep, and the batch loop that resolves every particle against them in shape order
// (docs/ALGORITHMS.md §14).
#include "drape/runtime/shape_collider_set.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <string>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "common/rigid_transform.h"
#include "drape/runtime/math.h"
#include "shapes/convex_bounds.h"
#include "shapes/shape_distance.h"
#include "shapes/shape_response.h"
#include "shapes/shape_sweep.h"
#include "tasks/parallel_for.h"

namespace drape {

using detail::DotD;
using detail::LengthD;
using detail::LocalContact;
using detail::LocalShape;
using detail::QuatD;
using detail::ToD;
using detail::ToF;
using detail::Vec3D;

namespace {

// Particles per block of the batch (both passes run block by block); shapes are posed kChunk at
// a time, on each thread's stack.
constexpr size_t kBlock = 256;
constexpr uint32_t kChunk = 32;

Status ShapeError(const char* function, uint32_t shape, const std::string& field,
                  const char* reason) {
  return Status(StatusCode::kInvalidArgument, std::string("ShapeColliderSet::") + function +
                                                  ": shape " + std::to_string(shape) + ": " +
                                                  field + " " + reason);
}

// Columns unit and orthogonal within kRigidTolerance, and no reflection (a mirrored frame would
// turn the shapes inside out).
bool IsRigid(const Mat34& m) {
  const Vec3D c[3] = {
      {m.m[0], m.m[4], m.m[8]}, {m.m[1], m.m[5], m.m[9]}, {m.m[2], m.m[6], m.m[10]}};
  constexpr double tol = ShapeColliderSet::kRigidTolerance;
  for (int i = 0; i < 3; ++i) {
    if (std::fabs(DotD(c[i], c[i]) - 1.0) > tol) return false;
    for (int j = i + 1; j < 3; ++j)
      if (std::fabs(DotD(c[i], c[j])) > tol) return false;
  }
  return DotD(detail::CrossD(c[0], c[1]), c[2]) > 0.0;
}

QuatD Nlerp(const double a[4], const double b[4], double s) {
  return detail::NormalizeQ({a[0] + (b[0] - a[0]) * s, a[1] + (b[1] - a[1]) * s,
                             a[2] + (b[2] - a[2]) * s, a[3] + (b[3] - a[3]) * s});
}

// Row-major 3x3 rotation of a unit quaternion.
void RotationRows(const QuatD& q, double r[9]) {
  const double xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
  const double xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
  const double wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
  r[0] = 1.0 - 2.0 * (yy + zz), r[1] = 2.0 * (xy - wz), r[2] = 2.0 * (xz + wy);
  r[3] = 2.0 * (xy + wz), r[4] = 1.0 - 2.0 * (xx + zz), r[5] = 2.0 * (yz - wx);
  r[6] = 2.0 * (xz - wy), r[7] = 2.0 * (yz + wx), r[8] = 1.0 - 2.0 * (xx + yy);
}

Vec3D Rotate(const double r[9], const Vec3D& v) {
  return {r[0] * v.x + r[1] * v.y + r[2] * v.z, r[3] * v.x + r[4] * v.y + r[5] * v.z,
          r[6] * v.x + r[7] * v.y + r[8] * v.z};
}
Vec3D RotateTransposed(const double r[9], const Vec3D& v) {
  return {r[0] * v.x + r[3] * v.y + r[6] * v.z, r[1] * v.x + r[4] * v.y + r[7] * v.z,
          r[2] * v.x + r[5] * v.y + r[8] * v.z};
}

// One shape posed at the substep's fractions s0 and s1.
struct PosedShape {
  LocalShape shape;
  double rotation0[9], rotation1[9];  // local -> world, row-major
  Vec3D translation0, translation1;   // metres

  Vec3D ToLocal0(const Vec3D& p) const { return RotateTransposed(rotation0, p - translation0); }
  Vec3D ToLocal1(const Vec3D& p) const { return RotateTransposed(rotation1, p - translation1); }
  Vec3D ToWorld0(const Vec3D& q) const { return Rotate(rotation0, q) + translation0; }
  Vec3D ToWorld1(const Vec3D& q) const { return Rotate(rotation1, q) + translation1; }
};

// What the broad phase sees of a particle's segment: its midpoint and half-length.
struct SegmentBound {
  Vec3D mid;
  double half = 0.0;
};
SegmentBound SegmentOf(const Vec3D& p0, const Vec3D& p1) {
  return {(p0 + p1) * 0.5, 0.5 * LengthD(p1 - p0)};
}

bool ValidFractions(float s0, float s1) { return s0 >= 0.f && s0 <= s1 && s1 <= 1.f; }

// Float outputs, or the input where rounding to float overflows.
Float3 FiniteOr(const Vec3D& v, Float3 fallback) {
  const Float3 f = ToF(v);
  return IsFinite(f) ? f : fallback;
}

}  // namespace

// One chunk of at most kChunk shapes posed over a substep, on the caller's stack; a batch's
// thread poses it once when the set has at most kChunk shapes.
//
// Broad phase: a shape's local origin moves linearly over the substep and its frame turns by an
// angle phi. With D the distance between the midpoints of that motion and of the particle's
// segment, h0 and h1 their half-lengths and k = 2 sin(phi / 2), every point of the segment in the
// shape's frame (from p0 at s0 to p1 at s1) lies at least D (1 - k) - (h0 + h1)(1 + k) from the
// local origin. So the segment can reach the shape only if shrink D <= reach + grow h1, with
// shrink = max(1 - k, 0), grow = 1 + k and reach = bound_radius + grow h0. Planes always pass.
struct ShapeColliderSet::Frames {
  PosedShape posed[kChunk];
  alignas(16) double mid_x[kChunk] = {}, mid_y[kChunk] = {}, mid_z[kChunk] = {};  // metres
  alignas(16) double shrink_squared[kChunk] = {}, reach[kChunk] = {}, grow[kChunk] = {};
  uint32_t planes = 0;  // bit k: shape k is a plane
  // A segment with |mid - union_center| > union_reach + union_grow * half passes no shape's test
  // but the planes' (union_reach < 0: nothing but planes; infinite: a shape turns too fast).
  Vec3D union_center;
  double union_reach = -1.0, union_grow = 0.0;
  uint32_t first = UINT32_MAX, count = 0;

  void Pose(const ShapeColliderSet& set, uint32_t chunk_first, double s0, double s1) {
    first = chunk_first;
    count = std::min<uint32_t>(kChunk, set.size() - chunk_first);
    planes = 0;
    for (uint32_t k = 0; k < count; ++k) {
      const Shape& s = set.shapes_[first + k];
      PosedShape& f = posed[k];
      f.shape = LocalOf(set, s);
      const QuatD q0 = Nlerp(s.rotation_start, s.rotation_end, s0);
      const QuatD q1 = Nlerp(s.rotation_start, s.rotation_end, s1);
      RotationRows(q0, f.rotation0);
      RotationRows(q1, f.rotation1);
      const Vec3D a{s.translation_start[0], s.translation_start[1], s.translation_start[2]};
      const Vec3D b{s.translation_end[0], s.translation_end[1], s.translation_end[2]};
      f.translation0 = a + (b - a) * s0;
      f.translation1 = a + (b - a) * s1;
      const Vec3D mid = (f.translation0 + f.translation1) * 0.5;
      mid_x[k] = mid.x;
      mid_y[k] = mid.y;
      mid_z[k] = mid.z;
      // cos(phi / 2) = |q0 . q1|; k grown by 1e-7 for the rounding of sqrt(1 - cos^2) near 0.
      const double c =
          std::min(1.0, std::fabs(q0.x * q1.x + q0.y * q1.y + q0.z * q1.z + q0.w * q1.w));
      const double turn = 2.0 * std::sqrt(std::max(0.0, 1.0 - c * c)) + 1e-7;
      const double shrink = std::max(1.0 - turn, 0.0);
      const bool plane = s.kind == ShapeKind::kPlane;
      planes |= plane ? 1u << k : 0u;
      grow[k] = 1.0 + turn;
      shrink_squared[k] = plane ? 0.0 : shrink * shrink;
      const double half_travel = 0.5 * LengthD(f.translation1 - f.translation0);
      reach[k] = plane ? 0.0 : (f.shape.bound_radius + grow[k] * half_travel) * (1.0 + 1e-9) + 1e-9;
    }
    PoseUnion();
  }

  // The union test's sphere around the shapes other than planes: centred on their midpoints'
  // box, radius the largest of |mid_k - center| + (reach_k + grow_k h1) / shrink_k.
  void PoseUnion() {
    Vec3D lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    bool any = false, turning = false;
    for (uint32_t k = 0; k < count; ++k) {
      if (planes & (1u << k)) continue;
      any = true;
      turning = turning || !(shrink_squared[k] > 0.0);
      lo = {std::min(lo.x, mid_x[k]), std::min(lo.y, mid_y[k]), std::min(lo.z, mid_z[k])};
      hi = {std::max(hi.x, mid_x[k]), std::max(hi.y, mid_y[k]), std::max(hi.z, mid_z[k])};
    }
    union_grow = 0.0;
    union_reach = any ? 0.0 : -1.0;
    if (!any) return;
    if (turning) {
      union_reach = INFINITY;
      return;
    }
    union_center = (lo + hi) * 0.5;
    for (uint32_t k = 0; k < count; ++k) {
      if (planes & (1u << k)) continue;
      const double shrink = std::sqrt(shrink_squared[k]);
      const Vec3D d = Vec3D{mid_x[k], mid_y[k], mid_z[k]} - union_center;
      union_reach = std::max(union_reach, LengthD(d) + reach[k] / shrink);
      union_grow = std::max(union_grow, grow[k] / shrink);
    }
    union_reach = union_reach * (1.0 + 1e-9) + 1e-9;
    union_grow *= 1.0 + 1e-9;
  }

  static LocalShape LocalOf(const ShapeColliderSet& set, const Shape& s) {
    switch (s.kind) {
      case ShapeKind::kSphere:
        return detail::SphereShape(s.radius0);
      case ShapeKind::kCapsule:
        return detail::CapsuleShape(s.half_length, s.radius0, s.radius1);
      case ShapeKind::kPlane:
        return detail::PlaneShape();
      case ShapeKind::kBox:
        return detail::BoxShape(ToD(s.half_extents));
      case ShapeKind::kConvex:
        return detail::ConvexShape(&set.planes_[s.plane_begin], s.plane_count, s.bound_radius);
    }
    return detail::PlaneShape();
  }

  // Bit k: shape k (>= from) may be reached by the segment.
  uint32_t Candidates(const SegmentBound& segment, uint32_t from) const {
    if (from >= count) return 0;
    const uint32_t live = (count == 32 ? ~0u : (1u << count) - 1) & (~0u << from);
    const uint32_t mask = planes & live;
    const Vec3D d = segment.mid - union_center;
    const double r = union_reach + union_grow * segment.half;
    if (!(r >= 0.0 && DotD(d, d) <= r * r)) return mask;
    // Every shape of the chunk at once, without a branch per shape (the outcome is not
    // predictable): two per instruction on SSE2. Entries past `count` (an odd one) are masked.
    const double mx = segment.mid.x, my = segment.mid.y, mz = segment.mid.z;
    const double half = segment.half;
    uint32_t bits = 0;
#if defined(__SSE2__)
    const __m128d vx = _mm_set1_pd(mx), vy = _mm_set1_pd(my), vz = _mm_set1_pd(mz);
    const __m128d vhalf = _mm_set1_pd(half);
    for (uint32_t k = 0; k < count; k += 2) {
      const __m128d dx = _mm_sub_pd(vx, _mm_load_pd(&mid_x[k]));
      const __m128d dy = _mm_sub_pd(vy, _mm_load_pd(&mid_y[k]));
      const __m128d dz = _mm_sub_pd(vz, _mm_load_pd(&mid_z[k]));
      const __m128d rhs =
          _mm_add_pd(_mm_load_pd(&reach[k]), _mm_mul_pd(_mm_load_pd(&grow[k]), vhalf));
      const __m128d d2 =
          _mm_add_pd(_mm_add_pd(_mm_mul_pd(dx, dx), _mm_mul_pd(dy, dy)), _mm_mul_pd(dz, dz));
      const __m128d lhs = _mm_mul_pd(_mm_load_pd(&shrink_squared[k]), d2);
      bits |= static_cast<uint32_t>(_mm_movemask_pd(_mm_cmple_pd(lhs, _mm_mul_pd(rhs, rhs)))) << k;
    }
#else
    for (uint32_t k = 0; k < count; ++k) {
      const double dx = mx - mid_x[k], dy = my - mid_y[k], dz = mz - mid_z[k];
      const double rhs = reach[k] + grow[k] * half;
      bits |= static_cast<uint32_t>(shrink_squared[k] * (dx * dx + dy * dy + dz * dz) <= rhs * rhs)
              << k;
    }
#endif
    return mask | (bits & live);
  }

  // Shape k of the chunk against the particle's segment p0 -> *x (world); on a contact applies
  // the response to *x and *v and returns true. second_pass: only when *x ends more than
  // kSecondPassDepth inside.
  bool Collide(uint32_t k, bool second_pass, const Vec3D& p0, Vec3D* x, Vec3D* v,
               const ResponseParams& params, double substep_seconds, uint8_t* flags) const {
    const PosedShape& f = posed[k];
    if (f.shape.kind == ShapeKind::kPlane) {
      // A plane's contact needs the end below it: local y, the rotation's second column.
      const Vec3D d = *x - f.translation1;
      if (!(f.rotation1[1] * d.x + f.rotation1[4] * d.y + f.rotation1[7] * d.z < 0.0)) return false;
    }
    const Vec3D q0 = f.ToLocal0(p0), q1 = f.ToLocal1(*x);
    if (second_pass && !(detail::Distance(f.shape, q1).value < -kSecondPassDepth)) return false;
    const LocalContact c = detail::Sweep(f.shape, q0, q1);
    if (!c.hit) return false;
    const Vec3D r = detail::ResolvePosition(c, q0, q1, params);
    const Vec3D world = f.ToWorld1(r);
    // The surface point the particle rests on, from its pose at s0 to its pose at s1.
    const Vec3D surface_velocity = (world - f.ToWorld0(r)) * (1.0 / substep_seconds);
    *v = detail::ResolveVelocity(*v, surface_velocity, Rotate(f.rotation1, c.normal), params);
    *x = world;
    *flags = static_cast<uint8_t>(*flags | kCollisionContact |
                                  (c.started_inside ? kCollisionStartedInside : 0));
    return true;
  }
};

void ShapeColliderSet::Reserve(uint32_t shapes, uint32_t planes) {
  shapes_.reserve(shapes);
  planes_.reserve(planes);
}

void ShapeColliderSet::Clear() {
  shapes_.clear();
  planes_.clear();
}

Status ShapeColliderSet::ValidateMotion(const char* function, const Mat34& start, const Mat34& end,
                                        Shape* shape) const {
  const uint32_t index = size();
  const Mat34* m[2] = {&start, &end};
  const char* names[2] = {"start", "end"};
  for (int i = 0; i < 2; ++i) {
    if (!IsFinite(*m[i])) return ShapeError(function, index, names[i], "is not finite");
    if (!IsRigid(*m[i]))
      return ShapeError(function, index, names[i],
                        "is not rigid (columns orthonormal within 1e-3, determinant +1)");
  }
  QuatD q0 = detail::RotationOf(start), q1 = detail::RotationOf(end);
  // The same hemisphere, so that nlerp turns the short way.
  if (q0.x * q1.x + q0.y * q1.y + q0.z * q1.z + q0.w * q1.w < 0.0)
    q1 = {-q1.x, -q1.y, -q1.z, -q1.w};
  const double r0[4] = {q0.x, q0.y, q0.z, q0.w}, r1[4] = {q1.x, q1.y, q1.z, q1.w};
  for (int i = 0; i < 4; ++i) {
    shape->rotation_start[i] = r0[i];
    shape->rotation_end[i] = r1[i];
  }
  for (int i = 0; i < 3; ++i) {
    shape->translation_start[i] = start.m[4 * i + 3];
    shape->translation_end[i] = end.m[4 * i + 3];
  }
  return Status::Ok();
}

Status ShapeColliderSet::AddSphere(const Mat34& start, const Mat34& end, float radius) {
  Shape s;
  if (Status st = ValidateMotion("AddSphere", start, end, &s); !st.ok()) return st;
  if (!(std::isfinite(radius) && radius > 0.f))
    return ShapeError("AddSphere", size(), "radius", "is not finite and > 0");
  s.kind = ShapeKind::kSphere;
  s.radius0 = radius;
  s.bound_radius = radius;
  shapes_.push_back(s);
  return Status::Ok();
}

Status ShapeColliderSet::AddCapsule(const Mat34& start, const Mat34& end, float half_length,
                                    float radius0, float radius1) {
  Shape s;
  if (Status st = ValidateMotion("AddCapsule", start, end, &s); !st.ok()) return st;
  if (!(std::isfinite(half_length) && half_length >= 0.f))
    return ShapeError("AddCapsule", size(), "half_length", "is not finite and >= 0");
  if (!(std::isfinite(radius0) && radius0 > 0.f))
    return ShapeError("AddCapsule", size(), "radius0", "is not finite and > 0");
  if (!(std::isfinite(radius1) && radius1 > 0.f))
    return ShapeError("AddCapsule", size(), "radius1", "is not finite and > 0");
  s.kind = ShapeKind::kCapsule;
  s.half_length = half_length;
  s.radius0 = radius0;
  s.radius1 = radius1;
  s.bound_radius = double(half_length) + std::max(radius0, radius1);
  shapes_.push_back(s);
  return Status::Ok();
}

Status ShapeColliderSet::AddPlane(const Mat34& start, const Mat34& end) {
  Shape s;
  if (Status st = ValidateMotion("AddPlane", start, end, &s); !st.ok()) return st;
  s.kind = ShapeKind::kPlane;
  s.bound_radius = INFINITY;
  shapes_.push_back(s);
  return Status::Ok();
}

Status ShapeColliderSet::AddBox(const Mat34& start, const Mat34& end, Float3 half_extents) {
  Shape s;
  if (Status st = ValidateMotion("AddBox", start, end, &s); !st.ok()) return st;
  const float e[3] = {half_extents.x, half_extents.y, half_extents.z};
  const char* fields[3] = {"half_extents.x", "half_extents.y", "half_extents.z"};
  for (int i = 0; i < 3; ++i)
    if (!(std::isfinite(e[i]) && e[i] > 0.f))
      return ShapeError("AddBox", size(), fields[i], "is not finite and > 0");
  s.kind = ShapeKind::kBox;
  s.half_extents = half_extents;
  s.bound_radius = LengthD(ToD(half_extents));
  shapes_.push_back(s);
  return Status::Ok();
}

Status ShapeColliderSet::AddConvex(const Mat34& start, const Mat34& end,
                                   std::span<const Plane> planes) {
  Shape s;
  if (Status st = ValidateMotion("AddConvex", start, end, &s); !st.ok()) return st;
  const uint32_t index = size();
  if (planes.size() < 4 || planes.size() > kMaxConvexPlanes)
    return ShapeError("AddConvex", index, "planes",
                      ("count " + std::to_string(planes.size()) + " is not in [4, 256]").c_str());
  for (size_t i = 0; i < planes.size(); ++i) {
    const std::string field = "planes[" + std::to_string(i) + "]";
    if (!IsFinite(planes[i].normal) || !std::isfinite(planes[i].offset))
      return ShapeError("AddConvex", index, field, "is not finite");
    if (std::fabs(LengthD(ToD(planes[i].normal)) - 1.0) > kRigidTolerance)
      return ShapeError("AddConvex", index, field + ".normal", "is not unit length within 1e-3");
  }
  // Appended renormalised, measured there, and taken back on error (no scratch allocation).
  const size_t begin = planes_.size();
  for (const Plane& p : planes) {
    const Vec3D n = ToD(p.normal);
    planes_.push_back({ToF(n * (1.0 / LengthD(n))), p.offset});
  }
  const detail::ConvexBounds bounds = detail::MeasureConvex(
      &planes_[begin], static_cast<uint32_t>(planes.size()), kMaxConvexExtent);
  if (bounds.extent != detail::ConvexExtent::kBounded) {
    planes_.resize(begin);
    return ShapeError("AddConvex", index, "planes",
                      bounds.extent == detail::ConvexExtent::kEmpty
                          ? "enclose nothing (no point inside all of them)"
                          : "are not bounded (the region reaches 1e4 m from the local origin)");
  }
  s.kind = ShapeKind::kConvex;
  s.plane_begin = static_cast<uint32_t>(begin);
  s.plane_count = static_cast<uint32_t>(planes.size());
  s.bound_radius = bounds.radius;
  shapes_.push_back(s);
  return Status::Ok();
}

Mat34 ShapeColliderSet::WorldTransform(uint32_t shape, float s) const {
  const Shape& r = shapes_[shape];
  detail::RigidD w;
  w.rotation = Nlerp(r.rotation_start, r.rotation_end, s);
  for (int i = 0; i < 3; ++i) {
    const double v = r.translation_start[i] + (r.translation_end[i] - r.translation_start[i]) * s;
    (i == 0 ? w.translation.x : i == 1 ? w.translation.y : w.translation.z) = v;
  }
  return detail::ToMat34(w);
}

Status ShapeColliderSet::CollideBatch(std::span<const Float3> x_start, std::span<Float3> x_end,
                                      std::span<Float3> velocities, std::span<uint8_t> flags,
                                      const ResponseParams& params, float s0, float s1,
                                      float substep_seconds, uint32_t* contact_count) const {
  static_assert(sizeof(Shape) == 160, "ShapeColliderSet::Shape: update the header's size comment");
  if (contact_count != nullptr) *contact_count = 0;
  const size_t n = x_end.size();
  if (x_start.size() != n || velocities.size() != n || flags.size() != n)
    return Status(StatusCode::kInvalidArgument,
                  "ShapeColliderSet::CollideBatch: x_start, x_end, velocities and flags differ in "
                  "size");
  if (!ValidResponse(params))
    return Status(StatusCode::kInvalidArgument,
                  "ShapeColliderSet::CollideBatch: response parameters out of range (friction in "
                  "[0, 1], static_friction in [0, 4], restitution in [0, 1], separation finite "
                  "and >= 0)");
  if (!ValidFractions(s0, s1))
    return Status(StatusCode::kInvalidArgument,
                  "ShapeColliderSet::CollideBatch: substep fractions are not 0 <= s0 <= s1 <= 1");
  if (!(std::isfinite(substep_seconds) && substep_seconds > 0.f))
    return Status(StatusCode::kInvalidArgument,
                  "ShapeColliderSet::CollideBatch: substep_seconds is not finite and > 0");
  const int64_t blocks = static_cast<int64_t>((n + kBlock - 1) / kBlock);
  // Blocks write only their own particles: the same bits under any task system. A chunk of
  // blocks poses the shapes on its own stack, once when they fit one chunk of shapes; below 2048
  // particles everything runs on the calling thread.
  const int64_t blocks_per_chunk =
      std::max<int64_t>(1, detail::kParticleGrain / static_cast<int64_t>(kBlock));
  detail::ChunkSum contacts;
  detail::ParallelRanges(
      blocks, n >= 2048 ? blocks_per_chunk : blocks, [&](int64_t begin, int64_t end) {
        Frames frames;
        uint32_t chunk_contacts = 0;
        for (int64_t b = begin; b < end; ++b) {
          const size_t first = static_cast<size_t>(b) * kBlock;
          chunk_contacts += CollideBlock(&frames, first, std::min(n, first + kBlock), x_start,
                                         x_end, velocities, flags, params, s0, s1, substep_seconds);
        }
        contacts.Add(chunk_contacts);
      });
  if (contact_count != nullptr) *contact_count = contacts.total();
  return Status::Ok();
}

uint32_t ShapeColliderSet::CollideBlock(Frames* frames, size_t first, size_t last,
                                        std::span<const Float3> x_start, std::span<Float3> x_end,
                                        std::span<Float3> velocities, std::span<uint8_t> flags,
                                        const ResponseParams& params, float s0, float s1,
                                        double substep_seconds) const {
  for (size_t i = first; i < last; ++i) {
    const bool finite = IsFinite(x_start[i]) && IsFinite(x_end[i]) && IsFinite(velocities[i]);
    flags[i] = finite ? kCollisionNone : kCollisionInvalidInput;
  }
  const uint32_t count = size();
  // Pass 0: every shape in index order (Gauss-Seidel). Pass 1: the particles in contact, against
  // the shapes they ended more than kSecondPassDepth inside (a later shape pushed them back in).
  for (int pass = 0; pass < 2; ++pass) {
    const auto skip = [&](size_t i) {
      return (flags[i] & kCollisionInvalidInput) || (pass == 1 && !(flags[i] & kCollisionContact));
    };
    for (uint32_t chunk = 0; chunk < count; chunk += kChunk) {
      if (frames->first != chunk) frames->Pose(*this, chunk, s0, s1);
      for (size_t i = first; i < last; ++i) {
        if (skip(i)) continue;
        const Vec3D p0 = ToD(x_start[i]);
        Vec3D x = ToD(x_end[i]), v = ToD(velocities[i]);
        bool moved = false;
        // The candidates of the segment as it stands: a response re-tests the later shapes.
        for (uint32_t mask = frames->Candidates(SegmentOf(p0, x), 0); mask != 0;) {
          const uint32_t k = static_cast<uint32_t>(std::countr_zero(mask));
          mask &= mask - 1;
          if (frames->Collide(k, pass == 1, p0, &x, &v, params, substep_seconds, &flags[i])) {
            moved = true;
            mask = frames->Candidates(SegmentOf(p0, x), k + 1);
          }
        }
        if (moved) {
          x_end[i] = FiniteOr(x, x_end[i]);
          velocities[i] = FiniteOr(v, velocities[i]);
        }
      }
    }
  }
  uint32_t contacts = 0;
  for (size_t i = first; i < last; ++i) contacts += (flags[i] & kCollisionContact) ? 1u : 0u;
  return contacts;
}

ContactQuery ShapeColliderSet::Query(Float3 p0, Float3 p1, float s0, float s1) const {
  ContactQuery best;
  if (!IsFinite(p0) || !IsFinite(p1) || !ValidFractions(s0, s1)) {
    best.flags = kCollisionInvalidInput;
    return best;
  }
  Frames frames;
  double depth = 0.0, best_t = INFINITY;
  for (uint32_t chunk = 0; chunk < size(); chunk += kChunk) {
    frames.Pose(*this, chunk, s0, s1);
    for (uint32_t k = 0; k < frames.count; ++k) {
      const PosedShape& f = frames.posed[k];
      const LocalContact c = detail::Sweep(f.shape, f.ToLocal0(ToD(p0)), f.ToLocal1(ToD(p1)));
      depth = std::max(depth, c.end_depth);
      best.inside_end = best.inside_end || c.end_depth > 0.0;
      if (!c.hit || !(c.t < best_t)) continue;  // ties: the lower index
      best_t = c.t;
      best.contact = true;
      best.t = static_cast<float>(c.t);
      best.point = ToF(f.ToWorld1(c.point));
      best.normal = ToF(Rotate(f.rotation1, c.normal));
      best.flags = c.started_inside ? kCollisionStartedInside : kCollisionNone;
    }
  }
  best.depth = static_cast<float>(depth);
  return best;
}

}  // namespace drape

#include "shapes/shape_distance.h"

#include <algorithm>
#include <cmath>

namespace drape::detail {
namespace {

// Unit vector along v, or `fallback` at (near) zero length.
Vec3D UnitOr(const Vec3D& v, double length, const Vec3D& fallback) {
  return length > 1e-300 ? v * (1.0 / length) : fallback;
}

SignedDistance SphereDistance(const LocalShape& s, const Vec3D& q) {
  const Vec3D v{q.x - s.center_x, q.y, q.z};
  const double length = LengthD(v);
  // At the centre every direction is nearest: +y, as a plane's.
  return {length - s.radius, UnitOr(v, length, {0.0, 1.0, 0.0})};
}

// The round cone in the half-plane (x, rho) through the axis, rho the distance from the axis:
// the convex hull of the circles C0 = (-h, 0), r0 and C1 = (h, 0), r1. Their common tangent line
// has outward normal n = (sin, cos) and direction u = (cos, -sin); the tangent points sit at
// (P - C0) . u = 0 and 2h cos. A point before the first is nearest sphere 0, after the second
// sphere 1, between them the side: exact inside and outside (the support function of the hull
// is the larger of the spheres', and its maximiser falls in the same three ranges).
SignedDistance RoundConeDistance(const LocalShape& s, const Vec3D& q) {
  const double h = s.half_length;
  const double rho = std::sqrt(q.y * q.y + q.z * q.z);
  const double along = (q.x + h) * s.side_cos - rho * s.side_sin;
  if (along <= 0.0) {
    const Vec3D v{q.x + h, q.y, q.z};
    const double length = LengthD(v);
    return {length - s.radius0, UnitOr(v, length, {-1.0, 0.0, 0.0})};
  }
  if (along >= 2.0 * h * s.side_cos) {
    const Vec3D v{q.x - h, q.y, q.z};
    const double length = LengthD(v);
    return {length - s.radius1, UnitOr(v, length, {1.0, 0.0, 0.0})};
  }
  // On the axis between the tangent points (deep inside) every radial direction is nearest.
  const Vec3D radial = UnitOr({0.0, q.y, q.z}, rho, {0.0, 1.0, 0.0});
  return {(q.x + h) * s.side_sin + rho * s.side_cos - s.radius0,
          {s.side_sin, radial.y * s.side_cos, radial.z * s.side_cos}};
}

SignedDistance BoxDistance(const LocalShape& s, const Vec3D& q) {
  const double a[3] = {std::fabs(q.x), std::fabs(q.y), std::fabs(q.z)};
  const double e[3] = {s.half_extents.x, s.half_extents.y, s.half_extents.z};
  const double sign[3] = {q.x < 0.0 ? -1.0 : 1.0, q.y < 0.0 ? -1.0 : 1.0, q.z < 0.0 ? -1.0 : 1.0};
  const double d[3] = {a[0] - e[0], a[1] - e[1], a[2] - e[2]};
  if (d[0] > 0.0 || d[1] > 0.0 || d[2] > 0.0) {
    // Outside: the distance to the nearest point, the point clamped to the box.
    const Vec3D o{std::max(d[0], 0.0) * sign[0], std::max(d[1], 0.0) * sign[1],
                  std::max(d[2], 0.0) * sign[2]};
    const double length = LengthD(o);
    return {length, UnitOr(o, length, {0.0, 1.0, 0.0})};
  }
  // Inside (or on a face): the nearest face, the lowest axis on ties.
  int axis = 0;
  if (d[1] > d[axis]) axis = 1;
  if (d[2] > d[axis]) axis = 2;
  Vec3D n;
  (axis == 0 ? n.x : axis == 1 ? n.y : n.z) = sign[axis];
  return {d[axis], n};
}

SignedDistance ConvexDistance(const LocalShape& s, const Vec3D& q) {
  // The largest plane distance: exact inside (the nearest face's plane), a lower bound outside.
  double best = -INFINITY;
  uint32_t arg = 0;
  for (uint32_t k = 0; k < s.plane_count; ++k) {
    const Plane& p = s.planes[k];
    const double v = double(p.normal.x) * q.x + double(p.normal.y) * q.y +
                     double(p.normal.z) * q.z - double(p.offset);
    if (v > best) {
      best = v;
      arg = k;
    }
  }
  const Float3 n = s.planes[arg].normal;
  return {best, {n.x, n.y, n.z}};
}

}  // namespace

LocalShape SphereShape(double radius) {
  LocalShape s;
  s.kind = ShapeKind::kSphere;
  s.radius = radius;
  s.bound_radius = radius;
  return s;
}

LocalShape CapsuleShape(double half_length, double radius0, double radius1) {
  const double length = 2.0 * half_length;
  const double slope = radius0 - radius1;
  // One end sphere holds the other (the side would have no tangent line): that sphere.
  if (length <= std::fabs(slope)) {
    LocalShape s = SphereShape(std::max(radius0, radius1));
    s.center_x = radius0 >= radius1 ? -half_length : half_length;
    s.bound_radius = half_length + s.radius;
    return s;
  }
  LocalShape s;
  s.kind = ShapeKind::kCapsule;
  s.half_length = half_length;
  s.radius0 = radius0;
  s.radius1 = radius1;
  s.side_sin = slope / length;
  s.side_cos = std::sqrt((length - slope) * (length + slope)) / length;
  s.bound_radius = half_length + std::max(radius0, radius1);
  return s;
}

LocalShape PlaneShape() {
  LocalShape s;
  s.kind = ShapeKind::kPlane;
  s.bound_radius = INFINITY;
  return s;
}

LocalShape BoxShape(const Vec3D& half_extents) {
  LocalShape s;
  s.kind = ShapeKind::kBox;
  s.half_extents = half_extents;
  s.bound_radius = LengthD(half_extents);
  return s;
}

LocalShape ConvexShape(const Plane* planes, uint32_t plane_count, double bound_radius) {
  LocalShape s;
  s.kind = ShapeKind::kConvex;
  s.planes = planes;
  s.plane_count = plane_count;
  s.bound_radius = bound_radius;
  return s;
}

SignedDistance Distance(const LocalShape& shape, const Vec3D& q) {
  switch (shape.kind) {
    case ShapeKind::kSphere:
      return SphereDistance(shape, q);
    case ShapeKind::kCapsule:
      return RoundConeDistance(shape, q);
    case ShapeKind::kPlane:
      return {q.y, {0.0, 1.0, 0.0}};
    case ShapeKind::kBox:
      return BoxDistance(shape, q);
    case ShapeKind::kConvex:
      return ConvexDistance(shape, q);
  }
  return {INFINITY, {0.0, 1.0, 0.0}};
}

}  // namespace drape::detail

#pragma once
// Private to the runtime: the engine shapes of ShapeColliderSet in their local frames, and the
// signed distance of each kind with its outward unit gradient, in double (metres), negative
// inside. Exact, except outside a convex: there the largest plane distance, a lower bound with
// the same zero set. Every kind is convex, so the function is convex and 1-Lipschitz: along a
// segment it has one minimum (docs/ALGORITHMS.md §14).

#include <cstdint>

#include "common/rigid_transform.h"
#include "drape/formats/hull_collider_data.h"
#include "drape/runtime/shape_collider_set.h"

namespace drape::detail {

// The geometry the distance and the sweep read. kind kSphere also stands for a capsule that one
// of its end spheres holds (that sphere, centred at (center_x, 0, 0)).
struct LocalShape {
  ShapeKind kind = ShapeKind::kSphere;
  double radius = 0.0;    // sphere
  double center_x = 0.0;  // sphere: its centre on the local x axis (0 unless a reduced capsule)
  // Capsule (round cone): sphere radius0 at x = -half_length, radius1 at +half_length; its side
  // makes an angle with the axis whose sine is (radius0 - radius1) / (2 half_length).
  double half_length = 0.0, radius0 = 0.0, radius1 = 0.0;
  double side_sin = 0.0, side_cos = 1.0;
  Vec3D half_extents;             // box
  const Plane* planes = nullptr;  // convex: unit normals, inside where normal . x <= offset
  uint32_t plane_count = 0;
  double bound_radius = 0.0;  // a sphere about the local origin holding the shape (not planes)
};

LocalShape SphereShape(double radius);
// The round cone, or the larger end sphere when it holds the other.
LocalShape CapsuleShape(double half_length, double radius0, double radius1);
LocalShape PlaneShape();
LocalShape BoxShape(const Vec3D& half_extents);
LocalShape ConvexShape(const Plane* planes, uint32_t plane_count, double bound_radius);

struct SignedDistance {
  double value = 0.0;  // metres, < 0 inside
  Vec3D gradient;      // unit, outward; at a point with several (a box corner), a valid one
};

SignedDistance Distance(const LocalShape& shape, const Vec3D& q);

}  // namespace drape::detail

#pragma once
// Private to the runtime: the continuous test of one segment q0 -> q1 against one engine shape,
// in the shape's local frame (the particle's motion relative to the shape), in double
// (docs/ALGORITHMS.md §14).

#include "common/rigid_transform.h"
#include "shapes/shape_distance.h"

namespace drape::detail {

struct LocalContact {
  bool hit = false;
  bool started_inside = false;  // q0 and q1 inside: the contact is the nearest surface to q1
  double t = 1.0;               // the entry along q0 -> q1 in [0, 1]; 0 when started inside
  Vec3D point;                  // on the surface
  Vec3D normal;                 // unit, outward: n . x >= n . point is outside the shape
  double end_depth = 0.0;       // metres q1 lies inside the shape (0 outside)
};

// A segment that starts outside (signed distance >= 0) and reaches inside (< 0) enters at the
// first t where the distance is 0; one that starts and ends inside is pushed out of q1; one that
// starts inside and ends outside, or never goes inside, has no contact.
LocalContact Sweep(const LocalShape& shape, const Vec3D& q0, const Vec3D& q1);

}  // namespace drape::detail

#pragma once
// Private to the runtime: whether a convex given by its planes is bounded and non-empty, and a
// sphere about its local origin that holds it, from six small linear programs (the extremes of
// the polytope along +-x, +-y, +-z) solved in double without allocating.

#include <cstdint>

#include "drape/formats/hull_collider_data.h"

namespace drape::detail {

enum class ConvexExtent : uint8_t {
  kBounded = 0,
  kEmpty = 1,      // the half-spaces have no common point
  kUnbounded = 2,  // the region reaches `limit` from the origin along some axis
};

struct ConvexBounds {
  ConvexExtent extent = ConvexExtent::kEmpty;
  double radius = 0.0;  // metres: the farthest corner of the polytope's bounding box
};

// planes: unit normals, inside where normal . x <= offset. limit: metres, > 0.
ConvexBounds MeasureConvex(const Plane* planes, uint32_t plane_count, double limit);

}  // namespace drape::detail

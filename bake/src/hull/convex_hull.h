#pragma once
// The convex hull of a point set (CGAL's convex_hull_3), in a canonical order.

#include <vector>

#include "hull/hull_mesh.h"

namespace drape::bake::detail {

// Returns false unless the hull is a closed polytope with >= 4 faces, i.e. the points are not all
// coplanar. CGAL's vertex and face order depends on memory addresses, so the result is
// canonical: vertices sorted by coordinates, coplanar faces re-fanned (CanonicalTriangulation),
// triangles sorted.
bool ConvexHull(const std::vector<Vec3>& points, Mesh* out);

}  // namespace drape::bake::detail

#pragma once
// The faces of a triangle mesh: groups of edge-adjacent, exactly coplanar triangles (union-find
// over exact orientation tests) and the canonical triangulation of every such face.

#include <cstdint>
#include <vector>

#include "hull/hull_mesh.h"

namespace drape::bake::detail {

// Union-find over triangle indices; the smaller root wins a union.
uint32_t Find(std::vector<uint32_t>& parent, uint32_t i);
void Union(std::vector<uint32_t>& parent, uint32_t a, uint32_t b);

// Group id per triangle, ids numbered in order of each group's first triangle. parent_out, if
// given, gets the union-find forest (to merge groups further).
std::vector<uint32_t> GroupCoplanar(const Mesh& mesh, uint32_t* group_count,
                                    std::vector<uint32_t>* parent_out = nullptr);

// The triangulation of a coplanar face (a parallelogram of the Minkowski sum, a cube side) is
// CGAL's choice and varies between calls. Re-triangulate every face with more than one triangle
// canonically: its boundary cycle starting at the smallest vertex index, fanned from the first
// vertex that gives no collinear triangle (faces are convex polygons). Then rotate each triangle
// to start at its smallest index and sort them. Returns true (kept for the hull's signature).
bool CanonicalTriangulation(Mesh* mesh);

}  // namespace drape::bake::detail

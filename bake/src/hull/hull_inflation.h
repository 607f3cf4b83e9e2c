#pragma once
// Inflation of the input points by delta: H0, the "inflated hull" (header hull_builder.h, step 2).

#include <vector>

#include "hull/hull_mesh.h"

namespace drape::bake::detail {

// H0 = hull of the float-rounded points {x + r u_k} over the base points x and the 12 vertices
// u_k of a unit-circumradius icosahedron, r = (delta + margin) / inradius: every delta-ball of a
// base point is inside. False when the hull is degenerate.
bool InflateMinkowski(const std::vector<Vec3>& base, double delta, double margin, Mesh* h0);

// Paper B: every hull vertex moved by delta along its normal, hulled again. Angle-weighted
// vertex normals (Thuermer and Wuethrich): unlike area weights they do not depend on how a flat
// face happens to be triangulated. False when the hull is degenerate.
bool InflateVertexNormals(const Mesh& hull, double delta, Mesh* h0);

}  // namespace drape::bake::detail

#pragma once
// The oriented bounding box of a hull (header hull_builder.h, step 6): axes from the paper's
// covariance method or CGAL's optimiser, extents that cover every collider vertex and input
// delta-ball in the runtime's float arithmetic.

#include <array>
#include <cstdint>
#include <vector>

#include "drape/formats/hull_collider_data.h"
#include "hull/hull_mesh.h"

namespace drape::bake::detail {

// Orthonormal right-handed axes (rows) -> OBB covering the collider vertices and the input
// delta-balls in float arithmetic; axes sorted by extent, longest first.
Obb FitObb(const std::array<Vec3, 3>& axes_in, const Mesh& mesh, const std::vector<Vec3>& inputs,
           double delta);

// Paper B's statistical axes: eigenvectors of the area-weighted covariance of the hull surface
// (Gottschalk), largest eigenvalue first.
std::array<Vec3, 3> CovarianceAxes(const Mesh& mesh);

// CGAL::oriented_bounding_box's axes, seeded (deterministic).
std::array<Vec3, 3> CgalOptimalAxes(const Mesh& mesh, uint32_t seed);

}  // namespace drape::bake::detail

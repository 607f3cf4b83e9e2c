#pragma once
// Exact checks on a hull mesh (CGAL predicates and rational arithmetic on the stored
// coordinates): closed convex polytope, and containment of delta-balls.

#include <cstdint>

#include "drape/formats/hull_collider_data.h"
#include "hull/hull_mesh.h"

namespace drape::bake::detail {

// True when the mesh is a closed, consistently oriented 2-manifold of genus 0 without degenerate
// triangles and every vertex lies on or below every triangle's plane; *violations counts the
// vertices strictly above a triangle's plane.
bool MeshIsConvex(const Mesh& mesh, uint32_t* violations);

// Number of exact orient3d violations (a vertex strictly above a triangle's plane); a triangle
// with an index out of range counts as one.
uint32_t CountViolations(const Mesh& mesh);

// The stored collider as a Mesh: float vertices widened to double, indices as stored.
Mesh MeshFromCollider(const HullColliderData& collider);

// The closed ball B(x, radius) is inside every triangle's closed half-space (exact).
bool PointBallInside(const Mesh& mesh, const Vec3& x, double radius);

// Approximate (double) amount by which the ball B(x, radius) pokes out of the mesh, metres.
double BallDeficit(const Mesh& mesh, const Vec3& x, double radius);

}  // namespace drape::bake::detail

#pragma once
// Exact reference queries against a triangle mesh, in double: the ground truth the colliders are
// measured against. Character meshes are open and self-overlapping, so inside/outside is the
// generalised winding number (Jacobson et al. 2013), never a parity ray test (docs/ALGORITHMS.md
// §11.1). Brute force over all triangles: O(triangles) per query; fine for tests and reports.

#include <cstdint>
#include <span>
#include <vector>

#include "drape/formats/types.h"

namespace drape::bake {

class ExactMesh {
 public:
  ExactMesh(std::span<const Float3> positions, std::span<const uint32_t> triangles);

  // Sum over triangles of the signed solid angle / 4 pi (Van Oosterom-Strackee). About 1 inside a
  // closed outward-wound surface, 0 outside, 2 where two parts overlap.
  double WindingNumber(const double q[3]) const;
  bool Inside(const double q[3]) const { return WindingNumber(q) > 0.5; }
  // Unsigned distance to the nearest triangle, metres.
  double Distance(const double q[3]) const;

  size_t triangle_count() const { return corners_.size() / 9; }

 private:
  std::vector<double> corners_;  // 9 doubles per triangle
};

// Distance from p to the triangle abc (Ericson, Real-Time Collision Detection §5.1.5).
double PointTriangleDistance(const double p[3], const double a[3], const double b[3],
                             const double c[3]);

}  // namespace drape::bake

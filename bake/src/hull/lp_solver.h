#pragma once
// Seidel's incremental LP in 3, 2 and 1 variables, deterministic order (the constraint order as
// given). Minimises c.x subject to a_i.x <= b_i (|a_i| = 1) and the box |x_j| <= bound. A
// constraint counts as violated when a.x > b + tol. Floating point: the answer is a candidate
// that the exact predicates accept or refuse later, so tolerances only need to be sensible.

#include <vector>

#include "hull/hull_mesh.h"

namespace drape::bake::detail {

struct Halfspace3 {
  Vec3 a;
  double b = 0.0;
};
struct Halfspace2 {
  double a0 = 0.0, a1 = 0.0, b = 0.0;
};

class LpSolver {
 public:
  bool Solve3(const std::vector<Halfspace3>& hs, Vec3 c, double bound, double tol, Vec3* x);

 private:
  // Over plane_ (2D halfspaces) and the box |y_j| <= bound.
  bool Solve2(double c0, double c1, double bound, double tol, double* y0, double* y1) const;

  std::vector<Halfspace2> plane_;
};

}  // namespace drape::bake::detail

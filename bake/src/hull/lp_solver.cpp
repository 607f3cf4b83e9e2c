#include "hull/lp_solver.h"

#include <algorithm>
#include <cmath>

namespace drape::bake::detail {

bool LpSolver::Solve3(const std::vector<Halfspace3>& hs, Vec3 c, double bound, double tol,
                      Vec3* x) {
  Vec3 cur{c.x > 0.0 ? -bound : (c.x < 0.0 ? bound : 0.0),
           c.y > 0.0 ? -bound : (c.y < 0.0 ? bound : 0.0),
           c.z > 0.0 ? -bound : (c.z < 0.0 ? bound : 0.0)};
  for (size_t i = 0; i < hs.size(); ++i) {
    const Halfspace3& h = hs[i];
    if (Dot(h.a, cur) <= h.b + tol) continue;
    // The optimum of the first i+1 constraints lies on plane i: solve there in 2D.
    const Vec3 origin = h.a * h.b;
    const Vec3 helper =
        std::fabs(h.a.x) <= std::fabs(h.a.y) && std::fabs(h.a.x) <= std::fabs(h.a.z)
            ? Vec3{1, 0, 0}
            : (std::fabs(h.a.y) <= std::fabs(h.a.z) ? Vec3{0, 1, 0} : Vec3{0, 0, 1});
    Vec3 e1 = Cross(h.a, helper);
    e1 = e1 * (1.0 / Norm(e1));
    const Vec3 e2 = Cross(h.a, e1);
    plane_.clear();
    auto project = [&](Vec3 a, double b) {
      const double p0 = Dot(a, e1), p1 = Dot(a, e2);
      const double rhs = b - Dot(a, origin);
      const double len = std::sqrt(p0 * p0 + p1 * p1);
      if (len < 1e-9) return rhs >= -tol;  // parallel: all or nothing
      plane_.push_back({p0 / len, p1 / len, rhs / len});
      return true;
    };
    // Box faces first: the 2D start is a corner of an even larger box, so they bind early.
    const Vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (const Vec3& axis : axes) {
      if (!project(axis, bound) || !project(axis * -1.0, bound)) return false;
    }
    for (size_t j = 0; j < i; ++j) {
      if (!project(hs[j].a, hs[j].b)) return false;
    }
    double y0 = 0.0, y1 = 0.0;
    if (!Solve2(Dot(c, e1), Dot(c, e2), 2.0 * bound + std::fabs(h.b), tol, &y0, &y1)) {
      return false;
    }
    cur = origin + e1 * y0 + e2 * y1;
  }
  *x = cur;
  return true;
}

bool LpSolver::Solve2(double c0, double c1, double bound, double tol, double* y0,
                      double* y1) const {
  double x0 = c0 > 0.0 ? -bound : (c0 < 0.0 ? bound : 0.0);
  double x1 = c1 > 0.0 ? -bound : (c1 < 0.0 ? bound : 0.0);
  for (size_t i = 0; i < plane_.size(); ++i) {
    const Halfspace2& h = plane_[i];
    if (h.a0 * x0 + h.a1 * x1 <= h.b + tol) continue;
    // On the line h: o + t e.
    const double o0 = h.a0 * h.b, o1 = h.a1 * h.b;
    const double e0 = -h.a1, e1 = h.a0;
    const double line_bound = 2.0 * bound + std::fabs(h.b);
    double lo = -line_bound, hi = line_bound;
    auto clip = [&](double a0, double a1, double b) {
      const double alpha = a0 * e0 + a1 * e1;
      const double beta = b - (a0 * o0 + a1 * o1);
      if (std::fabs(alpha) < 1e-12) return beta >= -tol;
      if (alpha > 0.0) {
        hi = std::min(hi, beta / alpha);
      } else {
        lo = std::max(lo, beta / alpha);
      }
      return true;
    };
    for (size_t j = 0; j < i; ++j) {
      if (!clip(plane_[j].a0, plane_[j].a1, plane_[j].b)) return false;
    }
    if (!clip(1, 0, bound) || !clip(-1, 0, bound) || !clip(0, 1, bound) || !clip(0, -1, bound)) {
      return false;
    }
    if (lo > hi + tol) return false;
    const double ce = c0 * e0 + c1 * e1;
    double t;
    if (lo > hi) {
      t = 0.5 * (lo + hi);
    } else if (ce > 0.0) {
      t = lo;
    } else if (ce < 0.0) {
      t = hi;
    } else {
      t = std::clamp(0.0, lo, hi);
    }
    x0 = o0 + t * e0;
    x1 = o1 + t * e1;
  }
  *y0 = x0;
  *y1 = x1;
  return true;
}

}  // namespace drape::bake::detail

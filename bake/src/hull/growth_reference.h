#pragma once
// Distance to the inflated hull H0: the reference the simplifiers measure "growth" against.
// Header-only: LowerBound is the simplifiers' inner loop.

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "hull/hull_mesh.h"

namespace drape::bake::detail {

class GrowthReference {
 public:
  explicit GrowthReference(const Mesh& h0) {
    const size_t n = h0.triangles.size();
    nx_.resize(n);
    ny_.resize(n);
    nz_.resize(n);
    d_.resize(n);
    a_.resize(n);
    b_.resize(n);
    c_.resize(n);
    for (size_t t = 0; t < n; ++t) {
      const Vec3 a = h0.points[h0.triangles[t][0]];
      const Vec3 b = h0.points[h0.triangles[t][1]];
      const Vec3 c = h0.points[h0.triangles[t][2]];
      Vec3 normal = Cross(b - a, c - a);
      const double len = Norm(normal);
      normal = len > 0.0 ? normal * (1.0 / len) : Vec3{};
      nx_[t] = normal.x;
      ny_[t] = normal.y;
      nz_[t] = normal.z;
      d_[t] = std::max({Dot(normal, a), Dot(normal, b), Dot(normal, c)});
      a_[t] = a;
      b_[t] = b;
      c_[t] = c;
    }
  }

  // max over H0's triangle planes of the signed height of p, clamped at 0: a lower bound of
  // Distance(p) (exact up to double rounding).
  double LowerBound(Vec3 p) const {
    double best = 0.0;
    const size_t n = d_.size();
    for (size_t t = 0; t < n; ++t) {
      const double h = nx_[t] * p.x + ny_[t] * p.y + nz_[t] * p.z - d_[t];
      best = h > best ? h : best;
    }
    return best;
  }

  // Euclidean distance from p to the polytope H0 (0 inside). For p outside, the nearest point
  // lies on a triangle whose plane has p strictly on its outer side.
  double Distance(Vec3 p) const {
    // Outside p: the nearest boundary point q lies on a triangle T with n_T.(p - q) >= 0, i.e.
    // h_T(p) >= 0. Triangles with h slightly below 0 (rounding) are kept: extra candidates are
    // harmless, a missing one is not (a point on the surface must find its own triangle).
    const double tol = 1e-12 * (1.0 + MaxAbs(p));
    if (LowerBound(p) <= 0.0) return 0.0;
    double best = std::numeric_limits<double>::infinity();
    for (size_t t = 0; t < d_.size(); ++t) {
      const double h = nx_[t] * p.x + ny_[t] * p.y + nz_[t] * p.z - d_[t];
      if (h < -tol || h >= best) continue;
      best = std::min(best, PointTriangleDistance(p, a_[t], b_[t], c_[t]));
    }
    return best;
  }

 private:
  // Ericson, Real-Time Collision Detection, 5.1.5.
  static double PointTriangleDistance(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = Dot(ab, ap), d2 = Dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return Norm(p - a);
    const Vec3 bp = p - b;
    const double d3 = Dot(ab, bp), d4 = Dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return Norm(p - b);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
      const double v = d1 / (d1 - d3);
      return Norm(p - (a + ab * v));
    }
    const Vec3 cp = p - c;
    const double d5 = Dot(ab, cp), d6 = Dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return Norm(p - c);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
      const double w = d2 / (d2 - d6);
      return Norm(p - (a + ac * w));
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
      const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
      return Norm(p - (b + (c - b) * w));
    }
    const double denom = 1.0 / (va + vb + vc);
    const double v = vb * denom, w = vc * denom;
    return Norm(p - (a + ab * v + ac * w));
  }

  std::vector<double> nx_, ny_, nz_, d_;
  std::vector<Vec3> a_, b_, c_;
};

}  // namespace drape::bake::detail

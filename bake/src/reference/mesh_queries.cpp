#include "drape/bake/mesh_queries.h"

#include <algorithm>
#include <cmath>

namespace drape::bake {

ExactMesh::ExactMesh(std::span<const Float3> positions, std::span<const uint32_t> triangles) {
  corners_.reserve(triangles.size() * 3);
  for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
    for (int k = 0; k < 3; ++k) {
      const Float3 p = positions[triangles[t + k]];
      corners_.insert(corners_.end(), {p.x, p.y, p.z});
    }
  }
}

double ExactMesh::WindingNumber(const double q[3]) const {
  double sum = 0.0;
  for (size_t t = 0; t < corners_.size(); t += 9) {
    double a[3], b[3], c[3];
    for (int k = 0; k < 3; ++k) {
      a[k] = corners_[t + k] - q[k];
      b[k] = corners_[t + 3 + k] - q[k];
      c[k] = corners_[t + 6 + k] - q[k];
    }
    const double la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    const double lb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    const double lc = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    const double det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                       a[2] * (b[0] * c[1] - b[1] * c[0]);
    const double ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    const double bc = b[0] * c[0] + b[1] * c[1] + b[2] * c[2];
    const double ca = c[0] * a[0] + c[1] * a[1] + c[2] * a[2];
    const double denominator = la * lb * lc + ab * lc + bc * la + ca * lb;
    sum += 2.0 * std::atan2(det, denominator);
  }
  return sum / (4.0 * M_PI);
}

double PointTriangleDistance(const double p[3], const double a[3], const double b[3],
                             const double c[3]) {
  auto sub = [](const double* x, const double* y, double* r) {
    for (int k = 0; k < 3; ++k) r[k] = x[k] - y[k];
  };
  auto dot = [](const double* x, const double* y) {
    return x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
  };
  double ab[3], ac[3], ap[3], bp[3], cp[3], closest[3];
  sub(b, a, ab), sub(c, a, ac), sub(p, a, ap);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  auto at = [&](double u, double v) {  // a + u ab + v ac
    for (int k = 0; k < 3; ++k) closest[k] = a[k] + u * ab[k] + v * ac[k];
  };
  if (d1 <= 0 && d2 <= 0) {
    at(0, 0);
  } else {
    sub(p, b, bp);
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    sub(p, c, cp);
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
    if (d3 >= 0 && d4 <= d3) {
      at(1, 0);
    } else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
      at(d1 / (d1 - d3), 0);
    } else if (d6 >= 0 && d5 <= d6) {
      at(0, 1);
    } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
      at(0, d2 / (d2 - d6));
    } else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
      const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
      at(1 - w, w);
    } else {
      const double denom = 1.0 / (va + vb + vc);
      at(vb * denom, vc * denom);
    }
  }
  double d[3];
  sub(p, closest, d);
  return std::sqrt(dot(d, d));
}

double ExactMesh::Distance(const double q[3]) const {
  double best = INFINITY;
  for (size_t t = 0; t < corners_.size(); t += 9) {
    best =
        std::min(best, PointTriangleDistance(q, &corners_[t], &corners_[t + 3], &corners_[t + 6]));
  }
  return best;
}

}  // namespace drape::bake

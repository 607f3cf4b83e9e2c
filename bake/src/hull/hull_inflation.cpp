#include "hull/hull_inflation.h"

#include <array>
#include <cmath>

#include "hull/convex_hull.h"

namespace drape::bake::detail {
namespace {

// Unit-circumradius icosahedron vertices (12) and the inradius of that icosahedron.
std::array<Vec3, 12> Icosahedron(double* inradius) {
  const double phi = (1.0 + std::sqrt(5.0)) / 2.0;
  const double s = 1.0 / std::sqrt(1.0 + phi * phi);
  const double a = s, b = phi * s;
  *inradius = phi * phi / (std::sqrt(3.0) * std::sqrt(1.0 + phi * phi));
  return {Vec3{0, a, b}, Vec3{0, -a, b}, Vec3{0, a, -b}, Vec3{0, -a, -b},
          Vec3{a, b, 0}, Vec3{-a, b, 0}, Vec3{a, -b, 0}, Vec3{-a, -b, 0},
          Vec3{b, 0, a}, Vec3{-b, 0, a}, Vec3{b, 0, -a}, Vec3{-b, 0, -a}};
}

}  // namespace

// H0 = hull of the float-rounded points {x + r u_k}, r = (delta + margin) / inradius.
bool InflateMinkowski(const std::vector<Vec3>& base, double delta, double margin, Mesh* h0) {
  double inradius = 0.0;
  const std::array<Vec3, 12> ico = Icosahedron(&inradius);
  // 1e-12: the double icosahedron is not exact; err on the large side.
  const double radius = (delta + margin) / inradius * (1.0 + 1e-12);
  std::vector<Vec3> points;
  points.reserve(base.size() * 12);
  for (const Vec3& x : base) {
    for (const Vec3& u : ico) points.push_back(RoundToFloat(x + u * radius));
  }
  SortUnique(&points);
  return ConvexHull(points, h0);
}

bool InflateVertexNormals(const Mesh& hull, double delta, Mesh* h0) {
  std::vector<Vec3> normals(hull.points.size());
  for (const auto& tri : hull.triangles) {
    Vec3 n =
        Cross(hull.points[tri[1]] - hull.points[tri[0]], hull.points[tri[2]] - hull.points[tri[0]]);
    const double len = Norm(n);
    if (!(len > 0.0)) continue;
    n = n * (1.0 / len);
    for (int k = 0; k < 3; ++k) {
      const Vec3 p = hull.points[tri[k]];
      const Vec3 a = hull.points[tri[(k + 1) % 3]] - p, b = hull.points[tri[(k + 2) % 3]] - p;
      const double angle = std::atan2(Norm(Cross(a, b)), Dot(a, b));
      normals[tri[k]] = normals[tri[k]] + n * angle;
    }
  }
  std::vector<Vec3> points;
  points.reserve(hull.points.size());
  for (size_t i = 0; i < hull.points.size(); ++i) {
    const double len = Norm(normals[i]);
    const Vec3 n = len > 0.0 ? normals[i] * (1.0 / len) : Vec3{};
    points.push_back(RoundToFloat(hull.points[i] + n * delta));
  }
  return ConvexHull(points, h0);
}

}  // namespace drape::bake::detail

#include "hull/hull_checks.h"

#include "hull/hull_kernel.h"  // first of the CGAL headers

#include <CGAL/Exact_rational.h>
#include <CGAL/Interval_nt.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "hull/convex_hull.h"

namespace drape::bake::detail {
namespace {

// Closed ball B(x, r) inside the closed half-space below the oriented plane of (a, b, c):
// with n = (b - a) x (c - a): n.(a - x) >= r |n|. Interval filter, then exact rationals.
bool BallBelowPlane(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& x, double r) {
  if (r <= 0.0) {
    return CGAL::orientation(ToPoint(a), ToPoint(b), ToPoint(c), ToPoint(x)) != CGAL::POSITIVE;
  }
  {
    using I = CGAL::Interval_nt<false>;
    CGAL::Protect_FPU_rounding<true> protect;
    const I abx = I(b.x) - I(a.x), aby = I(b.y) - I(a.y), abz = I(b.z) - I(a.z);
    const I acx = I(c.x) - I(a.x), acy = I(c.y) - I(a.y), acz = I(c.z) - I(a.z);
    const I nx = aby * acz - abz * acy, ny = abz * acx - abx * acz, nz = abx * acy - aby * acx;
    const I s = nx * (I(a.x) - I(x.x)) + ny * (I(a.y) - I(x.y)) + nz * (I(a.z) - I(x.z));
    const I len2 = nx * nx + ny * ny + nz * nz;
    const I rr = I(r) * I(r);
    const I margin = s * s - rr * len2;
    if (s.sup() < 0.0 || margin.sup() < 0.0) return false;
    if (s.inf() > 0.0 && margin.inf() > 0.0) return true;
  }
  using Q = CGAL::Exact_rational;
  const Q abx = Q(b.x) - Q(a.x), aby = Q(b.y) - Q(a.y), abz = Q(b.z) - Q(a.z);
  const Q acx = Q(c.x) - Q(a.x), acy = Q(c.y) - Q(a.y), acz = Q(c.z) - Q(a.z);
  const Q nx = aby * acz - abz * acy, ny = abz * acx - abx * acz, nz = abx * acy - aby * acx;
  const Q s = nx * (Q(a.x) - Q(x.x)) + ny * (Q(a.y) - Q(x.y)) + nz * (Q(a.z) - Q(x.z));
  if (s < 0) return false;
  const Q len2 = nx * nx + ny * ny + nz * nz;
  return s * s >= Q(r) * Q(r) * len2;
}

}  // namespace

bool MeshIsConvex(const Mesh& mesh, uint32_t* violations) {
  *violations = 0;
  const size_t n = mesh.points.size(), t = mesh.triangles.size();
  if (n < 4 || t < 4) return false;
  for (const Vec3& p : mesh.points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return false;
  }
  std::vector<uint64_t> directed;
  std::vector<uint8_t> used(n, 0);
  for (const auto& tri : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tri[static_cast<size_t>(k)], b = tri[static_cast<size_t>((k + 1) % 3)];
      if (a >= n || b >= n || a == b) return false;
      used[a] = 1;
      directed.push_back((static_cast<uint64_t>(a) << 32) | b);
    }
  }
  for (uint8_t u : used) {
    if (!u) return false;
  }
  std::sort(directed.begin(), directed.end());
  if (std::adjacent_find(directed.begin(), directed.end()) != directed.end()) return false;
  for (uint64_t e : directed) {
    const uint64_t reverse = (e << 32) | (e >> 32);
    if (!std::binary_search(directed.begin(), directed.end(), reverse)) return false;
  }
  // Euler characteristic of a sphere.
  const long long euler = static_cast<long long>(n) - static_cast<long long>(directed.size() / 2) +
                          static_cast<long long>(t);
  if (euler != 2) return false;
  std::vector<Point> points;
  points.reserve(n);
  for (const Vec3& p : mesh.points) points.push_back(ToPoint(p));
  bool strictly_below_somewhere = false;
  for (const auto& tri : mesh.triangles) {
    const Point& a = points[tri[0]];
    const Point& b = points[tri[1]];
    const Point& c = points[tri[2]];
    if (CGAL::collinear(a, b, c)) return false;
    for (const Point& q : points) {
      const CGAL::Orientation o = CGAL::orientation(a, b, c, q);
      if (o == CGAL::POSITIVE) ++*violations;
      if (o == CGAL::NEGATIVE) strictly_below_somewhere = true;
    }
  }
  if (*violations != 0 || !strictly_below_somewhere) return false;
  // A closed sphere whose triangles all support the polytope could still cover its boundary
  // twice (a branched cover); its enclosed volume would then be a multiple of the hull's.
  Mesh hull;
  if (!ConvexHull(mesh.points, &hull)) return false;
  auto volume = [](const Mesh& m) {
    const Vec3 o = m.points[0];
    double v = 0.0;
    for (const auto& tri : m.triangles) {
      v += Dot(m.points[tri[0]] - o, Cross(m.points[tri[1]] - o, m.points[tri[2]] - o));
    }
    return v / 6.0;
  };
  const double mesh_volume = volume(mesh), hull_volume = volume(hull);
  return mesh_volume > 0.0 && std::fabs(mesh_volume - hull_volume) <= 1e-6 * hull_volume;
}

uint32_t CountViolations(const Mesh& mesh) {
  uint32_t violations = 0;
  for (const auto& tri : mesh.triangles) {
    if (tri[0] >= mesh.points.size() || tri[1] >= mesh.points.size() ||
        tri[2] >= mesh.points.size()) {
      ++violations;
      continue;
    }
    const Point a = ToPoint(mesh.points[tri[0]]), b = ToPoint(mesh.points[tri[1]]),
                c = ToPoint(mesh.points[tri[2]]);
    for (const Vec3& q : mesh.points) {
      if (CGAL::orientation(a, b, c, ToPoint(q)) == CGAL::POSITIVE) ++violations;
    }
  }
  return violations;
}

Mesh MeshFromCollider(const HullColliderData& collider) {
  Mesh mesh;
  mesh.points.reserve(collider.vertices.size());
  for (const Float3& v : collider.vertices) mesh.points.push_back(ToVec3(v));
  for (size_t i = 0; i + 2 < collider.triangles.size(); i += 3) {
    mesh.triangles.push_back(
        {collider.triangles[i], collider.triangles[i + 1], collider.triangles[i + 2]});
  }
  return mesh;
}

bool PointBallInside(const Mesh& mesh, const Vec3& x, double radius) {
  for (const auto& tri : mesh.triangles) {
    if (!BallBelowPlane(mesh.points[tri[0]], mesh.points[tri[1]], mesh.points[tri[2]], x, radius)) {
      return false;
    }
  }
  return true;
}

// Approximate (double) amount by which the ball B(x, radius) pokes out of the mesh, metres.
double BallDeficit(const Mesh& mesh, const Vec3& x, double radius) {
  double worst = -std::numeric_limits<double>::infinity();
  for (const auto& tri : mesh.triangles) {
    const Vec3 a = mesh.points[tri[0]];
    Vec3 n = Cross(mesh.points[tri[1]] - a, mesh.points[tri[2]] - a);
    const double len = Norm(n);
    if (!(len > 0.0)) continue;
    n = n * (1.0 / len);
    worst = std::max(worst, Dot(n, x - a) + radius);
  }
  return worst;
}

}  // namespace drape::bake::detail

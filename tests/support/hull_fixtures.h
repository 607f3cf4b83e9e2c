#pragma once
// Hand-made convex hulls shared by the hull-collider tests and benchmarks: a box and a tessellated
// ellipsoid (icosphere), planes with offsets rounded outward in the runtime's float arithmetic,
// plus rotation and sampling helpers. Header-only and runtime-only (formats/runtime headers and the
// standard library): tests/runtime builds it with -DDRAPE_BUILD_BAKE=OFF.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "drape/formats/hull_collider_data.h"
#include "drape/formats/types.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"

namespace drape::test {

inline constexpr double kPi = 3.14159265358979323846;

// ---- Hand-made convex hulls -------------------------------------------------------------------

// Orients every face outward (against the vertex centroid), merges exactly coplanar faces into one
// plane and rounds each offset outward: every vertex is inside in the runtime's arithmetic.
inline HullColliderData MakeHull(const std::vector<Float3>& vertices,
                                 std::vector<std::array<uint32_t, 3>> faces, const Obb& obb) {
  HullColliderData h;
  h.joint = 0;
  h.vertices = vertices;
  h.obb = obb;
  double cx = 0, cy = 0, cz = 0;
  for (const Float3& v : vertices) cx += v.x, cy += v.y, cz += v.z;
  cx /= double(vertices.size()), cy /= double(vertices.size()), cz /= double(vertices.size());
  for (auto& f : faces) {
    const Float3 a = vertices[f[0]], b = vertices[f[1]], c = vertices[f[2]];
    const double ux = double(b.x) - a.x, uy = double(b.y) - a.y, uz = double(b.z) - a.z;
    const double vx = double(c.x) - a.x, vy = double(c.y) - a.y, vz = double(c.z) - a.z;
    double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    const double mx = (double(a.x) + b.x + c.x) / 3 - cx, my = (double(a.y) + b.y + c.y) / 3 - cy,
                 mz = (double(a.z) + b.z + c.z) / 3 - cz;
    if (nx * mx + ny * my + nz * mz < 0) {
      std::swap(f[1], f[2]);
      nx = -nx, ny = -ny, nz = -nz;
    }
    const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
    const Float3 n{float(nx / len), float(ny / len), float(nz / len)};
    const double offset = (double(n.x) * a.x + double(n.y) * a.y + double(n.z) * a.z);
    int32_t plane = -1;
    for (size_t p = 0; p < h.planes.size(); ++p) {
      const Float3 q = h.planes[p].normal;
      if (std::fabs(q.x - n.x) + std::fabs(q.y - n.y) + std::fabs(q.z - n.z) < 1e-6f &&
          std::fabs(double(q.x) * a.x + double(q.y) * a.y + double(q.z) * a.z - offset) < 1e-6)
        plane = int32_t(p);
    }
    if (plane < 0) {
      plane = int32_t(h.planes.size());
      h.planes.push_back({n, 0.f});
    }
    h.triangles.insert(h.triangles.end(), {f[0], f[1], f[2]});
    h.triangle_planes.push_back(uint32_t(plane));
  }
  // As bake/hull_builder.h does: the max over the vertices of n.x plus the worst-case rounding
  // of a float dot product (3 ulps of sum |n_i x_i|), rounded up to float, plus one more ulp.
  for (Plane& p : h.planes) {
    double worst = -std::numeric_limits<double>::infinity();
    for (const Float3& v : vertices) {
      const double nx = double(p.normal.x) * v.x, ny = double(p.normal.y) * v.y,
                   nz = double(p.normal.z) * v.z;
      worst = std::max(worst, nx + ny + nz +
                                  3.0 * std::numeric_limits<float>::epsilon() *
                                      (std::fabs(nx) + std::fabs(ny) + std::fabs(nz)));
    }
    float d = static_cast<float>(worst);
    if (double(d) < worst) d = std::nextafter(d, std::numeric_limits<float>::infinity());
    p.offset = std::nextafter(d, std::numeric_limits<float>::infinity());
  }
  return h;
}

inline Float3 Rotate(const Float3 axes[3], Float3 local) {
  return axes[0] * local.x + axes[1] * local.y + axes[2] * local.z;
}

// Box with half extents he, rotated to `axes`, centred at `center` (collider frame).
inline HullColliderData MakeBox(Float3 he, Float3 center = {}, const Float3* axes = nullptr) {
  const Float3 identity[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  if (axes == nullptr) axes = identity;
  std::vector<Float3> v;
  for (int i = 0; i < 8; ++i) {
    const Float3 local{(i & 1) ? he.x : -he.x, (i & 2) ? he.y : -he.y, (i & 4) ? he.z : -he.z};
    v.push_back(center + Rotate(axes, local));
  }
  const std::vector<std::array<uint32_t, 3>> faces = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                                      {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                                      {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  Obb obb;
  obb.center = center;
  for (int k = 0; k < 3; ++k) obb.axes[k] = axes[k];
  obb.half_extents = he;
  return MakeHull(v, faces, obb);
}

// Icosphere subdivided `levels` times, scaled to semi-axes `r`, rotated and centred. All its
// vertices lie on the ellipsoid, so every face is a convex-hull face.
inline HullColliderData MakeEllipsoid(Float3 r, int levels, Float3 center, const Float3 axes[3]) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<std::array<double, 3>> p = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                          {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                          {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<uint32_t, 3>> f = {
      {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& q : p) {
    const double l = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    for (double& x : q) x /= l;
  }
  for (int level = 0; level < levels; ++level) {
    std::vector<std::array<uint32_t, 3>> next;
    std::vector<std::pair<uint64_t, uint32_t>> cache;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      const uint64_t key = (uint64_t(std::min(a, b)) << 32) | std::max(a, b);
      for (auto& [k, v] : cache)
        if (k == key) return v;
      std::array<double, 3> m = {p[a][0] + p[b][0], p[a][1] + p[b][1], p[a][2] + p[b][2]};
      const double l = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
      for (double& x : m) x /= l;
      p.push_back(m);
      cache.push_back({key, uint32_t(p.size() - 1)});
      return uint32_t(p.size() - 1);
    };
    for (const auto& tri : f) {
      const uint32_t a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]),
                     c = midpoint(tri[2], tri[0]);
      next.push_back({tri[0], a, c});
      next.push_back({tri[1], b, a});
      next.push_back({tri[2], c, b});
      next.push_back({a, b, c});
    }
    f = next;
  }
  std::vector<Float3> v;
  for (const auto& q : p)
    v.push_back(center +
                Rotate(axes, Float3{float(q[0] * r.x), float(q[1] * r.y), float(q[2] * r.z)}));
  Obb obb;
  obb.center = center;
  for (int k = 0; k < 3; ++k) obb.axes[k] = axes[k];
  obb.half_extents = r;
  return MakeHull(v, f, obb);
}

inline void RotatedAxes(double angle_deg, Float3 axis, Float3 out[3]) {
  const double a = angle_deg * kPi / 180.0;
  const double l =
      std::sqrt(double(axis.x) * axis.x + double(axis.y) * axis.y + double(axis.z) * axis.z);
  const double x = axis.x / l, y = axis.y / l, z = axis.z / l, c = std::cos(a), s = std::sin(a);
  const double m[3][3] = {{c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s},
                          {y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s},
                          {z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)}};
  for (int k = 0; k < 3; ++k) out[k] = {float(m[0][k]), float(m[1][k]), float(m[2][k])};
}

// Rigid matrix rotating by angle about `axis` through `pivot`.
inline Mat34 RotationAbout(double angle_deg, Float3 axis, Float3 pivot) {
  Float3 cols[3];
  RotatedAxes(angle_deg, axis, cols);
  Mat34 m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m.m[4 * r + c] = (&cols[c].x)[r];
  const Float3 rp = TransformVector(m, pivot);
  m.m[3] = pivot.x - rp.x;
  m.m[7] = pivot.y - rp.y;
  m.m[11] = pivot.z - rp.z;
  return m;
}

inline float MaxPlane(const HullColliderData& h, Float3 p) {
  float m = -std::numeric_limits<float>::infinity();
  for (const Plane& pl : h.planes) m = std::max(m, PlaneSignedDistance(pl, p));
  return m;
}

inline Float3 RandomIn(std::mt19937& rng, Float3 lo, Float3 hi) {
  std::uniform_real_distribution<float> u(0.f, 1.f);
  return {lo.x + (hi.x - lo.x) * u(rng), lo.y + (hi.y - lo.y) * u(rng),
          lo.z + (hi.z - lo.z) * u(rng)};
}

}  // namespace drape::test

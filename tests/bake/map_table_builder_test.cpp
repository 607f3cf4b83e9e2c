// Tests of the map sphere / map cylinder builder (bake/map_table_builder.h) and of the runtime's
// map-table ray response on its tables. The hulls are hand-made (ellipsoids tessellated from an
// icosphere, boxes); no CGAL.

#include "drape/bake/map_table_builder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "drape/runtime/hull_collider.h"
#include "drape/runtime/math.h"

namespace drape::bake {
namespace {

constexpr double kPi = 3.14159265358979323846;

// ---- Hand-made convex hulls -------------------------------------------------------------------

// Orients every face outward (against the vertex centroid), merges exactly coplanar faces into one
// plane and rounds each offset outward: every vertex is inside in the runtime's arithmetic.
HullColliderData MakeHull(const std::vector<Float3>& vertices,
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

Float3 Rotate(const Float3 axes[3], Float3 local) {
  return axes[0] * local.x + axes[1] * local.y + axes[2] * local.z;
}

// Box with half extents he, rotated to `axes`, centred at `center` (collider frame).
HullColliderData MakeBox(Float3 he, Float3 center = {}, const Float3* axes = nullptr) {
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
HullColliderData MakeEllipsoid(Float3 r, int levels, Float3 center, const Float3 axes[3]) {
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

void RotatedAxes(double angle_deg, Float3 axis, Float3 out[3]) {
  const double a = angle_deg * kPi / 180.0;
  const double l =
      std::sqrt(double(axis.x) * axis.x + double(axis.y) * axis.y + double(axis.z) * axis.z);
  const double x = axis.x / l, y = axis.y / l, z = axis.z / l, c = std::cos(a), s = std::sin(a);
  const double m[3][3] = {{c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s},
                          {y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s},
                          {z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)}};
  for (int k = 0; k < 3; ++k) out[k] = {float(m[0][k]), float(m[1][k]), float(m[2][k])};
}

float MaxPlane(const HullColliderData& h, Float3 p) {
  float m = -std::numeric_limits<float>::infinity();
  for (const Plane& pl : h.planes) m = std::max(m, PlaneSignedDistance(pl, p));
  return m;
}

struct NamedHull {
  std::string name;
  HullColliderData hull;
  MapTableKind expected;
};

std::vector<NamedHull> TestHulls() {
  Float3 tilted[3], tilted2[3];
  RotatedAxes(37.0, {1.f, 2.f, 3.f}, tilted);
  RotatedAxes(-58.0, {0.3f, -1.f, 0.2f}, tilted2);
  std::vector<NamedHull> hulls;
  hulls.push_back({"round", MakeEllipsoid({0.1f, 0.09f, 0.08f}, 2, {0.2f, 1.1f, -0.1f}, tilted),
                   MapTableKind::kSphere});
  hulls.push_back({"limb", MakeEllipsoid({0.035f, 0.2f, 0.045f}, 2, {-0.05f, 0.3f, 0.02f}, tilted2),
                   MapTableKind::kCylinder});
  hulls.push_back({"box", MakeBox({0.04f, 0.15f, 0.06f}, {0.1f, -0.3f, 0.7f}, tilted),
                   MapTableKind::kCylinder});
  hulls.push_back({"cube", MakeBox({0.05f, 0.05f, 0.05f}), MapTableKind::kSphere});
  return hulls;
}

// Ray S + t d (t > 0) against a triangle in double (Moller-Trumbore); edges count as hits with a
// relative tolerance of 1e-9 so a ray through a shared edge or vertex hits both neighbours.
bool RayHit(const double s[3], const double d[3], const Float3& a, const Float3& b, const Float3& c,
            double* t) {
  const double e1[3] = {double(b.x) - a.x, double(b.y) - a.y, double(b.z) - a.z};
  const double e2[3] = {double(c.x) - a.x, double(c.y) - a.y, double(c.z) - a.z};
  const double p[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2],
                       d[0] * e2[1] - d[1] * e2[0]};
  const double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
  if (std::fabs(det) < 1e-300) return false;
  const double inv = 1.0 / det;
  const double tv[3] = {s[0] - a.x, s[1] - a.y, s[2] - a.z};
  const double u = (tv[0] * p[0] + tv[1] * p[1] + tv[2] * p[2]) * inv;
  const double q[3] = {tv[1] * e1[2] - tv[2] * e1[1], tv[2] * e1[0] - tv[0] * e1[2],
                       tv[0] * e1[1] - tv[1] * e1[0]};
  const double v = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) * inv;
  const double tol = 1e-9;
  if (u < -tol || v < -tol || u + v > 1.0 + tol) return false;
  *t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) * inv;
  return *t > 0.0;
}

// Nearest hit over the listed triangles and over all triangles; false if the list has none.
bool CellRay(const HullColliderData& h, uint32_t cell, const double s[3], const double d[3],
             double* t_list, double* t_all) {
  *t_list = *t_all = std::numeric_limits<double>::infinity();
  for (uint32_t t = 0; t < h.triangles.size() / 3; ++t) {
    double hit;
    if (RayHit(s, d, h.vertices[h.triangles[3 * t]], h.vertices[h.triangles[3 * t + 1]],
               h.vertices[h.triangles[3 * t + 2]], &hit))
      *t_all = std::min(*t_all, hit);
  }
  for (uint32_t e = h.map.cell_offsets[cell]; e < h.map.cell_offsets[cell + 1]; ++e) {
    const uint32_t t = h.map.cell_triangles[e];
    double hit;
    if (RayHit(s, d, h.vertices[h.triangles[3 * t]], h.vertices[h.triangles[3 * t + 1]],
               h.vertices[h.triangles[3 * t + 2]], &hit))
      *t_list = std::min(*t_list, hit);
  }
  return *t_list < std::numeric_limits<double>::infinity();
}

TEST(MapTableBuilderTest, KindFollowsElongationAndOptions) {
  for (const NamedHull& named : TestHulls()) {
    HullColliderData h = named.hull;
    MapTableStats stats;
    const Status s = BuildMapTable(&h, MapTableOptions{}, &stats);
    ASSERT_TRUE(s.ok()) << named.name << ": " << s.message();
    EXPECT_EQ(h.map.kind, named.expected) << named.name;
    EXPECT_EQ(stats.kind, named.expected);
    EXPECT_EQ(h.map.cell_offsets.size(), size_t(h.map.rows) * h.map.cols + 1);
    EXPECT_EQ(stats.empty_cells, 0u) << named.name;
    EXPECT_LT(stats.mean_list, double(h.triangles.size() / 3)) << named.name;
    EXPECT_NEAR(Length(h.map.axis), 1.f, 1e-6f);
    EXPECT_NEAR(Dot(h.map.axis, h.map.reference), 0.f, 1e-6f);
    // The sources are strictly inside.
    EXPECT_LT(MaxPlane(h, h.map.origin), 0.f) << named.name;
    if (h.map.kind == MapTableKind::kCylinder) {
      EXPECT_GT(h.map.length, 0.f);
      EXPECT_LT(MaxPlane(h, h.map.origin + h.map.axis * h.map.length), 0.f) << named.name;
    }
    std::printf(
        "[ stats    ] %-6s %s %ux%u, %zu triangles: mean list %.1f, max %u, source at OBB centre "
        "%d\n",
        named.name.c_str(), h.map.kind == MapTableKind::kSphere ? "sphere  " : "cylinder",
        h.map.rows, h.map.cols, h.triangles.size() / 3, stats.mean_list, stats.max_list,
        int(stats.source_at_obb_center));
  }
  HullColliderData h = TestHulls()[0].hull;
  MapTableOptions o;
  o.kind = MapTableChoice::kCylinder;
  o.cylinder_rows = 5;
  o.cylinder_cols = 7;
  ASSERT_TRUE(BuildMapTable(&h, o).ok());
  EXPECT_EQ(h.map.kind, MapTableKind::kCylinder);
  EXPECT_EQ(h.map.rows, 5u);
  EXPECT_EQ(h.map.cols, 7u);
  o.kind = MapTableChoice::kSphere;
  o.sphere_rows = 3;
  o.sphere_cols = 1;
  ASSERT_TRUE(BuildMapTable(&h, o).ok());
  EXPECT_EQ(h.map.kind, MapTableKind::kSphere);
  o = MapTableOptions{};
  o.cylinder_elongation = 1.f;  // everything is elongated enough
  ASSERT_TRUE(BuildMapTable(&h, o).ok());
  EXPECT_EQ(h.map.kind, MapTableKind::kCylinder);
  // Bad options and input.
  o = MapTableOptions{};
  o.sphere_rows = 0;
  EXPECT_FALSE(BuildMapTable(&h, o).ok());
  EXPECT_TRUE(h.map.cell_offsets.empty());
  o = MapTableOptions{};
  o.margin_fraction = -1.f;
  EXPECT_FALSE(BuildMapTable(&h, o).ok());
  HullColliderData flat = h;
  for (Plane& p : flat.planes) p.offset = -1.f;  // no point is inside every plane
  EXPECT_FALSE(BuildMapTable(&flat).ok());
  HullColliderData broken = h;
  broken.triangles[0] = 100000;
  EXPECT_FALSE(BuildMapTable(&broken).ok());
}

TEST(MapTableBuilderTest, EveryCellRayHitsAListedTriangle) {
  // Rays through each cell's centre, corners and edge midpoints (and, for the cylinder's end rows,
  // the end sources' rays at elevations up to the axis) find their first hull hit among the
  // triangles the cell lists.
  for (const NamedHull& named : TestHulls()) {
    for (const uint32_t resolution : {8u, 24u}) {
      HullColliderData h = named.hull;
      MapTableOptions o;
      o.sphere_rows = o.cylinder_rows = resolution;
      o.sphere_cols = o.cylinder_cols = 2 * resolution;
      ASSERT_TRUE(BuildMapTable(&h, o).ok());
      const MapTableData& m = h.map;
      const double axis[3] = {m.axis.x, m.axis.y, m.axis.z},
                   ref[3] = {m.reference.x, m.reference.y, m.reference.z};
      const double bin[3] = {axis[1] * ref[2] - axis[2] * ref[1],
                             axis[2] * ref[0] - axis[0] * ref[2],
                             axis[0] * ref[1] - axis[1] * ref[0]};
      uint32_t rays = 0, misses = 0, not_first = 0;
      for (uint32_t row = 0; row < m.rows; ++row)
        for (uint32_t col = 0; col < m.cols; ++col) {
          const uint32_t cell = row * m.cols + col;
          for (int a = 0; a <= 2; ++a)
            for (int b = 0; b <= 2; ++b) {
              const double phi = 2.0 * kPi * (col + 0.5 * b) / m.cols;
              std::vector<std::array<double, 6>> tests;  // source, direction
              if (m.kind == MapTableKind::kSphere) {
                const double theta = kPi * (row + 0.5 * a) / m.rows;
                std::array<double, 6> r{};
                for (int k = 0; k < 3; ++k) {
                  r[k] = (&m.origin.x)[k];
                  r[3 + k] = std::cos(theta) * axis[k] +
                             std::sin(theta) * (std::cos(phi) * ref[k] + std::sin(phi) * bin[k]);
                }
                tests.push_back(r);
              } else {
                const double z = m.length * (row + 0.5 * a) / m.rows;
                std::array<double, 6> r{};
                for (int k = 0; k < 3; ++k) {
                  r[k] = (&m.origin.x)[k] + z * axis[k];
                  r[3 + k] = std::cos(phi) * ref[k] + std::sin(phi) * bin[k];
                }
                tests.push_back(r);
                // End rows: rays from the end sources tilted towards the axis.
                const bool first = row == 0 && a == 0, last = row + 1 == m.rows && a == 2;
                if (first || last) {
                  for (double elevation : {0.3, 0.8, 1.3, 1.5707963}) {
                    std::array<double, 6> e = r;
                    const double sign = first ? -1.0 : 1.0;
                    for (int k = 0; k < 3; ++k)
                      e[3 + k] =
                          std::cos(elevation) * r[3 + k] + sign * std::sin(elevation) * axis[k];
                    tests.push_back(e);
                  }
                }
              }
              for (const auto& r : tests) {
                double t_list, t_all;
                ++rays;
                if (!CellRay(h, cell, &r[0], &r[3], &t_list, &t_all)) {
                  ++misses;
                  continue;
                }
                if (std::fabs(t_list - t_all) > 1e-9 * (1.0 + t_all)) ++not_first;
              }
            }
        }
      EXPECT_EQ(misses, 0u) << named.name << " at " << resolution;
      EXPECT_EQ(not_first, 0u) << named.name << " at " << resolution;
      EXPECT_GT(rays, 9u * m.rows * m.cols - 1u);
    }
  }
}

TEST(MapTableBuilderTest, RuntimeRayResponseNeverFallsBackFromInside) {
  for (const NamedHull& named : TestHulls()) {
    HullColliderData h = named.hull;
    ASSERT_TRUE(BuildMapTable(&h).ok());
    HullColliderOptions options;
    options.response = HullResponse::kMapTableRay;
    HullColliderSet set;
    ASSERT_TRUE(set.Build(std::vector<HullColliderData>{h}, {}, 1, options).ok());
    std::mt19937 rng(21);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    uint32_t inside = 0, fallbacks = 0;
    double excess = 0.0;
    for (int i = 0; i < 200000; ++i) {
      Float3 p = h.obb.center + h.obb.axes[0] * (u(rng) * h.obb.half_extents.x) +
                 h.obb.axes[1] * (u(rng) * h.obb.half_extents.y) +
                 h.obb.axes[2] * (u(rng) * h.obb.half_extents.z);
      if (MaxPlane(h, p) > 0.f) continue;
      ++inside;
      const ContactQuery c = set.QueryHullLocal(0, p, p);
      ASSERT_TRUE(c.contact);
      if (c.flags & kCollisionFallback) {
        ++fallbacks;
        continue;
      }
      // On the surface (on or just outside, within rounding of the hit) ...
      const float m = MaxPlane(h, c.point);
      EXPECT_GE(m, 0.f);
      EXPECT_LE(m, 2e-6f) << named.name;
      // ... along the ray from the source through p, beyond p.
      Float3 source = h.map.origin;
      if (h.map.kind == MapTableKind::kCylinder) {
        const float z = std::min(std::max(Dot(p - h.map.origin, h.map.axis), 0.f), h.map.length);
        source = h.map.origin + h.map.axis * z;
      }
      const Float3 d = p - source, e = c.point - source;
      EXPECT_LE(Length(Cross(d, e)), 2e-6f * Length(e) + 1e-9f) << named.name;
      EXPECT_GE(Dot(d, e), Dot(d, d) * (1.f - 1e-5f)) << named.name;
      // The ray response moves at least as far as the minimal push-out.
      excess += double(Length(c.point - p)) - double(-MaxPlane(h, p));
    }
    EXPECT_GT(inside, 10000u);
    EXPECT_EQ(fallbacks, 0u) << named.name;
    std::printf(
        "[ stats    ] %-6s %u interior points: %u fallbacks, mean overshoot vs push-out %.2f mm\n",
        named.name.c_str(), inside, fallbacks, 1e3 * excess / inside);
  }
}

TEST(MapTableBuilderTest, BuildIsDeterministic) {
  for (const NamedHull& named : TestHulls()) {
    HullColliderData a = named.hull, b = named.hull;
    ASSERT_TRUE(BuildMapTable(&a).ok());
    ASSERT_TRUE(BuildMapTable(&b).ok());
    EXPECT_EQ(a.map.cell_offsets, b.map.cell_offsets);
    EXPECT_EQ(a.map.cell_triangles, b.map.cell_triangles);
    EXPECT_EQ(std::memcmp(&a.map.origin, &b.map.origin, sizeof(Float3)), 0);
  }
}

TEST(MapTableBuilderTest, LargeHullAndFineTableBuildQuickly) {
  Float3 axes[3];
  RotatedAxes(21.0, {0.2f, 1.f, -0.7f}, axes);
  HullColliderData h =
      MakeEllipsoid({0.06f, 0.25f, 0.08f}, 3, {0.f, 0.4f, 0.f}, axes);  // 1280 faces
  MapTableOptions o;
  o.cylinder_rows = 64;
  o.cylinder_cols = 64;
  MapTableStats stats;
  const auto start = std::chrono::steady_clock::now();
  ASSERT_TRUE(BuildMapTable(&h, o, &stats).ok());
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(stats.kind, MapTableKind::kCylinder);
  EXPECT_EQ(stats.empty_cells, 0u);
  std::printf("[ stats    ] 1280 faces, 64x64 cylinder: %.1f ms, mean list %.1f, max %u\n", ms,
              stats.mean_list, stats.max_list);
}

}  // namespace
}  // namespace drape::bake

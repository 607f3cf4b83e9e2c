// Tests of the map sphere / map cylinder builder (bake/map_table_builder.h) and of the runtime's
// map-table ray response on its tables. The hulls are hand-made (ellipsoids tessellated from an
// icosphere, boxes); no CGAL.

#include "drape/bake/map_table_builder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"
#include "hull/hull_collider_set_access.h"
#include "hull_fixtures.h"

namespace drape::bake {
namespace {

// Hand-made hulls and helpers shared with the other hull tests (tests/support/hull_fixtures.h).
using test::kPi;
using test::MakeBox;
using test::MakeEllipsoid;
using test::MaxPlane;
using test::RotatedAxes;

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
      const ContactQuery c = HullColliderSetAccess::QueryHullLocal(set, 0, p, p);
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
    EXPECT_EQ(fallbacks, 0u) << named.name << ": " << inside
                             << " interior points, mean overshoot vs push-out "
                             << 1e3 * excess / inside << " mm";
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

// bench_hull_bake's BM_MapTableBuild times this build.
TEST(MapTableBuilderTest, LargeHullAndFineTableLeaveNoCellEmpty) {
  Float3 axes[3];
  RotatedAxes(21.0, {0.2f, 1.f, -0.7f}, axes);
  HullColliderData h =
      MakeEllipsoid({0.06f, 0.25f, 0.08f}, 3, {0.f, 0.4f, 0.f}, axes);  // 1280 faces
  MapTableOptions o;
  o.cylinder_rows = 64;
  o.cylinder_cols = 64;
  MapTableStats stats;
  ASSERT_TRUE(BuildMapTable(&h, o, &stats).ok());
  EXPECT_EQ(stats.kind, MapTableKind::kCylinder);
  EXPECT_EQ(stats.empty_cells, 0u) << "mean list " << stats.mean_list << ", max " << stats.max_list;
}

}  // namespace
}  // namespace drape::bake

// Tests of the Kirkpatrick point-location builder (bake/kirkpatrick_builder.h) and of the
// runtime's Kirkpatrick inside test against the plane test. The hulls are hand-made convex
// polytopes (box, octahedron, tessellated ellipsoids: every vertex of a tessellated ellipsoid is
// on its convex hull, so every face is a hull face); no CGAL.

#include "drape/bake/kirkpatrick_builder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "drape/runtime/exact_orientation.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"
#include "hull/hull_collider_set_access.h"
#include "hull_fixtures.h"

namespace drape::bake {
namespace {

// Hand-made hulls and helpers shared with the other hull tests (tests/support/hull_fixtures.h).
using test::MakeBox;
using test::MakeEllipsoid;
using test::MakeHull;
using test::Rotate;
using test::RotatedAxes;

HullColliderData MakeOctahedron(Float3 r, Float3 center, const Float3 axes[3]) {
  std::vector<Float3> v;
  for (int k = 0; k < 3; ++k)
    for (float s : {1.f, -1.f}) {
      Float3 local{0, 0, 0};
      (&local.x)[k] = s * (&r.x)[k];
      v.push_back(center + Rotate(axes, local));
    }
  // vertices: 0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z
  std::vector<std::array<uint32_t, 3>> f;
  for (uint32_t x : {0u, 1u})
    for (uint32_t y : {2u, 3u})
      for (uint32_t z : {4u, 5u}) f.push_back({x, y, z});
  Obb obb;
  obb.center = center;
  for (int k = 0; k < 3; ++k) obb.axes[k] = axes[k];
  obb.half_extents = r;
  return MakeHull(v, f, obb);
}

float HullSize(const HullColliderData& h) {
  return std::max({h.obb.half_extents.x, h.obb.half_extents.y, h.obb.half_extents.z});
}

struct NamedHull {
  std::string name;
  HullColliderData hull;
};

std::vector<NamedHull> TestHulls() {
  const Float3 identity[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  Float3 tilted[3], tilted2[3];
  RotatedAxes(37.0, {1.f, 2.f, 3.f}, tilted);
  RotatedAxes(-58.0, {0.3f, -1.f, 0.2f}, tilted2);
  std::vector<NamedHull> hulls;
  hulls.push_back({"box", MakeBox({0.1f, 0.2f, 0.05f})});
  hulls.push_back({"rotated_box", MakeBox({0.04f, 0.15f, 0.06f}, {0.1f, -0.3f, 0.7f}, tilted)});
  hulls.push_back({"octahedron", MakeOctahedron({0.1f, 0.07f, 0.12f}, {0.f, 0.f, 0.f}, identity)});
  hulls.push_back(
      {"ellipsoid", MakeEllipsoid({0.08f, 0.06f, 0.1f}, 2, {0.2f, 1.1f, -0.1f}, tilted)});
  hulls.push_back(
      {"limb", MakeEllipsoid({0.035f, 0.2f, 0.045f}, 2, {-0.05f, 0.3f, 0.02f}, tilted2)});
  return hulls;
}

KirkpatrickOptions AxisOptions(ProjectionAxis axis) {
  KirkpatrickOptions o;
  o.axis = axis;
  return o;
}

// Structural invariants of one flat hierarchy.
void ExpectWellFormed(const KirkpatrickHierarchy& k, size_t planes, const std::string& what) {
  const uint32_t nodes = k.node_count();
  ASSERT_GT(nodes, 0u) << what;
  ASSERT_EQ(k.child_offsets.size(), nodes + 1) << what;
  ASSERT_EQ(k.leaf_planes.size(), nodes) << what;
  EXPECT_EQ(k.root_end, nodes) << what;
  EXPECT_EQ(k.root_begin + 1, k.root_end) << what;
  uint32_t leaves_on_planes = 0;
  for (uint32_t n = 0; n < nodes; ++n) {
    for (uint32_t e = k.child_offsets[n]; e < k.child_offsets[n + 1]; ++e)
      ASSERT_LT(k.children[e], n) << what;
    const bool leaf = k.child_offsets[n] == k.child_offsets[n + 1];
    if (!leaf) {
      EXPECT_EQ(k.leaf_planes[n], -1) << what;
    }
    if (leaf && k.leaf_planes[n] >= 0) ++leaves_on_planes;
    EXPECT_LT(k.leaf_planes[n], static_cast<int32_t>(planes)) << what;
    // Kirkpatrick: a node covers at most the hole of one removed vertex.
    EXPECT_LE(k.child_offsets[n + 1] - k.child_offsets[n], 12u) << what;
  }
  EXPECT_GT(leaves_on_planes, 0u) << what;
}

// The exact orientation every topological decision uses (and the runtime's validation at load):
// its floating-point filter must never decide a sign the exact sum would not. Points on a grid of
// 2^-10 with integer coordinates below 2^21 have an integer determinant in 2^-20 units (the
// points lie within 4 200 steps of each other: computed exactly in 64 bits); a third point on the
// line through the first two, or one grid step off it, leaves the collinear ones to the exact sum.
// Where the double arithmetic rounds (magnitudes 60 orders apart), the signs are checked by hand.
TEST(KirkpatrickBuilderTest, ExactOrientationMatchesIntegerArithmetic) {
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int64_t> coord(-(int64_t{1} << 20), int64_t{1} << 20);
  std::uniform_int_distribution<int64_t> step(-64, 64), nudge(-1, 1);
  const auto grid = [](int64_t k) { return static_cast<float>(std::ldexp(double(k), -10)); };
  int collinear = 0;
  for (int trial = 0; trial < 200000; ++trial) {
    const int64_t ax = coord(rng), ay = coord(rng);
    const int64_t dx = step(rng), dy = step(rng);
    const int64_t t = step(rng);
    // b = a + d and c = a + t d, c nudged by a grid step in some trials.
    const int64_t bx = ax + dx, by = ay + dy;
    const int64_t cx = ax + t * dx + (trial % 2 == 0 ? nudge(rng) : 0);
    const int64_t cy = ay + t * dy + (trial % 3 == 0 ? nudge(rng) : 0);
    const int64_t det = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);  // |.| < 2^20: exact
    const int expected = det > 0 ? 1 : (det < 0 ? -1 : 0);
    collinear += expected == 0;
    ASSERT_EQ(Orient2dExact(grid(ax), grid(ay), grid(bx), grid(by), grid(cx), grid(cy)), expected)
        << "a (" << ax << ", " << ay << ") b (" << bx << ", " << by << ") c (" << cx << ", " << cy
        << ")";
  }
  EXPECT_GT(collinear, 10000);  // the exact path is exercised, not only the filter
  // Magnitudes far apart: the differences and their products round, the sign must not (the
  // third case is collinear in double arithmetic and not in exact arithmetic).
  const float big = 1e30f, tiny = 1e-30f;
  EXPECT_EQ(Orient2dExact(0.f, 0.f, big, 0.f, big, tiny), 1);
  EXPECT_EQ(Orient2dExact(0.f, 0.f, big, 0.f, big, -tiny), -1);
  EXPECT_EQ(Orient2dExact(-big, -big, big, big, 1.f, std::nextafter(1.f, 2.f)), 1);
  EXPECT_EQ(Orient2dExact(-big, -big, big, big, 1.f, 1.f), 0);
  EXPECT_EQ(Orient2dExact(tiny, 0.f, 0.f, tiny, 0.f, 0.f), 1);
}

TEST(KirkpatrickBuilderTest, PlanarHierarchyLocatesEveryPointOfAJitteredGrid) {
  // A 9 x 9 jittered grid over the unit square, two triangles per cell, labelled by index.
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> jitter(-0.03f, 0.03f);
  const int n = 9;
  std::vector<float> uv;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const bool border = i == 0 || j == 0 || i == n - 1 || j == n - 1;
      uv.push_back(float(i) / float(n - 1) + (border ? 0.f : jitter(rng)));
      uv.push_back(float(j) / float(n - 1) + (border ? 0.f : jitter(rng)));
    }
  std::vector<uint32_t> tris;
  std::vector<int32_t> labels;
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const uint32_t a = uint32_t(j * n + i), b = a + 1, c = a + uint32_t(n), d = c + 1;
      tris.insert(tris.end(), {a, b, d, a, d, c});
      labels.push_back(int32_t(labels.size()));
      labels.push_back(int32_t(labels.size()));
    }
  KirkpatrickHierarchy k;
  KirkpatrickSideStats stats;
  const Status s = BuildPlanarHierarchy(uv, tris, labels, KirkpatrickOptions{}, &k, &stats);
  ASSERT_TRUE(s.ok()) << s.message();
  ExpectWellFormed(k, labels.size(), "grid");
  EXPECT_EQ(stats.faces, tris.size() / 3);
  EXPECT_EQ(stats.boundary_vertices, uint32_t(4 * (n - 1)));
  EXPECT_EQ(stats.fill_triangles, stats.boundary_vertices + 3);
  EXPECT_GE(stats.levels, 3u);
  EXPECT_LE(stats.levels, 40u);
  // Every original vertex plus the three corners.
  EXPECT_EQ(k.vertices_uv.size(), 2u * (n * n + 3));
  // Walk (double, no ties for random points) and compare with brute force over the leaves.
  auto point = [&](uint32_t v) {
    return std::array<double, 2>{k.vertices_uv[2 * v], k.vertices_uv[2 * v + 1]};
  };
  auto inside = [&](uint32_t node, double u, double v) {
    const uint32_t* t = &k.node_triangles[3 * node];
    for (int e = 0; e < 3; ++e) {
      const auto a = point(t[e]), b = point(t[(e + 1) % 3]);
      if ((b[0] - a[0]) * (v - a[1]) - (b[1] - a[1]) * (u - a[0]) < 0) return false;
    }
    return true;
  };
  std::uniform_real_distribution<double> q(-0.5, 1.5);
  for (int trial = 0; trial < 20000; ++trial) {
    const double u = q(rng), v = q(rng);
    uint32_t node = k.root_begin;
    ASSERT_TRUE(inside(node, u, v));
    while (k.child_offsets[node + 1] > k.child_offsets[node]) {
      uint32_t next = UINT32_MAX;
      for (uint32_t e = k.child_offsets[node]; e < k.child_offsets[node + 1]; ++e)
        if (inside(k.children[e], u, v)) {
          next = k.children[e];
          break;
        }
      ASSERT_NE(next, UINT32_MAX) << "no child contains (" << u << ", " << v << ")";
      node = next;
    }
    const bool in_square = u > 0 && u < 1 && v > 0 && v < 1;
    if (!in_square) {
      EXPECT_EQ(k.leaf_planes[node], -1);
      continue;
    }
    ASSERT_GE(k.leaf_planes[node], 0);
    // The located leaf is the one face containing the point.
    int32_t brute = -1;
    for (size_t t = 0; t < tris.size() / 3; ++t) {
      bool all = true;
      for (int e = 0; e < 3 && all; ++e) {
        const uint32_t a = tris[3 * t + e], b = tris[3 * t + (e + 1) % 3];
        const double au = uv[2 * a], av = uv[2 * a + 1], bu = uv[2 * b], bv = uv[2 * b + 1];
        all = (bu - au) * (v - av) - (bv - av) * (u - au) >= 0;
      }
      if (all) brute = labels[t];
    }
    EXPECT_EQ(k.leaf_planes[node], brute);
  }
}

TEST(KirkpatrickBuilderTest, RejectsBadInput) {
  HullColliderData box = MakeBox({0.1f, 0.1f, 0.1f});
  HullColliderData h = box;
  h.triangles[5] = 99;
  EXPECT_FALSE(BuildKirkpatrick(&h).ok());
  EXPECT_TRUE(h.upper.node_triangles.empty());
  h = box;
  h.triangles.resize(h.triangles.size() - 3);  // open mesh
  h.triangle_planes.pop_back();
  const Status open = BuildKirkpatrick(&h);
  EXPECT_FALSE(open.ok());
  EXPECT_NE(open.message().find("not closed"), std::string::npos) << open.message();
  h = box;
  std::swap(h.triangles[0], h.triangles[1]);  // one face flipped
  EXPECT_FALSE(BuildKirkpatrick(&h).ok());
  h = box;
  h.obb.axes[0] = {0.f, 1.f, 0.f};
  EXPECT_FALSE(BuildKirkpatrick(&h).ok());
  KirkpatrickOptions o;
  o.max_removal_degree = 2;
  h = box;
  EXPECT_FALSE(BuildKirkpatrick(&h, o).ok());
  // Planar: a clockwise triangle, and a region with a hole (two boundary cycles).
  KirkpatrickHierarchy k;
  const std::vector<float> uv = {0, 0, 1, 0, 0, 1};
  EXPECT_FALSE(
      BuildPlanarHierarchy(uv, std::vector<uint32_t>{0, 2, 1}, std::vector<int32_t>{0}, {}, &k)
          .ok());
  EXPECT_TRUE(
      BuildPlanarHierarchy(uv, std::vector<uint32_t>{0, 1, 2}, std::vector<int32_t>{0}, {}, &k)
          .ok());
  // Two triangles touching at a vertex: the boundary touches itself.
  const std::vector<float> bow = {0, 0, 1, 0, 0, 1, -1, 0, 0, -1};
  EXPECT_FALSE(BuildPlanarHierarchy(bow, std::vector<uint32_t>{0, 1, 2, 0, 3, 4},
                                    std::vector<int32_t>{0, 1}, {}, &k)
                   .ok());
}

TEST(KirkpatrickBuilderTest, EveryAxisChoiceBuildsValidHierarchiesAndAutoMeasuresBest) {
  for (const NamedHull& named : TestHulls()) {
    for (ProjectionAxis axis :
         {ProjectionAxis::kAuto, ProjectionAxis::kLongest, ProjectionAxis::kShortest}) {
      HullColliderData h = named.hull;
      KirkpatrickStats stats;
      const Status s = BuildKirkpatrick(&h, AxisOptions(axis), &stats);
      ASSERT_TRUE(s.ok()) << named.name << ": " << s.message();
      EXPECT_FALSE(stats.axis_fallback) << named.name;
      ExpectWellFormed(h.upper, h.planes.size(), named.name + " upper");
      ExpectWellFormed(h.lower, h.planes.size(), named.name + " lower");
      EXPECT_NEAR(Length(Cross(h.projection_u, h.projection_v) - h.projection_axis), 0.f, 1e-5f);
      // Every hull triangle is a leaf of exactly one side, or (near) vertical.
      const uint32_t faces = stats.upper.faces + stats.lower.faces;
      EXPECT_LE(faces, h.triangles.size() / 3);
      const float hx = h.obb.half_extents.x, hy = h.obb.half_extents.y, hz = h.obb.half_extents.z;
      const float he[3] = {hx, hy, hz};
      if (axis == ProjectionAxis::kLongest) {
        EXPECT_EQ(he[stats.axis_index], std::max({hx, hy, hz})) << named.name;
      }
      if (axis == ProjectionAxis::kShortest) {
        EXPECT_EQ(he[stats.axis_index], std::min({hx, hy, hz})) << named.name;
      }
      if (axis == ProjectionAxis::kAuto) {
        for (double other : stats.axis_mean_tests) {
          ASSERT_GE(other, 0.0) << named.name;
          EXPECT_LE(stats.mean_tests, other)
              << named.name << ": auto axis " << stats.axis_index << ", mean node tests per axis "
              << stats.axis_mean_tests[0] << ", " << stats.axis_mean_tests[1] << ", "
              << stats.axis_mean_tests[2];
        }
      }
      // The runtime accepts it.
      HullColliderSet set;
      HullColliderOptions options;
      options.inside_test = InsideTest::kKirkpatrick;
      const Status b = set.Build(std::vector<HullColliderData>{h}, {}, 1, options);
      EXPECT_TRUE(b.ok()) << named.name << ": " << b.message();
    }
  }
}

TEST(KirkpatrickBuilderTest, BuildIsDeterministic) {
  for (const NamedHull& named : TestHulls()) {
    HullColliderData a = named.hull, b = named.hull;
    ASSERT_TRUE(BuildKirkpatrick(&a).ok());
    ASSERT_TRUE(BuildKirkpatrick(&b).ok());
    EXPECT_EQ(a.upper.vertices_uv, b.upper.vertices_uv);
    EXPECT_EQ(a.upper.node_triangles, b.upper.node_triangles);
    EXPECT_EQ(a.upper.children, b.upper.children);
    EXPECT_EQ(a.lower.node_triangles, b.lower.node_triangles);
    EXPECT_EQ(a.lower.leaf_planes, b.lower.leaf_planes);
    // The stored (u, v) of a hull vertex is the runtime's projection of it, bit for bit.
    const HullUv q = ProjectHullUv(a.vertices[0], a.obb.center, a.projection_u, a.projection_v);
    bool found = false;
    for (const KirkpatrickHierarchy* k : {&a.upper, &a.lower})
      for (size_t v = 0; v + 1 < k->vertices_uv.size(); v += 2)
        found = found || (k->vertices_uv[v] == q.u && k->vertices_uv[v + 1] == q.v);
    EXPECT_TRUE(found) << named.name;
  }
}

// Points per hull: uniform in the grown OBB, near the surface (offsets along a face normal with
// log-uniform magnitude 1e-7 .. 1e-2 of the hull size, both signs), on faces, on edges, and the
// vertices themselves.
struct Sample {
  Float3 p;
  int kind;  // 0 uniform, 1 near, 2 on face, 3 on edge, 4 vertex
};
std::vector<Sample> AgreementSamples(const HullColliderData& h, size_t count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  const float size = HullSize(h);
  std::vector<Sample> out;
  out.reserve(count + h.vertices.size());
  for (const Float3& v : h.vertices) out.push_back({v, 4});
  const size_t tri_count = h.triangles.size() / 3;
  while (out.size() < count) {
    const int kind = static_cast<int>(rng() % 10);
    const uint32_t t = static_cast<uint32_t>(rng() % tri_count);
    const Float3 a = h.vertices[h.triangles[3 * t]], b = h.vertices[h.triangles[3 * t + 1]],
                 c = h.vertices[h.triangles[3 * t + 2]];
    float r1 = unit(rng), r2 = unit(rng);
    if (r1 + r2 > 1.f) r1 = 1.f - r1, r2 = 1.f - r2;
    const Float3 on_face = a + (b - a) * r1 + (c - a) * r2;
    if (kind < 4) {
      Float3 p = h.obb.center;
      const float he[3] = {h.obb.half_extents.x, h.obb.half_extents.y, h.obb.half_extents.z};
      for (int k = 0; k < 3; ++k) p = p + h.obb.axes[k] * ((2.f * unit(rng) - 1.f) * 1.2f * he[k]);
      out.push_back({p, 0});
    } else if (kind < 8) {
      const float magnitude =
          size * std::pow(10.f, -7.f + 5.f * unit(rng)) * (rng() % 2 ? 1.f : -1.f);
      out.push_back({on_face + h.planes[h.triangle_planes[t]].normal * magnitude, 1});
    } else if (kind == 8) {
      out.push_back({on_face, 2});
    } else {
      out.push_back({a + (b - a) * unit(rng), 3});
    }
  }
  return out;
}

TEST(KirkpatrickBuilderTest, KirkpatrickAndPlaneTestsAgreeOnAMillionPointsPerHull) {
  // Ties: points on the surface count as inside for both tests (plane test: max <= 0; Kirkpatrick:
  // ties in 2D broken towards the interior of the shadow, then the located planes' <= 0). Away
  // from float rounding of the surface the two must agree exactly; within it (|max plane| below
  // a few float ulps of the hull's coordinates) they test different planes of one edge or
  // silhouette, and a disagreement is a rounding tie, counted and bounded.
  for (const NamedHull& named : TestHulls()) {
    HullColliderData h = named.hull;
    ASSERT_TRUE(BuildKirkpatrick(&h).ok()) << named.name;
    HullColliderSet set;
    ASSERT_TRUE(set.Build(std::vector<HullColliderData>{h}, {}, 1).ok());
    const float size = HullSize(h);
    float scale = Length(h.obb.center) + size;
    const float band =
        8.f * std::numeric_limits<float>::epsilon() * scale;  // float rounding of the surface
    const std::vector<Sample> samples = AgreementSamples(h, 1000000, 77);
    uint32_t disagree[5] = {0, 0, 0, 0, 0}, inside_count[5] = {0, 0, 0, 0, 0},
             total[5] = {0, 0, 0, 0, 0};
    uint32_t outside_band = 0;
    for (const Sample& s : samples) {
      const bool planes = HullColliderSetAccess::InsideLocal(set, 0, s.p, InsideTest::kPlanes);
      const bool kirk = HullColliderSetAccess::InsideLocal(set, 0, s.p, InsideTest::kKirkpatrick);
      ++total[s.kind];
      if (planes) ++inside_count[s.kind];
      if (planes != kirk) {
        ++disagree[s.kind];
        if (std::fabs(HullColliderSetAccess::MaxPlaneDistanceLocal(set, 0, s.p)) > band) {
          ++outside_band;
          if (outside_band < 5)
            ADD_FAILURE() << named.name << ": disagreement away from the surface at (" << s.p.x
                          << ", " << s.p.y << ", " << s.p.z << ") kind " << s.kind << " planes "
                          << planes << " max plane "
                          << HullColliderSetAccess::MaxPlaneDistanceLocal(set, 0, s.p);
        }
      }
    }
    SCOPED_TRACE(testing::Message()
                 << samples.size() << " points: disagreements uniform " << disagree[0] << "/"
                 << total[0] << ", near " << disagree[1] << "/" << total[1] << ", face "
                 << disagree[2] << "/" << total[2] << ", edge " << disagree[3] << "/" << total[3]
                 << ", vertex " << disagree[4] << "/" << total[4]);
    EXPECT_EQ(outside_band, 0u) << named.name;
    EXPECT_EQ(disagree[0], 0u) << named.name;
    EXPECT_EQ(disagree[4], 0u) << named.name;  // exact ties on vertices resolve the same way
    EXPECT_EQ(inside_count[4], total[4]) << named.name;  // vertices are inside (on the surface)
    // Measured: 0 of 5 x 10^6 (five hulls). A tie within float rounding of an edge could in
    // principle go either way; allow a handful.
    const uint32_t all = disagree[1] + disagree[2] + disagree[3];
    EXPECT_LE(all, 5u) << named.name << ": rounding ties are rare";
    // Sanity: the sample really straddles the surface.
    EXPECT_GT(inside_count[1], total[1] / 4) << named.name;
    EXPECT_LT(inside_count[1], 3 * total[1] / 4 + total[1] / 8) << named.name;
  }
}

TEST(KirkpatrickBuilderTest, AxisAlignedBoxSurfacePointsAreInsideForBothTests) {
  // Exactly representable surface points: faces (including the vertical faces, which project
  // onto the silhouette), edges and vertices of an axis-aligned box, for every projection axis.
  for (ProjectionAxis axis :
       {ProjectionAxis::kAuto, ProjectionAxis::kLongest, ProjectionAxis::kShortest}) {
    HullColliderData h = MakeBox({0.125f, 0.25f, 0.0625f});
    ASSERT_TRUE(BuildKirkpatrick(&h, AxisOptions(axis)).ok());
    HullColliderSet set;
    ASSERT_TRUE(set.Build(std::vector<HullColliderData>{h}, {}, 1).ok());
    const float he[3] = {0.125f, 0.25f, 0.0625f};
    std::mt19937 rng(3);
    int checked = 0;
    for (int fixed = 0; fixed < 3; ++fixed)
      for (float sign : {-1.f, 1.f})
        for (int i = 0; i <= 8; ++i)
          for (int j = 0; j <= 8; ++j) {
            float c[3];
            c[fixed] = sign * he[fixed];
            c[(fixed + 1) % 3] = he[(fixed + 1) % 3] * (float(i) / 4.f - 1.f);
            c[(fixed + 2) % 3] = he[(fixed + 2) % 3] * (float(j) / 4.f - 1.f);
            const Float3 p{c[0], c[1], c[2]};
            EXPECT_TRUE(HullColliderSetAccess::InsideLocal(set, 0, p, InsideTest::kPlanes));
            EXPECT_TRUE(HullColliderSetAccess::InsideLocal(set, 0, p, InsideTest::kKirkpatrick))
                << p.x << " " << p.y << " " << p.z;
            // Just outside (by 1/1024 of the box): outside for both.
            Float3 q = p;
            (&q.x)[fixed] += sign * 1.f / 1024.f;
            EXPECT_FALSE(HullColliderSetAccess::InsideLocal(set, 0, q, InsideTest::kPlanes));
            EXPECT_FALSE(HullColliderSetAccess::InsideLocal(set, 0, q, InsideTest::kKirkpatrick));
            ++checked;
          }
    EXPECT_EQ(checked, 6 * 81);
  }
}

TEST(KirkpatrickBuilderTest, KirkpatrickModeCollidesLikeThePlaneMode) {
  std::vector<HullColliderData> hulls;
  for (const NamedHull& named : TestHulls()) {
    HullColliderData h = named.hull;
    ASSERT_TRUE(BuildKirkpatrick(&h).ok());
    hulls.push_back(h);
  }
  HullColliderSet planes, kirk;
  HullColliderOptions options;
  ASSERT_TRUE(planes.Build(hulls, {}, 1, options).ok());
  options.inside_test = InsideTest::kKirkpatrick;
  ASSERT_TRUE(kirk.Build(hulls, {}, 1, options).ok());
  // Particles around every hull (its OBB grown by half), moving up to 2 cm.
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> u(-1.5f, 1.5f), d(-0.02f, 0.02f);
  std::vector<Float3> previous, positions, velocities;
  for (const HullColliderData& h : hulls)
    for (int i = 0; i < 20000; ++i) {
      Float3 p = h.obb.center;
      p = p + h.obb.axes[0] * (u(rng) * h.obb.half_extents.x) +
          h.obb.axes[1] * (u(rng) * h.obb.half_extents.y) +
          h.obb.axes[2] * (u(rng) * h.obb.half_extents.z);
      previous.push_back(p);
      positions.push_back(p + Float3{d(rng), d(rng), d(rng)});
      velocities.push_back({0.f, -1.f, 0.f});
    }
  std::vector<Float3> p1 = positions, v1 = velocities, p2 = positions, v2 = velocities;
  std::vector<uint8_t> f1(p1.size()), f2(p1.size());
  uint32_t c1 = 0, c2 = 0;
  ASSERT_TRUE(planes.CollideBatch(previous, p1, v1, f1, ResponseParams{}, 0.f, 1.f, &c1).ok());
  ASSERT_TRUE(kirk.CollideBatch(previous, p2, v2, f2, ResponseParams{}, 0.f, 1.f, &c2).ok());
  EXPECT_GT(c1, 10000u);
  EXPECT_EQ(c1, c2);
  EXPECT_EQ(f1, f2);
  EXPECT_EQ(std::memcmp(p1.data(), p2.data(), p1.size() * sizeof(Float3)), 0);
}

TEST(KirkpatrickBuilderTest, LargeHullBuildsWithLogarithmicDepth) {
  // 1280 faces (icosphere subdivided 3 times; 4096 planes is the runtime's limit): levels grow like
  // log(n), the walk stays short. bench_hull_bake's BM_KirkpatrickBuild times this build.
  Float3 axes[3];
  RotatedAxes(21.0, {0.2f, 1.f, -0.7f}, axes);
  HullColliderData h = MakeEllipsoid({0.06f, 0.25f, 0.08f}, 3, {0.f, 0.4f, 0.f}, axes);
  KirkpatrickStats stats;
  const Status s = BuildKirkpatrick(&h, KirkpatrickOptions{}, &stats);
  ASSERT_TRUE(s.ok()) << s.message();
  ExpectWellFormed(h.upper, h.planes.size(), "large upper");
  ExpectWellFormed(h.lower, h.planes.size(), "large lower");
  EXPECT_LE(stats.upper.levels, 30u) << "lower " << stats.lower.levels;
  EXPECT_LE(stats.mean_tests, 80.0);
  HullColliderSet set;
  const Status built = set.Build(std::vector<HullColliderData>{h}, {}, 1);
  ASSERT_TRUE(built.ok()) << built.message();
  const std::vector<Sample> samples = AgreementSamples(h, 100000, 5);
  uint32_t disagree = 0;
  for (const Sample& p : samples)
    disagree += HullColliderSetAccess::InsideLocal(set, 0, p.p, InsideTest::kPlanes) !=
                HullColliderSetAccess::InsideLocal(set, 0, p.p, InsideTest::kKirkpatrick);
  EXPECT_EQ(disagree, 0u);
}

}  // namespace
}  // namespace drape::bake

// MeshReference against brute force: the hierarchical winding number against ExactMesh (every
// triangle's solid angle) on an icosphere, the mannequin and a shared character; distance and
// closest point against ExactMesh::Distance; crossings against Moller-Trumbore over every
// triangle; degenerate input. The cost of each query and of each winding-number setting is
// bench/gbench/mesh_reference_bench.cpp's.

#include "drape/bake/mesh_reference.h"

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "drape/bake/importer.h"
#include "drape/bake/mesh_queries.h"
#include "reference_meshes.h"
#include "test_support.h"

namespace drape {
namespace {

using bake::ExactMesh;
using bake::MeshReference;
using bake::SurfaceHit;
using bake::WindingNumberOptions;

using test::BoxPoints;
using test::Corner;
using test::LoadRestPose;
using test::MakeIcosphere;
using test::Mesh;
using test::NearSurfacePoints;
using test::Ptr;
using test::ToV3;
using test::V3;

// Moller-Trumbore in double: the segment parameter where p0 + t d crosses triangle abc, or -1.
double SegmentTriangle(V3 p0, V3 d, V3 a, V3 b, V3 c) {
  const V3 e1 = b - a, e2 = c - a;
  const V3 p = d.cross(e2);
  const double det = e1.dot(p);
  if (det == 0.0) return -1.0;
  const double inverse = 1.0 / det;
  const V3 s = p0 - a;
  const double u = s.dot(p) * inverse;
  if (u < 0.0 || u > 1.0) return -1.0;
  const V3 qv = s.cross(e1);
  const double v = d.dot(qv) * inverse;
  if (v < 0.0 || u + v > 1.0) return -1.0;
  const double t = e2.dot(qv) * inverse;
  return (t >= 0.0 && t <= 1.0) ? t : -1.0;
}

// Every (t, triangle) crossing of the segment, by brute force, sorted by t.
std::vector<std::pair<double, uint32_t>> BruteCrossings(const Mesh& m, V3 p0, V3 p1) {
  std::vector<std::pair<double, uint32_t>> hits;
  const V3 d = p1 - p0;
  for (size_t t = 0; t < m.triangles.size() / 3; ++t) {
    const double s = SegmentTriangle(p0, d, Corner(m, t, 0), Corner(m, t, 1), Corner(m, t, 2));
    if (s >= 0.0) hits.emplace_back(s, static_cast<uint32_t>(t));
  }
  std::sort(hits.begin(), hits.end());
  return hits;
}

struct WindingComparison {
  double max_error = 0.0;
  size_t disagreements = 0;        // Inside() differs from the brute force
  size_t clear_disagreements = 0;  // ... where the brute force is farther than 0.1 from 0.5
};

WindingComparison CompareWinding(const MeshReference& fast, const ExactMesh& brute,
                                 const std::vector<V3>& points) {
  WindingComparison result;
  std::vector<double> w_fast(points.size()), w_brute(points.size());
  for (size_t i = 0; i < points.size(); ++i) w_fast[i] = fast.WindingNumber(Ptr(points[i]));
  for (size_t i = 0; i < points.size(); ++i) w_brute[i] = brute.WindingNumber(Ptr(points[i]));
  for (size_t i = 0; i < points.size(); ++i) {
    result.max_error = std::max(result.max_error, std::fabs(w_fast[i] - w_brute[i]));
    if ((w_fast[i] > 0.5) != (w_brute[i] > 0.5)) {
      ++result.disagreements;
      if (std::fabs(w_brute[i] - 0.5) > 0.1) ++result.clear_disagreements;
    }
  }
  return result;
}

// ---------------------------------------------------------------------------------------------
// Winding number

TEST(MeshReference, IcosphereWindingNumberMatchesBruteForce) {
  const Mesh sphere = MakeIcosphere(4, 0.3, {0.1, -0.2, 0.05});  // 5120 triangles
  const MeshReference fast(sphere.positions, sphere.triangles);
  const ExactMesh brute(sphere.positions, sphere.triangles);
  std::vector<V3> points = BoxPoints(sphere, 2000, 11);
  const std::vector<V3> near = NearSurfacePoints(sphere, 2000, 0.02, 12);
  points.insert(points.end(), near.begin(), near.end());
  double max_error = 0.0;
  size_t checked = 0;
  for (const V3& p : points) {
    const double w = fast.WindingNumber(Ptr(p)), reference = brute.WindingNumber(Ptr(p));
    max_error = std::max(max_error, std::fabs(w - reference));
    EXPECT_NEAR(fast.ExactWindingNumber(Ptr(p)), reference, 1e-12);
    if (brute.Distance(Ptr(p)) > 1e-3) {
      ++checked;
      EXPECT_EQ(fast.Inside(Ptr(p)), brute.Inside(Ptr(p)));
      EXPECT_NEAR(reference, brute.Inside(Ptr(p)) ? 1.0 : 0.0, 1e-9) << "closed sphere";
    }
  }
  EXPECT_LE(max_error, 1e-3) << "icosphere (" << fast.triangle_count() << " triangles, "
                             << fast.bvh_node_count() << " BVH nodes), " << points.size()
                             << " points";
  EXPECT_GT(checked, 3000u);
}

// A bumpy open heightfield over an irregular domain: no multipole term vanishes by symmetry.
Mesh MakeBumpyPatch() {
  Mesh mesh;
  const int n = 24;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      const double u = i / double(n), v = j / double(n);
      const double x = 0.3 * u + 0.05 * v * v, y = 0.2 * v;
      const double z =
          0.06 * std::sin(7.0 * x + 1.0) * std::cos(5.0 * y) + 0.4 * x * y + 0.1 * x * x;
      mesh.positions.push_back(
          {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
    }
  }
  for (uint32_t i = 0; i < n; ++i) {
    for (uint32_t j = 0; j < n; ++j) {
      if (i + j > 36) continue;  // cut a corner off: an irregular outline
      const uint32_t a = i * (n + 1) + j, b = a + n + 1;
      mesh.triangles.insert(mesh.triangles.end(), {a, b, a + 1, a + 1, b, b + 1});
    }
  }
  return mesh;
}

// The node expansion alone (the root accepted for a far q): its error must fall as d^-(k+3) for
// expansion order k (the dipole field falls as d^-2, each further term one more power of r/d).
// A wrong moment formula leaves an error of the order of that term: the slope of the order below.
TEST(MeshReference, ExpansionErrorFallsWithTheExpectedPower) {
  const Mesh patch = MakeBumpyPatch();
  const ExactMesh brute(patch.positions, patch.triangles);
  const V3 direction = V3{0.3, 0.8, -0.5}.normalized();
  double error_at_2m[3] = {0, 0, 0};
  for (int order = 0; order <= 2; ++order) {
    WindingNumberOptions options;
    options.expansion_order = order;
    options.beta = 1.0001;  // the root is accepted as soon as q is outside its sphere
    const MeshReference fast(patch.positions, patch.triangles, options);
    double previous_error = 0.0;
    for (double distance : {1.0, 2.0, 4.0, 8.0}) {  // metres; the patch radius is about 0.2 m
      const V3 q = V3{0.15, 0.1, 0.0} + (direction * distance);
      const double error = std::fabs(fast.WindingNumber(Ptr(q)) - brute.WindingNumber(Ptr(q)));
      if (distance == 2.0) error_at_2m[order] = error;
      if (previous_error > 0.0) {
        const double ratio = previous_error / error;
        const double expected = std::pow(2.0, order + 3);
        if (distance >= 4.0) {  // past the pre-asymptotic range
          EXPECT_GT(ratio, 0.75 * expected)
              << "order " << order << " at " << distance << " m: error " << error
              << ", expected ratio " << expected;
          EXPECT_LT(ratio, 1.33 * expected)
              << "order " << order << " at " << distance << " m: error " << error
              << ", expected ratio " << expected;
        }
      }
      previous_error = error;
    }
  }
  EXPECT_LT(error_at_2m[1], 0.3 * error_at_2m[0]);
  EXPECT_LT(error_at_2m[2], 0.3 * error_at_2m[1]);
}

void CheckCharacterWinding(const std::string& name, const Mesh& mesh) {
  const MeshReference fast(mesh.positions, mesh.triangles);
  const ExactMesh brute(mesh.positions, mesh.triangles);
  const std::vector<V3> box = BoxPoints(mesh, 2000, 21);
  const std::vector<V3> near = NearSurfacePoints(mesh, 2000, 0.01, 22);
  const WindingComparison in_box = CompareWinding(fast, brute, box);
  const WindingComparison at_surface = CompareWinding(fast, brute, near);
  SCOPED_TRACE(testing::Message() << name << ": " << fast.triangle_count() << " triangles ("
                                  << fast.degenerate_triangle_count() << " degenerate, "
                                  << fast.skipped_triangle_count() << " skipped)");
  EXPECT_EQ(in_box.clear_disagreements, 0u)
      << "box: Inside disagrees on " << in_box.disagreements << " of " << box.size();
  EXPECT_EQ(at_surface.clear_disagreements, 0u)
      << "surface: Inside disagrees on " << at_surface.disagreements << " of " << near.size();
  EXPECT_LE(in_box.max_error, 1e-3) << "box";
  EXPECT_LE(at_surface.max_error, 1e-3) << "surface";
}

TEST(MeshReference, MannequinWindingNumberMatchesBruteForce) {
  const std::string path = test::MannequinPath();
  DRAPE_REQUIRE_FILE(path);
  Mesh mesh;
  ASSERT_TRUE(LoadRestPose(path, &mesh));
  CheckCharacterWinding("mannequin", mesh);
}

TEST(MeshReference, CesiumManWindingNumberMatchesBruteForce) {
  const std::string path = test::CharacterPath("CesiumMan/CesiumMan.glb");
  DRAPE_REQUIRE_FILE(path);
  Mesh mesh;
  ASSERT_TRUE(LoadRestPose(path, &mesh));
  CheckCharacterWinding("CesiumMan", mesh);
}

// Every winding-number setting bench/gbench/mesh_reference_bench.cpp compares (order 2, leaf
// size 4, beta 2 to 4) classifies every point the brute force sees clearly (farther than 0.1
// from 1/2) as the brute force does. The brute force is evaluated once per point.
void ExpectWindingSettingsClassifyClearPoints(const std::string& name, const Mesh& mesh) {
  SCOPED_TRACE(name);
  const ExactMesh brute(mesh.positions, mesh.triangles);
  std::vector<V3> points = BoxPoints(mesh, 1000, 31);
  const std::vector<V3> near = NearSurfacePoints(mesh, 1000, 0.01, 32);
  points.insert(points.end(), near.begin(), near.end());
  std::vector<double> reference(points.size());
  for (size_t i = 0; i < points.size(); ++i) reference[i] = brute.WindingNumber(Ptr(points[i]));
  for (uint32_t leaf : {4u}) {
    for (int order = 2; order <= 2; ++order) {
      for (double beta : {2.0, 3.0, 3.5, 4.0}) {
        WindingNumberOptions options;
        options.beta = beta;
        options.expansion_order = order;
        options.leaf_size = leaf;
        const MeshReference fast(mesh.positions, mesh.triangles, options);
        size_t clear_disagreements = 0;
        for (size_t i = 0; i < points.size(); ++i) {
          const double w = fast.WindingNumber(Ptr(points[i]));
          if ((w > 0.5) != (reference[i] > 0.5) && std::fabs(reference[i] - 0.5) > 0.1) {
            ++clear_disagreements;
          }
        }
        EXPECT_EQ(clear_disagreements, 0u) << "beta " << beta << " order " << order;
      }
    }
  }
}

TEST(MeshReference, EveryWindingSettingClassifiesClearPointsLikeBruteForce) {
  ExpectWindingSettingsClassifyClearPoints("icosphere", MakeIcosphere(4, 0.3, {0.1, -0.2, 0.05}));
  for (const std::string& path :
       {test::MannequinPath(), test::CharacterPath("CesiumMan/CesiumMan.glb")}) {
    if (!std::filesystem::exists(path)) continue;
    Mesh mesh;
    ASSERT_TRUE(LoadRestPose(path, &mesh));
    ExpectWindingSettingsClassifyClearPoints(path.substr(path.rfind('/') + 1), mesh);
  }
}

// ---------------------------------------------------------------------------------------------
// Distance and closest point

void CheckDistances(const Mesh& mesh, const std::vector<V3>& points) {
  const MeshReference fast(mesh.positions, mesh.triangles);
  const ExactMesh brute(mesh.positions, mesh.triangles);
  for (const V3& p : points) {
    const double reference = brute.Distance(Ptr(p));
    const double distance = fast.Distance(Ptr(p));
    double point[3], normal[3];
    uint32_t triangle = bake::kNoTriangle;
    const double closest = fast.ClosestPoint(Ptr(p), point, &triangle, normal);
    EXPECT_NEAR(distance, reference, 1e-9);
    EXPECT_NEAR(closest, reference, 1e-9);
    ASSERT_LT(triangle, mesh.triangles.size() / 3);
    const V3 a = Corner(mesh, triangle, 0), b = Corner(mesh, triangle, 1),
             c = Corner(mesh, triangle, 2);
    const double off = bake::PointTriangleDistance(point, Ptr(a), Ptr(b), Ptr(c));
    EXPECT_LT(off, 1e-9);
    const V3 face = (b - a).cross(c - a);
    const V3 n{normal[0], normal[1], normal[2]};
    EXPECT_NEAR(n.norm(), 1.0, 1e-12);
    EXPECT_NEAR(n.dot(face) / face.norm(), 1.0, 1e-12) << "the face normal, winding order";
    EXPECT_NEAR((V3{point[0], point[1], point[2]} - p).norm(), reference, 1e-9);
  }
}

TEST(MeshReference, IcosphereDistanceAndClosestPointMatchBruteForce) {
  const Mesh sphere = MakeIcosphere(3, 0.25, {-0.1, 0.4, 0.2});
  std::vector<V3> points = BoxPoints(sphere, 1000, 41);
  const std::vector<V3> near = NearSurfacePoints(sphere, 500, 0.005, 42);
  points.insert(points.end(), near.begin(), near.end());
  CheckDistances(sphere, points);
}

TEST(MeshReference, MannequinDistanceAndClosestPointMatchBruteForce) {
  const std::string path = test::MannequinPath();
  DRAPE_REQUIRE_FILE(path);
  Mesh mesh;
  ASSERT_TRUE(LoadRestPose(path, &mesh));
  std::vector<V3> points = BoxPoints(mesh, 1000, 51);
  const std::vector<V3> near = NearSurfacePoints(mesh, 1000, 0.01, 52);
  points.insert(points.end(), near.begin(), near.end());
  CheckDistances(mesh, points);
}

// ---------------------------------------------------------------------------------------------
// Crossings along a segment

TEST(MeshReference, FirstCrossingMatchesMollerTrumbore) {
  const V3 centre{0.05, 0.1, -0.03};
  const double radius = 0.3;
  const Mesh sphere = MakeIcosphere(3, radius, centre);
  const MeshReference reference(sphere.positions, sphere.triangles);
  std::mt19937_64 rng(61);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto random_direction = [&]() -> V3 {  // a vector, not an expression of the local d
    V3 d{gauss(rng), gauss(rng), gauss(rng)};
    return d * (1.0 / d.norm());
  };
  int entries = 0, exits = 0, misses = 0;
  std::vector<double> ts;
  for (int i = 0; i < 300; ++i) {
    // Start outside, inside or far; end anywhere: entries, exits, two crossings and misses.
    const V3 p0 = centre + (random_direction() * (radius * (0.2 + 1.8 * unit(rng))));
    const V3 p1 = centre + (random_direction() * (radius * (0.2 + 1.8 * unit(rng))));
    const auto expected = BruteCrossings(sphere, p0, p1);
    const SurfaceHit hit = reference.FirstCrossing(Ptr(p0), Ptr(p1));
    reference.Crossings(Ptr(p0), Ptr(p1), &ts);
    ASSERT_EQ(hit.hit, !expected.empty()) << "segment " << i;
    EXPECT_TRUE(std::is_sorted(ts.begin(), ts.end()));
    // A generic segment crosses no edge: one hit per crossed triangle.
    ASSERT_EQ(ts.size(), expected.size()) << "segment " << i;
    for (size_t k = 0; k < ts.size(); ++k) EXPECT_NEAR(ts[k], expected[k].first, 1e-9);
    if (!hit.hit) {
      ++misses;
      EXPECT_EQ(hit.triangle, bake::kNoTriangle);
      continue;
    }
    EXPECT_NEAR(hit.t, expected.front().first, 1e-9) << "segment " << i;
    EXPECT_EQ(hit.triangle, expected.front().second) << "segment " << i;
    const V3 d = p1 - p0;
    const V3 at = p0 + (d * hit.t);
    EXPECT_NEAR((V3{hit.point[0], hit.point[1], hit.point[2]} - at).norm(), 0.0, 1e-9);
    const V3 n{hit.normal[0], hit.normal[1], hit.normal[2]};
    EXPECT_NEAR(n.norm(), 1.0, 1e-12);
    const bool starts_inside = (p0 - centre).norm() < radius * 0.9;
    if (starts_inside) {
      ++exits;
      EXPECT_GT(n.dot(d), 0.0) << "leaving an outward-wound surface";
    } else if ((p0 - centre).norm() > radius) {
      ++entries;
      EXPECT_LT(n.dot(d), 0.0) << "entering an outward-wound surface";
    }
  }
  EXPECT_GT(entries, 30) << exits << " exits, " << misses << " misses";
  EXPECT_GT(exits, 30) << entries << " entries, " << misses << " misses";
  EXPECT_GT(misses, 10) << entries << " entries, " << exits << " exits";
}

TEST(MeshReference, SegmentThroughTheSphereCrossesTwiceEvenThroughVertices) {
  const V3 centre{0.0, 1.0, 0.0};
  const Mesh sphere = MakeIcosphere(2, 0.3, centre);
  const MeshReference reference(sphere.positions, sphere.triangles);
  std::vector<double> ts;
  // A generic diameter.
  const V3 d = V3{0.31, 0.52, 0.79}.normalized();
  const V3 p0 = centre + (d * -0.5), p1 = centre + (d * 0.5);
  reference.Crossings(Ptr(p0), Ptr(p1), &ts);
  ASSERT_EQ(ts.size(), 2u);
  EXPECT_LT(ts[0], ts[1]);
  EXPECT_NEAR(ts[0], 0.2, 0.01);  // the sphere spans t in [0.2, 0.8] up to faceting
  EXPECT_NEAR(ts[1], 0.8, 0.01);
  // Through two antipodal vertices: five or six triangles meet at each, one crossing each side.
  const V3 vertex = ToV3(sphere.positions[0]);
  const V3 through = vertex - centre;
  const V3 q0 = centre + (through * 1.5), q1 = centre + (through * -1.5);
  reference.Crossings(Ptr(q0), Ptr(q1), &ts);
  ASSERT_EQ(ts.size(), 2u) << "one crossing per vertex, however many triangles meet there";
  EXPECT_NEAR(ts[0], 1.0 / 6.0, 1e-6);
  EXPECT_NEAR(ts[1], 5.0 / 6.0, 1e-6);
  const SurfaceHit hit = reference.FirstCrossing(Ptr(q0), Ptr(q1));
  ASSERT_TRUE(hit.hit);
  EXPECT_NEAR(hit.t, 1.0 / 6.0, 1e-6);
  // A miss.
  const V3 m0{1.0, 1.0, 1.0}, m1{1.0, 2.0, 1.0};
  EXPECT_FALSE(reference.FirstCrossing(Ptr(m0), Ptr(m1)).hit);
  reference.Crossings(Ptr(m0), Ptr(m1), &ts);
  EXPECT_TRUE(ts.empty());
}

// A segment in the plane of a triangle comes back from CGAL as a segment: its near end counts.
TEST(MeshReference, CoplanarSegmentCrossesWhereItEntersTheTriangle) {
  const std::vector<Float3> positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<uint32_t> triangles = {0, 1, 2};
  const MeshReference reference(positions, triangles);
  const double p0[3] = {-0.5, 0.25, 0.0}, p1[3] = {1.5, 0.25, 0.0};
  const SurfaceHit hit = reference.FirstCrossing(p0, p1);
  ASSERT_TRUE(hit.hit);
  EXPECT_NEAR(hit.t, 0.25, 1e-12);  // enters at x = 0
  EXPECT_NEAR(hit.point[0], 0.0, 1e-12);
  EXPECT_NEAR(hit.normal[2], 1.0, 1e-12);
  // Reversed, it enters at x = 0.75.
  const SurfaceHit back = reference.FirstCrossing(p1, p0);
  ASSERT_TRUE(back.hit);
  EXPECT_NEAR(back.t, 0.375, 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Degenerate input

TEST(MeshReference, EmptyMeshAnswersWithoutCrashing) {
  const MeshReference empty(std::span<const Float3>{}, std::span<const uint32_t>{});
  const double q[3] = {0.1, 0.2, 0.3}, p1[3] = {1, 1, 1};
  EXPECT_EQ(empty.WindingNumber(q), 0.0);
  EXPECT_FALSE(empty.Inside(q));
  EXPECT_EQ(empty.Distance(q), INFINITY);
  double point[3], normal[3] = {1, 1, 1};
  uint32_t triangle = 0;
  EXPECT_EQ(empty.ClosestPoint(q, point, &triangle, normal), INFINITY);
  EXPECT_EQ(triangle, bake::kNoTriangle);
  EXPECT_EQ(normal[0], 0.0);
  EXPECT_FALSE(empty.FirstCrossing(q, p1).hit);
  std::vector<double> ts = {3.0};
  empty.Crossings(q, p1, &ts);
  EXPECT_TRUE(ts.empty());
  EXPECT_EQ(empty.triangle_count(), 0u);
}

TEST(MeshReference, ZeroAreaOutOfRangeAndNonFiniteTrianglesAreSkipped) {
  const Mesh sphere = MakeIcosphere(2, 0.3);
  Mesh damaged = sphere;
  const uint32_t n = static_cast<uint32_t>(sphere.positions.size());
  damaged.positions.push_back({0.f, 0.f, std::numeric_limits<float>::quiet_NaN()});  // index n
  // Three distinct collinear points: n + 1 .. n + 3.
  damaged.positions.push_back({0.f, 0.f, 0.f});
  damaged.positions.push_back({0.1f, 0.f, 0.f});
  damaged.positions.push_back({0.2f, 0.f, 0.f});
  const std::vector<uint32_t> extra = {
      0,           0,     1,      // repeated index: zero area
      2,           5,     5,      // repeated index: zero area
      n + 1,       n + 2, n + 3,  // collinear: zero area
      0,           n + 5, 1,      // out of range
      0xFFFFFFFFu, 1,     2,      // out of range
      0,           1,     n,      // NaN corner
      3,           4,             // not a whole triple: ignored
  };
  damaged.triangles.insert(damaged.triangles.end(), extra.begin(), extra.end());
  const MeshReference clean(sphere.positions, sphere.triangles);
  const MeshReference reference(damaged.positions, damaged.triangles);
  EXPECT_EQ(reference.triangle_count(), sphere.triangles.size() / 3 + 6);
  EXPECT_EQ(reference.skipped_triangle_count(), 3u);
  EXPECT_EQ(reference.degenerate_triangle_count(), 3u);
  const std::vector<V3> points = BoxPoints(sphere, 200, 71);
  for (const V3& p : points) {
    EXPECT_EQ(reference.WindingNumber(Ptr(p)), clean.WindingNumber(Ptr(p)));
    EXPECT_EQ(reference.Distance(Ptr(p)), clean.Distance(Ptr(p)));
  }
  // On the collinear triangle itself: it contributes no winding and has no distance of its own.
  const double on_segment[3] = {0.05, 0.0, 0.0};
  EXPECT_EQ(reference.WindingNumber(on_segment), clean.WindingNumber(on_segment));
  EXPECT_NEAR(reference.ExactWindingNumber(on_segment), 1.0, 1e-9);
  const double p0[3] = {0.0, 0.0, 0.0}, p1[3] = {0.0, 0.0, 1.0};
  const SurfaceHit hit = reference.FirstCrossing(p0, p1);
  ASSERT_TRUE(hit.hit);
  EXPECT_LT(hit.triangle, sphere.triangles.size() / 3) << "a sphere triangle, not a skipped one";
  // Non-finite queries return NaN or no hit, never crash.
  const double bad[3] = {NAN, 0.0, 0.0};
  EXPECT_TRUE(std::isnan(reference.WindingNumber(bad)));
  EXPECT_TRUE(std::isnan(reference.Distance(bad)));
  EXPECT_FALSE(reference.FirstCrossing(bad, p1).hit);
  EXPECT_FALSE(reference.FirstCrossing(p0, p0).hit) << "a zero-length segment";
}

// Moves keep the tree valid (it points into storage the move does not copy); queries from two
// threads give the single-threaded answers bit for bit.
TEST(MeshReference, MovedAndConcurrentQueriesGiveTheSameAnswers) {
  const Mesh sphere = MakeIcosphere(3, 0.3);
  MeshReference original(sphere.positions, sphere.triangles);
  const std::vector<V3> points = BoxPoints(sphere, 400, 81);
  std::vector<std::array<double, 4>> expected(points.size());
  const double far[3] = {2.0, 0.1, 0.2};
  for (size_t i = 0; i < points.size(); ++i) {
    expected[i] = {original.WindingNumber(Ptr(points[i])), original.Distance(Ptr(points[i])),
                   original.FirstCrossing(Ptr(points[i]), far).t, 0.0};
  }
  MeshReference moved(std::move(original));
  MeshReference assigned(std::span<const Float3>{}, std::span<const uint32_t>{});
  assigned = std::move(moved);
  std::vector<std::array<double, 4>> got[2];
  auto run = [&](int k) {
    got[k].resize(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      got[k][i] = {assigned.WindingNumber(Ptr(points[i])), assigned.Distance(Ptr(points[i])),
                   assigned.FirstCrossing(Ptr(points[i]), far).t, 0.0};
    }
  };
  std::thread a(run, 0), b(run, 1);
  a.join(), b.join();
  EXPECT_EQ(got[0], expected);
  EXPECT_EQ(got[1], expected);
  EXPECT_GT(assigned.memory_bytes(), 0u);
}

}  // namespace
}  // namespace drape

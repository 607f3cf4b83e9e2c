// Tests of drape::bake::BuildHullGeometry (bake/include/drape/bake/hull_builder.h): containment of
// every input delta-ball in the stored float planes (runtime arithmetic) and in the stored
// triangles (exact predicates), convexity, budgets, growth bound, OBB, degenerate inputs and
// determinism.

#include "drape/bake/hull_builder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "drape/runtime/math.h"

namespace drape::bake {
namespace {

// SplitMix64: the same numbers on every platform (std distributions are implementation-defined).
class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed) {}
  uint64_t Next() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  double Uniform(double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(Next() >> 11) * 0x1.0p-53;
  }
  Float3 UnitVector() {
    for (;;) {
      const double x = Uniform(-1, 1), y = Uniform(-1, 1), z = Uniform(-1, 1);
      const double len2 = x * x + y * y + z * z;
      if (len2 > 1e-4 && len2 <= 1.0) {
        const double inv = 1.0 / std::sqrt(len2);
        return {static_cast<float>(x * inv), static_cast<float>(y * inv),
                static_cast<float>(z * inv)};
      }
    }
  }

 private:
  uint64_t state_;
};

Float3 F3(double x, double y, double z) {
  return {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)};
}

std::vector<Float3> RandomCloud(uint64_t seed, int count, Float3 centre, Float3 half) {
  Random random(seed);
  std::vector<Float3> points;
  for (int i = 0; i < count; ++i) {
    points.push_back(F3(centre.x + random.Uniform(-half.x, half.x),
                        centre.y + random.Uniform(-half.y, half.y),
                        centre.z + random.Uniform(-half.z, half.z)));
  }
  return points;
}

std::vector<Float3> Cube(double half) {
  std::vector<Float3> points;
  for (int i = 0; i < 8; ++i) {
    points.push_back(F3(i & 1 ? half : -half, i & 2 ? half : -half, i & 4 ? half : -half));
  }
  return points;
}

// A forearm-like cloud: points on and near a capsule along x (length 0.25 m, radius 3.5 cm),
// off the origin like a bone-local frame.
std::vector<Float3> Forearm(uint64_t seed, int count) {
  Random random(seed);
  std::vector<Float3> points;
  const double length = 0.25, radius = 0.035;
  for (int i = 0; i < count; ++i) {
    const double t = random.Uniform(-radius, length + radius);
    const Float3 dir = random.UnitVector();
    double r = radius * random.Uniform(0.9, 1.0);
    Float3 p;
    if (t < 0.0 || t > length) {
      const double cx = t < 0.0 ? 0.0 : length;
      p = F3(cx + dir.x * r, 0.02 + dir.y * r, -0.01 + dir.z * r);
    } else {
      const double len = std::sqrt(double(dir.y) * dir.y + double(dir.z) * dir.z) + 1e-12;
      r *= 1.0 - 0.2 * t / length;  // tapers towards the wrist
      p = F3(t, 0.02 + dir.y / len * r, -0.01 + dir.z / len * r);
    }
    points.push_back(p);
  }
  return points;
}

std::vector<Float3> Disc(uint64_t seed, int count, double radius) {
  Random random(seed);
  std::vector<Float3> points;
  for (int i = 0; i < count; ++i) {
    const double a = random.Uniform(0, 2 * M_PI), r = radius * std::sqrt(random.Uniform(0, 1));
    points.push_back(F3(0.1 + r * std::cos(a), 0.3, -0.2 + r * std::sin(a)));
  }
  return points;
}

// The runtime's test, in float: inside <=> dot(n, p) <= d for every plane.
bool FloatPlanesContain(const HullColliderData& collider, Float3 p) {
  for (const Plane& plane : collider.planes) {
    if (Dot(plane.normal, p) > plane.offset) return false;
  }
  return true;
}

// Float points within delta of x: x itself, x pushed along every plane normal (the worst point of
// the ball for that plane) and along random directions; 1e-4 relative slack keeps the rounded
// point within the ball.
std::vector<Float3> BallSamples(Float3 x, float delta, const HullColliderData& collider,
                                Random* random) {
  std::vector<Float3> samples{x};
  const float r = delta * (1.f - 1e-4f);
  if (r <= 0.f) return samples;
  for (const Plane& plane : collider.planes) samples.push_back(x + plane.normal * r);
  for (int i = 0; i < 8; ++i) samples.push_back(x + random->UnitVector() * r);
  return samples;
}

struct Built {
  HullColliderData collider;
  HullStats stats;
  Status status;
};

Built Build(const std::vector<Float3>& points, const HullOptions& options) {
  Built built;
  built.status = BuildHullGeometry(points, options, &built.collider, &built.stats);
  return built;
}

// Every invariant a successful build must satisfy.
void ExpectValidCollider(const std::vector<Float3>& points, const HullOptions& options,
                         const Built& built, bool expect_exact_containment = true) {
  ASSERT_TRUE(built.status.ok()) << built.status.message();
  const HullColliderData& c = built.collider;
  const HullStats& s = built.stats;
  EXPECT_TRUE(s.skip_reason.empty());
  ASSERT_GE(c.triangles.size(), 12u);
  ASSERT_EQ(c.triangles.size() % 3, 0u);
  ASSERT_EQ(c.triangle_planes.size(), c.triangles.size() / 3);
  EXPECT_EQ(s.triangles_after, c.triangles.size() / 3);
  EXPECT_EQ(s.planes_after, c.planes.size());
  EXPECT_LE(c.planes.size(), c.triangles.size() / 3);
  for (uint32_t index : c.triangles) ASSERT_LT(index, c.vertices.size());

  // Convex, exactly, on the stored floats.
  EXPECT_TRUE(HullIsConvex(c));
  EXPECT_EQ(CountConvexityViolations(c), 0u);

  // Exact containment of every input delta-ball in the triangles.
  if (expect_exact_containment) {
    EXPECT_TRUE(HullContainsPoints(c, points, options.delta));
    EXPECT_EQ(s.uncovered_points, 0u);
  }

  // Runtime float plane test: every collider vertex is inside, and every delta-ball sample when
  // the inflation guarantees it.
  for (const Float3& v : c.vertices) EXPECT_TRUE(FloatPlanesContain(c, v));
  if (expect_exact_containment) {
    Random random(7);
    size_t outside = 0;
    for (const Float3& x : points) {
      for (const Float3& q : BallSamples(x, options.delta, c, &random)) {
        if (!FloatPlanesContain(c, q)) ++outside;
      }
    }
    EXPECT_EQ(outside, 0u);
  }
  // The OBB covers the polytope the planes bound, not only the vertices: near the hull's corners
  // (where the planes, rounded outward and pushed over the delta-balls, meet beyond the stored
  // vertices) every point the plane test holds must pass the runtime's OBB rejection.
  {
    Random random(11);
    size_t in_planes = 0, outside_obb = 0;
    for (const Float3& v : c.vertices) {
      for (int k = 0; k < 64; ++k) {
        const auto jitter = [&]() { return static_cast<float>(random.Uniform(-0.01, 0.01)); };
        const Float3 q{v.x + jitter(), v.y + jitter(), v.z + jitter()};
        if (!FloatPlanesContain(c, q)) continue;
        ++in_planes;
        const Float3 d{q.x - c.obb.center.x, q.y - c.obb.center.y, q.z - c.obb.center.z};
        const float extent[3] = {c.obb.half_extents.x, c.obb.half_extents.y, c.obb.half_extents.z};
        for (int a = 0; a < 3; ++a) {
          if (std::fabs(Dot(d, c.obb.axes[a])) > extent[a] * (1.f + 1e-5f) + 1e-6f) {
            ++outside_obb;
            break;
          }
        }
      }
    }
    if (c.obb.half_extents.z > 1e-3f) {  // not the 1e-13 m solid
      EXPECT_GT(in_planes, 0u);
    }
    EXPECT_EQ(outside_obb, 0u) << "of " << in_planes << " points inside the planes";
  }

  // Planes: unit normals, each triangle's plane matches its orientation, the plane holds its
  // triangle's vertices within float rounding.
  for (const Plane& plane : c.planes) EXPECT_NEAR(Length(plane.normal), 1.f, 1e-6f);
  for (size_t t = 0; t < c.triangle_planes.size(); ++t) {
    ASSERT_LT(c.triangle_planes[t], c.planes.size());
    const Plane& plane = c.planes[c.triangle_planes[t]];
    const Float3 a = c.vertices[c.triangles[3 * t]], b = c.vertices[c.triangles[3 * t + 1]],
                 cc = c.vertices[c.triangles[3 * t + 2]];
    // Triangle normal in double (float cross products of slivers are noise).
    const double e1[3] = {double(b.x) - a.x, double(b.y) - a.y, double(b.z) - a.z};
    const double e2[3] = {double(cc.x) - a.x, double(cc.y) - a.y, double(cc.z) - a.z};
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                         e1[0] * e2[1] - e1[1] * e2[0]};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    ASSERT_GT(len, 0.0) << "degenerate triangle " << t;
    const double cosine =
        (n[0] * plane.normal.x + n[1] * plane.normal.y + n[2] * plane.normal.z) / len;
    EXPECT_GT(cosine, 0.99) << "triangle " << t;
  }

  // Budget or growth bound.
  if (s.budget_reached) {
    EXPECT_LE(s.triangles_after, options.max_triangles);
  } else {
    EXPECT_GT(s.triangles_after, options.max_triangles);
  }
  EXPECT_LE(s.growth_mm, options.max_growth * 1000.f * (1.f + 1e-5f) + 1e-6f);

  // OBB: orthonormal, right-handed, contains every vertex in float.
  const Obb& obb = c.obb;
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(Length(obb.axes[k]), 1.f, 1e-6f);
    for (int j = k + 1; j < 3; ++j) EXPECT_NEAR(Dot(obb.axes[k], obb.axes[j]), 0.f, 1e-6f);
  }
  EXPECT_GT(Dot(Cross(obb.axes[0], obb.axes[1]), obb.axes[2]), 0.999f);
  // Longest axis first (the order is decided before the outward rounding of the extents).
  EXPECT_GE(obb.half_extents.x, obb.half_extents.y * (1.f - 1e-4f));
  EXPECT_GE(obb.half_extents.y, obb.half_extents.z * (1.f - 1e-4f));
  const float half[3] = {obb.half_extents.x, obb.half_extents.y, obb.half_extents.z};
  for (const Float3& v : c.vertices) {
    const Float3 local = v - obb.center;
    for (int k = 0; k < 3; ++k) EXPECT_LE(std::fabs(Dot(obb.axes[k], local)), half[k]);
  }
  EXPECT_NEAR(s.obb_volume, 8.f * half[0] * half[1] * half[2], 1e-6f * s.obb_volume);
}

TEST(HullBuilder, RandomCloudDefaults) {
  const std::vector<Float3> points = RandomCloud(1, 300, F3(0.1, -0.2, 0.3), F3(0.05, 0.08, 0.04));
  const HullOptions options;
  const Built built = Build(points, options);
  ExpectValidCollider(points, options, built);
  EXPECT_TRUE(built.stats.budget_reached);
  EXPECT_GT(built.stats.hull_triangles_before, options.max_triangles);
}

TEST(HullBuilder, ForearmAndCube) {
  const std::vector<Float3> forearm = Forearm(2, 400);
  for (uint32_t budget : {16u, 50u, 200u}) {
    HullOptions options;
    options.max_triangles = budget;
    const Built built = Build(forearm, options);
    ExpectValidCollider(forearm, options, built);
  }
  const std::vector<Float3> cube = Cube(0.05);
  HullOptions options;
  options.max_triangles = 16;
  const Built built = Build(cube, options);
  ExpectValidCollider(cube, options, built);
}

TEST(HullBuilder, FlatDiscIsInflatedToASolid) {
  const std::vector<Float3> disc = Disc(3, 200, 0.06);
  const HullOptions options;
  const Built built = Build(disc, options);
  ExpectValidCollider(disc, options, built);
  // The slab is at least 2 delta thick along the disc normal (y).
  EXPECT_GE(built.collider.obb.half_extents.z, options.delta * 0.999f);
}

TEST(HullBuilder, CoplanarTrianglesShareOnePlane) {
  // delta = 0, no simplification: the cube's hull has 12 triangles on exactly 6 planes.
  HullOptions options;
  options.delta = 0.f;
  options.simplify = SimplifyMode::kNone;
  const std::vector<Float3> cube = Cube(0.5);
  const Built built = Build(cube, options);
  ExpectValidCollider(cube, options, built);
  EXPECT_EQ(built.stats.triangles_after, 12u);
  EXPECT_EQ(built.stats.planes_after, 6u);
  for (const Plane& plane : built.collider.planes) {
    EXPECT_NEAR(std::fabs(plane.normal.x) + std::fabs(plane.normal.y) + std::fabs(plane.normal.z),
                1.f, 1e-6f);
    EXPECT_GE(plane.offset, 0.5f);
    EXPECT_LE(plane.offset, 0.5f * (1.f + 1e-6f));  // rounded outward by a few ulps only
  }
  // The inflated cube keeps its 6 square faces as merged planes.
  options.delta = 0.01f;
  const Built inflated = Build(cube, options);
  ExpectValidCollider(cube, options, inflated);
  EXPECT_LT(inflated.stats.planes_before, inflated.stats.hull_triangles_before);
}

TEST(HullBuilder, TriangleBudgetsAndGrowthBound) {
  const std::vector<Float3> points = Forearm(4, 300);
  float previous_growth = std::numeric_limits<float>::infinity();
  for (uint32_t budget : {16u, 25u, 50u, 100u, 200u, 400u}) {
    HullOptions options;
    options.max_triangles = budget;
    options.max_growth = 0.05f;
    const Built built = Build(points, options);
    ExpectValidCollider(points, options, built);
    EXPECT_TRUE(built.stats.budget_reached) << budget;
    previous_growth = built.stats.growth_mm;
  }
  EXPECT_LT(previous_growth, 5.f);  // 400 triangles: barely simplified
  // A tight growth bound stops the simplification before the budget.
  HullOptions tight;
  tight.max_triangles = 16;
  tight.max_growth = 0.001f;
  const Built built = Build(points, tight);
  ExpectValidCollider(points, tight, built);
  EXPECT_FALSE(built.stats.budget_reached);
  EXPECT_LE(built.stats.growth_mm, 1.f + 1e-4f);
}

TEST(HullBuilder, SimplifyModes) {
  const std::vector<Float3> points = Forearm(5, 300);
  for (SimplifyMode mode :
       {SimplifyMode::kEdgeCollapse, SimplifyMode::kPlaneRemoval, SimplifyMode::kNone}) {
    HullOptions options;
    options.simplify = mode;
    const Built built = Build(points, options);
    ExpectValidCollider(points, options, built);
    if (mode == SimplifyMode::kNone) {
      EXPECT_EQ(built.stats.triangles_after, built.stats.hull_triangles_before);
      EXPECT_EQ(built.stats.growth_mm, 0.f);
    } else {
      EXPECT_LT(built.stats.triangles_after, built.stats.hull_triangles_before);
    }
  }
}

TEST(HullBuilder, VertexNormalInflationReportsContainment) {
  const std::vector<Float3> points = Cube(0.05);
  HullOptions options;
  options.inflation = InflationMode::kVertexNormalOffset;
  options.simplify = SimplifyMode::kNone;
  const Built built = Build(points, options);
  // No containment guarantee: the planes support the paper's offset vertices, and the balls poke
  // out by the reported deficit (the Minkowski inflation is the guaranteed mode).
  ExpectValidCollider(points, options, built, /*expect_exact_containment=*/false);
  // Cube corners offset along the diagonal by delta: the faces are only delta/sqrt(3) out, so
  // every corner's ball pokes out by delta (1 - 1/sqrt(3)) = 2.11 mm.
  EXPECT_EQ(built.stats.uncovered_points, 8u);
  EXPECT_NEAR(built.stats.containment_deficit_mm, 5.f * (1.f - 1.f / std::sqrt(3.f)), 0.01f);
  EXPECT_FALSE(HullContainsPoints(built.collider, points, options.delta));
  EXPECT_TRUE(HullContainsPoints(built.collider, points, 0.f));
  size_t balls_outside_planes = 0;
  for (const Float3& corner : points) {  // the ball's point straight out through a face
    const Float3 q{corner.x + (corner.x > 0.f ? options.delta : -options.delta), corner.y,
                   corner.z};
    balls_outside_planes += !FloatPlanesContain(built.collider, q);
  }
  EXPECT_EQ(balls_outside_planes, points.size()) << "the planes are the paper's hull";
  // Every plane supports the stored vertices (a vertex lies on it within float rounding): the
  // plane set is the polytope the vertices, triangles, Kirkpatrick hierarchies and map table
  // describe.
  for (size_t k = 0; k < built.collider.planes.size(); ++k) {
    double closest = std::numeric_limits<double>::infinity();
    for (const Float3& v : built.collider.vertices) {
      const double gap = double(built.collider.planes[k].offset) -
                         (double(built.collider.planes[k].normal.x) * v.x +
                          double(built.collider.planes[k].normal.y) * v.y +
                          double(built.collider.planes[k].normal.z) * v.z);
      closest = std::min(closest, gap);
    }
    EXPECT_LT(closest, 1e-5) << "plane " << k << " lies " << closest << " m beyond every vertex";
  }
}

TEST(HullBuilder, ObbModes) {
  const std::vector<Float3> points = Forearm(6, 300);
  HullOptions options;
  const Built covariance = Build(points, options);
  ExpectValidCollider(points, options, covariance);
  options.obb = ObbMode::kCgalOptimal;
  const Built optimal = Build(points, options);
  ExpectValidCollider(points, options, optimal);
  // Same collider, different box.
  EXPECT_EQ(covariance.collider.vertices.size(), optimal.collider.vertices.size());
  const float ratio = optimal.stats.obb_volume / covariance.stats.obb_volume;
  // The optimiser is a heuristic; on an elongated cloud it should not be much worse than PCA.
  EXPECT_LT(ratio, 1.1f) << "OBB volume: covariance " << covariance.stats.obb_volume
                         << " m^3, CGAL " << optimal.stats.obb_volume << " m^3";
  // Seeded: two runs agree.
  const Built again = Build(points, options);
  EXPECT_EQ(std::memcmp(&again.collider.obb, &optimal.collider.obb, sizeof(Obb)), 0);
}

TEST(HullBuilder, DegenerateInputs) {
  HullOptions options;
  // Empty and too few points: skipped with a reason.
  for (size_t n : {0u, 1u, 2u, 3u}) {
    const std::vector<Float3> points =
        RandomCloud(10 + n, static_cast<int>(n), F3(0, 0, 0), F3(1, 1, 1));
    const Built built = Build(points, options);
    EXPECT_FALSE(built.status.ok());
    EXPECT_EQ(built.status.code(), StatusCode::kInvalidArgument);
    EXPECT_FALSE(built.stats.skip_reason.empty());
    EXPECT_TRUE(built.collider.vertices.empty());
  }
  // Five duplicates are one distinct point: skipped at min_points 4, a valid collider at 1.
  const std::vector<Float3> duplicates(5, F3(0.3, 0.2, 0.1));
  EXPECT_FALSE(Build(duplicates, options).status.ok());
  HullOptions one = options;
  one.min_points = 1;
  ExpectValidCollider(duplicates, one, Build(duplicates, one));
  // 1, 2, 3 points with min_points 1.
  for (int n : {1, 2, 3}) {
    const std::vector<Float3> points = RandomCloud(20 + n, n, F3(0, 1, 0), F3(0.1, 0.1, 0.1));
    ExpectValidCollider(points, one, Build(points, one));
  }
  // Collinear and coplanar.
  std::vector<Float3> collinear;
  for (int i = 0; i < 10; ++i) collinear.push_back(F3(0.01 * i, 0.02 * i, -0.03 * i));
  ExpectValidCollider(collinear, options, Build(collinear, options));
  const std::vector<Float3> square{F3(0, 0, 0), F3(1, 0, 0), F3(1, 1, 0), F3(0, 1, 0),
                                   F3(0.5, 0.5, 0)};
  ExpectValidCollider(square, options, Build(square, options));
  // A solid 1e-13 thin: 4 coplanar points and one 1e-13 off the plane.
  std::vector<Float3> thin = square;
  thin.back() = F3(0.5, 0.5, 1e-13);
  ExpectValidCollider(thin, options, Build(thin, options));
  // Coordinates around 1e4 m (float ulp ~1 mm there).
  std::vector<Float3> far = RandomCloud(30, 100, F3(1e4, -1e4, 1e4), F3(0.1, 0.1, 0.1));
  const Built far_built = Build(far, options);
  ExpectValidCollider(far, options, far_built);
  // delta = 0 needs a full-dimensional input.
  HullOptions zero = options;
  zero.delta = 0.f;
  EXPECT_FALSE(Build(square, zero).status.ok());
  EXPECT_FALSE(Build(collinear, zero).status.ok());
  const Built thin_zero = Build(thin, zero);  // exactly full-dimensional, so accepted
  ExpectValidCollider(thin, zero, thin_zero);
  // Vertex-normal inflation of a flat input falls back to Minkowski, with a note.
  HullOptions paper = options;
  paper.inflation = InflationMode::kVertexNormalOffset;
  const Built flat_paper = Build(square, paper);
  ExpectValidCollider(square, paper, flat_paper);
  EXPECT_FALSE(flat_paper.stats.note.empty());
  // Invalid input and options: errors, no crash.
  std::vector<Float3> bad = square;
  bad[2].y = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(Build(bad, options).status.ok());
  bad[2].y = std::numeric_limits<float>::infinity();
  EXPECT_FALSE(Build(bad, options).status.ok());
  HullOptions invalid = options;
  invalid.delta = -1.f;
  EXPECT_FALSE(Build(square, invalid).status.ok());
  invalid = options;
  invalid.max_triangles = 3;
  EXPECT_FALSE(Build(square, invalid).status.ok());
  EXPECT_FALSE(BuildHullGeometry(square, options, nullptr, nullptr).ok());
}

TEST(HullBuilder, Deterministic) {
  // CGAL's hull output order and its triangulation of coplanar faces vary between calls (they
  // depend on memory addresses): the builder canonicalises both. Repeat with allocations between
  // the runs so that a regression shows.
  std::vector<Float3> points = Forearm(8, 300);
  auto same = [](const HullColliderData& x, const HullColliderData& y) {
    return x.vertices.size() == y.vertices.size() && x.triangles == y.triangles &&
           x.triangle_planes == y.triangle_planes && x.planes.size() == y.planes.size() &&
           std::memcmp(x.vertices.data(), y.vertices.data(), x.vertices.size() * sizeof(Float3)) ==
               0 &&
           std::memcmp(x.planes.data(), y.planes.data(), x.planes.size() * sizeof(Plane)) == 0 &&
           std::memcmp(&x.obb, &y.obb, sizeof(Obb)) == 0;
  };
  for (SimplifyMode mode :
       {SimplifyMode::kEdgeCollapse, SimplifyMode::kPlaneRemoval, SimplifyMode::kNone}) {
    HullOptions options;
    options.simplify = mode;
    const Built first = Build(points, options);
    ASSERT_TRUE(first.status.ok());
    for (int run = 0; run < 4; ++run) {
      std::vector<std::vector<char>> churn(static_cast<size_t>(run + 1) * 7);
      for (size_t i = 0; i < churn.size(); ++i) churn[i].resize(64 * (i + 1));
      const Built again = Build(points, options);
      ASSERT_TRUE(again.status.ok());
      EXPECT_TRUE(same(first.collider, again.collider)) << "mode " << static_cast<int>(mode);
    }
    // The input order does not matter either (points are sorted first).
    std::vector<Float3> reversed(points.rbegin(), points.rend());
    EXPECT_TRUE(same(first.collider, Build(reversed, options).collider));
  }
}

TEST(HullBuilder, ContainmentChecksDetectViolations) {
  const std::vector<Float3> cube = Cube(0.5);
  HullOptions options;
  options.delta = 0.f;
  options.simplify = SimplifyMode::kNone;
  const Built built = Build(cube, options);
  ASSERT_TRUE(built.status.ok());
  const std::vector<Float3> inside{F3(0.25, 0.25, 0.25)};
  EXPECT_TRUE(HullContainsPoints(built.collider, inside, 0.25f));  // touches three faces
  EXPECT_FALSE(HullContainsPoints(built.collider, inside, 0.2500001f));
  const std::vector<Float3> outside{F3(0.5, 0.5, 0.50000006)};
  EXPECT_FALSE(HullContainsPoints(built.collider, outside, 0.f));
  // A dented cube is not convex.
  HullColliderData dented = built.collider;
  dented.vertices[0] = F3(-0.4, -0.4, -0.4);  // corner (-,-,-) pushed inwards
  EXPECT_FALSE(HullIsConvex(dented));
  EXPECT_GT(CountConvexityViolations(dented), 0u);
  // Broken topology is not convex.
  HullColliderData open = built.collider;
  open.triangles.resize(open.triangles.size() - 3);
  EXPECT_FALSE(HullIsConvex(open));
}

}  // namespace
}  // namespace drape::bake

// Paper A's image-space collider at run time, on analytic maps built here (no bake dependency):
// a sphere, a texel-aligned box, a slab thinner than one step, two boxes with a gap; the
// row-span layout of the same maps answers bit for bit as the dense one.

#include "drape/runtime/body_map_collider.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <vector>

namespace drape {

// The lanes CollideBatch can take with kNearest (BodyMapCollider::LaneKernel): four in SSE2,
// eight in AVX2, eight in AVX2 with AVX-512.
enum class TestLanes { kSse2, kAvx2, kAvx512 };
constexpr TestLanes kEveryLanes[] = {TestLanes::kSse2, TestLanes::kAvx2, TestLanes::kAvx512};
const char* LanesName(TestLanes lanes) {
  return lanes == TestLanes::kSse2   ? "four SSE2 lanes"
         : lanes == TestLanes::kAvx2 ? "eight AVX2 lanes"
                                     : "eight AVX-512 lanes";
}

// Reaches the collider's general path (clip and walk), which Query skips for motions that stay
// in one texel or clearly pass through air.
struct BodyMapColliderTestAccess {
  static ContactQuery QueryWalk(const BodyMapCollider& c, Float3 p0, Float3 p1) {
    return c.QueryWalk(p0, p1);
  }
  // Whether each quick path answers this motion (nearest sampling for the first).
  static bool SingleTexelAnswers(const BodyMapCollider& c, Float3 p0, Float3 p1) {
    ContactQuery unused;
    return c.sampling() == DepthSampling::kNearest &&
           c.QuerySingleTexel(p0, p1, c.ToTexels(p0, p1), &unused);
  }
  static bool ClearlyFree(const BodyMapCollider& c, Float3 p0, Float3 p1) {
    return c.ClearlyFree(p0, p1, c.ToTexels(p0, p1));
  }
  // Sets c (and so CollideBatch) to take `lanes`; false, with c unchanged, where the CPU lacks
  // them (a test skips those).
  static bool UseLanes(BodyMapCollider* c, TestLanes lanes) {
    static_assert(static_cast<int>(TestLanes::kSse2) ==
                          static_cast<int>(BodyMapCollider::LaneKernel::kSse2) &&
                      static_cast<int>(TestLanes::kAvx2) ==
                          static_cast<int>(BodyMapCollider::LaneKernel::kAvx2) &&
                      static_cast<int>(TestLanes::kAvx512) ==
                          static_cast<int>(BodyMapCollider::LaneKernel::kAvx512),
                  "TestLanes names LaneKernel's values");
    BodyMapCollider probe;
    probe.AllowAvx2(lanes != TestLanes::kSse2);
    probe.AllowAvx512(lanes == TestLanes::kAvx512);
    if (static_cast<int>(probe.lane_kernel()) != static_cast<int>(lanes)) return false;
    c->AllowAvx2(lanes != TestLanes::kSse2);
    c->AllowAvx512(lanes == TestLanes::kAvx512);
    return true;
  }
  static int LaneWidth(TestLanes lanes) { return lanes == TestLanes::kSse2 ? 4 : 8; }
#if defined(__SSE2__)
  // CollideBatch's short-motion lanes alone, those `lanes` (which lanes they answer is not visible
  // through the batch). Call only where UseLanes gave true.
  static uint32_t CollideShort(const BodyMapCollider& c, TestLanes lanes, const Float3* previous,
                               Float3* positions, Float3* velocities, uint8_t* flags,
                               const ResponseParams& params, uint32_t* long_motions) {
    const auto short_lanes =
        lanes == TestLanes::kAvx512 ? &BodyMapCollider::CollideEightShortMotionsAvx512
        : lanes == TestLanes::kAvx2 ? &BodyMapCollider::CollideEightShortMotionsAvx2
                                    : &BodyMapCollider::CollideFourShortMotions;
    return (c.*short_lanes)(previous, positions, velocities, flags, params, long_motions);
  }
  // CollideBatch's walking lanes alone, on particles index[l] for l in the mask `lanes_in_use`.
  static uint32_t CollideWalks(const BodyMapCollider& c, TestLanes lanes, const uint32_t* index,
                               uint32_t lanes_in_use, const Float3* previous, Float3* positions,
                               Float3* velocities, uint8_t* flags, const ResponseParams& params) {
    const auto walk_lanes = lanes == TestLanes::kAvx512 ? &BodyMapCollider::CollideEightWalksAvx512
                            : lanes == TestLanes::kAvx2 ? &BodyMapCollider::CollideEightWalksAvx2
                                                        : &BodyMapCollider::CollideFourWalks;
    return (c.*walk_lanes)(index, lanes_in_use, previous, positions, velocities, flags, params);
  }
#endif
};

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kTexel = 1.f / 128.f;  // metres; a power of two, so texel edges are exact floats
// A side-wall contact point is stepped back across the wall by 1e-3 texel (so a particle placed
// there is outside): wall positions are compared with that allowance.
constexpr float kWallTolerance = 1.01e-3f * kTexel + 1e-6f;

struct SurfaceSample {
  bool valid = false;
  double top = 0.0, bottom = 0.0;  // asset-frame z of the front / back surface
  Float3 front_normal{0.f, 0.f, 1.f}, back_normal{0.f, 0.f, -1.f};
};
using SurfaceFn = std::function<SurfaceSample(double x, double y)>;

struct GridSpec {
  uint32_t width = 0, height = 0;
  float origin_x = 0.f, origin_y = 0.f;
  float texel = kTexel;
  float front_z = 0.5f;
  float depth_range = 1.f;
};

// An empty pose of the grid with its arrays sized, in the given encodings, for every texel plus
// `gap_entries` gap-layer entries (body_map_data.h: (layers - 1) * gap_texels.size()).
BodyMapPose EmptyPose(const GridSpec& g, DepthEncoding depth_encoding,
                      NormalEncoding normal_encoding, size_t gap_entries = 0) {
  BodyMapPose pose;
  pose.width = g.width;
  pose.height = g.height;
  pose.origin_x = g.origin_x;
  pose.origin_y = g.origin_y;
  pose.texel_size = g.texel;
  pose.front_z = g.front_z;
  pose.depth_range = g.depth_range;
  pose.depth_encoding = depth_encoding;
  pose.normal_encoding = normal_encoding;
  const size_t entries = static_cast<size_t>(g.width) * g.height + gap_entries;
  for (int view = 0; view < 2; ++view) {
    if (depth_encoding == DepthEncoding::kFloat32) pose.depth_f32[view].resize(entries);
    if (depth_encoding == DepthEncoding::kUnorm16) pose.depth_u16[view].resize(entries);
    if (normal_encoding == NormalEncoding::kFloat32) pose.normal_f32[view].resize(3 * entries);
    if (normal_encoding == NormalEncoding::kOct16) pose.normal_oct16[view].resize(2 * entries);
    if (normal_encoding == NormalEncoding::kRgb8) pose.normal_rgb8[view].resize(3 * entries);
  }
  return pose;
}

// Writes array entry `index` of one view: the depth (metres from that view's plane) and normal
// of a surface, or background when !valid.
void PutSurface(BodyMapPose& pose, size_t index, int view, bool valid, double depth,
                Float3 normal) {
  if (pose.depth_encoding == DepthEncoding::kFloat32) {
    pose.depth_f32[view][index] = valid ? static_cast<float>(depth) : pose.depth_range;
  } else {
    const double q = std::round(depth / pose.depth_range * 65535.0);
    pose.depth_u16[view][index] =
        valid ? static_cast<uint16_t>(std::clamp(q, 0.0, 65534.0)) : uint16_t{65535};
  }
  const Float3 nv = valid ? normal : Float3{};
  if (pose.normal_encoding == NormalEncoding::kFloat32) {
    pose.normal_f32[view][3 * index] = nv.x;
    pose.normal_f32[view][3 * index + 1] = nv.y;
    pose.normal_f32[view][3 * index + 2] = nv.z;
  } else if (pose.normal_encoding == NormalEncoding::kOct16) {
    const std::array<uint16_t, 2> q = EncodeOct16(nv);
    pose.normal_oct16[view][2 * index] = q[0];
    pose.normal_oct16[view][2 * index + 1] = q[1];
  } else {
    const float c[3] = {nv.x, nv.y, nv.z};
    for (int a = 0; a < 3; ++a) {
      pose.normal_rgb8[view][3 * index + a] =
          static_cast<uint8_t>(std::lround((c[a] * 0.5f + 0.5f) * 255.f));
    }
  }
}

// Fills a pose by evaluating the surface at every texel centre, in the requested encodings.
BodyMapPose MakePose(const GridSpec& g, const SurfaceFn& surface,
                     DepthEncoding depth_encoding = DepthEncoding::kFloat32,
                     NormalEncoding normal_encoding = NormalEncoding::kFloat32) {
  BodyMapPose pose = EmptyPose(g, depth_encoding, normal_encoding);
  const double back_plane = static_cast<double>(g.front_z) - g.depth_range;
  for (uint32_t j = 0; j < g.height; ++j) {
    for (uint32_t i = 0; i < g.width; ++i) {
      const size_t k = static_cast<size_t>(j) * g.width + i;
      const double x = g.origin_x + (i + 0.5) * g.texel;
      const double y = g.origin_y + (j + 0.5) * g.texel;
      const SurfaceSample s = surface(x, y);
      PutSurface(pose, k, 0, s.valid, g.front_z - s.top, s.front_normal);
      PutSurface(pose, k, 1, s.valid, s.bottom - back_plane, s.back_normal);
    }
  }
  return pose;
}

// Sphere of radius 0.3 m at the origin on an 88 x 88 grid of 1/128 m texels.
constexpr double kSphereRadius = 0.3;
GridSpec SphereGrid() {
  GridSpec g;
  g.width = g.height = 88;
  g.origin_x = g.origin_y = -44.f * kTexel;
  return g;
}
double SphereHeight(double x, double y) {
  const double r2 = x * x + y * y;
  return r2 < kSphereRadius * kSphereRadius ? std::sqrt(kSphereRadius * kSphereRadius - r2) : -1.0;
}
SurfaceSample Sphere(double x, double y) {
  SurfaceSample s;
  const double h = SphereHeight(x, y);
  if (h < 0.0) return s;
  s.valid = true;
  s.top = h;
  s.bottom = -h;
  const auto r = static_cast<float>(kSphereRadius);
  s.front_normal = {static_cast<float>(x) / r, static_cast<float>(y) / r,
                    static_cast<float>(h) / r};
  s.back_normal = {static_cast<float>(x) / r, static_cast<float>(y) / r,
                   static_cast<float>(-h) / r};
  return s;
}

// Texel-aligned box: x in [-25, 25) texels, y in [-12, 12) texels, z in [-1/16, 1/16] (exact
// through the float depth encoding with front_z = 0.5, depth_range = 1).
constexpr float kBoxTop = 0.0625f, kBoxBottom = -0.0625f;
GridSpec BoxGrid() {
  GridSpec g;
  g.width = 64;
  g.height = 40;
  g.origin_x = -32.f * kTexel;
  g.origin_y = -20.f * kTexel;
  return g;
}
SurfaceSample Box(double x, double y) {
  SurfaceSample s;
  if (std::fabs(x) >= 25 * kTexel || std::fabs(y) >= 12 * kTexel) return s;
  s.valid = true;
  s.top = kBoxTop;
  s.bottom = kBoxBottom;
  return s;
}

// A horizontal slab 2 mm thick (z in [0, 0.002]), far thinner than the 10 cm steps thrown at it.
constexpr float kSlabThickness = 0.002f;
SurfaceSample ThinSlab(double x, double y) {
  SurfaceSample s;
  if (std::fabs(x) > 0.25 || std::fabs(y) > 0.25) return s;
  s.valid = true;
  s.top = kSlabThickness;
  s.bottom = 0.0;
  return s;
}

BodyMapCollider BuildOrDie(const BodyMapPose& pose,
                           DepthSampling sampling = DepthSampling::kNearest) {
  BodyMapCollider collider;
  const Status status = collider.Build(pose, sampling);
  EXPECT_TRUE(status.ok()) << status.message();
  return collider;
}

// In double via atan2(|a x b|, a.b): acos of a float dot product cannot resolve 0.01 degrees.
double AngleDegrees(Float3 a, Float3 b) {
  const double ax = a.x, ay = a.y, az = a.z, bx = b.x, by = b.y, bz = b.z;
  const double cx = ay * bz - az * by, cy = az * bx - ax * bz, cz = ax * by - ay * bx;
  const double cross = std::sqrt(cx * cx + cy * cy + cz * cz);
  return std::atan2(cross, ax * bx + ay * by + az * bz) * 180.0 / kPi;
}

// Exact first entry of p0 -> p1 into the union of the collider's texel columns
// [x_i, x_i + s] x [y_j, y_j + s] x [bottom, top] (nearest sampling; one column per interval
// when the texel has air gaps), by brute force in double over every texel. Returns -1 when the
// segment misses all of them.
double ReferenceFirstEntry(const BodyMapCollider& c, Float3 p0, Float3 p1) {
  double best = -1.0;
  const double s = c.texel_size();
  for (uint32_t j = 0; j < c.height(); ++j) {
    for (uint32_t i = 0; i < c.width(); ++i) {
      float top, bottom, upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers];
      if (!c.TexelSlab(i, j, &top, &bottom)) continue;
      // The texel's inside intervals: the slab split by its air gaps.
      const uint32_t gaps = c.TexelGaps(i, j, upper, lower);
      for (uint32_t interval = 0; interval <= gaps; ++interval) {
        const double lo[3] = {c.origin_x() + i * s, c.origin_y() + j * s,
                              interval == gaps ? bottom : upper[interval]};
        const double hi[3] = {c.origin_x() + (i + 1) * s, c.origin_y() + (j + 1) * s,
                              interval == 0 ? top : lower[interval - 1]};
        const double a[3] = {p0.x, p0.y, p0.z};
        const double d[3] = {static_cast<double>(p1.x) - p0.x, static_cast<double>(p1.y) - p0.y,
                             static_cast<double>(p1.z) - p0.z};
        double t0 = 0.0, t1 = 1.0;
        bool miss = false;
        for (int k = 0; k < 3 && !miss; ++k) {
          if (d[k] == 0.0) {
            miss = a[k] < lo[k] || a[k] > hi[k];
            continue;
          }
          double ta = (lo[k] - a[k]) / d[k], tb = (hi[k] - a[k]) / d[k];
          if (ta > tb) std::swap(ta, tb);
          t0 = std::max(t0, ta);
          t1 = std::min(t1, tb);
          miss = t0 > t1;
        }
        if (!miss && (best < 0.0 || t0 < best)) best = t0;
      }
    }
  }
  return best;
}

Float3 RandomPoint(std::mt19937& rng, float lo, float hi, float z_lo, float z_hi) {
  std::uniform_real_distribution<float> xy(lo, hi), z(z_lo, z_hi);
  const float x = xy(rng), y = xy(rng);
  return {x, y, z(rng)};
}

// Even k: a long segment from anywhere in a 0.8 m cube through a point near the shapes (many
// texels, the 8x8 block walk). Odd k: a short one (up to ~3 texels) near the surfaces.
void RandomSegment(std::mt19937& rng, int k, Float3* p0, Float3* p1) {
  const Float3 target = RandomPoint(rng, -0.25f, 0.25f, -0.2f, 0.2f);
  if (k % 2 == 0) {
    *p0 = RandomPoint(rng, -0.4f, 0.4f, -0.4f, 0.4f);
    *p1 = *p0 + (target - *p0) * 1.6f;
  } else {
    *p0 = target + RandomPoint(rng, -0.01f, 0.01f, -0.01f, 0.01f);
    *p1 = *p0 + RandomPoint(rng, -0.012f, 0.012f, -0.012f, 0.012f);
  }
}

// ---------------------------------------------------------------------------------------------

TEST(Oct16, RoundTripErrorBelowFiveThousandthsOfADegree) {
  std::mt19937 rng(7);
  std::normal_distribution<float> gauss;
  double worst = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const Float3 n = NormalizeOr({gauss(rng), gauss(rng), gauss(rng)}, {0.f, 0.f, 1.f});
    const std::array<uint16_t, 2> q = EncodeOct16(n);
    worst = std::max(worst, AngleDegrees(n, DecodeOct16(q[0], q[1])));
  }
  EXPECT_LT(worst, 0.005);  // notes/algorithms.md §0: 0.0037 degrees max
  const Float3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const Float3& a : axes) {
    const std::array<uint16_t, 2> q = EncodeOct16(a);
    EXPECT_LT(AngleDegrees(a, DecodeOct16(q[0], q[1])), 0.005);
  }
  EXPECT_LT(AngleDegrees(DecodeRgb8(128, 128, 255), {0.f, 0.f, 1.f}), 0.5);
}

TEST(BodyMapCollider, SphereClassificationAtTexelCentresIsTheSameForEveryEncoding) {
  const GridSpec g = SphereGrid();
  // 0.1 mm from either surface: well above the unorm16 step (1 m / 65535 = 15 um).
  constexpr double kMargin = 1e-4;
  const DepthEncoding depths[2] = {DepthEncoding::kFloat32, DepthEncoding::kUnorm16};
  const NormalEncoding normals[3] = {NormalEncoding::kFloat32, NormalEncoding::kOct16,
                                     NormalEncoding::kRgb8};
  for (DepthEncoding de : depths) {
    for (NormalEncoding ne : normals) {
      const BodyMapCollider c = BuildOrDie(MakePose(g, Sphere, de, ne));
      int checked = 0;
      for (uint32_t j = 0; j < g.height; ++j) {
        for (uint32_t i = 0; i < g.width; ++i) {
          const double x = g.origin_x + (i + 0.5) * g.texel, y = g.origin_y + (j + 0.5) * g.texel;
          const double h = SphereHeight(x, y);
          const auto at = [&](double z) {
            return c.IsInside(
                {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
          };
          if (h < 0.0) {
            EXPECT_FALSE(at(0.0)) << i << "," << j;
            continue;
          }
          if (h < 2 * kMargin) continue;
          EXPECT_TRUE(at(h - kMargin)) << i << "," << j;
          EXPECT_FALSE(at(h + kMargin)) << i << "," << j;
          EXPECT_TRUE(at(-h + kMargin)) << i << "," << j;
          EXPECT_FALSE(at(-h - kMargin)) << i << "," << j;
          EXPECT_TRUE(at(0.0));
          ++checked;
        }
      }
      EXPECT_GT(checked, 4000);
      EXPECT_FALSE(c.IsInside({0.f, 0.f, 0.31f}));
      EXPECT_FALSE(c.IsInside({1.f, 0.f, 0.f}));  // outside the stored rectangle
      EXPECT_FALSE(c.IsInside({-1.f, -1.f, 0.f}));
      // Normals within the encoding's error (rgb8: 0.385 degrees, oct16: 0.004).
      const double tolerance = ne == NormalEncoding::kRgb8 ? 0.8 : 0.01;  // degrees
      for (uint32_t t : {20u, 44u, 60u}) {
        const SurfaceSample s =
            Sphere(g.origin_x + (t + 0.5) * g.texel, g.origin_y + (44 + 0.5) * g.texel);
        EXPECT_LT(AngleDegrees(c.TexelNormal(t, 44, false), s.front_normal), tolerance);
        EXPECT_LT(AngleDegrees(c.TexelNormal(t, 44, true), s.back_normal), tolerance);
      }
    }
  }
}

TEST(BodyMapCollider, StraightDownOnSphereGivesSurfacePointAndNormal) {
  const BodyMapCollider c = BuildOrDie(MakePose(SphereGrid(), Sphere));
  EXPECT_EQ(c.width(), 88u);
  EXPECT_FLOAT_EQ(c.texel_size(), kTexel);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> xy(-0.25f, 0.25f);
  int contacts = 0;
  for (int k = 0; k < 500; ++k) {
    const float x = xy(rng), y = xy(rng);
    if (std::sqrt(x * x + y * y) > 0.8 * kSphereRadius) continue;
    // Pure z motion: a zero-length 2D segment visits one texel.
    const ContactQuery q = c.Query({x, y, 0.5f}, {x, y, 0.f});
    ASSERT_TRUE(q.contact);
    ++contacts;
    EXPECT_TRUE(q.inside_end);
    EXPECT_EQ(q.flags, kCollisionNone);
    // Nearest sampling: the surface is the height at the texel centre, at most |grad h| * s/sqrt2
    // (slope <= 0.8/0.6 here) from the true height.
    const double slope_bound = 0.8 / 0.6 * kTexel * 0.7072 + 1e-6;
    EXPECT_NEAR(q.point.z, SphereHeight(x, y), slope_bound);
    EXPECT_FLOAT_EQ(q.point.x, x);
    EXPECT_FLOAT_EQ(q.point.y, y);
    EXPECT_NEAR(q.t, (0.5 - q.point.z) / 0.5, 1e-6);
    // Normal: the texel centre's analytic normal (oct16 re-encoded float: < 0.005 degrees).
    const double xc = c.origin_x() + (std::floor((x - c.origin_x()) / kTexel) + 0.5) * kTexel;
    const double yc = c.origin_y() + (std::floor((y - c.origin_y()) / kTexel) + 0.5) * kTexel;
    const Float3 expected = NormalizeOr(
        {static_cast<float>(xc), static_cast<float>(yc), static_cast<float>(SphereHeight(xc, yc))},
        {});
    EXPECT_LT(AngleDegrees(q.normal, expected), 0.01);
    EXPECT_NEAR(q.depth, q.point.z, 1e-6);  // p1 at z = 0, nearer surface is the front one
    // From below: enters through the back surface, back normal.
    const ContactQuery b = c.Query({x, y, -0.5f}, {x, y, 0.f});
    ASSERT_TRUE(b.contact);
    EXPECT_LT(b.point.z, 0.f);
    EXPECT_LT(b.normal.z, 0.f);
    EXPECT_NEAR(b.point.z, -q.point.z, 1e-6);
  }
  EXPECT_GT(contacts, 200);
}

// The walk against an exact brute-force reference over every texel column, for random segments
// of every length (short ones walk texel by texel, long ones use the 8x8 min/max blocks).
// Query against the brute-force first entry on `segments` random segments (RandomSegment) that
// start outside: contact, t, point on the segment and a unit normal. `start` sees each p0.
struct WalkCounts {
  int hits = 0, misses = 0, side_walls = 0;
};
WalkCounts ExpectWalkMatchesReference(const BodyMapCollider& c, uint32_t seed, int segments,
                                      const std::function<void(Float3)>& start = {}) {
  std::mt19937 rng(seed);
  WalkCounts counts;
  for (int k = 0; k < segments; ++k) {
    Float3 p0, p1;
    RandomSegment(rng, k, &p0, &p1);
    if (c.IsInside(p0)) continue;
    if (start) start(p0);
    const ContactQuery q = c.Query(p0, p1);
    const double reference = ReferenceFirstEntry(c, p0, p1);
    EXPECT_EQ(q.inside_end, c.IsInside(p1));
    EXPECT_TRUE(!q.inside_end || q.contact);
    EXPECT_EQ(q.contact, reference >= 0.0) << "segment " << k << " ref " << reference;
    if (!q.contact || reference < 0.0) {
      ++counts.misses;
      continue;
    }
    ++counts.hits;
    if (q.flags & kCollisionSideWall) ++counts.side_walls;
    // t resolution: float positions (~1e-7 m here) over the segment's length.
    EXPECT_NEAR(q.t, reference, 2e-6 + 2e-7 / Length(p1 - p0)) << "segment " << k;
    // The point lies on the segment (x, y exactly up to rounding) and on the surface (z).
    const Float3 on_segment = Lerp(p0, p1, q.t);
    EXPECT_NEAR(q.point.x, on_segment.x, 1e-5) << "segment " << k;
    EXPECT_NEAR(q.point.y, on_segment.y, 1e-5) << "segment " << k;
    EXPECT_NEAR(q.point.z, on_segment.z, 1e-5) << "segment " << k;
    EXPECT_NEAR(Length(q.normal), 1.f, 1e-5);
  }
  return counts;
}

TEST(BodyMapCollider, WalkMatchesExactReferenceOnRandomSegments) {
  for (int shape = 0; shape < 2; ++shape) {
    const BodyMapCollider c = shape == 0 ? BuildOrDie(MakePose(SphereGrid(), Sphere))
                                         : BuildOrDie(MakePose(BoxGrid(), Box));
    const WalkCounts n = ExpectWalkMatchesReference(c, 11 + shape, 1200);
    std::printf("shape %d: %d hits (%d side walls), %d misses\n", shape, n.hits, n.side_walls,
                n.misses);
    EXPECT_GT(n.hits, 200) << shape;
    EXPECT_GT(n.misses, 50) << shape;
    EXPECT_GT(n.side_walls, 20) << shape;
  }
}

TEST(BodyMapCollider, FastParticleThroughThinSlabIsCaught) {
  const BodyMapCollider c = BuildOrDie(MakePose(SphereGrid(), ThinSlab));
  // 10 cm per step across a 2 mm slab: both end points are outside.
  const Float3 p0{0.01f, 0.02f, 0.05f}, p1{0.01f, 0.02f, -0.05f};
  EXPECT_FALSE(c.IsInside(p0));
  EXPECT_FALSE(c.IsInside(p1));  // an endpoint-only test (paper A literal) misses this one
  const ContactQuery q = c.Query(p0, p1);
  ASSERT_TRUE(q.contact);
  EXPECT_FALSE(q.inside_end);
  EXPECT_FLOAT_EQ(q.depth, 0.f);
  EXPECT_NEAR(q.t, (0.05 - kSlabThickness) / 0.1, 1e-6);
  EXPECT_NEAR(q.point.z, kSlabThickness, 1e-7);
  EXPECT_LT(AngleDegrees(q.normal, {0.f, 0.f, 1.f}), 0.01);
  // From below, entering through the back surface, with the back normal (-z), not an average.
  const ContactQuery b = c.Query(p1, p0);
  ASSERT_TRUE(b.contact);
  EXPECT_NEAR(b.t, 0.5, 1e-6);
  EXPECT_LT(AngleDegrees(b.normal, {0.f, 0.f, -1.f}), 0.01);
  // Diagonally across many texels: caught in the texel where z crosses the slab.
  const Float3 d0{-0.2f, -0.1f, 0.04f}, d1{0.2f, 0.15f, -0.04f};
  const ContactQuery diagonal = c.Query(d0, d1);
  ASSERT_TRUE(diagonal.contact);
  EXPECT_NEAR(diagonal.t, (0.04 - kSlabThickness) / 0.08, 1e-5);
  EXPECT_EQ(diagonal.flags, kCollisionNone);
}

TEST(BodyMapCollider, SideWallEntryIsFlaggedWithTheNearerSurfacesNormal) {
  const BodyMapCollider c = BuildOrDie(MakePose(BoxGrid(), Box));
  const float edge = -25.f * kTexel;  // the box's -x side, a texel edge
  const ContactQuery q = c.Query({-0.3f, 0.f, 0.03f}, {-0.1f, 0.f, 0.03f});
  ASSERT_TRUE(q.contact);
  EXPECT_TRUE(q.flags & kCollisionSideWall);
  EXPECT_NEAR(q.point.x, edge, kWallTolerance);
  EXPECT_LT(q.point.x, edge) << "the contact point is on the outer side of the wall";
  EXPECT_FALSE(c.IsInside(q.point)) << "a particle placed at the contact must not test inside";
  EXPECT_NEAR(q.t, (edge + 0.3) / 0.2, 1e-5);
  EXPECT_LT(AngleDegrees(q.normal, {0.f, 0.f, 1.f}), 0.01);  // z = 0.03 is nearer the front
  const ContactQuery low = c.Query({-0.3f, 0.f, -0.03f}, {-0.1f, 0.f, -0.03f});
  ASSERT_TRUE(low.contact);
  EXPECT_LT(AngleDegrees(low.normal, {0.f, 0.f, -1.f}), 0.01);
}

TEST(BodyMapCollider, GrazingSegments) {
  const BodyMapCollider c = BuildOrDie(MakePose(BoxGrid(), Box));
  // Sinking by 2 um over 40 texels: crosses the top surface half way, through the front.
  const ContactQuery q = c.Query({-0.15f, 0.f, kBoxTop + 1e-6f}, {0.15f, 0.f, kBoxTop - 1e-6f});
  ASSERT_TRUE(q.contact);
  EXPECT_EQ(q.flags, kCollisionNone);
  EXPECT_NEAR(q.t, 0.5, 0.02);
  EXPECT_FLOAT_EQ(q.point.z, kBoxTop);
  EXPECT_GE(q.t, 0.f);
  EXPECT_LE(q.t, 1.f);
  // Parallel, 1 um above: no contact. Parallel exactly on the surface (z = top is inside):
  // entered through the box's side wall.
  EXPECT_FALSE(c.Query({-0.3f, 0.f, kBoxTop + 1e-6f}, {0.3f, 0.f, kBoxTop + 1e-6f}).contact);
  const ContactQuery on = c.Query({-0.3f, 0.f, kBoxTop}, {0.3f, 0.f, kBoxTop});
  ASSERT_TRUE(on.contact);
  EXPECT_TRUE(on.flags & kCollisionSideWall);
  EXPECT_NEAR(on.point.x, -25.f * kTexel, kWallTolerance);
}

TEST(BodyMapCollider, PointsExactlyOnTexelBoundaries) {
  const BodyMapCollider c = BuildOrDie(MakePose(BoxGrid(), Box));
  // Texel (i) covers [x_i, x_i + s): the box's low edges belong to it, its high edges do not.
  const float lo = -25.f * kTexel, hi = 25.f * kTexel;
  EXPECT_TRUE(c.IsInside({lo, 0.f, 0.f}));
  EXPECT_FALSE(c.IsInside({hi, 0.f, 0.f}));
  EXPECT_TRUE(c.IsInside({0.f, -12.f * kTexel, 0.f}));
  EXPECT_FALSE(c.IsInside({0.f, 12.f * kTexel, 0.f}));
  EXPECT_TRUE(c.IsInside({0.f, 0.f, kBoxTop}));  // both surfaces are inside (closed slab)
  EXPECT_TRUE(c.IsInside({0.f, 0.f, kBoxBottom}));
  // Segments running exactly along a texel edge agree with the point test.
  EXPECT_FALSE(c.Query({hi, -0.2f, 0.f}, {hi, 0.2f, 0.f}).contact);
  const ContactQuery along = c.Query({lo, -0.2f, 0.f}, {lo, 0.2f, 0.f});
  ASSERT_TRUE(along.contact);
  EXPECT_NEAR(along.point.y, -12.f * kTexel, kWallTolerance);
  EXPECT_TRUE(along.flags & kCollisionSideWall);
  // Ending exactly on the high edge (just outside), coming along x: no contact.
  EXPECT_FALSE(c.Query({0.3f, 0.f, 0.f}, {hi, 0.f, 0.f}).contact);
  // Exactly through a texel corner of the box.
  const ContactQuery corner =
      c.Query({lo - 0.05f, -12.f * kTexel - 0.05f, 0.f}, {lo, -12.f * kTexel, 0.f});
  ASSERT_TRUE(corner.contact);
  EXPECT_NEAR(corner.t, 1.0, 1e-6);
}

TEST(BodyMapCollider, StartInsidePushesOutToTheNearerSurface) {
  const BodyMapCollider c = BuildOrDie(MakePose(BoxGrid(), Box));
  const ContactQuery up = c.Query({0.01f, 0.01f, 0.03f}, {0.02f, 0.01f, 0.03f});
  ASSERT_TRUE(up.contact);
  EXPECT_EQ(up.flags, kCollisionStartedInside);
  EXPECT_FLOAT_EQ(up.t, 0.f);
  EXPECT_FLOAT_EQ(up.point.x, 0.02f);  // p1 is pushed out along z
  EXPECT_FLOAT_EQ(up.point.z, kBoxTop);
  EXPECT_NEAR(up.depth, kBoxTop - 0.03f, 1e-7);
  EXPECT_LT(AngleDegrees(up.normal, {0.f, 0.f, 1.f}), 0.01);
  const ContactQuery down = c.Query({0.f, 0.f, -0.04f}, {0.f, 0.f, -0.04f});
  ASSERT_TRUE(down.contact);
  EXPECT_EQ(down.flags, kCollisionStartedInside);
  EXPECT_FLOAT_EQ(down.point.z, kBoxBottom);
  EXPECT_NEAR(down.depth, -0.04f - kBoxBottom, 1e-7);
  EXPECT_LT(AngleDegrees(down.normal, {0.f, 0.f, -1.f}), 0.01);
  // Leaving the body by itself: no contact.
  EXPECT_FALSE(c.Query({0.f, 0.f, 0.f}, {0.f, 0.f, 0.2f}).contact);
}

TEST(BodyMapCollider, StartInsideThenReEnteringAnotherPartIsASweptContact) {
  // Two boxes with a 10-texel gap: x in [-25, -5) and [5, 25) texels.
  const auto two_boxes = [](double x, double y) {
    SurfaceSample s = Box(x, y);
    if (std::fabs(x) < 5 * kTexel) s.valid = false;
    return s;
  };
  const BodyMapCollider c = BuildOrDie(MakePose(BoxGrid(), two_boxes));
  const ContactQuery q = c.Query({-0.1f, 0.f, 0.f}, {0.1f, 0.f, 0.f});
  ASSERT_TRUE(q.contact);
  EXPECT_EQ(q.flags, kCollisionSideWall);  // not kCollisionStartedInside
  EXPECT_NEAR(q.point.x, 5.f * kTexel, kWallTolerance);
}

TEST(BodyMapCollider, ResponseFollowsPaperEquation5) {
  const BodyMapCollider c = BuildOrDie(MakePose(BoxGrid(), Box));
  ResponseParams params;
  params.friction = 0.3f;
  params.restitution = 0.5f;
  params.separation = 1e-4f;
  // 0: falls onto the top. 1: same motion but a separating velocity (+z). 2: free, untouched.
  // 3: NaN position. 4: infinite velocity.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<Float3> previous = {
      {0.f, 0.f, 0.1f}, {0.f, 0.f, 0.1f}, {0.f, 0.f, 0.3f}, {0.f, 0.f, 0.1f}, {0.f, 0.f, 0.1f}};
  std::vector<Float3> positions = {
      {0.f, 0.f, 0.f}, {0.f, 0.f, 0.f}, {0.f, 0.f, 0.2f}, {nan, 0.f, 0.f}, {0.f, 0.f, 0.f}};
  std::vector<Float3> velocities = {{1.f, 0.f, -2.f},
                                    {1.f, 0.f, 1.f},
                                    {1.f, 2.f, -3.f},
                                    {1.f, 0.f, -2.f},
                                    {std::numeric_limits<float>::infinity(), 0.f, 0.f}};
  std::vector<uint8_t> flags(5, 0xff);
  uint32_t contacts = 0;
  ASSERT_TRUE(c.CollideBatch(previous, positions, velocities, flags, params, &contacts).ok());
  EXPECT_EQ(contacts, 2u);
  // V.N = -2 < 0: V_n = (0, 0, -2), V' = (V - V_n)(1 - 0.3) - V_n * 0.5 = (0.7, 0, 1), up to the
  // oct16 normal (+z is 0.0012 degrees off: 65535 steps have no exact midpoint).
  EXPECT_EQ(flags[0], kCollisionContact);
  EXPECT_NEAR(positions[0].z, kBoxTop + params.separation, 1e-6);
  EXPECT_NEAR(velocities[0].x, 0.7f, 1e-4);
  EXPECT_NEAR(velocities[0].y, 0.f, 1e-4);
  EXPECT_NEAR(velocities[0].z, 1.f, 1e-4);
  {  // exactly eq. 5 with the contact's own normal
    const ContactQuery q = c.Query(previous[0], {0.f, 0.f, 0.f});
    const Float3 v{1.f, 0.f, -2.f};
    const Float3 vn = q.normal * Dot(v, q.normal);
    const Float3 expected = (v - vn) * (1.f - params.friction) - vn * params.restitution;
    EXPECT_NEAR(velocities[0].x, expected.x, 1e-6);
    EXPECT_NEAR(velocities[0].y, expected.y, 1e-6);
    EXPECT_NEAR(velocities[0].z, expected.z, 1e-6);
    EXPECT_NEAR(positions[0].x, q.point.x + q.normal.x * params.separation, 1e-7);
  }
  // Separating (V.N > 0): the position is put on the surface, the velocity is kept.
  EXPECT_EQ(flags[1], kCollisionContact);
  EXPECT_NEAR(positions[1].z, kBoxTop + params.separation, 1e-6);
  EXPECT_EQ(velocities[1].x, 1.f);
  EXPECT_EQ(velocities[1].z, 1.f);
  EXPECT_EQ(flags[2], kCollisionNone);
  EXPECT_EQ(positions[2].z, 0.2f);
  EXPECT_EQ(velocities[2].y, 2.f);
  EXPECT_EQ(flags[3], kCollisionInvalidInput);
  EXPECT_TRUE(std::isnan(positions[3].x));
  EXPECT_EQ(velocities[3].z, -2.f);
  EXPECT_EQ(flags[4], kCollisionInvalidInput);
  EXPECT_EQ(positions[4].z, 0.f);
  // A query with NaN reports invalid input and no contact.
  const ContactQuery bad = c.Query({nan, 0.f, 0.f}, {0.f, 0.f, 0.f});
  EXPECT_FALSE(bad.contact);
  EXPECT_EQ(bad.flags, kCollisionInvalidInput);
  // Mismatched spans are an error, not a crash.
  std::vector<uint8_t> short_flags(2);
  EXPECT_EQ(c.CollideBatch(previous, positions, velocities, short_flags, params).code(),
            StatusCode::kInvalidArgument);
}

TEST(BodyMapCollider, HugeCoordinatesAreClippedNotOverflowed) {
  const BodyMapCollider c = BuildOrDie(MakePose(BoxGrid(), Box));
  const ContactQuery q = c.Query({1e30f, 0.f, 0.f}, {-1e30f, 0.f, 0.f});
  ASSERT_TRUE(q.contact);
  EXPECT_TRUE(q.flags & kCollisionSideWall);
  EXPECT_NEAR(q.point.x, 25.f * kTexel, 2e-3);  // the +x side (float t resolution at 1e30)
  EXPECT_NEAR(q.t, 0.5, 1e-6);
  const float big = 3e38f;
  EXPECT_FALSE(c.Query({big, big, big}, {big, -big, big}).contact);
  // Through the origin from +-3e38: the double clip cannot place the crossing to the metre, but
  // the walk stays bounded by the map and the answer is well formed.
  const ContactQuery through = c.Query({big, big, big}, {-big, -big, -big});
  EXPECT_GE(through.t, 0.f);
  EXPECT_LE(through.t, 1.f);
  EXPECT_TRUE(IsFinite(through.point));
  EXPECT_FALSE(c.IsInside({big, 0.f, 0.f}));
  // Found by fuzzing: the exit parameter rounds to exactly 1 in double although p1 is 9e9 m
  // outside the box; the end must still be clamped (an unclamped end overflowed the walk).
  const ContactQuery far = c.Query({0.3f, 4.4e27f, 0.f}, {-0.39f, -8.9e9f, 0.45f});
  EXPECT_FALSE(far.inside_end);
  EXPECT_GE(far.t, 0.f);
  EXPECT_LE(far.t, 1.f);
  EXPECT_TRUE(IsFinite(far.point));
}

TEST(BodyMapCollider, BilinearDepthIsMoreAccurateThanNearestOnASphere) {
  const BodyMapPose pose = MakePose(SphereGrid(), Sphere);
  const BodyMapCollider nearest = BuildOrDie(pose, DepthSampling::kNearest);
  const BodyMapCollider bilinear = BuildOrDie(pose, DepthSampling::kBilinear);
  EXPECT_GT(bilinear.stats().bilinear_blocks, 3500u);  // of ~4600 texels on the disc
  EXPECT_EQ(nearest.stats().bilinear_blocks, 0u);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> xy(-0.25f, 0.25f);
  double sum[2] = {0, 0}, worst[2] = {0, 0}, normal_sum[2] = {0, 0};
  int n = 0;
  for (int k = 0; k < 2000; ++k) {
    const float x = xy(rng), y = xy(rng);
    const double h = SphereHeight(x, y);
    if (std::sqrt(x * x + y * y) > 0.8 * kSphereRadius) continue;
    const Float3 truth_normal{x, y, static_cast<float>(h)};
    const BodyMapCollider* colliders[2] = {&nearest, &bilinear};
    for (int m = 0; m < 2; ++m) {
      const ContactQuery q = colliders[m]->Query({x, y, 0.5f}, {x, y, 0.f});
      ASSERT_TRUE(q.contact);
      const double error = std::fabs(q.point.z - h);
      sum[m] += error;
      worst[m] = std::max(worst[m], error);
      normal_sum[m] += AngleDegrees(q.normal, truth_normal);
    }
    ++n;
  }
  ASSERT_GT(n, 500);
  // Nearest: error ~ slope * s / 2 (mm). Bilinear: ~ curvature * s^2 / 8 (um).
  std::printf("depth error mean/max: nearest %.3g/%.3g m, bilinear %.3g/%.3g m\n", sum[0] / n,
              worst[0], sum[1] / n, worst[1]);
  EXPECT_LT(sum[1], 0.1 * sum[0]) << "mean nearest " << sum[0] / n << " bilinear " << sum[1] / n;
  EXPECT_LT(worst[1], worst[0]);
  EXPECT_LT(worst[1], 4e-4);  // s^2 / 8 * |h''| * 2 at r = 0.8 R
  EXPECT_LT(normal_sum[1], normal_sum[0]);
}

TEST(BodyMapCollider, BilinearWalkAgreesWithBilinearPointTest) {
  const BodyMapCollider c = BuildOrDie(MakePose(SphereGrid(), Sphere), DepthSampling::kBilinear);
  std::mt19937 rng(21);
  int hits = 0;
  for (int k = 0; k < 600; ++k) {
    Float3 p0, p1;
    RandomSegment(rng, k, &p0, &p1);
    if (c.IsInside(p0)) continue;
    const ContactQuery q = c.Query(p0, p1);
    EXPECT_EQ(q.inside_end, c.IsInside(p1));
    EXPECT_TRUE(!q.inside_end || q.contact);
    // Dense sampling of the point test: the walk never reports its entry later than the first
    // inside sample, and every swept contact lies on the segment.
    constexpr int kSamples = 20000;
    int first = -1;
    for (int s = 0; s <= kSamples && first < 0; ++s) {
      if (c.IsInside(Lerp(p0, p1, static_cast<float>(s) / kSamples))) first = s;
    }
    if (first >= 0) {
      ASSERT_TRUE(q.contact) << k;
      EXPECT_LE(q.t, static_cast<double>(first) / kSamples + 1e-5) << k;
      ++hits;
    }
    if (q.contact) {
      const Float3 on_segment = Lerp(p0, p1, q.t);
      EXPECT_NEAR(q.point.x, on_segment.x, 1e-5);
      EXPECT_NEAR(q.point.y, on_segment.y, 1e-5);
      EXPECT_NEAR(q.point.z, on_segment.z, 1e-4);
      // On the true sphere within the bilinear error (the silhouette blocks are nearest).
      if (!(q.flags & kCollisionSideWall)) {
        EXPECT_NEAR(Length(q.point), kSphereRadius, 2.0 * kTexel) << k;
      }
    }
  }
  EXPECT_GT(hits, 150);
}

TEST(BodyMapCollider, BatchIsBitwiseIdenticalAtOneAndTwoThreads) {
  const BodyMapCollider c = BuildOrDie(MakePose(SphereGrid(), Sphere));
  std::mt19937 rng(9);
  constexpr size_t kCount = 20000;
  std::vector<Float3> previous(kCount), positions(kCount), velocities(kCount);
  for (size_t k = 0; k < kCount; ++k) {
    previous[k] = RandomPoint(rng, -0.35f, 0.35f, -0.35f, 0.35f);
    positions[k] = previous[k] + RandomPoint(rng, -0.05f, 0.05f, -0.05f, 0.05f);
    velocities[k] = RandomPoint(rng, -1.f, 1.f, -1.f, 1.f);
  }
  const ResponseParams params;
  std::vector<Float3> result_positions[2], result_velocities[2];
  std::vector<uint8_t> result_flags[2];
  uint32_t contacts[2] = {0, 0};
  const int saved_threads = omp_get_max_threads();
  for (int run = 0; run < 2; ++run) {
    omp_set_num_threads(run + 1);
    result_positions[run] = positions;
    result_velocities[run] = velocities;
    result_flags[run].assign(kCount, 0);
    ASSERT_TRUE(c.CollideBatch(previous, result_positions[run], result_velocities[run],
                               result_flags[run], params, &contacts[run])
                    .ok());
  }
  omp_set_num_threads(saved_threads);
  EXPECT_GT(contacts[0], 1000u);
  EXPECT_EQ(contacts[0], contacts[1]);
  EXPECT_EQ(0, std::memcmp(result_positions[0].data(), result_positions[1].data(),
                           kCount * sizeof(Float3)));
  EXPECT_EQ(0, std::memcmp(result_velocities[0].data(), result_velocities[1].data(),
                           kCount * sizeof(Float3)));
  EXPECT_EQ(result_flags[0], result_flags[1]);
  // And each equals the single query.
  for (size_t k = 0; k < kCount; k += 97) {
    const ContactQuery q = c.Query(previous[k], positions[k]);
    EXPECT_EQ(q.contact, (result_flags[0][k] & kCollisionContact) != 0);
  }
}

TEST(BodyMapCollider, BuildRejectsInconsistentData) {
  const BodyMapPose good = MakePose(BoxGrid(), Box);
  const auto expect_rejected = [](const BodyMapPose& pose, const char* what) {
    BodyMapCollider c;
    const Status status = c.Build(pose);
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << what;
    EXPECT_FALSE(status.message().empty()) << what;
    EXPECT_TRUE(c.empty()) << what;
    EXPECT_FALSE(c.IsInside({0.f, 0.f, 0.f})) << what;
    EXPECT_FALSE(c.Query({0.f, 0.f, 1.f}, {0.f, 0.f, -1.f}).contact) << what;
  };
  BodyMapPose p = good;
  p.depth_f32[1].pop_back();
  expect_rejected(p, "short back depth");
  p = good;
  p.normal_f32[0].push_back(0.f);
  expect_rejected(p, "long front normals");
  p = good;
  p.texel_size = 0.f;
  expect_rejected(p, "zero texel size");
  p = good;
  p.texel_size = std::numeric_limits<float>::quiet_NaN();
  expect_rejected(p, "NaN texel size");
  p = good;
  p.depth_range = -1.f;
  expect_rejected(p, "negative depth range");
  p = good;
  p.depth_f32[0][100] = std::numeric_limits<float>::quiet_NaN();
  expect_rejected(p, "NaN depth");
  p = good;
  p.depth_f32[1][7] = -0.5f;
  expect_rejected(p, "negative depth");
  p = good;
  p.normal_f32[1][5] = std::numeric_limits<float>::infinity();
  expect_rejected(p, "infinite normal");
  p = good;
  p.width = 0;
  expect_rejected(p, "zero width");
  p = good;
  p.origin_x = std::numeric_limits<float>::infinity();
  expect_rejected(p, "infinite origin");
  p = good;
  p.depth_u16[0].resize(p.depth_f32[0].size());
  expect_rejected(p, "an unchosen encoding filled");
  p = good;
  p.depth_encoding = static_cast<DepthEncoding>(9);
  expect_rejected(p, "unknown encoding");
  // Not built: the batch says so.
  BodyMapCollider unbuilt;
  std::vector<Float3> a(1), b(1), v(1);
  std::vector<uint8_t> f(1);
  EXPECT_EQ(unbuilt.CollideBatch(a, b, v, f, ResponseParams{}).code(), StatusCode::kInvalidState);
}

TEST(BodyMapCollider, SilhouetteDisagreementIsBackgroundAndCounted) {
  BodyMapPose p = MakePose(BoxGrid(), Box);
  const size_t k = 20 * 64 + 32;      // texel (32, 20): inside the box
  p.depth_f32[1][k] = p.depth_range;  // the back map says background there
  const BodyMapCollider c = BuildOrDie(p);
  EXPECT_EQ(c.stats().one_sided_texels, 1u);
  EXPECT_FALSE(c.IsInside({0.5f * kTexel, 0.5f * kTexel, 0.f}));
  EXPECT_TRUE(c.IsInside({1.5f * kTexel, 0.5f * kTexel, 0.f}));
  EXPECT_EQ(c.stats().valid_texels, 50u * 24u - 1u);
  // 16 bytes per texel plus small change.
  EXPECT_GE(c.memory_bytes(), 64u * 40u * 16u);
  EXPECT_LT(c.memory_bytes(), 64u * 40u * 16u + 2048u);
}

// --- Row-span layout: the same grid as the dense layout, bit for bit -------------------------

uint32_t Bits(float v) { return std::bit_cast<uint32_t>(v); }

// The bake writes zero normal codes on background and the row-span layout cannot carry any
// other value there (expanding it writes zeros), so the dense reference gets the same.
void ZeroBackgroundNormals(BodyMapPose& pose) {
  const size_t n = static_cast<size_t>(pose.width) * pose.height;
  for (size_t k = 0; k < n; ++k) {
    const bool background =
        pose.depth_encoding == DepthEncoding::kFloat32
            ? pose.depth_f32[0][k] >= pose.depth_range && pose.depth_f32[1][k] >= pose.depth_range
            : pose.depth_u16[0][k] == 65535 && pose.depth_u16[1][k] == 65535;
    if (!background) continue;
    for (int view = 0; view < 2; ++view) {
      for (size_t c = 0; c < pose.normal_f32[view].size() / n; ++c)
        pose.normal_f32[view][3 * k + c] = 0.f;
      for (size_t c = 0; c < pose.normal_oct16[view].size() / n; ++c)
        pose.normal_oct16[view][2 * k + c] = 0;
      for (size_t c = 0; c < pose.normal_rgb8[view].size() / n; ++c)
        pose.normal_rgb8[view][3 * k + c] = 0;
    }
  }
}

void ExpectSameBits(Float3 a, Float3 b, const char* what, int k) {
  EXPECT_EQ(Bits(a.x), Bits(b.x)) << what << " " << k;
  EXPECT_EQ(Bits(a.y), Bits(b.y)) << what << " " << k;
  EXPECT_EQ(Bits(a.z), Bits(b.z)) << what << " " << k;
}

// What CollideBatch must answer for these motions: Query and ApplyResponse, particle by
// particle (the queries too, for the callers' counts).
struct OneByOne {
  std::vector<ContactQuery> queries;
  std::vector<Float3> positions, velocities;
  std::vector<uint8_t> flags;
};
OneByOne QueryOneByOne(const BodyMapCollider& c, const std::vector<Float3>& previous,
                       const std::vector<Float3>& positions, const std::vector<Float3>& velocities,
                       const ResponseParams& params) {
  OneByOne want{{}, positions, velocities, std::vector<uint8_t>(positions.size())};
  for (size_t k = 0; k < positions.size(); ++k) {
    const ContactQuery q = c.Query(previous[k], positions[k]);
    want.queries.push_back(q);
    want.flags[k] = q.contact ? static_cast<uint8_t>(kCollisionContact | q.flags)
                              : static_cast<uint8_t>(kCollisionNone);
    if (q.contact) ApplyResponse(q, params, &want.positions[k], &want.velocities[k]);
  }
  return want;
}

// Every field of two answers, bit for bit (query k).
void ExpectSameAnswer(const ContactQuery& a, const ContactQuery& b, int k) {
  EXPECT_EQ(a.inside_end, b.inside_end) << k;
  EXPECT_EQ(a.contact, b.contact) << k;
  EXPECT_EQ(Bits(a.t), Bits(b.t)) << k;
  ExpectSameBits(a.point, b.point, "point", k);
  ExpectSameBits(a.normal, b.normal, "normal", k);
  EXPECT_EQ(Bits(a.depth), Bits(b.depth)) << k;
  EXPECT_EQ(a.flags, b.flags) << k;
}

// Every texel's slab and normals, the bounds and stats, and `segments` random queries: equal bit
// for bit. Segments run between points of the colliders' box widened by `pad` metres.
void ExpectIdenticalColliders(const BodyMapCollider& a, const BodyMapCollider& b, int segments,
                              float pad) {
  ASSERT_EQ(a.width(), b.width());
  ASSERT_EQ(a.height(), b.height());
  EXPECT_EQ(Bits(a.origin_x()), Bits(b.origin_x()));
  EXPECT_EQ(Bits(a.origin_y()), Bits(b.origin_y()));
  EXPECT_EQ(Bits(a.texel_size()), Bits(b.texel_size()));
  ExpectSameBits(a.bounds_min(), b.bounds_min(), "bounds_min", 0);
  ExpectSameBits(a.bounds_max(), b.bounds_max(), "bounds_max", 0);
  EXPECT_EQ(a.stats().valid_texels, b.stats().valid_texels);
  EXPECT_EQ(a.stats().one_sided_texels, b.stats().one_sided_texels);
  EXPECT_EQ(a.stats().inverted_texels, b.stats().inverted_texels);
  EXPECT_EQ(a.stats().bilinear_blocks, b.stats().bilinear_blocks);
  EXPECT_EQ(a.memory_bytes(), b.memory_bytes());
  size_t different = 0;
  for (uint32_t j = 0; j < a.height(); ++j) {
    for (uint32_t i = 0; i < a.width(); ++i) {
      float at = 0.f, ab = 0.f, bt = 0.f, bb = 0.f;
      const bool av = a.TexelSlab(i, j, &at, &ab), bv = b.TexelSlab(i, j, &bt, &bb);
      for (bool back : {false, true}) {
        const Float3 an = a.TexelNormal(i, j, back), bn = b.TexelNormal(i, j, back);
        different +=
            Bits(an.x) != Bits(bn.x) || Bits(an.y) != Bits(bn.y) || Bits(an.z) != Bits(bn.z);
      }
      different += av != bv || Bits(at) != Bits(bt) || Bits(ab) != Bits(bb);
    }
  }
  EXPECT_EQ(different, 0u) << "texels whose slab or normals differ";
  const Float3 lo = a.bounds_min(), hi = a.bounds_max();
  std::mt19937 rng(20261122);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  const auto point = [&] {
    return Float3{lo.x - pad + unit(rng) * (hi.x - lo.x + 2.f * pad),
                  lo.y - pad + unit(rng) * (hi.y - lo.y + 2.f * pad),
                  lo.z - pad + unit(rng) * (hi.z - lo.z + 2.f * pad)};
  };
  int contacts = 0;
  for (int k = 0; k < segments; ++k) {
    const Float3 p0 = point();
    // Alternately long segments across the box and short ones (a few texels).
    const Float3 p1 = k % 2 == 0 ? point() : p0 + (point() - p0) * 0.02f;
    const ContactQuery qa = a.Query(p0, p1), qb = b.Query(p0, p1);
    ExpectSameAnswer(qa, qb, k);
    EXPECT_EQ(a.IsInside(p1), b.IsInside(p1)) << k;
    contacts += qa.contact;
  }
  EXPECT_GT(contacts, segments / 20) << "the segments must exercise contacts";
}

// Query's quick paths (one texel, clearly through air) give exactly the general path's answer:
// points, sub-texel motions, short and long ones, starting inside, beyond the box in z, on
// texel edges, on the three analytic bodies, in both samplings.
TEST(BodyMapCollider, QuickPathsAnswerBitForBitAsTheWalk) {
  const BodyMapCollider bodies[3] = {BuildOrDie(MakePose(SphereGrid(), Sphere)),
                                     BuildOrDie(MakePose(BoxGrid(), Box)),
                                     BuildOrDie(MakePose(SphereGrid(), ThinSlab))};
  std::mt19937 rng(20261123);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  for (int body = 0; body < 3; ++body) {
    for (DepthSampling sampling : {DepthSampling::kNearest, DepthSampling::kBilinear}) {
      SCOPED_TRACE(::testing::Message() << "body " << body << " sampling " << int(sampling));
      const BodyMapCollider& c =
          sampling == DepthSampling::kNearest
              ? bodies[body]
              : BuildOrDie(MakePose(body == 1 ? BoxGrid() : SphereGrid(), body == 0   ? Sphere
                                                                          : body == 1 ? Box
                                                                                      : ThinSlab),
                           sampling);
      const Float3 lo = c.bounds_min(), hi = c.bounds_max();
      const auto point = [&](float pad) {
        return Float3{lo.x - pad + unit(rng) * (hi.x - lo.x + 2.f * pad),
                      lo.y - pad + unit(rng) * (hi.y - lo.y + 2.f * pad),
                      lo.z - pad + unit(rng) * (hi.z - lo.z + 2.f * pad)};
      };
      int contacts = 0, started_inside = 0, single_texel = 0, clearly_free = 0;
      for (int k = 0; k < 48000; ++k) {
        Float3 p0 = point(0.02f), p1 = p0;
        const float texel = c.texel_size();
        switch (k % 6) {
          case 0:  // a point
            break;
          case 1:  // sub-texel, mostly along z through a surface
            p1 = p0 + Float3{(unit(rng) - 0.5f) * 0.5f * texel, (unit(rng) - 0.5f) * 0.5f * texel,
                             (unit(rng) - 0.5f) * 0.05f};
            break;
          case 2:  // one to three texels
            p1 = p0 + Float3{(unit(rng) - 0.5f) * 6.f * texel, (unit(rng) - 0.5f) * 6.f * texel,
                             (unit(rng) - 0.5f) * 0.02f};
            break;
          case 3:  // long, across the box
            p1 = point(0.1f);
            break;
          case 4:  // on a texel edge, moving along z only
            p0.x = c.origin_x() + std::floor((p0.x - c.origin_x()) / texel) * texel;
            p1 = Float3{p0.x, p0.y, p0.z + (unit(rng) - 0.5f) * 0.1f};
            break;
          default: {  // starting or ending exactly on a surface value of the texel's slab
            const float u = (p0.x - c.origin_x()) / texel, v = (p0.y - c.origin_y()) / texel;
            float top = 0.f, bottom = 0.f;
            if (u >= 0.f && v >= 0.f &&
                c.TexelSlab(static_cast<uint32_t>(u), static_cast<uint32_t>(v), &top, &bottom)) {
              const float surface = unit(rng) < 0.5f ? top : bottom;
              if (unit(rng) < 0.5f) {
                p0.z = surface;
                p1 = Float3{p0.x, p0.y, surface + (unit(rng) - 0.5f) * 0.01f};
              } else {
                p1 = Float3{p0.x, p0.y, surface};
              }
            }
            break;
          }
        }
        const ContactQuery quick = c.Query(p0, p1);
        const ContactQuery walk = BodyMapColliderTestAccess::QueryWalk(c, p0, p1);
        ExpectSameAnswer(quick, walk, k);
        contacts += walk.contact;
        started_inside += (walk.flags & kCollisionStartedInside) != 0;
        const bool single = BodyMapColliderTestAccess::SingleTexelAnswers(c, p0, p1);
        single_texel += single;
        clearly_free += !single && BodyMapColliderTestAccess::ClearlyFree(c, p0, p1);
      }
      // The sets must exercise both quick paths and the walk.
      EXPECT_GT(contacts, 2000);
      EXPECT_GT(started_inside, 200);
      if (sampling == DepthSampling::kNearest) {
        EXPECT_GT(single_texel, 4000);  // the thin slab's 2 mm clip box sends most to the walk
      }
      EXPECT_GT(clearly_free, 2000);
    }
  }
}

TEST(BodyMapCollider, RowSpanLayoutAnswersExactlyAsDense) {
  const NormalEncoding normals[3] = {NormalEncoding::kFloat32, NormalEncoding::kOct16,
                                     NormalEncoding::kRgb8};
  for (const bool sphere : {true, false}) {
    for (DepthEncoding de : {DepthEncoding::kFloat32, DepthEncoding::kUnorm16}) {
      for (NormalEncoding ne : normals) {
        BodyMapPose dense =
            sphere ? MakePose(SphereGrid(), Sphere, de, ne) : MakePose(BoxGrid(), Box, de, ne);
        ZeroBackgroundNormals(dense);
        BodyMapPose spans;
        ASSERT_TRUE(ConvertBodyMapLayout(dense, BodyMapLayout::kRowSpans, &spans).ok());
        ASSERT_EQ(spans.layout, BodyMapLayout::kRowSpans);
        EXPECT_LT(BodyMapStoredTexels(spans), BodyMapStoredTexels(dense));
        // Back to dense: the very same arrays.
        BodyMapPose back;
        ASSERT_TRUE(ConvertBodyMapLayout(spans, BodyMapLayout::kDense, &back).ok());
        EXPECT_EQ(back.depth_f32[1], dense.depth_f32[1]);
        EXPECT_EQ(back.depth_u16[0], dense.depth_u16[0]);
        EXPECT_EQ(back.normal_f32[0], dense.normal_f32[0]);
        EXPECT_EQ(back.normal_oct16[1], dense.normal_oct16[1]);
        EXPECT_EQ(back.normal_rgb8[1], dense.normal_rgb8[1]);
        for (DepthSampling sampling : {DepthSampling::kNearest, DepthSampling::kBilinear}) {
          SCOPED_TRACE(::testing::Message()
                       << (sphere ? "sphere" : "box") << " depth " << int(de) << " normal "
                       << int(ne) << " sampling " << int(sampling));
          const BodyMapCollider a = BuildOrDie(dense, sampling);
          const BodyMapCollider b = BuildOrDie(spans, sampling);
          ExpectIdenticalColliders(a, b, 1000, 0.05f);
        }
      }
    }
  }
}

TEST(BodyMapCollider, BuildRejectsACorruptSpanTable) {
  BodyMapPose good;
  ASSERT_TRUE(ConvertBodyMapLayout(MakePose(BoxGrid(), Box), BodyMapLayout::kRowSpans, &good).ok());
  ASSERT_TRUE(BodyMapCollider().Build(good).ok());
  const auto expect_rejected = [](const BodyMapPose& pose, const char* field) {
    BodyMapCollider c;
    const Status status = c.Build(pose);
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << field;
    EXPECT_NE(status.message().find(field), std::string::npos) << status.message();
    EXPECT_TRUE(c.empty()) << field;
  };
  const size_t row = 10;  // a row of the box: one span [7, 57)
  const uint32_t s = good.row_span_offsets[row];
  BodyMapPose p = good;
  p.span_begin[s] = 20;  // the span now ends at 70 > width 64
  expect_rejected(p, "beyond width");
  p = good;
  p.row_span_offsets[row] = p.row_span_offsets[row + 1] + 1;
  expect_rejected(p, "row_span_offsets");
  p = good;
  p.row_span_offsets.pop_back();
  expect_rejected(p, "row_span_offsets");
  p = good;
  p.span_texel_offsets[s + 1] = p.span_texel_offsets[s];
  expect_rejected(p, "span_texel_offsets");
  p = good;
  p.depth_f32[0].pop_back();
  expect_rejected(p, "depth_f32_front");
  p = good;
  p.layout = static_cast<BodyMapLayout>(7);
  expect_rejected(p, "layout");
  p = good;
  p.layout = BodyMapLayout::kDense;  // a dense pose with a span table: inconsistent
  expect_rejected(p, "span");
}

TEST(BodyMapSequence, NearestAndBracketingPoses) {
  // The sphere raised by 0.1 m between t = 0 and t = 1.
  const auto raised = [](double dz) {
    return [dz](double x, double y) {
      SurfaceSample s = Sphere(x, y);
      s.top += dz;
      s.bottom += dz;
      return s;
    };
  };
  std::vector<BodyMapPose> poses = {MakePose(SphereGrid(), raised(0.0)),
                                    MakePose(SphereGrid(), raised(0.1))};
  poses[0].clip = poses[1].clip = 2;
  poses[0].time = 0.f;
  poses[1].time = 1.f;
  BodyMapSequence nearest;
  ASSERT_TRUE(nearest.Build(poses).ok());
  EXPECT_EQ(nearest.size(), 2u);
  EXPECT_EQ(&nearest.At(-5.f), &nearest.pose(0));
  EXPECT_EQ(&nearest.At(0.3f), &nearest.pose(0));
  EXPECT_EQ(&nearest.At(0.5f), &nearest.pose(0));  // ties go to the earlier pose
  EXPECT_EQ(&nearest.At(0.7f), &nearest.pose(1));
  EXPECT_EQ(&nearest.At(9.f), &nearest.pose(1));

  BodyMapSequence bracket;
  ASSERT_TRUE(bracket.Build(poses, DepthSampling::kNearest, PoseBlend::kBracket).ok());
  BodyMapCollider scratch;
  const BodyMapCollider& blended = bracket.At(0.25f, &scratch);
  EXPECT_EQ(&blended, &scratch);
  EXPECT_FLOAT_EQ(blended.time(), 0.25f);
  float top, bottom, top0, bottom0;
  ASSERT_TRUE(blended.TexelSlab(44, 44, &top, &bottom));
  ASSERT_TRUE(bracket.pose(0).TexelSlab(44, 44, &top0, &bottom0));
  EXPECT_NEAR(top, top0 + 0.025f, 1e-6);
  EXPECT_NEAR(bottom, bottom0 + 0.025f, 1e-6);
  const ContactQuery q = blended.Query({0.f, 0.f, 0.5f}, {0.f, 0.f, 0.f});
  ASSERT_TRUE(q.contact);
  EXPECT_NEAR(q.point.z, top, 1e-6);
  // Refilling the same scratch with another time does not allocate more.
  const size_t bytes = scratch.memory_bytes();
  bracket.At(0.75f, &scratch);
  EXPECT_EQ(scratch.memory_bytes(), bytes);
  EXPECT_EQ(&bracket.At(0.75f), &bracket.pose(1));          // no scratch: nearest
  EXPECT_EQ(&bracket.At(0.f, &scratch), &bracket.pose(0));  // on a key: that pose

  // Different grids: nearest.
  std::vector<BodyMapPose> mixed = poses;
  mixed[1] = MakePose(BoxGrid(), Box);
  mixed[1].clip = 2;
  mixed[1].time = 1.f;
  BodyMapSequence different;
  ASSERT_TRUE(different.Build(mixed, DepthSampling::kNearest, PoseBlend::kBracket).ok());
  EXPECT_EQ(&different.At(0.6f, &scratch), &different.pose(1));

  // Invalid sequences.
  BodyMapSequence bad;
  std::vector<BodyMapPose> unsorted = poses;
  std::swap(unsorted[0].time, unsorted[1].time);
  EXPECT_EQ(bad.Build(unsorted).code(), StatusCode::kInvalidArgument);
  std::vector<BodyMapPose> two_clips = poses;
  two_clips[1].clip = 3;
  EXPECT_EQ(bad.Build(two_clips).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(bad.Build({}).code(), StatusCode::kInvalidArgument);
  std::vector<BodyMapPose> broken = poses;
  broken[1].texel_size = 0.f;
  const Status status = bad.Build(broken);
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("pose 1"), std::string::npos) << status.message();
  EXPECT_TRUE(bad.At(0.f).empty());
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Air gaps (BodyMapPose::layers > 1): a plate held in front of a block, and a second, smaller
// plate between them on one side, so texels have zero, one or two gaps.

namespace {

struct ZBox {
  float x_lo, x_hi, y_lo, y_hi, z_lo, z_hi;  // metres
};
// Edges on texel boundaries (multiples of 1/128 m), so every texel centre is clearly in or out.
constexpr ZBox kBlock{-30 * kTexel, 30 * kTexel, -30 * kTexel, 30 * kTexel, -0.10f, 0.05f};
constexpr ZBox kPlate{-20 * kTexel, 20 * kTexel, -20 * kTexel, 20 * kTexel, 0.10f, 0.12f};
constexpr ZBox kMidPlate{0.f, 10 * kTexel, -10 * kTexel, 10 * kTexel, 0.065f, 0.075f};
// Distinct gap-boundary normals, so a test can tell which array an answer read.
const Float3 kGapUpperNormal = NormalizeOr(Float3{0.3f, 0.f, -1.f}, Float3{});
const Float3 kGapLowerNormal = NormalizeOr(Float3{0.f, 0.3f, 1.f}, Float3{});

// The boxes' z intervals (top, bottom) at the centre of texel (i, j), from the top; disjoint by
// construction.
std::vector<std::pair<float, float>> BoxSpans(const std::vector<ZBox>& boxes, uint32_t i,
                                              uint32_t j) {
  const GridSpec g = SphereGrid();
  const double x = g.origin_x + (i + 0.5) * g.texel;
  const double y = g.origin_y + (j + 0.5) * g.texel;
  std::vector<std::pair<float, float>> spans;
  for (const ZBox& b : boxes) {
    if (x > b.x_lo && x < b.x_hi && y > b.y_lo && y < b.y_hi) spans.push_back({b.z_hi, b.z_lo});
  }
  std::sort(spans.begin(), spans.end(), std::greater<>());
  return spans;
}

// One gap as a test writes it; a boundary may be left out, to test the checks.
struct GapSpec {
  double upper = 0.0, lower = 0.0;  // asset-frame z
  bool has_upper = true, has_lower = true;
};
using GapsByTexel = std::map<size_t, std::vector<GapSpec>>;  // dense texel -> gaps from the top

// The air between the boxes at every texel: at most layers - 1 gaps, the widest (as the bake
// keeps them), in order from the top.
GapsByTexel BoxGaps(uint8_t layers, const std::vector<ZBox>& boxes) {
  const GridSpec g = SphereGrid();
  GapsByTexel result;
  for (uint32_t j = 0; j < g.height; ++j) {
    for (uint32_t i = 0; i < g.width; ++i) {
      const std::vector<std::pair<float, float>> spans = BoxSpans(boxes, i, j);
      std::vector<GapSpec> gaps;
      for (size_t s = 1; s < spans.size(); ++s)
        gaps.push_back({spans[s - 1].second, spans[s].first});
      std::stable_sort(gaps.begin(), gaps.end(), [](const GapSpec& a, const GapSpec& b) {
        return a.upper - a.lower > b.upper - b.lower;
      });
      if (gaps.size() > layers - 1u) gaps.resize(layers - 1u);
      std::sort(gaps.begin(), gaps.end(),
                [](const GapSpec& a, const GapSpec& b) { return a.upper > b.upper; });
      if (!gaps.empty()) result[static_cast<size_t>(j) * g.width + i] = gaps;
    }
  }
  return result;
}

// A dense pose of the boxes' slab with the given gaps, stored as the format stores them: layer 0
// of every texel, then the gap layers of the texels in gap_texels.
BodyMapPose PackLayered(uint8_t layers, const std::vector<ZBox>& boxes, const GapsByTexel& gaps,
                        DepthEncoding depth_encoding = DepthEncoding::kFloat32,
                        NormalEncoding normal_encoding = NormalEncoding::kFloat32) {
  const GridSpec g = SphereGrid();
  const size_t n = static_cast<size_t>(g.width) * g.height;
  BodyMapPose pose = EmptyPose(g, depth_encoding, normal_encoding, (layers - 1u) * gaps.size());
  pose.layers = layers;
  for (const auto& [texel, list] : gaps) pose.gap_texels.push_back(static_cast<uint32_t>(texel));
  const double back_plane = static_cast<double>(g.front_z) - g.depth_range;
  for (uint32_t j = 0; j < g.height; ++j) {
    for (uint32_t i = 0; i < g.width; ++i) {
      const size_t k = static_cast<size_t>(j) * g.width + i;
      const std::vector<std::pair<float, float>> spans = BoxSpans(boxes, i, j);
      const bool valid = !spans.empty();
      const double top = valid ? spans.front().first : 0.0;
      const double bottom = valid ? spans.back().second : 0.0;
      PutSurface(pose, k, 0, valid, g.front_z - top, Float3{0.f, 0.f, 1.f});
      PutSurface(pose, k, 1, valid, bottom - back_plane, Float3{0.f, 0.f, -1.f});
    }
  }
  size_t t = 0;
  for (const auto& [texel, list] : gaps) {
    for (size_t layer = 1; layer < layers; ++layer) {
      const size_t entry = n + (layer - 1) * gaps.size() + t;
      const GapSpec gap = layer <= list.size() ? list[layer - 1] : GapSpec{0, 0, false, false};
      PutSurface(pose, entry, 0, gap.has_upper, g.front_z - gap.upper, kGapUpperNormal);
      PutSurface(pose, entry, 1, gap.has_lower, gap.lower - back_plane, kGapLowerNormal);
    }
    ++t;
  }
  return pose;
}

BodyMapPose LayeredPose(uint8_t layers, const std::vector<ZBox>& boxes,
                        DepthEncoding depth_encoding = DepthEncoding::kFloat32,
                        NormalEncoding normal_encoding = NormalEncoding::kFloat32) {
  return PackLayered(layers, boxes, BoxGaps(layers, boxes), depth_encoding, normal_encoding);
}

const std::vector<ZBox> kStack = {kBlock, kPlate, kMidPlate};
// The stack with two posts off the block, one lower and one higher than the stack: the clip box
// then reaches beyond the slabs of the texels with gaps, so a walk can leave such a slab
// through its back or front surface within one texel.
constexpr ZBox kLowPost{34 * kTexel, 40 * kTexel, -6 * kTexel, 0.f, -0.2f, -0.15f};
constexpr ZBox kHighPost{34 * kTexel, 40 * kTexel, kTexel, 6 * kTexel, 0.15f, 0.2f};
const std::vector<ZBox> kStackAndPosts = {kBlock, kPlate, kMidPlate, kLowPost, kHighPost};

}  // namespace

TEST(BodyMapGaps, InsideSetIsTheSlabMinusItsGaps) {
  const BodyMapCollider paper = BuildOrDie(LayeredPose(1, kStack));
  const BodyMapCollider two = BuildOrDie(LayeredPose(2, kStack));
  const BodyMapCollider three = BuildOrDie(LayeredPose(3, kStack));
  EXPECT_EQ(paper.layers(), 1u);
  EXPECT_EQ(three.layers(), 3u);
  EXPECT_EQ(paper.stats().gap_texels, 0u);
  EXPECT_EQ(three.stats().gap_texels, 40u * 40u);  // the plate's texels
  EXPECT_EQ(two.stats().gap_texels, 40u * 40u);
  // Stored compactly: two gap slots of 16 bytes per gap texel, and one bit per texel and a count
  // per 32 texels (which texels have gaps, and where theirs start).
  const size_t words = (size_t{three.width()} * three.height() + 31) / 32;
  EXPECT_LE(three.memory_bytes() - paper.memory_bytes(), 40u * 40u * 2 * 16 + words * 4 * 2 + 64);
  // Under the plate only (x < 0): one gap (0.05, 0.10).
  const Float3 plate_only{-0.05f, 0.01f, 0.f}, both_plates{0.03f, 0.01f, 0.f};
  const auto at = [](Float3 p, float z) { return Float3{p.x, p.y, z}; };
  for (const BodyMapCollider* c : {&two, &three}) {
    EXPECT_TRUE(c->IsInside(at(plate_only, 0.11f)));
    EXPECT_FALSE(c->IsInside(at(plate_only, 0.075f)));
    EXPECT_TRUE(c->IsInside(at(plate_only, 0.0f)));
    EXPECT_FALSE(c->IsInside(at(plate_only, 0.13f)));
    EXPECT_TRUE(c->IsInside(at(plate_only, 0.10f)));  // gap boundaries are inside
    EXPECT_TRUE(c->IsInside(at(plate_only, 0.05f)));
  }
  EXPECT_TRUE(paper.IsInside(at(plate_only, 0.075f)));  // paper A: the air counts as inside
  // Under both plates: gaps (0.075, 0.10) and (0.05, 0.065); with two layers only the wider,
  // upper one.
  EXPECT_TRUE(three.IsInside(at(both_plates, 0.07f)));
  EXPECT_FALSE(three.IsInside(at(both_plates, 0.09f)));
  EXPECT_FALSE(three.IsInside(at(both_plates, 0.06f)));
  EXPECT_FALSE(two.IsInside(at(both_plates, 0.09f)));
  EXPECT_TRUE(two.IsInside(at(both_plates, 0.06f)));
  float upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers];
  const uint32_t i = static_cast<uint32_t>((both_plates.x + 44 * kTexel) / kTexel);
  const uint32_t j = static_cast<uint32_t>((both_plates.y + 44 * kTexel) / kTexel);
  ASSERT_EQ(three.TexelGaps(i, j, upper, lower), 2u);
  EXPECT_NEAR(upper[0], 0.10f, 1e-6);
  EXPECT_NEAR(lower[0], 0.075f, 1e-6);
  EXPECT_NEAR(upper[1], 0.065f, 1e-6);
  EXPECT_NEAR(lower[1], 0.05f, 1e-6);
  EXPECT_EQ(paper.TexelGaps(i, j, upper, lower), 0u);
  // The batch and the bilinear sampling classify the same way (the gap texels stay nearest).
  const BodyMapCollider bilinear = BuildOrDie(LayeredPose(3, kStack), DepthSampling::kBilinear);
  std::mt19937 rng(31);
  std::vector<Float3> points(20000);
  for (Float3& p : points) p = RandomPoint(rng, -0.3f, 0.3f, -0.15f, 0.15f);
  std::vector<uint8_t> inside(points.size());
  ASSERT_TRUE(three.InsideBatch(points, inside).ok());
  int gap_points = 0;
  for (size_t k = 0; k < points.size(); ++k) {
    EXPECT_EQ(inside[k] != 0, three.IsInside(points[k])) << k;
    EXPECT_EQ(bilinear.IsInside(points[k]), three.IsInside(points[k])) << k;
    gap_points += paper.IsInside(points[k]) && !three.IsInside(points[k]);
  }
  EXPECT_GT(gap_points, 500);
}

TEST(BodyMapGaps, EntriesAcrossAGapUseTheGapsSurfaces) {
  const BodyMapCollider paper = BuildOrDie(LayeredPose(1, kStack));
  // Oct16 normals (the runtime's storage) are within 0.004 degrees.
  for (NormalEncoding ne : {NormalEncoding::kFloat32, NormalEncoding::kOct16}) {
    SCOPED_TRACE(::testing::Message() << "normal encoding " << int(ne));
    const BodyMapCollider c = BuildOrDie(LayeredPose(3, kStack, DepthEncoding::kFloat32, ne));
    const float x = -0.05f, y = 0.01f;  // under the plate only: one gap (0.05, 0.10)
    // From the gap down into the block: a front entry on the gap's lower boundary.
    ContactQuery q = c.Query({x, y, 0.09f}, {x, y, 0.03f});
    ASSERT_TRUE(q.contact);
    EXPECT_EQ(q.flags, kCollisionNone);
    EXPECT_NEAR(q.t, (0.09f - 0.05f) / 0.06f, 1e-5);
    EXPECT_NEAR(q.point.z, 0.05f, 1e-6);
    EXPECT_LT(AngleDegrees(q.normal, kGapLowerNormal), 0.01);
    EXPECT_NEAR(q.depth, 0.02f, 1e-6);  // below the block's top, in the block's interval
    // From the gap up into the plate: a back entry on the gap's upper boundary.
    q = c.Query({x, y, 0.06f}, {x, y, 0.105f});
    ASSERT_TRUE(q.contact);
    EXPECT_NEAR(q.point.z, 0.10f, 1e-6);
    EXPECT_LT(AngleDegrees(q.normal, kGapUpperNormal), 0.01);
    // Moving inside the gap: air, no contact. Paper A's slab calls it inside.
    q = c.Query({x, y, 0.06f}, {x + 0.01f, y, 0.09f});
    EXPECT_FALSE(q.contact);
    EXPECT_FALSE(q.inside_end);
    EXPECT_TRUE(paper.Query({x, y, 0.06f}, {x + 0.01f, y, 0.09f}).contact);
    // From inside the plate through the gap into the block: a swept entry into the block.
    q = c.Query({x, y, 0.11f}, {x, y, 0.04f});
    ASSERT_TRUE(q.contact);
    EXPECT_EQ(q.flags & kCollisionStartedInside, 0);
    EXPECT_NEAR(q.point.z, 0.05f, 1e-6);
    EXPECT_LT(AngleDegrees(q.normal, kGapLowerNormal), 0.01);
    // Deep in the plate and staying: pushed out to the plate's nearer surface, its lower one.
    q = c.Query({x, y, 0.105f}, {x, y, 0.102f});
    ASSERT_TRUE(q.contact);
    EXPECT_EQ(q.flags, kCollisionStartedInside);
    EXPECT_NEAR(q.point.z, 0.10f, 1e-6);
    EXPECT_NEAR(q.depth, 0.002f, 1e-6);
    EXPECT_LT(AngleDegrees(q.normal, kGapUpperNormal), 0.01);
    // From above through everything: the plate's front surface.
    q = c.Query({x, y, 0.2f}, {x, y, -0.2f});
    ASSERT_TRUE(q.contact);
    EXPECT_NEAR(q.point.z, 0.12f, 1e-6);
    EXPECT_LT(AngleDegrees(q.normal, Float3{0.f, 0.f, 1.f}), 0.01);
    // Sideways at gap height from beyond the plate (slab = the block only) in under it: air.
    // Paper A's slab grows there and reports a side wall.
    q = c.Query({-0.2f, y, 0.075f}, {-0.1f, y, 0.075f});
    EXPECT_FALSE(q.contact);
    q = paper.Query({-0.2f, y, 0.075f}, {-0.1f, y, 0.075f});
    ASSERT_TRUE(q.contact);
    EXPECT_NE(q.flags & kCollisionSideWall, 0);
    // Sideways in the gap into the edge of the mid plate (x = 0): a side wall, with the normal of
    // the nearer surface of the mid plate's interval, its top (gap 0's lower boundary).
    q = c.Query({-0.02f, y, 0.073f}, {0.02f, y, 0.073f});
    ASSERT_TRUE(q.contact);
    EXPECT_NE(q.flags & kCollisionSideWall, 0);
    EXPECT_NEAR(q.point.x, 0.f, kWallTolerance);
    EXPECT_LT(AngleDegrees(q.normal, kGapLowerNormal), 0.01);
  }
}

TEST(BodyMapGaps, WalkMatchesExactReferenceOnRandomSegments) {
  const BodyMapCollider paper = BuildOrDie(LayeredPose(1, kStack));
  for (uint8_t layers : {uint8_t{2}, uint8_t{3}}) {
    const BodyMapCollider c = BuildOrDie(LayeredPose(layers, kStack));
    int from_gap = 0;  // starts that paper A's slab would call inside
    const WalkCounts n = ExpectWalkMatchesReference(
        c, 17 + layers, 3000, [&](Float3 p0) { from_gap += paper.IsInside(p0); });
    std::printf("layers %d: %d hits (%d side walls), %d misses, %d starts in a gap\n", layers,
                n.hits, n.side_walls, n.misses, from_gap);
    EXPECT_GT(n.hits, 300);
    EXPECT_GT(n.misses, 100);
    EXPECT_GT(from_gap, 50);
  }
}

TEST(BodyMapGaps, QuickPathsAndBatchAnswerAsTheWalkAtAnyThreadCount) {
  for (DepthSampling sampling : {DepthSampling::kNearest, DepthSampling::kBilinear}) {
    SCOPED_TRACE(::testing::Message() << "sampling " << int(sampling));
    const BodyMapCollider c = BuildOrDie(LayeredPose(3, kStack), sampling);
    std::mt19937 rng(41);
    std::uniform_real_distribution<float> unit(0.f, 1.f);
    constexpr size_t kCount = 30000;
    std::vector<Float3> previous(kCount), positions(kCount), velocities(kCount);
    for (size_t k = 0; k < kCount; ++k) {
      previous[k] = RandomPoint(rng, -0.3f, 0.3f, -0.15f, 0.15f);
      const float reach = k % 3 == 0 ? 0.3f * kTexel : (k % 3 == 1 ? 3.f * kTexel : 0.1f);
      positions[k] = previous[k] + RandomPoint(rng, -reach, reach, -0.03f, 0.03f);
      velocities[k] = RandomPoint(rng, -1.f, 1.f, -1.f, 1.f);
    }
    int contacts = 0;
    for (size_t k = 0; k < kCount; ++k) {
      const ContactQuery walk = BodyMapColliderTestAccess::QueryWalk(c, previous[k], positions[k]);
      ExpectSameAnswer(c.Query(previous[k], positions[k]), walk, static_cast<int>(k));
      contacts += walk.contact;
    }
    EXPECT_GT(contacts, 3000);
    std::vector<Float3> out_positions[2], out_velocities[2];
    std::vector<uint8_t> flags[2];
    const int saved_threads = omp_get_max_threads();
    for (int run = 0; run < 2; ++run) {
      omp_set_num_threads(run + 1);
      out_positions[run] = positions;
      out_velocities[run] = velocities;
      flags[run].assign(kCount, 0);
      ASSERT_TRUE(c.CollideBatch(previous, out_positions[run], out_velocities[run], flags[run],
                                 ResponseParams{})
                      .ok());
    }
    omp_set_num_threads(saved_threads);
    EXPECT_EQ(
        0, std::memcmp(out_positions[0].data(), out_positions[1].data(), kCount * sizeof(Float3)));
    EXPECT_EQ(flags[0], flags[1]);
  }
}

TEST(BodyMapGaps, BuildRejectsGapsThatDoNotNest) {
  const GridSpec g = SphereGrid();
  const uint32_t i = 30, j = 44;  // under the plate only (x = -0.11 m)
  const size_t k = static_cast<size_t>(j) * g.width + i;
  const auto expect_rejected = [](const BodyMapPose& pose, const std::string& words) {
    BodyMapCollider c;
    const Status status = c.Build(pose);
    EXPECT_FALSE(status.ok()) << words;
    EXPECT_NE(status.message().find(words), std::string::npos) << status.message();
    EXPECT_TRUE(c.empty());
  };
  // The stack's own gaps with texel `texel`'s replaced by `gaps`.
  const auto with_gaps = [&](size_t texel, const std::vector<GapSpec>& gaps) {
    GapsByTexel all = BoxGaps(3, kStack);
    all[texel] = gaps;
    return PackLayered(3, kStack, all);
  };
  const auto with_gap = [&](size_t texel, bool front_valid, double upper, bool back_valid,
                            double lower) {
    return with_gaps(texel, {GapSpec{upper, lower, front_valid, back_valid}});
  };
  ASSERT_TRUE(BodyMapCollider().Build(with_gap(k, true, 0.09, true, 0.06)).ok());
  for (uint8_t layers : {uint8_t{0}, uint8_t{5}}) {
    BodyMapPose pose = LayeredPose(3, kStack);
    pose.layers = layers;
    expect_rejected(pose, "layers = " + std::to_string(layers));
  }
  {  // arrays sized for three layers, pose says two
    BodyMapPose pose = LayeredPose(3, kStack);
    pose.layers = 2;
    expect_rejected(pose, "2 layer(s)");
  }
  {  // a gap list with one layer
    BodyMapPose pose = LayeredPose(1, kStack);
    pose.gap_texels = {static_cast<uint32_t>(k)};
    expect_rejected(pose, "layers = 1 (no gap layers)");
  }
  {  // a gap list that does not increase
    BodyMapPose pose = LayeredPose(3, kStack);
    ASSERT_GE(pose.gap_texels.size(), 2u);
    std::swap(pose.gap_texels[0], pose.gap_texels[1]);
    expect_rejected(pose, "does not increase");
  }
  expect_rejected(with_gap(k, true, 0.09, false, 0.0), "only one of its two boundaries");
  expect_rejected(with_gap(k, true, 0.13, true, 0.06), "not strictly inside");  // above top
  expect_rejected(with_gap(k, true, 0.07, true, 0.09), "not strictly inside");  // inverted
  expect_rejected(with_gap(k, true, 0.09, true, -0.2), "not strictly inside");  // below bottom
  const size_t block_only = static_cast<size_t>(j) * g.width + 16;  // x = -0.215 m: no gap
  expect_rejected(with_gaps(block_only, {GapSpec{0, 0, false, false}, GapSpec{0.0, -0.05}}),
                  "has no gap 1");
  expect_rejected(with_gap(0, true, 0.09, true, 0.06), "background texel");
  // Gap 2 overlapping gap 1.
  expect_rejected(with_gaps(k, {GapSpec{0.10, 0.05}, GapSpec{0.07, 0.03}}), "gap layer 2");
}

TEST(BodyMapGaps, RowSpanLayoutAnswersExactlyAsDense) {
  for (DepthEncoding de : {DepthEncoding::kFloat32, DepthEncoding::kUnorm16}) {
    BodyMapPose dense = LayeredPose(3, kStack, de, NormalEncoding::kOct16);
    ZeroBackgroundNormals(dense);
    BodyMapPose spans, back;
    ASSERT_TRUE(ConvertBodyMapLayout(dense, BodyMapLayout::kRowSpans, &spans).ok());
    ASSERT_TRUE(ConvertBodyMapLayout(spans, BodyMapLayout::kDense, &back).ok());
    EXPECT_EQ(spans.gap_texels.size(), dense.gap_texels.size());
    EXPECT_NE(spans.gap_texels, dense.gap_texels);  // renumbered: spans store fewer texels
    EXPECT_EQ(back.gap_texels, dense.gap_texels);
    EXPECT_EQ(back.depth_f32[0], dense.depth_f32[0]);
    EXPECT_EQ(back.depth_u16[1], dense.depth_u16[1]);
    EXPECT_EQ(back.normal_oct16[0], dense.normal_oct16[0]);
    for (DepthSampling sampling : {DepthSampling::kNearest, DepthSampling::kBilinear}) {
      SCOPED_TRACE(::testing::Message() << "depth " << int(de) << " sampling " << int(sampling));
      const BodyMapCollider a = BuildOrDie(dense, sampling), b = BuildOrDie(spans, sampling);
      EXPECT_EQ(a.stats().gap_texels, b.stats().gap_texels);
      ExpectIdenticalColliders(a, b, 2000, 0.05f);
    }
  }
}

TEST(BodyMapGaps, SequenceBlendsGapsWhereBothPosesHaveThem) {
  // The plate rises by 0.04 m from t = 0 to t = 1; at t = 1 the mid plate is gone.
  ZBox raised = kPlate;
  raised.z_lo += 0.04f;
  raised.z_hi += 0.04f;
  std::vector<BodyMapPose> poses = {LayeredPose(3, kStack), LayeredPose(3, {kBlock, raised})};
  poses[0].time = 0.f;
  poses[1].time = 1.f;
  BodyMapSequence sequence;
  ASSERT_TRUE(sequence.Build(poses, DepthSampling::kNearest, PoseBlend::kBracket).ok());
  BodyMapCollider scratch;
  const BodyMapCollider& blended = sequence.At(0.25f, &scratch);
  ASSERT_EQ(&blended, &scratch);
  EXPECT_EQ(blended.layers(), 3u);
  float upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers];
  // Under the plate only: one gap in both poses, blended.
  ASSERT_EQ(blended.TexelGaps(30, 44, upper, lower), 1u);
  EXPECT_NEAR(upper[0], 0.11f, 1e-6);
  EXPECT_NEAR(lower[0], 0.05f, 1e-6);
  // Under both plates at t = 0, the raised plate only at t = 1: the first gap is blended (the
  // mid plate's top at t = 0 with the block's top at t = 1), the second, which pose 1 lacks,
  // ends the list.
  ASSERT_EQ(blended.TexelGaps(48, 44, upper, lower), 1u);
  EXPECT_NEAR(upper[0], 0.11f, 1e-6);
  EXPECT_NEAR(lower[0], 0.75f * 0.075f + 0.25f * 0.05f, 1e-6);
  EXPECT_FALSE(blended.IsInside({-0.05f, 0.01f, 0.08f}));
  EXPECT_TRUE(blended.IsInside({-0.05f, 0.01f, 0.115f}));

  // The batch's lanes find a blend's gap texels as Query does (the blend refreshes the per-texel
  // gap bits they test): motions in and across the plates, bit for bit, on every lane path.
  constexpr size_t kCount = 4000;
  std::mt19937 rng(20261123u);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  const auto in = [&](float lo, float hi) { return lo + (hi - lo) * unit(rng); };
  std::vector<Float3> previous(kCount), positions(kCount),
      velocities(kCount, Float3{0.f, 0.f, -1.f});
  for (size_t k = 0; k < kCount; ++k) {
    previous[k] = {in(-24.f, 24.f) * kTexel, in(-24.f, 24.f) * kTexel, in(-0.12f, 0.14f)};
    const float reach = k % 2 == 0 ? 1.f : 6.f;  // texels: short lanes, and walks
    positions[k] = {previous[k].x + in(-reach, reach) * kTexel,
                    previous[k].y + in(-reach, reach) * kTexel, previous[k].z + in(-0.04f, 0.04f)};
  }
  ResponseParams params;
  params.friction = 0.3f;
  const OneByOne want = QueryOneByOne(blended, previous, positions, velocities, params);
  // Contacts on a gap's upper boundary (a plate's underside, its normal facing down).
  const size_t gap_contacts =
      std::count_if(want.queries.begin(), want.queries.end(), [](const ContactQuery& q) {
        return q.contact && q.normal.z < 0.f && q.point.z > 0.f && q.point.z < 0.11f;
      });
  EXPECT_GT(gap_contacts, kCount / 50);
  for (TestLanes lanes : kEveryLanes) {
    if (!BodyMapColliderTestAccess::UseLanes(&scratch, lanes)) continue;  // (scratch is the blend)
    SCOPED_TRACE(LanesName(lanes));
    std::vector<Float3> got_positions = positions, got_velocities = velocities;
    std::vector<uint8_t> got_flags(kCount);
    ASSERT_TRUE(
        scratch.CollideBatch(previous, got_positions, got_velocities, got_flags, params).ok());
    for (size_t k = 0; k < kCount; ++k) {
      ASSERT_EQ(got_flags[k], want.flags[k]) << k;
      ExpectSameBits(got_positions[k], want.positions[k], "position", static_cast<int>(k));
      ExpectSameBits(got_velocities[k], want.velocities[k], "velocity", static_cast<int>(k));
    }
  }
}

// With gap layers the lanes read whether a texel has gaps from its slab's top (its lowest mantissa
// bit, set by Finish), not from a second table: the bit must mark exactly the texels with gaps,
// after Build and after a blend, and move a top by at most one ulp, upward. Without gap layers
// the tops are the maps' own values.
TEST(BodyMapGaps, SlabTopsCarryTheGapFlagWithinOneUlp) {
  const auto flag = [](float top) { return (std::bit_cast<uint32_t>(top) & 1u) != 0u; };
  const auto check = [&](const BodyMapCollider& c, const BodyMapPose* pose) {
    float upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers];
    size_t valid = 0, with_gaps = 0, moved = 0, moved_below_zero = 0;
    for (uint32_t j = 0; j < c.height(); ++j) {
      for (uint32_t i = 0; i < c.width(); ++i) {
        float top = 0.f, bottom = 0.f;
        if (!c.TexelSlab(i, j, &top, &bottom)) continue;
        ++valid;
        const bool gaps = c.TexelGaps(i, j, upper, lower) != 0u;
        with_gaps += gaps;
        if (c.layers() > 1) {
          EXPECT_EQ(flag(top), gaps) << i << ", " << j;
        }
        if (pose == nullptr) continue;
        const float map_top = pose->front_z - pose->depth_f32[0][size_t{j} * c.width() + i];
        if (c.layers() == 1) {
          EXPECT_EQ(std::bit_cast<uint32_t>(top), std::bit_cast<uint32_t>(map_top));
        } else {
          EXPECT_TRUE(top == map_top || top == std::nextafter(map_top, 1.f)) << i << ", " << j;
        }
        moved += top != map_top;
        moved_below_zero += top != map_top && map_top < 0.f;
      }
    }
    return std::array<size_t, 4>{valid, with_gaps, moved, moved_below_zero};
  };
  // The stack, and eight stacks of two posts below z = 0 (a gap between them, tops a millimetre
  // apart): moving a negative top up is a step the other way in its bits.
  std::vector<ZBox> boxes = kStackAndPosts;
  for (int m = 0; m < 8; ++m) {
    const float y = static_cast<float>(10 + 4 * m) * kTexel;
    const float top = -0.15f - 0.001f * static_cast<float>(m);
    boxes.push_back({34 * kTexel, 38 * kTexel, y, y + 3 * kTexel, -0.2f, -0.18f});
    boxes.push_back({34 * kTexel, 38 * kTexel, y, y + 3 * kTexel, -0.17f, top});
  }
  const BodyMapPose paper_pose = LayeredPose(1, boxes);
  const BodyMapPose layered_pose = LayeredPose(3, boxes);
  const std::array<size_t, 4> paper = check(BuildOrDie(paper_pose), &paper_pose);
  EXPECT_EQ(paper[1], 0u);
  EXPECT_EQ(paper[2], 0u);
  const std::array<size_t, 4> layered = check(BuildOrDie(layered_pose), &layered_pose);
  EXPECT_EQ(layered[1], 40u * 40u + 8u * 4u * 3u);  // under the plate, and the posts
  // Tops that held the other bit are moved, some of them below z = 0 (a test that moved none
  // would test nothing).
  EXPECT_GT(layered[2], 0u);
  EXPECT_GT(layered[3], 0u);
  // A blend: the plate rises and the mid plate goes, so texels gain and lose gaps between poses.
  ZBox raised = kPlate;
  raised.z_lo += 0.04f;
  raised.z_hi += 0.04f;
  std::vector<BodyMapPose> poses = {layered_pose, LayeredPose(3, {kBlock, raised, kLowPost})};
  poses[0].time = 0.f;
  poses[1].time = 1.f;
  BodyMapSequence sequence;
  ASSERT_TRUE(sequence.Build(poses, DepthSampling::kNearest, PoseBlend::kBracket).ok());
  BodyMapCollider scratch;
  for (float t : {0.25f, 0.75f, 0.4f}) {
    SCOPED_TRACE(::testing::Message() << "t = " << t);
    const std::array<size_t, 4> blended = check(sequence.At(t, &scratch), nullptr);
    EXPECT_GT(blended[1], 0u);
  }
}

// CollideBatch answers every particle as Query and ApplyResponse do, bit for bit, whichever of
// its paths (four particles at once when they stay in one texel or cross one edge, or one by
// one) takes the particle: resting and sliding motions, points, starts inside, background,
// motions off the grid or beyond the clip box, longer motions, texels with gaps, and non-finite
// input in any of the three arrays.
// Query's long walks step 8x8 blocks; the batch's lanes step texels. A segment through a texel
// corner on a block's edge is where the block walk could begin a block in another texel than the
// texel walk (the crossing point's other coordinate rounds across an edge): both must visit the
// same texels, so the answers are the same bits. (Without 7497812, 190 of the sphere's 40 000
// differ.)
TEST(BodyMapBatch, LongWalksThroughBlockEdgeCornersAnswerAsQuery) {
  BodyMapCollider bodies[2] = {BuildOrDie(MakePose(SphereGrid(), Sphere)),
                               BuildOrDie(LayeredPose(3, kStack))};
  ResponseParams params;
  params.friction = 0.3f;
  params.restitution = 0.25f;
  params.separation = 2e-4f;
  std::mt19937 rng(20261124);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  for (BodyMapCollider& c : bodies) {
    const float texel = c.texel_size();
    const Float3 lo = c.bounds_min(), hi = c.bounds_max();
    const int blocks_u = static_cast<int>(c.width()) / 8,
              blocks_v = static_cast<int>(c.height()) / 8;
    ASSERT_GT(blocks_u, 2);
    ASSERT_GT(blocks_v, 2);
    constexpr size_t kCount = 40000;
    std::vector<Float3> previous(kCount), positions(kCount), velocities(kCount);
    for (size_t k = 0; k < kCount; ++k) {
      // Through a texel corner on a block's edge (a lattice point with u or v a multiple of 8),
      // at a random fraction of a 12-30 texel motion.
      const bool on_u_edge = unit(rng) < 0.5f;
      const auto lattice = [&](int blocks, bool block_edge) {
        const float block =
            static_cast<float>(1 + static_cast<int>(unit(rng) * static_cast<float>(blocks - 2)));
        return 8.f * block +
               (block_edge ? 0.f : static_cast<float>(static_cast<int>(unit(rng) * 8.f)));
      };
      const float corner_u = lattice(blocks_u, on_u_edge);
      const float corner_v = lattice(blocks_v, !on_u_edge);
      const float angle = unit(rng) * 6.2831853f, length = 12.f + 18.f * unit(rng);
      const float before = (0.2f + 0.6f * unit(rng)) * length;
      const float du = std::cos(angle), dv = std::sin(angle);
      const Float3 corner{c.origin_x() + corner_u * texel, c.origin_y() + corner_v * texel, 0.f};
      const float z0 = lo.z + (hi.z - lo.z) * (1.2f * unit(rng) - 0.1f);
      const float z1 = lo.z + (hi.z - lo.z) * (1.2f * unit(rng) - 0.1f);
      previous[k] = {corner.x - du * before * texel, corner.y - dv * before * texel, z0};
      positions[k] = {corner.x + du * (length - before) * texel,
                      corner.y + dv * (length - before) * texel, z1};
      velocities[k] = RandomPoint(rng, -1.f, 1.f, -1.f, 1.f);
    }
    const OneByOne want = QueryOneByOne(c, previous, positions, velocities, params);
    const size_t contacts = std::count_if(want.queries.begin(), want.queries.end(),
                                          [](const ContactQuery& q) { return q.contact; });
    EXPECT_GT(contacts, kCount / 10);
    for (TestLanes lanes : kEveryLanes) {  // each the CPU has
      if (!BodyMapColliderTestAccess::UseLanes(&c, lanes)) continue;
      SCOPED_TRACE(LanesName(lanes));
      std::vector<Float3> got_positions = positions, got_velocities = velocities;
      std::vector<uint8_t> got_flags(kCount);
      ASSERT_TRUE(c.CollideBatch(previous, got_positions, got_velocities, got_flags, params).ok());
      size_t differing = 0;
      for (size_t k = 0; k < kCount; ++k) {
        differing += got_flags[k] != want.flags[k] ||
                     std::memcmp(&got_positions[k], &want.positions[k], sizeof(Float3)) != 0 ||
                     std::memcmp(&got_velocities[k], &want.velocities[k], sizeof(Float3)) != 0;
      }
      EXPECT_EQ(differing, 0u);
    }
  }
}

TEST(BodyMapBatch, AnswersAsQueryAndResponseBitForBit) {
  // The stack and posts with 3 and with 4 layers: groups whose lanes' texels have fewer gaps than
  // the collider has layers for gather only the layers some lane has (GatherGapLanes).
  constexpr int kBodies = 5;
  BodyMapCollider bodies[kBodies] = {
      BuildOrDie(MakePose(SphereGrid(), Sphere)), BuildOrDie(MakePose(BoxGrid(), Box)),
      BuildOrDie(MakePose(SphereGrid(), ThinSlab)), BuildOrDie(LayeredPose(3, kStackAndPosts)),
      BuildOrDie(LayeredPose(4, kStackAndPosts))};
  ResponseParams params;
  params.friction = 0.3f;
  params.restitution = 0.25f;
  params.separation = 2e-4f;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  std::mt19937 rng(20261123);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  size_t answered_walls = 0, answered_inside = 0, answered_entries = 0;  // four-lane path
  size_t answered_outside = 0, answered_gap_contacts = 0, answered_gap_inside = 0;
  size_t walked_answered = 0, walked_walls = 0, walked_inside = 0, walked_entries = 0;
  size_t walked_clipped_entries = 0, walked_z_face = 0, walked_long = 0;  // walking lanes
  size_t walked_gap_contacts = 0, walked_gap_starts = 0;
  size_t steep_short = 0, steep_walked = 0;  // from a gap through the start texel's whole slab
  size_t eight_lanes_answered[3] = {};       // by TestLanes: AVX2, AVX-512
  for (int body = 0; body < kBodies; ++body) {
    SCOPED_TRACE(::testing::Message() << "body " << body);
    BodyMapCollider& c = bodies[body];
    const Float3 lo = c.bounds_min(), hi = c.bounds_max();
    const float texel = c.texel_size();
    const auto point = [&](float pad) {
      return Float3{lo.x - pad + unit(rng) * (hi.x - lo.x + 2.f * pad),
                    lo.y - pad + unit(rng) * (hi.y - lo.y + 2.f * pad),
                    lo.z - pad + unit(rng) * (hi.z - lo.z + 2.f * pad)};
    };
    constexpr size_t kCount = 40001;  // not a multiple of four: the one-by-one tail runs too
    std::vector<Float3> previous(kCount), positions(kCount), velocities(kCount);
    for (size_t k = 0; k < kCount; ++k) {
      Float3 p0 = point(0.01f), p1 = p0;
      switch (k % 8) {
        case 0:  // a point (a particle at rest)
          break;
        case 1: {  // cloth on the surface: from up to 2 mm above the front or below the back
                   // surface, a hundredth of a texel or up to 0.6 texel sideways, into it
          const float u = (p0.x - c.origin_x()) / texel, v = (p0.y - c.origin_y()) / texel;
          float top = 0.f, bottom = 0.f;
          if (u >= 0.f && v >= 0.f &&
              c.TexelSlab(static_cast<uint32_t>(u), static_cast<uint32_t>(v), &top, &bottom)) {
            const bool front = unit(rng) < 0.7f;
            p0.z = front ? top + 0.002f * unit(rng) : bottom - 0.002f * unit(rng);
            const float reach = (unit(rng) < 0.3f ? 0.02f : 1.2f) * texel;
            p1 = p0 + Float3{(unit(rng) - 0.5f) * reach, (unit(rng) - 0.5f) * reach,
                             (front ? -1.f : 1.f) * 0.004f * unit(rng)};
          }
          break;
        }
        case 2: {  // sliding: under half a texel, along z through a surface; a quarter of them
                   // steep, through a whole part
          const float rise = unit(rng) < 0.25f ? 1.f : 0.05f;
          p1 = p0 + Float3{(unit(rng) - 0.5f) * 0.8f * texel, (unit(rng) - 0.5f) * 0.8f * texel,
                           (unit(rng) - 0.5f) * rise};
          break;
        }
        case 3: {  // a few texels; a quarter of them steep, through a whole part in one texel
          const float rise = unit(rng) < 0.25f ? 1.f : 0.02f;
          p1 = p0 + Float3{(unit(rng) - 0.5f) * 6.f * texel, (unit(rng) - 0.5f) * 6.f * texel,
                           (unit(rng) - 0.5f) * rise};
          break;
        }
        case 4:  // beyond the clip box in z, or off the grid
          p0.z = unit(rng) < 0.5f ? hi.z + 0.01f : lo.z - 0.01f;
          p1 = unit(rng) < 0.5f ? Float3{p0.x, p0.y, 0.f} : point(0.3f);
          break;
        case 5: {  // starting or ending exactly on a surface value of the texel's slab
          const float u = (p0.x - c.origin_x()) / texel, v = (p0.y - c.origin_y()) / texel;
          float top = 0.f, bottom = 0.f;
          if (u >= 0.f && v >= 0.f &&
              c.TexelSlab(static_cast<uint32_t>(u), static_cast<uint32_t>(v), &top, &bottom)) {
            p0.z = unit(rng) < 0.5f ? top : bottom;
            p1 = Float3{p0.x, p0.y, p0.z + (unit(rng) - 0.5f) * 0.01f};
          }
          if (unit(rng) < 0.5f) {  // or ending exactly on one, 1-4 texels sideways
            const float angle = unit(rng) * 6.2831853f, reach = (1.f + 3.f * unit(rng)) * texel;
            p1 = p0 + Float3{reach * std::cos(angle), reach * std::sin(angle), 0.f};
            const float u1 = (p1.x - c.origin_x()) / texel, v1 = (p1.y - c.origin_y()) / texel;
            if (u1 >= 0.f && v1 >= 0.f &&
                c.TexelSlab(static_cast<uint32_t>(u1), static_cast<uint32_t>(v1), &top, &bottom)) {
              bool front = unit(rng) < 0.5f;
              // In a texel with gaps, on a gap's boundary half the time (the lower one is the
              // top of the interval below it).
              float upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers];
              const uint32_t gaps =
                  c.TexelGaps(static_cast<uint32_t>(u1), static_cast<uint32_t>(v1), upper, lower);
              if (gaps > 0 && unit(rng) < 0.5f) {
                const uint32_t g =
                    static_cast<uint32_t>(unit(rng) * static_cast<float>(gaps)) % gaps;
                front = unit(rng) < 0.5f;
                top = lower[g];
                bottom = upper[g];
              }
              p1.z = front ? top : bottom;
              p0.z = p1.z + (front ? 1.f : -1.f) * 0.001f * unit(rng);
            }
            // Or starting exactly on a gap's boundary of its own texel, moving sideways.
            float upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers];
            const uint32_t gaps =
                u >= 0.f && v >= 0.f
                    ? c.TexelGaps(static_cast<uint32_t>(u), static_cast<uint32_t>(v), upper, lower)
                    : 0u;
            if (gaps > 0 && unit(rng) < 0.5f) {
              const uint32_t g = static_cast<uint32_t>(unit(rng) * static_cast<float>(gaps)) % gaps;
              p0.z = unit(rng) < 0.5f ? upper[g] : lower[g];
              p1.z = p0.z + (unit(rng) - 0.5f) * 0.004f;
            }
          }
          break;
        }
        case 6: {  // non-finite input in one coordinate of one of the three arrays
          const float bad = unit(rng) < 0.5f ? nan : (unit(rng) < 0.5f ? inf : -inf);
          float* target[3] = {&p0.x, &p1.z, nullptr};
          const int which = static_cast<int>(unit(rng) * 3.f) % 3;
          if (target[which] != nullptr) *target[which] = bad;
          break;
        }
        default:  // long, across the box
          p1 = point(0.1f);
          break;
      }
      previous[k] = p0;
      positions[k] = p1;
      velocities[k] = RandomPoint(rng, -1.f, 1.f, -1.f, 1.f);
      if (k % 8 == 6 && k % 24 == 22) velocities[k].y = nan;
      // Motions from a gap out through the whole slab of their start texel, where that slab
      // ends inside the clip box (so the clipped motion leaves it too): the lanes must not take
      // a texel's slab for its gaps there.
      const float u = (p0.x - c.origin_x()) / texel, v = (p0.y - c.origin_y()) / texel;
      float upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers], top = 0.f, bottom = 0.f;
      if (u >= 0.f && v >= 0.f && IsFinite(p1) &&
          c.TexelSlab(static_cast<uint32_t>(u), static_cast<uint32_t>(v), &top, &bottom)) {
        const uint32_t gaps =
            c.TexelGaps(static_cast<uint32_t>(u), static_cast<uint32_t>(v), upper, lower);
        bool in_gap = false;
        for (uint32_t g = 0; g < gaps; ++g) in_gap |= p0.z < upper[g] && p0.z > lower[g];
        if (in_gap && ((p1.z > top && top < hi.z) || (p1.z < bottom && bottom > lo.z))) {
          const float edges = std::fabs(std::floor((p1.x - c.origin_x()) / texel) - std::floor(u)) +
                              std::fabs(std::floor((p1.y - c.origin_y()) / texel) - std::floor(v));
          (edges <= 1.f ? steep_short : steep_walked) += 1;
        }
      }
    }
    // The reference: one particle at a time through the documented contract.
    std::vector<Float3> want_positions = positions, want_velocities = velocities;
    std::vector<uint8_t> want_flags(kCount);
    uint32_t want_contacts = 0;
    for (size_t k = 0; k < kCount; ++k) {
      if (!IsFinite(previous[k]) || !IsFinite(positions[k]) || !IsFinite(velocities[k])) {
        want_flags[k] = kCollisionInvalidInput;
        continue;
      }
      const ContactQuery q = c.Query(previous[k], positions[k]);
      if (!q.contact) {
        want_flags[k] = kCollisionNone;
        continue;
      }
      ApplyResponse(q, params, &want_positions[k], &want_velocities[k]);
      want_flags[k] = static_cast<uint8_t>(kCollisionContact | q.flags);
      ++want_contacts;
    }
    EXPECT_GT(want_contacts, kCount / 10);
    for (int run = 0; run < 6; ++run) {  // 1 and 2 threads; each lane path the CPU has
      const int threads = 1 + run % 2;
      const TestLanes lanes = kEveryLanes[run / 2];
      if (!BodyMapColliderTestAccess::UseLanes(&c, lanes)) continue;
      SCOPED_TRACE(::testing::Message() << threads << " thread(s), " << LanesName(lanes));
      const int saved_threads = omp_get_max_threads();
      omp_set_num_threads(threads);
      std::vector<Float3> got_positions = positions, got_velocities = velocities;
      std::vector<uint8_t> got_flags(kCount, 0xee);
      uint32_t got_contacts = 0;
      const Status status =
          c.CollideBatch(previous, got_positions, got_velocities, got_flags, params, &got_contacts);
      omp_set_num_threads(saved_threads);
      ASSERT_TRUE(status.ok()) << status.message();
      EXPECT_EQ(got_contacts, want_contacts);
      int differing = 0;
      for (size_t k = 0; k < kCount && differing < 10; ++k) {
        const bool same = got_flags[k] == want_flags[k] &&
                          std::memcmp(&got_positions[k], &want_positions[k], sizeof(Float3)) == 0 &&
                          std::memcmp(&got_velocities[k], &want_velocities[k], sizeof(Float3)) == 0;
        if (!same) {
          ++differing;
          ADD_FAILURE() << "particle " << k << " (kind " << k % 8 << "): flags "
                        << int(got_flags[k]) << " want " << int(want_flags[k]);
        }
      }
    }
#if defined(__SSE2__)
    // The short-motion lanes must carry a real share of these particles: points, resting and
    // sliding motions, surface starts, in one texel or across one texel edge. Eight lanes (with
    // AVX2) answer the lanes four do, with the same bits and the same long motions.
    size_t answered = 0;
    // Whether p's texel has gaps: the lanes solve those texels' intervals themselves.
    const auto has_gaps = [&](Float3 p) {
      const float u = (p.x - c.origin_x()) / texel, v = (p.y - c.origin_y()) / texel;
      float upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers];
      return u >= 0.f && v >= 0.f &&
             c.TexelGaps(static_cast<uint32_t>(u), static_cast<uint32_t>(v), upper, lower) > 0;
    };
    std::vector<Float3> scratch_positions = positions, scratch_velocities = velocities;
    std::vector<uint8_t> scratch_flags(kCount);
    std::vector<uint32_t> four_answered, four_long;
    for (TestLanes kind : kEveryLanes) {
      if (!BodyMapColliderTestAccess::UseLanes(&c, kind)) {
        std::printf("this CPU lacks the %s: their short motions are not tested\n", LanesName(kind));
        continue;
      }
      const int width = BodyMapColliderTestAccess::LaneWidth(kind);
      SCOPED_TRACE(::testing::Message() << LanesName(kind) << ", short motions");
      scratch_positions = positions;
      scratch_velocities = velocities;
      for (size_t k = 0; k + static_cast<size_t>(width) <= kCount;
           k += static_cast<size_t>(width)) {
        uint32_t long_motions = 0;
        const uint32_t lanes = BodyMapColliderTestAccess::CollideShort(
            c, kind, &previous[k], &scratch_positions[k], &scratch_velocities[k], &scratch_flags[k],
            params, &long_motions);
        if (width == 4) {
          four_answered.push_back(lanes);
          four_long.push_back(long_motions);
        } else {
          const size_t group = k / 4;
          ASSERT_EQ(lanes, four_answered[group] | four_answered[group + 1] << 4) << "group " << k;
          ASSERT_EQ(long_motions, four_long[group] | four_long[group + 1] << 4) << "group " << k;
        }
        for (int lane = 0; lane < width; ++lane) {
          const size_t q = k + static_cast<size_t>(lane);
          if (!((lanes >> lane) & 1u)) {
            // Not answered: written back, the same bits, for the walk to read.
            ASSERT_TRUE(std::memcmp(&scratch_positions[q], &positions[q], sizeof(Float3)) == 0 &&
                        std::memcmp(&scratch_velocities[q], &velocities[q], sizeof(Float3)) == 0)
                << "short-motion lane not answered, but changed: particle " << q;
            continue;
          }
          ASSERT_TRUE(scratch_flags[q] == want_flags[q] &&
                      std::memcmp(&scratch_positions[q], &want_positions[q], sizeof(Float3)) == 0 &&
                      std::memcmp(&scratch_velocities[q], &want_velocities[q], sizeof(Float3)) == 0)
              << "short-motion lane: particle " << q << " (kind " << q % 8 << ")";
          if (width == 8) continue;
          ++answered;
          answered_outside +=
              !(previous[q].x >= lo.x && previous[q].x <= hi.x && previous[q].y >= lo.y &&
                previous[q].y <= hi.y && previous[q].z >= lo.z && previous[q].z <= hi.z);
          const uint8_t f = scratch_flags[q];
          answered_walls += (f & kCollisionSideWall) != 0;
          answered_inside += (f & kCollisionStartedInside) != 0;
          answered_entries += f == kCollisionContact;
          const bool at_gaps = has_gaps(previous[q]) || has_gaps(positions[q]);
          answered_gap_contacts += at_gaps && (f & kCollisionContact) != 0;
          answered_gap_inside += at_gaps && (f & kCollisionStartedInside) != 0;
        }
      }
    }

    // (The thin slab's 2 mm clip box sends most motions to the walk.)
    EXPECT_GT(answered, kCount / (body == 2 ? 40 : 5));

    // The walking lanes alone, four at a time and (with AVX2) eight, on groups of particles
    // spread over the set (and on partial groups): every lane they answer is the reference bit
    // for bit, and lanes they do not answer (or that are not in the mask) are untouched. The
    // counts below are of the four lanes.
    for (TestLanes kind : kEveryLanes) {
      if (!BodyMapColliderTestAccess::UseLanes(&c, kind)) {
        std::printf("this CPU lacks the %s: their walks are not tested\n", LanesName(kind));
        continue;
      }
      const int width = BodyMapColliderTestAccess::LaneWidth(kind);
      SCOPED_TRACE(::testing::Message() << LanesName(kind) << ", walks");
      const bool count = width == 4;
      scratch_positions = positions;
      scratch_velocities = velocities;
      std::fill(scratch_flags.begin(), scratch_flags.end(), uint8_t{0xee});
      size_t answered_here = 0;
      const uint32_t all = (1u << width) - 1u;
      for (uint32_t k = 0; k + static_cast<uint32_t>(width) * 997 < kCount; ++k) {
        uint32_t index[8];
        for (int lane = 0; lane < width; ++lane)
          index[lane] = k + static_cast<uint32_t>(lane) * 997;
        const uint32_t mask =
            k % 7 == 3 ? 0x5u : (k % 7 == 5 ? 0x2u : (k % 7 == 6 ? 0xa6u & all : all));
        const uint32_t lanes = BodyMapColliderTestAccess::CollideWalks(
            c, kind, index, mask, previous.data(), scratch_positions.data(),
            scratch_velocities.data(), scratch_flags.data(), params);
        ASSERT_EQ(lanes & ~mask, 0u);
        for (int lane = 0; lane < width; ++lane) {
          const uint32_t q = index[lane];
          if (!((lanes >> lane) & 1u)) {
            ASSERT_EQ(scratch_flags[q], 0xee) << "particle " << q << " not answered but written";
            continue;
          }
          ++answered_here;
          const bool same =
              scratch_flags[q] == want_flags[q] &&
              std::memcmp(&scratch_positions[q], &want_positions[q], sizeof(Float3)) == 0 &&
              std::memcmp(&scratch_velocities[q], &want_velocities[q], sizeof(Float3)) == 0;
          ASSERT_TRUE(same) << "walking lane: particle " << q << " (kind " << q % 8 << "): flags "
                            << int(scratch_flags[q]) << " want " << int(want_flags[q]);
          if (!count) continue;
          const bool clipped = !(previous[q].z >= lo.z && previous[q].z <= hi.z &&
                                 positions[q].z >= lo.z && positions[q].z <= hi.z);
          const uint32_t texels =
              static_cast<uint32_t>(std::abs(std::floor((positions[q].x - c.origin_x()) / texel) -
                                             std::floor((previous[q].x - c.origin_x()) / texel)) +
                                    std::abs(std::floor((positions[q].y - c.origin_y()) / texel) -
                                             std::floor((previous[q].y - c.origin_y()) / texel)));
          const uint8_t f = want_flags[q];
          walked_walls += (f & kCollisionSideWall) != 0;
          walked_inside += (f & kCollisionStartedInside) != 0;
          walked_entries += f == kCollisionContact;
          walked_clipped_entries += clipped && f == kCollisionContact;
          walked_z_face += clipped && f == kCollisionContact && previous[q].x == positions[q].x &&
                           previous[q].y == positions[q].y;
          walked_long += texels >= 3 && (f & kCollisionContact) != 0;
          // Contacts where the motion starts or ends in a texel with gaps (the walk's own visit
          // and IntervalAt answer those inside the lanes).
          walked_gap_contacts +=
              (f & kCollisionContact) != 0 && (has_gaps(previous[q]) || has_gaps(positions[q]));
          // Starts strictly inside a gap, which the lanes' start test does not look for (their
          // answers must match anyway: the note at start_inside in body_map_lane_walk.inl).
          const auto in_a_gap = [&](Float3 p) {
            const float u = (p.x - c.origin_x()) / texel, v = (p.y - c.origin_y()) / texel;
            float upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers];
            if (!(u >= 0.f && v >= 0.f)) return false;
            const uint32_t gaps =
                c.TexelGaps(static_cast<uint32_t>(u), static_cast<uint32_t>(v), upper, lower);
            for (uint32_t g = 0; g < gaps; ++g) {
              if (p.z < upper[g] && p.z > lower[g]) return true;
            }
            return false;
          };
          walked_gap_starts += in_a_gap(previous[q]);
        }
        // Restore what the lanes wrote, so later groups see the input.
        for (int lane = 0; lane < width; ++lane) {
          const uint32_t q = index[lane];
          scratch_positions[q] = positions[q];
          scratch_velocities[q] = velocities[q];
          scratch_flags[q] = 0xee;
        }
      }
      (count ? walked_answered : eight_lanes_answered[static_cast<int>(kind)]) += answered_here;
    }
#endif
  }
#if defined(__SSE2__)
  // ... and every kind of contact it can give: side walls, surface entries, push-outs.
  EXPECT_GT(answered_walls, 200u);
  EXPECT_GT(answered_entries, 2000u);
  EXPECT_GT(answered_inside, 10000u);
  EXPECT_GT(answered_outside, 1000u);  // points that stay outside the clip box
  // ... in texels with gaps too (their intervals, gap surfaces' normals, push-outs among gaps).
  EXPECT_GT(answered_gap_contacts, 1000u);
  EXPECT_GT(answered_gap_inside, 500u);
  // The layered body's posts and the steep motions make these (see kStackAndPosts).
  EXPECT_GT(steep_short, 10u);
  EXPECT_GT(steep_walked, 50u);
  // ... and the walking lanes: most particles, every kind of contact, entries of motions clipped
  // to the box (through its top or bottom face among them), contacts three or more texels away.
  EXPECT_GT(walked_answered, 60000u);
  EXPECT_GT(walked_walls, 500u);
  EXPECT_GT(walked_entries, 5000u);
  EXPECT_GT(walked_inside, 5000u);
  EXPECT_GT(walked_clipped_entries, 500u);
  EXPECT_GT(walked_z_face, 500u);
  EXPECT_GT(walked_long, 500u);
  EXPECT_GT(walked_gap_contacts, 500u);
  EXPECT_GT(walked_gap_starts, 100u);
  // Eight lanes answer about as many as four: the walks they give up on are the same.
  for (TestLanes kind : {TestLanes::kAvx2, TestLanes::kAvx512}) {
    if (BodyMapColliderTestAccess::UseLanes(&bodies[0], kind)) {
      EXPECT_GT(eight_lanes_answered[static_cast<int>(kind)], 300000u) << LanesName(kind);
    }
  }
  std::printf("short-motion lanes: %zu contacts at texels with gaps, %zu of them pushed out\n",
              answered_gap_contacts, answered_gap_inside);
  std::printf("motions from a gap through the whole slab: %zu within one texel edge, %zu walked\n",
              steep_short, steep_walked);
  std::printf(
      "walking lanes: %zu answered, %zu walls, %zu entries (%zu clipped, %zu through the "
      "box's z face), %zu pushed out, %zu contacts >= 3 texels away, %zu at texels with gaps, "
      "%zu starts in a gap; eight lanes: %zu answered (AVX2), %zu (AVX-512)\n",
      walked_answered, walked_walls, walked_entries, walked_clipped_entries, walked_z_face,
      walked_inside, walked_long, walked_gap_contacts, walked_gap_starts, eight_lanes_answered[1],
      eight_lanes_answered[2]);
#endif
}

}  // namespace drape

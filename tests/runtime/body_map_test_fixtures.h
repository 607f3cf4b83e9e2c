#pragma once
// Shared by the body-map tests: analytic bodies (a sphere, a box, a thin slab, stacks of boxes
// with air gaps) rasterised into poses on a grid of power-of-two texels, an exact reference for
// the first entry of a segment, comparisons bit for bit, and the lane packs to run.

#include <gtest/gtest.h>

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
#include <utility>
#include <vector>

#include "body_map/body_map_collider_access.h"
#include "drape/runtime/body_map_collider.h"
#include "drape/runtime/body_map_sequence.h"
#include "drape/runtime/math.h"
#include "drape/runtime/normal_encoding.h"

namespace drape::test {

// The lane packs CollideBatch can take with kNearest: each instruction set's.
inline constexpr InstructionSet kEveryLanes[] = {InstructionSet::kScalar, InstructionSet::kSse2,
                                                 InstructionSet::kAvx2};
inline const char* LanesName(InstructionSet set) {
  return set == InstructionSet::kScalar ? "four scalar lanes"
         : set == InstructionSet::kSse2 ? "four SSE2 lanes"
                                        : "eight AVX2 lanes";
}
// Sets c (and so CollideBatch) to take `set`'s lanes; false, with c unchanged, where the CPU
// lacks them (a test skips those).
inline bool UseLanes(BodyMapCollider* c, InstructionSet set) {
  if (UsableInstructionSet(set) != set) return false;
  c->LimitInstructionSet(set);
  return true;
}

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr float kTexel =
    1.f / 128.f;  // metres; a power of two, so texel edges are exact floats
// A side-wall contact point is stepped back across the wall by 1e-3 texel (so a particle placed
// there is outside): wall positions are compared with that allowance.
inline constexpr float kWallTolerance = 1.01e-3f * kTexel + 1e-6f;

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
inline BodyMapPose EmptyPose(const GridSpec& g, DepthEncoding depth_encoding,
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
inline void PutSurface(BodyMapPose& pose, size_t index, int view, bool valid, double depth,
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
inline BodyMapPose MakePose(const GridSpec& g, const SurfaceFn& surface,
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
inline constexpr double kSphereRadius = 0.3;
inline GridSpec SphereGrid() {
  GridSpec g;
  g.width = g.height = 88;
  g.origin_x = g.origin_y = -44.f * kTexel;
  return g;
}
inline double SphereHeight(double x, double y) {
  const double r2 = x * x + y * y;
  return r2 < kSphereRadius * kSphereRadius ? std::sqrt(kSphereRadius * kSphereRadius - r2) : -1.0;
}
inline SurfaceSample Sphere(double x, double y) {
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
inline constexpr float kBoxTop = 0.0625f, kBoxBottom = -0.0625f;
inline GridSpec BoxGrid() {
  GridSpec g;
  g.width = 64;
  g.height = 40;
  g.origin_x = -32.f * kTexel;
  g.origin_y = -20.f * kTexel;
  return g;
}
inline SurfaceSample Box(double x, double y) {
  SurfaceSample s;
  if (std::fabs(x) >= 25 * kTexel || std::fabs(y) >= 12 * kTexel) return s;
  s.valid = true;
  s.top = kBoxTop;
  s.bottom = kBoxBottom;
  return s;
}

// A horizontal slab 2 mm thick (z in [0, 0.002]), far thinner than the 10 cm steps thrown at it.
inline constexpr float kSlabThickness = 0.002f;
inline SurfaceSample ThinSlab(double x, double y) {
  SurfaceSample s;
  if (std::fabs(x) > 0.25 || std::fabs(y) > 0.25) return s;
  s.valid = true;
  s.top = kSlabThickness;
  s.bottom = 0.0;
  return s;
}

inline BodyMapCollider BuildOrDie(const BodyMapPose& pose,
                                  DepthSampling sampling = DepthSampling::kNearest) {
  BodyMapCollider collider;
  const Status status = collider.Build(pose, sampling);
  EXPECT_TRUE(status.ok()) << status.message();
  return collider;
}

// In double via atan2(|a x b|, a.b): acos of a float dot product cannot resolve 0.01 degrees.
inline double AngleDegrees(Float3 a, Float3 b) {
  const double ax = a.x, ay = a.y, az = a.z, bx = b.x, by = b.y, bz = b.z;
  const double cx = ay * bz - az * by, cy = az * bx - ax * bz, cz = ax * by - ay * bx;
  const double cross = std::sqrt(cx * cx + cy * cy + cz * cz);
  return std::atan2(cross, ax * bx + ay * by + az * bz) * 180.0 / kPi;
}

// Exact first entry of p0 -> p1 into the union of the collider's texel columns
// [x_i, x_i + s] x [y_j, y_j + s] x [bottom, top] (nearest sampling; one column per interval
// when the texel has air gaps), by brute force in double over every texel. Returns -1 when the
// segment misses all of them.
inline double ReferenceFirstEntry(const BodyMapCollider& c, Float3 p0, Float3 p1) {
  double best = -1.0;
  const double s = c.texel_size();
  for (uint32_t j = 0; j < c.height(); ++j) {
    for (uint32_t i = 0; i < c.width(); ++i) {
      float top, bottom, upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers];
      if (!BodyMapColliderAccess::TexelSlab(c, i, j, &top, &bottom)) continue;
      // The texel's inside intervals: the slab split by its air gaps.
      const uint32_t gaps = BodyMapColliderAccess::TexelGaps(c, i, j, upper, lower);
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

inline Float3 RandomPoint(std::mt19937& rng, float lo, float hi, float z_lo, float z_hi) {
  std::uniform_real_distribution<float> xy(lo, hi), z(z_lo, z_hi);
  const float x = xy(rng), y = xy(rng);
  return {x, y, z(rng)};
}

// Even k: a long segment from anywhere in a 0.8 m cube through a point near the shapes (many
// texels, the 8x8 block walk). Odd k: a short one (up to ~3 texels) near the surfaces.
inline void RandomSegment(std::mt19937& rng, int k, Float3* p0, Float3* p1) {
  const Float3 target = RandomPoint(rng, -0.25f, 0.25f, -0.2f, 0.2f);
  if (k % 2 == 0) {
    *p0 = RandomPoint(rng, -0.4f, 0.4f, -0.4f, 0.4f);
    *p1 = *p0 + (target - *p0) * 1.6f;
  } else {
    *p0 = target + RandomPoint(rng, -0.01f, 0.01f, -0.01f, 0.01f);
    *p1 = *p0 + RandomPoint(rng, -0.012f, 0.012f, -0.012f, 0.012f);
  }
}

struct WalkCounts {
  int hits = 0, misses = 0, side_walls = 0;
};
inline WalkCounts ExpectWalkMatchesReference(const BodyMapCollider& c, uint32_t seed, int segments,
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

// --- Row-span layout: the same grid as the dense layout, bit for bit -------------------------

inline uint32_t Bits(float v) { return std::bit_cast<uint32_t>(v); }

// The bake writes zero normal codes on background and the row-span layout cannot carry any
// other value there (expanding it writes zeros), so the dense reference gets the same.
inline void ZeroBackgroundNormals(BodyMapPose& pose) {
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

inline void ExpectSameBits(Float3 a, Float3 b, const char* what, int k) {
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
inline OneByOne QueryOneByOne(const BodyMapCollider& c, const std::vector<Float3>& previous,
                              const std::vector<Float3>& positions,
                              const std::vector<Float3>& velocities, const ResponseParams& params) {
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

// A particle resting at `p` (16 of them, one lane pack's worth and more): CollideBatch in every
// lane pack moves them as Query and ApplyResponse do, bit for bit, with the same flags.
inline void ExpectEveryLanePackAnswersAsQuery(const BodyMapCollider& c, Float3 p) {
  const std::vector<Float3> previous(16, p), velocities(16);
  ResponseParams params;
  params.separation = 1e-3f;
  const OneByOne want = QueryOneByOne(c, previous, previous, velocities, params);
  for (const InstructionSet set : kEveryLanes) {
    BodyMapCollider lanes = c;
    if (!UseLanes(&lanes, set)) continue;
    std::vector<Float3> positions = previous, got_velocities = velocities;
    std::vector<uint8_t> flags(16);
    ASSERT_TRUE(lanes.CollideBatch(previous, positions, got_velocities, flags, params).ok());
    for (int k = 0; k < 16; ++k) {
      ExpectSameBits(positions[k], want.positions[k], LanesName(set), k);
      EXPECT_EQ(flags[k], want.flags[k]) << LanesName(set);
    }
  }
}

// Every field of two answers, bit for bit (query k).
inline void ExpectSameAnswer(const ContactQuery& a, const ContactQuery& b, int k) {
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
inline void ExpectIdenticalColliders(const BodyMapCollider& a, const BodyMapCollider& b,
                                     int segments, float pad) {
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
      const bool av = BodyMapColliderAccess::TexelSlab(a, i, j, &at, &ab),
                 bv = BodyMapColliderAccess::TexelSlab(b, i, j, &bt, &bb);
      for (bool back : {false, true}) {
        const Float3 an = BodyMapColliderAccess::TexelNormal(a, i, j, back),
                     bn = BodyMapColliderAccess::TexelNormal(b, i, j, back);
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

struct ZBox {
  float x_lo, x_hi, y_lo, y_hi, z_lo, z_hi;  // metres
};
// Edges on texel boundaries (multiples of 1/128 m), so every texel centre is clearly in or out.
inline constexpr ZBox kBlock{-30 * kTexel, 30 * kTexel, -30 * kTexel, 30 * kTexel, -0.10f, 0.05f};
inline constexpr ZBox kPlate{-20 * kTexel, 20 * kTexel, -20 * kTexel, 20 * kTexel, 0.10f, 0.12f};
inline constexpr ZBox kMidPlate{0.f, 10 * kTexel, -10 * kTexel, 10 * kTexel, 0.065f, 0.075f};
// Distinct gap-boundary normals, so a test can tell which array an answer read.
inline const Float3 kGapUpperNormal = NormalizeOr(Float3{0.3f, 0.f, -1.f}, Float3{});
inline const Float3 kGapLowerNormal = NormalizeOr(Float3{0.f, 0.3f, 1.f}, Float3{});

// The boxes' z intervals (top, bottom) at the centre of texel (i, j), from the top; disjoint by
// construction.
inline std::vector<std::pair<float, float>> BoxSpans(const std::vector<ZBox>& boxes, uint32_t i,
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
inline GapsByTexel BoxGaps(uint8_t layers, const std::vector<ZBox>& boxes) {
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
inline BodyMapPose PackLayered(uint8_t layers, const std::vector<ZBox>& boxes,
                               const GapsByTexel& gaps,
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

inline BodyMapPose LayeredPose(uint8_t layers, const std::vector<ZBox>& boxes,
                               DepthEncoding depth_encoding = DepthEncoding::kFloat32,
                               NormalEncoding normal_encoding = NormalEncoding::kFloat32) {
  return PackLayered(layers, boxes, BoxGaps(layers, boxes), depth_encoding, normal_encoding);
}

inline const std::vector<ZBox> kStack = {kBlock, kPlate, kMidPlate};
// The stack with two posts off the block, one lower and one higher than the stack: the clip box
// then reaches beyond the slabs of the texels with gaps, so a walk can leave such a slab
// through its back or front surface within one texel.
inline constexpr ZBox kLowPost{34 * kTexel, 40 * kTexel, -6 * kTexel, 0.f, -0.2f, -0.15f};
inline constexpr ZBox kHighPost{34 * kTexel, 40 * kTexel, kTexel, 6 * kTexel, 0.15f, 0.2f};
inline const std::vector<ZBox> kStackAndPosts = {kBlock, kPlate, kMidPlate, kLowPost, kHighPost};

}  // namespace drape::test

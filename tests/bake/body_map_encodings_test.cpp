// Body-map encodings: the oct16 and rgb8 normal codecs and the unorm16 depth codec round-trip
// within their documented errors, and bakes in the compact encodings read as the float32 bake
// does within the same bounds.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "body_map_fixtures.h"
#include "drape/bake/body_map_baker.h"

namespace drape::bake {
namespace {

using namespace body_map_fixtures;

TEST(BodyMapBaker, CodecsRoundTripWithinTheirDocumentedErrors) {
  std::mt19937 rng(12345);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<Vec3d> directions = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},   {0, -1, 0},       {0, 0, 1},
                                   {0, 0, -1}, {1, 1, 1},  {-1, 1, -1}, {0.3, -0.2, -0.9}};
  for (int k = 0; k < 20000; ++k) directions.push_back({gauss(rng), gauss(rng), gauss(rng)});
  double max_oct = 0.0, max_rgb = 0.0;
  for (const Vec3d& d : directions) {
    const Vec3d n = Scale(d, 1.0 / Len(d));
    const Float3 nf{float(n.x), float(n.y), float(n.z)};
    max_oct = std::max(max_oct, AngleDeg(ToD3(DecodeNormalOct16(EncodeNormalOct16(nf))), n));
    uint8_t rgb[3];
    EncodeNormalRgb8(nf, rgb);
    max_rgb = std::max(max_rgb, AngleDeg(ToD3(DecodeNormalRgb8(rgb)), n));
  }
  EXPECT_LE(max_oct, 0.01);
  EXPECT_LE(max_rgb, 0.5);
  // The rgb8 formula is paper A's: round((n * 0.5 + 0.5) * 255).
  uint8_t rgb[3];
  EncodeNormalRgb8({0.f, -1.f, 0.6f}, rgb);
  EXPECT_EQ(rgb[0], 128);
  EXPECT_EQ(rgb[1], 0);
  EXPECT_EQ(rgb[2], 204);
  // Depth: unorm16 error <= depth_range / 65535, 65535 reserved for background.
  const float range = 0.73f;
  for (int k = 0; k <= 1000; ++k) {
    const float depth = range * float(k) / 1000.f * 0.99999f;
    const uint16_t code = EncodeDepthUnorm16(depth, range);
    EXPECT_LE(code, 65534);
    EXPECT_LE(std::fabs(DecodeDepthUnorm16(code, range) - depth), range / 65535.0);
  }
  EXPECT_EQ(EncodeDepthUnorm16(range, range), 65534);
}

TEST(BodyMapBaker, EncodedBakesMatchTheFloatBake) {
  const Mesh sphere = MakeSphere({0.0, 0.0, 0.0}, 0.3, 40, 40);
  const BodyMapPose reference = BakeOrDie(sphere, FloatOptions(256));
  BodyMapOptions compact = FloatOptions(256), paper = FloatOptions(256);
  compact.depth_encoding = DepthEncoding::kUnorm16;
  compact.normal_encoding = NormalEncoding::kOct16;
  paper.normal_encoding = NormalEncoding::kRgb8;
  // Dense, so the arrays can be indexed by j * width + i below (row spans read the same through
  // ReadBodyMapTexel: RowSpansHoldTheSameMapsAsDenseOnASphere).
  compact.layout = paper.layout = BodyMapLayout::kDense;
  BodyMapOptions dense_reference = FloatOptions(256);
  dense_reference.layout = BodyMapLayout::kDense;
  const BodyMapPose reference_dense = BakeOrDie(sphere, dense_reference);
  BodyMapPoseStats compact_stats;
  const BodyMapPose a = BakeOrDie(sphere, compact, &compact_stats);
  const BodyMapPose b = BakeOrDie(sphere, paper);
  ASSERT_EQ(a.width, reference.width);
  ASSERT_EQ(a.height, reference.height);
  EXPECT_TRUE(a.depth_f32[0].empty() && a.normal_f32[0].empty() && a.normal_rgb8[0].empty());
  EXPECT_EQ(a.depth_u16[1].size(), size_t(a.width) * a.height);
  EXPECT_EQ(a.normal_oct16[1].size(), 2 * size_t(a.width) * a.height);
  EXPECT_EQ(compact_stats.bytes, 2 * size_t(a.width) * a.height * (2 + 4));
  double max_depth = 0.0, max_oct = 0.0, max_rgb = 0.0;
  size_t valid = 0;
  for (uint32_t j = 0; j < a.height; ++j) {
    for (uint32_t i = 0; i < a.width; ++i) {
      for (int view = 0; view < 2; ++view) {
        const BodyMapTexel r = ReadBodyMapTexel(reference, view, i, j);
        const BodyMapTexel ta = ReadBodyMapTexel(a, view, i, j);
        const BodyMapTexel tb = ReadBodyMapTexel(b, view, i, j);
        ASSERT_EQ(r.valid, ta.valid);
        ASSERT_EQ(r.valid, tb.valid);
        if (!r.valid) {
          EXPECT_EQ(a.depth_u16[view][size_t(j) * a.width + i], 65535);
          EXPECT_EQ(reference_dense.depth_f32[view][size_t(j) * a.width + i],
                    reference.depth_range);
          continue;
        }
        ++valid;
        max_depth = std::max(max_depth, std::fabs(double(ta.depth) - r.depth));
        max_oct = std::max(max_oct, AngleDeg(ToD3(ta.normal), ToD3(r.normal)));
        max_rgb = std::max(max_rgb, AngleDeg(ToD3(tb.normal), ToD3(r.normal)));
      }
    }
  }
  EXPECT_GT(valid, 1000u);
  EXPECT_LE(max_depth, double(reference.depth_range) / 65535.0);
  EXPECT_LE(max_oct, 0.01);
  EXPECT_LE(max_rgb, 0.5);
}

}  // namespace
}  // namespace drape::bake

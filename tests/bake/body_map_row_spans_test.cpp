// The row-span layout against the dense one: the same maps once expanded, the same texels read,
// runtime colliders that answer every texel and random segments bit for bit, every gap layer
// carried, and the built-in mannequin at N = 512 in a fraction of the dense bytes.

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "body_map/body_map_collider_access.h"
#include "body_map_fixtures.h"
#include "body_map_gap_fixtures.h"
#include "drape/bake/bake_config.h"
#include "drape/bake/bake_pipeline.h"
#include "drape/bake/body_map_baker.h"
#include "drape/runtime/body_map_collider.h"
#include "test_support.h"

namespace drape::bake {
namespace {

using namespace body_map_fixtures;

// --- Layouts: row spans hold the same maps as the dense rectangle, in a fraction of the bytes ---

// The two layouts of one bake: the same arrays once expanded, the same texels read, and the
// runtime colliders built from them answer every texel and `segments` random queries bit for bit.
// `spans` expanded to the dense layout holds exactly `dense`'s arrays and gap list.
void ExpandsToTheSameArrays(const BodyMapPose& spans, const BodyMapPose& dense) {
  BodyMapPose expanded;
  const Status status = ConvertBodyMapLayout(spans, BodyMapLayout::kDense, &expanded);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(expanded.gap_texels, dense.gap_texels);
  for (int view = 0; view < 2; ++view) {
    EXPECT_EQ(expanded.depth_f32[view], dense.depth_f32[view]);
    EXPECT_EQ(expanded.depth_u16[view], dense.depth_u16[view]);
    EXPECT_EQ(expanded.normal_f32[view], dense.normal_f32[view]);
    EXPECT_EQ(expanded.normal_oct16[view], dense.normal_oct16[view]);
    EXPECT_EQ(expanded.normal_rgb8[view], dense.normal_rgb8[view]);
  }
}

void ExpectLayoutsEquivalent(const BodyMapPose& dense, const BodyMapPose& spans, int segments) {
  ASSERT_EQ(dense.layout, BodyMapLayout::kDense);
  ASSERT_EQ(spans.layout, BodyMapLayout::kRowSpans);
  ASSERT_EQ(spans.width, dense.width);
  ASSERT_EQ(spans.height, dense.height);
  EXPECT_EQ(Bits(spans.origin_x), Bits(dense.origin_x));
  EXPECT_EQ(Bits(spans.origin_y), Bits(dense.origin_y));
  EXPECT_EQ(Bits(spans.front_z), Bits(dense.front_z));
  EXPECT_EQ(Bits(spans.depth_range), Bits(dense.depth_range));
  ExpandsToTheSameArrays(spans, dense);
  size_t texel_mismatches = 0;
  for (uint32_t j = 0; j < dense.height; ++j) {
    for (uint32_t i = 0; i < dense.width; ++i) {
      for (int view = 0; view < 2; ++view) {
        const BodyMapTexel a = ReadBodyMapTexel(dense, view, i, j);
        const BodyMapTexel b = ReadBodyMapTexel(spans, view, i, j);
        texel_mismatches +=
            a.valid != b.valid || Bits(a.depth) != Bits(b.depth) || !SameBits(a.normal, b.normal);
      }
    }
  }
  EXPECT_EQ(texel_mismatches, 0u);

  for (DepthSampling sampling : {DepthSampling::kNearest, DepthSampling::kBilinear}) {
    BodyMapCollider a, b;
    ASSERT_TRUE(a.Build(dense, sampling).ok());
    ASSERT_TRUE(b.Build(spans, sampling).ok());
    ASSERT_EQ(a.width(), b.width());
    ASSERT_EQ(a.height(), b.height());
    EXPECT_EQ(a.stats().valid_texels, b.stats().valid_texels);
    EXPECT_EQ(a.stats().bilinear_blocks, b.stats().bilinear_blocks);
    EXPECT_TRUE(SameBits(a.bounds_min(), b.bounds_min()));
    EXPECT_TRUE(SameBits(a.bounds_max(), b.bounds_max()));
    size_t slab_mismatches = 0;
    for (uint32_t j = 0; j < a.height(); ++j) {
      for (uint32_t i = 0; i < a.width(); ++i) {
        float at = 0.f, ab = 0.f, bt = 0.f, bb = 0.f;
        const bool av = BodyMapColliderAccess::TexelSlab(a, i, j, &at, &ab),
                   bv = BodyMapColliderAccess::TexelSlab(b, i, j, &bt, &bb);
        slab_mismatches += av != bv || Bits(at) != Bits(bt) || Bits(ab) != Bits(bb) ||
                           !SameBits(BodyMapColliderAccess::TexelNormal(a, i, j, false),
                                     BodyMapColliderAccess::TexelNormal(b, i, j, false)) ||
                           !SameBits(BodyMapColliderAccess::TexelNormal(a, i, j, true),
                                     BodyMapColliderAccess::TexelNormal(b, i, j, true));
      }
    }
    EXPECT_EQ(slab_mismatches, 0u);
    // Segments between points of the valid box widened by 5 % of its size: long ones across
    // the body and short ones of a few texels near it.
    const Float3 lo = a.bounds_min(), hi = a.bounds_max();
    const Float3 pad = (hi - lo) * 0.05f;
    std::mt19937_64 rng(0x5EA5);
    std::uniform_real_distribution<float> unit(0.f, 1.f);
    const auto point = [&] {
      return Float3{lo.x - pad.x + unit(rng) * (hi.x - lo.x + 2.f * pad.x),
                    lo.y - pad.y + unit(rng) * (hi.y - lo.y + 2.f * pad.y),
                    lo.z - pad.z + unit(rng) * (hi.z - lo.z + 2.f * pad.z)};
    };
    int query_mismatches = 0, contacts = 0;
    for (int k = 0; k < segments; ++k) {
      const Float3 p0 = point();
      const Float3 p1 = k % 2 == 0 ? point() : p0 + (point() - p0) * (4.f * a.texel_size());
      const ContactQuery qa = a.Query(p0, p1), qb = b.Query(p0, p1);
      query_mismatches += !SameBits(qa, qb) || a.IsInside(p1) != b.IsInside(p1);
      contacts += qa.contact;
    }
    EXPECT_EQ(query_mismatches, 0);
    EXPECT_GT(contacts, segments / 20) << "the segments must exercise contacts";
  }
}

TEST(BodyMapBaker, RowSpansHoldTheSameMapsAsDenseOnASphere) {
  const Mesh sphere = MakeSphere({0.01, 0.02, 0.03}, 0.3, 40, 40);
  for (const bool compact : {false, true}) {
    BodyMapOptions o = FloatOptions(256);
    if (compact) {
      o.depth_encoding = DepthEncoding::kUnorm16;
      o.normal_encoding = NormalEncoding::kOct16;
    }
    o.layout = BodyMapLayout::kDense;
    BodyMapPoseStats dense_stats, spans_stats;
    const BodyMapPose dense = BakeOrDie(sphere, o, &dense_stats);
    o.layout = BodyMapLayout::kRowSpans;
    const BodyMapPose spans = BakeOrDie(sphere, o, &spans_stats);
    SCOPED_TRACE(compact ? "unorm16 + oct16" : "float32");
    ExpectLayoutsEquivalent(dense, spans, 4000);
    // The stored texels are exactly the valid ones (both views agree after the bake's
    // consistency step), and the bytes are what the arrays and the span table hold.
    const size_t per_texel = compact ? 2 * (2 + 4) : 2 * (4 + 12);
    EXPECT_EQ(spans_stats.stored_texels, spans_stats.valid_texels);
    EXPECT_EQ(spans_stats.valid_texels, dense_stats.valid_texels);
    EXPECT_EQ(dense_stats.stored_texels, size_t(dense.width) * dense.height);
    EXPECT_EQ(dense_stats.bytes, per_texel * dense.width * dense.height);
    EXPECT_EQ(spans_stats.bytes, per_texel * spans_stats.stored_texels + SpanTableBytes(spans));
    // A disc in its square: pi/4 of the rectangle plus the border.
    EXPECT_LT(spans_stats.bytes, dense_stats.bytes * 4 / 5);
  }
}

// The built-in mannequin at N = 512 in the compact encodings: measured 581,232 bytes
// in row spans (47,770 texels of the 424 x 508 rectangle, 18.2 % of the window) against
// 2,584,704 bytes dense.
TEST(BodyMapBaker, MannequinAt512CompactIsUnderTwoMegabytesInRowSpans) {
  BakeConfig config;
  config.hulls_enabled = false;
  config.spheres_enabled = false;
  config.maps.resolution = 512;
  config.maps.depth_encoding = DepthEncoding::kUnorm16;
  config.maps.normal_encoding = NormalEncoding::kOct16;
  BakeResult spans, dense;
  ASSERT_EQ(config.maps.layout, BodyMapLayout::kRowSpans) << "row spans are the default";
  Status status = BakeCharacter(test::MannequinPath(), config, &spans);
  ASSERT_TRUE(status.ok()) << status.message();
  config.maps.layout = BodyMapLayout::kDense;
  status = BakeCharacter(test::MannequinPath(), config, &dense);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(spans.asset.body_maps.poses.size(), 1u);
  ASSERT_EQ(dense.asset.body_maps.poses.size(), 1u);
  const BodyMapPose& s = spans.asset.body_maps.poses[0];
  const BodyMapPose& d = dense.asset.body_maps.poses[0];
  const nlohmann::json& spans_report = spans.report["body_maps"]["poses"][0];
  const nlohmann::json& dense_report = dense.report["body_maps"]["poses"][0];
  const size_t spans_bytes = spans_report["bytes"].get<size_t>();
  const size_t dense_bytes = dense_report["bytes"].get<size_t>();
  EXPECT_EQ(spans_report["layout"], "spans");
  EXPECT_EQ(dense_report["layout"], "dense");
  EXPECT_EQ(spans_bytes, 12 * BodyMapStoredTexels(s) + SpanTableBytes(s));
  EXPECT_EQ(dense_bytes, 12 * size_t(d.width) * d.height);
  // The bound, and the measured figure with a 10 % margin (so a real regression shows).
  EXPECT_LT(spans_bytes, 2'000'000u);
  EXPECT_LT(spans_bytes, 640'000u) << "measured 581,232 bytes";
  EXPECT_GT(dense_bytes, 2'500'000u) << "measured 2,584,704 bytes (424 x 508 texels)";
  ExpectLayoutsEquivalent(d, s, 4000);
}

TEST(BodyMapBaker, RowSpansCarryEveryGapLayer) {
  const Mesh scene = GapScene();
  for (const bool compact : {false, true}) {
    SCOPED_TRACE(compact ? "unorm16 + oct16" : "float32");
    BodyMapOptions o = DenseGapOptions(256, 3, compact);
    BodyMapPoseStats dense_stats, spans_stats, slab_stats;
    const BodyMapPose dense = BakeOrDie(scene, o, &dense_stats);
    o.layout = BodyMapLayout::kRowSpans;
    const BodyMapPose spans = BakeOrDie(scene, o, &spans_stats);
    o.layers = 1;
    const BodyMapPose slab = BakeOrDie(scene, o, &slab_stats);
    ASSERT_EQ(spans.layers, 3);
    // Layer 0 decides the spans.
    EXPECT_EQ(spans.row_span_offsets, slab.row_span_offsets);
    EXPECT_EQ(spans.span_begin, slab.span_begin);
    EXPECT_EQ(spans.span_texel_offsets, slab.span_texel_offsets);
    EXPECT_EQ(spans_stats.gap_texels, dense_stats.gap_texels);
    EXPECT_EQ(spans_stats.stored_texels, slab_stats.stored_texels);
    const size_t per_texel = compact ? 2 * (2 + 4) : 2 * (4 + 12);
    const size_t listed = spans.gap_texels.size();
    EXPECT_EQ(listed, spans_stats.gap_texels);
    EXPECT_EQ(spans_stats.bytes, per_texel * (spans_stats.stored_texels + 2 * listed) +
                                     SpanTableBytes(spans) + 4 * listed);
    ExpandsToTheSameArrays(spans, dense);
    size_t mismatches = 0;
    for (uint32_t j = 0; j < dense.height; ++j) {
      for (uint32_t i = 0; i < dense.width; ++i) {
        for (uint32_t layer = 0; layer < 3; ++layer) {
          for (int view = 0; view < 2; ++view) {
            const BodyMapTexel a = ReadBodyMapTexel(dense, view, i, j, layer);
            const BodyMapTexel b = ReadBodyMapTexel(spans, view, i, j, layer);
            mismatches += a.valid != b.valid || Bits(a.depth) != Bits(b.depth) ||
                          !SameBits(a.normal, b.normal);
          }
        }
      }
    }
    EXPECT_EQ(mismatches, 0u);
  }
}

}  // namespace
}  // namespace drape::bake

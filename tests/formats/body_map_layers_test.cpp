// Depth layers of a body-map pose (BodyMapPose class version 3, format version 3): three layers
// round-trip in every encoding and both layouts, the layers byte sits where docs/FORMAT.md says,
// wrong layer counts, mis-sized arrays and gaps outside the slab are refused naming the field,
// layout conversion keeps every layer, and every truncation of a layered file fails cleanly.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "asset_fixtures.h"
#include "drape/formats/asset_file.h"

namespace drape {
namespace {

using test::Encode;
using test::ExpectSameMaps;
using test::FixChecksums;
using test::LayerDepth;
using test::LayeredAsset;
using test::LayeredDensePose;
using test::SmallAsset;

TEST(BodyMapLayers, ThreeLayersRoundTripInEveryEncodingAndBothLayouts) {
  const DepthEncoding depths[2] = {DepthEncoding::kFloat32, DepthEncoding::kUnorm16};
  const NormalEncoding normals[3] = {NormalEncoding::kFloat32, NormalEncoding::kOct16,
                                     NormalEncoding::kRgb8};
  for (DepthEncoding depth : depths) {
    for (NormalEncoding normal : normals) {
      for (BodyMapLayout layout : {BodyMapLayout::kDense, BodyMapLayout::kRowSpans}) {
        SCOPED_TRACE(testing::Message() << "depth " << int(depth) << ", normal " << int(normal)
                                        << ", layout " << int(layout));
        BodyMapPose pose;
        ASSERT_TRUE(ConvertBodyMapLayout(LayeredDensePose(depth, normal, 3), layout, &pose).ok());
        CharacterAsset a = SmallAsset();
        a.body_maps.poses.push_back(pose);
        const std::vector<uint8_t> bytes = Encode(a);
        CharacterAsset b;
        const Status s = DecodeAsset(bytes, "layers.drape", &b);
        ASSERT_TRUE(s.ok()) << s.message();
        EXPECT_EQ(AssetToJson(a), AssetToJson(b));
        ASSERT_EQ(b.body_maps.poses.size(), 2u);
        EXPECT_EQ(b.body_maps.poses[0].layers, 1);
        const BodyMapPose& back = b.body_maps.poses[1];
        EXPECT_EQ(back.layers, 3);
        ExpectSameMaps(back, pose);
        // Gap 2 at texel (0, 2) (dense texel 10, the last of the 5 gap texels), front view:
        // entry stored + 1 * 5 + 4.
        const size_t stored = BodyMapStoredTexels(back);
        EXPECT_EQ(stored, layout == BodyMapLayout::kDense ? 15u : 9u);
        const int64_t index = BodyMapTexelIndex(back, 0, 2);
        ASSERT_GE(index, 0);
        ASSERT_EQ(back.gap_texels.size(), 5u);
        EXPECT_EQ(back.gap_texels[4], static_cast<uint32_t>(index));
        EXPECT_EQ(BodyMapArrayEntries(back), stored + 2 * 5);
        const size_t entry = stored + 5 + 4;
        if (depth == DepthEncoding::kFloat32) {
          EXPECT_EQ(back.depth_f32[0].size(), stored + 10);
          EXPECT_EQ(back.depth_f32[0][entry], LayerDepth(0, 2, 10));
        } else {
          EXPECT_EQ(back.depth_u16[1].size(), stored + 10);
          EXPECT_EQ(back.depth_u16[1][entry], std::lround(LayerDepth(1, 2, 10) * 65535.f));
        }
        EXPECT_EQ(Encode(b), bytes) << "the writer is deterministic";
      }
    }
  }
}

// docs/FORMAT.md: `layers` is one byte right after `layout`, before the span table.
TEST(BodyMapLayers, LayersFollowLayoutBeforeTheSpanTable) {
  const std::vector<uint8_t> bytes = Encode(LayeredAsset());
  // texel_size, front_z, depth_range (float32), the encodings, layout (row spans), layers, the
  // view axis (z), then row_span_offsets' uint64 count (height + 1 = 4).
  const std::vector<uint8_t> pattern = {
      0, 0, 0, 0x3E, 0, 0, 0, 0x3F, 0, 0, 0x80, 0x3F,  // 0.125f, 0.5f, 1.f, little-endian
      0, 1, 1, 3,    0, 4, 0, 0,    0, 0, 0,    0,    0};
  const auto found = std::search(bytes.begin(), bytes.end(), pattern.begin(), pattern.end());
  ASSERT_NE(found, bytes.end());
  // The byte is the field: 3 -> 2 with the arrays left at three layers is refused by size.
  std::vector<uint8_t> bad = bytes;
  bad[static_cast<size_t>(found - bytes.begin()) + 15] = 2;
  FixChecksums(bad);
  CharacterAsset out;
  const Status s = DecodeAsset(bad, "layers.drape", &out);
  EXPECT_EQ(s.code(), StatusCode::kCorrupt);
  EXPECT_NE(s.message().find("body_maps.poses[1].depth_f32_front has 19 elements, expected 14"),
            std::string::npos)
      << s.message();
}

TEST(BodyMapLayers, LayerCountOutsideOneToFourIsRefusedNamingTheField) {
  const CharacterAsset good = LayeredAsset();
  ASSERT_TRUE(ValidateAsset(good).ok()) << ValidateAsset(good).message();
  for (uint8_t layers : {uint8_t{0}, uint8_t{5}}) {
    CharacterAsset a = good;
    a.body_maps.poses[1].layers = layers;
    const std::string expected =
        "body_maps.poses[1].layers = " + std::to_string(layers) + " is not in [1, 4]";
    const Status v = ValidateAsset(a);
    EXPECT_EQ(v.message(), expected);
    std::vector<uint8_t> refused;
    EXPECT_FALSE(EncodeAsset(a, &refused).ok()) << "the writer must refuse layers " << int(layers);
    BodyMapPose converted;
    const Status c = ConvertBodyMapLayout(a.body_maps.poses[1], BodyMapLayout::kDense, &converted);
    EXPECT_EQ(c.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(c.message().find("layers = " + std::to_string(layers)), std::string::npos)
        << c.message();
  }
  // The same in a file with valid checksums: a corrupt error naming the field.
  const std::vector<uint8_t> bytes = Encode(good);
  const std::vector<uint8_t> pattern = {0, 1, 1, 3, 0, 4, 0, 0, 0, 0, 0, 0, 0};  // encodings..count
  const auto found = std::search(bytes.begin(), bytes.end(), pattern.begin(), pattern.end());
  ASSERT_NE(found, bytes.end());
  for (uint8_t layers : {uint8_t{0}, uint8_t{5}}) {
    std::vector<uint8_t> bad = bytes;
    bad[static_cast<size_t>(found - bytes.begin()) + 3] = layers;
    FixChecksums(bad);
    CharacterAsset out;
    const Status s = DecodeAsset(bad, "layers.drape", &out);
    EXPECT_EQ(s.code(), StatusCode::kCorrupt);
    EXPECT_EQ(s.message(), "layers.drape: body_maps.poses[1].layers = " + std::to_string(layers) +
                               " is not in [1, 4]");
    EXPECT_TRUE(out.body_maps.poses.empty());
  }
}

TEST(BodyMapLayers, ArraysSizedForAnotherLayerCountAreRefusedNamingTheArray) {
  const CharacterAsset good = LayeredAsset();  // 9 stored texels, 3 layers, 5 gap texels: 19
  const auto expect = [](const CharacterAsset& a, const std::string& text) {
    const Status s = ValidateAsset(a);
    EXPECT_NE(s.message().find(text), std::string::npos) << s.message();
    std::vector<uint8_t> bytes;
    EXPECT_FALSE(EncodeAsset(a, &bytes).ok()) << "the writer must refuse it: " << text;
  };
  const std::string at = "body_maps.poses[1].";
  CharacterAsset a = good;
  a.body_maps.poses[1].layers = 2;  // the arrays hold two gap layers
  expect(a, at + "depth_f32_front has 19 elements, expected 14");
  a = good;
  a.body_maps.poses[1].layers = 4;
  expect(a, at + "depth_f32_front has 19 elements, expected 24");
  a = good;
  a.body_maps.poses[1].gap_texels.pop_back();  // a gap texel fewer: 9 + 2 * 4
  expect(a, at + "depth_f32_front has 19 elements, expected 17");
  a = good;
  a.body_maps.poses[1].depth_f32[1].resize(14);  // back depth of one gap layer only
  expect(a, at + "depth_f32_back has 14 elements, expected 19");
  a = good;
  a.body_maps.poses[1].normal_oct16[1].resize(2 * 9);  // the slab's normals only
  expect(a, at + "normal_oct16_back has 18 elements, expected 38");
  // Dense: 15 texels and 5 gap texels.
  CharacterAsset dense = SmallAsset();
  dense.body_maps.poses.push_back(
      LayeredDensePose(DepthEncoding::kUnorm16, NormalEncoding::kRgb8, 2));
  ASSERT_TRUE(ValidateAsset(dense).ok()) << ValidateAsset(dense).message();
  dense.body_maps.poses[1].normal_rgb8[0].resize(3 * 15);
  expect(dense, at + "normal_rgb8_front has 45 elements, expected 60");
}

// The gap list names stored texels with a slab, in increasing order, each holding gap 1; a gap
// holds a surface in both views or neither: otherwise the row spans, which follow the slab,
// would lose gaps, or a gap would read another texel's values.
TEST(BodyMapLayers, GapsOutsideTheSlabOrOutOfOrderAreRefused) {
  const auto expect = [](const BodyMapPose& pose, const std::string& text) {
    CharacterAsset a = SmallAsset();
    a.body_maps.poses.push_back(pose);
    const Status s = ValidateAsset(a);
    EXPECT_NE(s.message().find("body_maps.poses[1]." + text), std::string::npos) << s.message();
    BodyMapPose converted;
    const Status c = ConvertBodyMapLayout(pose, BodyMapLayout::kRowSpans, &converted);
    EXPECT_NE(c.message().find(text), std::string::npos) << c.message();
  };
  // 15 texels; gap_texels {1, 2, 7, 8, 10}: layer 1 of the t-th is entry 15 + t, layer 2 20 + t.
  const BodyMapPose good = LayeredDensePose(DepthEncoding::kFloat32, NormalEncoding::kFloat32, 3);
  ASSERT_EQ(good.gap_texels, (std::vector<uint32_t>{1, 2, 7, 8, 10}));
  BodyMapPose p = good;
  p.depth_f32[1][15] = p.depth_range;  // gap 1 at texel 1: upper boundary only
  expect(p,
         "depth_f32_back[15] is background where the other view is not (layer 1 of "
         "gap_texels[0] = 1: a gap has both boundaries or neither)");
  p = good;
  p.depth_f32[0][16] = p.depth_range;  // texel 2 is listed but has no gap 1
  p.depth_f32[1][16] = p.depth_range;
  expect(p, "depth_f32_front[16] is background (layer 1 of");
  p = good;
  p.gap_texels[2] = 3;  // texel 3 has no slab
  expect(p, "gap_texels[2] = 3 holds a gap where the slab (layer 0) is background");
  p = good;
  p.gap_texels[1] = 1;
  expect(p, "gap_texels[1] = 1 does not increase");
  p = good;
  p.gap_texels[4] = 15;
  expect(p, "gap_texels[4] = 15 is not a stored texel (15 stored)");
  p = LayeredDensePose(DepthEncoding::kFloat32, NormalEncoding::kFloat32, 1);
  p.gap_texels = {1};
  expect(p, "gap_texels has 1 entries but layers = 1 (no gap layers)");
  // unorm16 background is 65535.
  BodyMapPose u = LayeredDensePose(DepthEncoding::kUnorm16, NormalEncoding::kOct16, 2);
  u.depth_u16[0][15 + 1] = 65535;  // gap 1 at texel 2: lower boundary only
  expect(u, "depth_u16_front[16] is background where the other view is not");
}

// Spans are decided by the slab alone and carry every layer of each kept texel; dense -> spans
// -> dense gives back the same arrays. A two-layer pose with a gap on some texels only.
TEST(BodyMapLayers, ConvertKeepsEveryLayerBothWays) {
  for (DepthEncoding depth : {DepthEncoding::kFloat32, DepthEncoding::kUnorm16}) {
    SCOPED_TRACE(int(depth));
    const BodyMapPose dense = LayeredDensePose(depth, NormalEncoding::kRgb8, 2);
    BodyMapPose spans;
    ASSERT_TRUE(ConvertBodyMapLayout(dense, BodyMapLayout::kRowSpans, &spans).ok());
    EXPECT_EQ(spans.layers, 2);
    // The same spans as the slab alone: the gaps do not change which texels are stored.
    BodyMapPose slab_only;
    ASSERT_TRUE(ConvertBodyMapLayout(LayeredDensePose(depth, NormalEncoding::kRgb8, 1),
                                     BodyMapLayout::kRowSpans, &slab_only)
                    .ok());
    EXPECT_EQ(spans.row_span_offsets, slab_only.row_span_offsets);
    EXPECT_EQ(spans.span_begin, slab_only.span_begin);
    EXPECT_EQ(spans.span_texel_offsets, (std::vector<uint32_t>{0, 3, 4, 7, 9}));
    const size_t stored = BodyMapStoredTexels(spans);
    ASSERT_EQ(stored, 9u);
    // The gap list renumbered to span positions (dense 1, 2, 7, 8, 10), the gaps in order.
    EXPECT_EQ(spans.gap_texels, (std::vector<uint32_t>{1, 2, 5, 6, 7}));
    EXPECT_EQ(spans.normal_rgb8[0].size(), 3 * (stored + 5));
    // Layer 1 of texel (3, 1) (dense 8, the fourth gap texel).
    EXPECT_EQ(spans.gap_texels[3], static_cast<uint32_t>(BodyMapTexelIndex(spans, 3, 1)));
    const size_t gap = stored + 3;
    EXPECT_EQ(spans.normal_rgb8[1][3 * gap + 2], 40 + 2 * 8 + 1 + 2);
    if (depth == DepthEncoding::kFloat32) {
      EXPECT_EQ(spans.depth_f32[1][gap], LayerDepth(1, 1, 8));
    } else {
      EXPECT_EQ(spans.depth_u16[1][gap], std::lround(LayerDepth(1, 1, 8) * 65535.f));
    }
    BodyMapPose back;
    ASSERT_TRUE(ConvertBodyMapLayout(spans, BodyMapLayout::kDense, &back).ok());
    EXPECT_TRUE(back.row_span_offsets.empty());
    ExpectSameMaps(back, dense);
  }
}

TEST(BodyMapLayers, EveryTruncationOfALayeredFileFailsCleanly) {
  const std::vector<uint8_t> bytes = Encode(LayeredAsset());
  for (size_t length = 0; length < bytes.size(); ++length) {
    CharacterAsset out;
    const Status s = DecodeAsset({bytes.data(), length}, "cut.drape", &out);
    ASSERT_FALSE(s.ok()) << "length " << length;
    EXPECT_TRUE(out.body_maps.poses.empty()) << "half-loaded at length " << length;
  }
}

}  // namespace
}  // namespace drape

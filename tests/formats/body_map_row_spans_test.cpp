// The row-span layout of a body-map pose (BodyMapPose class version 2, format version 2): spans
// are the maximal runs of covered texels, both layouts round-trip, and a corrupt span table is
// refused naming its field, in memory and in a file.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "asset_fixtures.h"
#include "drape/formats/asset_file.h"

namespace drape {
namespace {

using test::Encode;
using test::FixChecksums;
using test::SpansAsset;

TEST(BodyMapLayout, SpansAreTheMaximalRunsOfCoveredTexels) {
  const CharacterAsset asset = SpansAsset();
  const BodyMapPose& p = asset.body_maps.poses[1];
  EXPECT_EQ(p.layout, BodyMapLayout::kRowSpans);
  EXPECT_EQ(p.row_span_offsets, (std::vector<uint32_t>{0, 2, 3, 3}));
  EXPECT_EQ(p.span_begin, (std::vector<uint16_t>{0, 3, 1}));
  EXPECT_EQ(p.span_texel_offsets, (std::vector<uint32_t>{0, 2, 4, 8}));
  EXPECT_EQ(BodyMapStoredTexels(p), 8u);
  EXPECT_EQ(p.depth_f32[1].size(), 8u);
  EXPECT_EQ(p.normal_rgb8[0].size(), 24u);
  EXPECT_EQ(BodyMapTexelIndex(p, 4, 0), 3);   // second span of row 0, second texel
  EXPECT_EQ(BodyMapTexelIndex(p, 2, 0), -1);  // the gap
  EXPECT_EQ(BodyMapTexelIndex(p, 5, 1), -1);  // after the last span
  EXPECT_EQ(BodyMapTexelIndex(p, 0, 2), -1);  // an empty row
  EXPECT_EQ(BodyMapTexelIndex(p, 6, 0), -1);  // outside the rectangle
  EXPECT_FLOAT_EQ(p.depth_f32[0][static_cast<size_t>(BodyMapTexelIndex(p, 3, 1))],
                  0.25f + 0.01f * 9.f);
  // Back to dense: background everywhere else.
  BodyMapPose dense;
  ASSERT_TRUE(ConvertBodyMapLayout(p, BodyMapLayout::kDense, &dense).ok());
  EXPECT_EQ(dense.depth_f32[0].size(), 18u);
  EXPECT_EQ(dense.depth_f32[0][2], 1.f);
  EXPECT_FLOAT_EQ(dense.depth_f32[0][9], 0.25f + 0.01f * 9.f);
  EXPECT_EQ(dense.normal_rgb8[0][3 * 9], 109);
  EXPECT_TRUE(dense.row_span_offsets.empty() && dense.span_begin.empty());
}

TEST(BodyMapLayout, RoundTripKeepsBothLayouts) {
  const CharacterAsset a = SpansAsset();
  const std::vector<uint8_t> bytes = Encode(a);
  CharacterAsset b;
  const Status s = DecodeAsset(bytes, "spans.drape", &b);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(AssetToJson(a), AssetToJson(b));
  ASSERT_EQ(b.body_maps.poses.size(), 2u);
  EXPECT_EQ(b.body_maps.poses[0].layout, BodyMapLayout::kDense);
  EXPECT_EQ(b.body_maps.poses[0].depth_u16[1][3], 300);
  const BodyMapPose& spans = b.body_maps.poses[1];
  EXPECT_EQ(spans.layout, BodyMapLayout::kRowSpans);
  EXPECT_EQ(spans.span_begin, a.body_maps.poses[1].span_begin);
  EXPECT_EQ(spans.span_texel_offsets, a.body_maps.poses[1].span_texel_offsets);
  EXPECT_EQ(spans.depth_f32[0], a.body_maps.poses[1].depth_f32[0]);
  EXPECT_EQ(spans.normal_rgb8[1], a.body_maps.poses[1].normal_rgb8[1]);
  EXPECT_EQ(Encode(b), bytes);
  // The writer writes format version 8 (BodyMapPose class version 4, one layer here).
  EXPECT_EQ(bytes[8], 8);
  EXPECT_EQ(kAssetFormatVersion, 8u);
  EXPECT_EQ(spans.layers, 1);
}

TEST(BodyMapLayout, EveryTruncationAndByteFlipOfASpansFileFailsCleanly) {
  const std::vector<uint8_t> bytes = Encode(SpansAsset());
  for (size_t length = 0; length < bytes.size(); ++length) {
    CharacterAsset out;
    const Status s = DecodeAsset({bytes.data(), length}, "cut.drape", &out);
    ASSERT_FALSE(s.ok()) << "length " << length;
    EXPECT_EQ(s.message().rfind("cut.drape: ", 0), 0u) << s.message();
    EXPECT_TRUE(out.body_maps.poses.empty()) << "half-loaded at length " << length;
  }
  for (size_t at = 0; at < bytes.size(); ++at) {
    for (uint8_t flip : {uint8_t{0x01}, uint8_t{0x80}, uint8_t{0xFF}}) {
      std::vector<uint8_t> bad = bytes;
      bad[at] ^= flip;
      CharacterAsset out;
      ASSERT_FALSE(DecodeAsset(bad, "flip.drape", &out).ok())
          << "byte " << at << " ^ " << int(flip);
    }
  }
}

// The validator names the pose and the field of a corrupt span table; nothing crashes.
TEST(BodyMapLayout, CorruptSpanTablesAreRefusedWithTheField) {
  const CharacterAsset good = SpansAsset();
  ASSERT_TRUE(ValidateAsset(good).ok()) << ValidateAsset(good).message();
  const auto expect = [](const CharacterAsset& a, const std::string& text) {
    const Status s = ValidateAsset(a);
    EXPECT_FALSE(s.ok()) << text;
    EXPECT_NE(s.message().find(text), std::string::npos) << s.message();
    std::vector<uint8_t> bytes;
    EXPECT_FALSE(EncodeAsset(a, &bytes).ok()) << "the writer must refuse it: " << text;
  };
  const std::string at = "body_maps.poses[1].";
  CharacterAsset a = good;
  a.body_maps.poses[1].span_begin[1] = 1;  // overlaps the first span of row 0, [0, 2)
  expect(a, at + "span_begin[1] = 1 is before the end of the previous span of row 0 (2)");
  a = good;
  a.body_maps.poses[1].span_begin[2] = 3;  // [3, 7) in a row of 6
  expect(a, at + "span_begin[2] = 3: the span of row 1 ends at 7, beyond width 6");
  a = good;
  a.body_maps.poses[1].row_span_offsets = {0, 2, 3};  // height 3 needs 4 entries
  expect(a, at + "row_span_offsets has 3 elements, expected height + 1 = 4");
  a = good;
  a.body_maps.poses[1].row_span_offsets = {0, 3, 2, 3};
  expect(a, at + "row_span_offsets[2] decreases");
  a = good;
  a.body_maps.poses[1].row_span_offsets = {1, 2, 3, 3};
  expect(a, at + "row_span_offsets does not start at 0");
  a = good;
  a.body_maps.poses[1].row_span_offsets = {0, 2, 2, 2};
  expect(a, at + "row_span_offsets ends at 2, expected the 3 spans of span_begin");
  a = good;
  a.body_maps.poses[1].span_texel_offsets = {0, 2, 2, 8};
  expect(a, at + "span_texel_offsets[2] does not increase (an empty span)");
  a = good;
  a.body_maps.poses[1].span_texel_offsets.pop_back();
  expect(a, at + "span_texel_offsets has 3 elements, expected span count + 1 = 4");
  a = good;
  a.body_maps.poses[1].span_texel_offsets = {0, 2, 4, 10};  // row 1: [1, 7)
  expect(a, at + "span_begin[2] = 1: the span of row 1 ends at 7, beyond width 6");
  a = good;
  a.body_maps.poses[1].span_texel_offsets = {0, 2, 4, 7};  // 7 texels, the arrays hold 8
  expect(a, at + "depth_f32_front has 8 elements, expected 7");
  a = good;
  a.body_maps.poses[1].normal_rgb8[1].pop_back();
  expect(a, at + "normal_rgb8_back has 23 elements, expected 24");
  a = good;
  a.body_maps.poses[1].layout = static_cast<BodyMapLayout>(2);
  expect(a, at + "layout = 2 is unknown");
  a = good;
  a.body_maps.poses[0].span_begin = {0};
  expect(a, "body_maps.poses[0].row_span_offsets, span_begin, span_texel_offsets are not empty");
  // A huge empty rectangle in a few bytes: the runtime would expand it to gigabytes.
  a = good;
  BodyMapPose& huge = a.body_maps.poses[1];
  huge.height = 16384;
  huge.width = 16384;
  huge.row_span_offsets.resize(huge.height + 1, huge.row_span_offsets.back());
  expect(a, at + "width x height = 268435456 texels for 8 stored: more than 256x");
}

// Byte edits in the file with valid checksums: the loader reports the field, never crashes.
TEST(BodyMapLayout, CorruptSpanTableInAFileIsACorruptError) {
  const std::vector<uint8_t> bytes = Encode(SpansAsset());
  // span_begin of pose 1 in the payload: its uint64 count 3, then 0, 3, 1 as uint16.
  const std::vector<uint8_t> pattern = {3, 0, 0, 0, 0, 0, 0, 0, 0, 0, 3, 0, 1, 0};
  const auto found = std::search(bytes.begin(), bytes.end(), pattern.begin(), pattern.end());
  ASSERT_NE(found, bytes.end());
  const size_t at = static_cast<size_t>(found - bytes.begin());
  std::vector<uint8_t> bad = bytes;
  bad[at + 8 + 2 * 2] = 200;  // span 2 begins at column 200 of a 6-texel row
  FixChecksums(bad);
  CharacterAsset out;
  Status s = DecodeAsset(bad, "bad.drape", &out);
  EXPECT_EQ(s.code(), StatusCode::kCorrupt);
  EXPECT_NE(s.message().find("bad.drape: body_maps.poses[1].span_begin[2] = 200"),
            std::string::npos)
      << s.message();
  bad = bytes;
  bad[at] = 0xFF;  // a count of 255 spans: more than the bytes left, or a mismatched table
  bad[at + 5] = 0xFF;
  FixChecksums(bad);
  s = DecodeAsset(bad, "bad.drape", &out);
  EXPECT_EQ(s.code(), StatusCode::kCorrupt);
  EXPECT_NE(s.message().find("payload bytes left"), std::string::npos) << s.message();
  EXPECT_TRUE(out.body_maps.poses.empty());
}

}  // namespace
}  // namespace drape

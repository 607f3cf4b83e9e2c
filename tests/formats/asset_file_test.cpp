// The .drape container treats every file as untrusted: each way a file can be wrong gives a
// status with a message that names the file and the reason, and nothing crashes or half-loads.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "drape/formats/asset_file.h"
#include "test_support.h"

namespace drape {
namespace {

// A small but complete asset: 3 joints, a clip, a skinned mesh, a body-map pose, a hull with a
// Kirkpatrick hierarchy and a map table, a joint sphere.
CharacterAsset SmallAsset() {
  CharacterAsset a;
  a.info.source_name = "small.gltf";
  a.info.tool_version = "test";
  a.skeleton.joint_names = {"root", "spine", "head"};
  a.skeleton.parents = {-1, 0, 1};
  a.skeleton.rest_local.resize(3);
  a.skeleton.rest_local[1].translation = {0.f, 0.5f, 0.f};
  a.skeleton.rest_local[2].translation = {0.f, 0.4f, 0.f};
  a.skeleton.inverse_bind.resize(3);
  a.skeleton.inverse_bind[1].m[7] = -0.5f;
  a.skeleton.inverse_bind[2].m[7] = -0.9f;
  ClipData clip;
  clip.name = "nod";
  clip.duration = 0.1f;
  clip.sample_rate = 30.f;
  clip.frame_count = 4;
  clip.keys.assign(12, Transform{});
  a.clips.push_back(clip);
  a.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  a.mesh.triangles = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  a.mesh.influence_offsets = {0, 1, 2, 4, 5};
  a.mesh.influence_joints = {0, 1, 1, 2, 2};
  a.mesh.influence_weights = {1.f, 1.f, 0.5f, 0.5f, 1.f};
  a.body_maps.epsilon = 0.005f;
  a.body_maps.resolution = 4;
  BodyMapPose pose;
  pose.width = 2;
  pose.height = 2;
  pose.texel_size = 0.5f;
  pose.depth_range = 1.f;
  pose.depth_encoding = DepthEncoding::kUnorm16;
  pose.normal_encoding = NormalEncoding::kOct16;
  for (int v = 0; v < 2; ++v) {
    pose.depth_u16[v] = {100, 200, 65535, 300};
    pose.normal_oct16[v] = {1, 2, 3, 4, 5, 6, 7, 8};
  }
  a.body_maps.poses.push_back(pose);
  HullColliderData hull;
  hull.joint = 1;
  hull.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  hull.triangles = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  hull.triangle_planes = {0, 1, 2, 3};
  hull.obb.axes[0] = {1, 0, 0};
  hull.obb.axes[1] = {0, 1, 0};
  hull.obb.axes[2] = {0, 0, 1};
  hull.planes = {
      {{0, 0, -1}, 0}, {{0, -1, 0}, 0}, {{-1, 0, 0}, 0}, {{0.577f, 0.577f, 0.577f}, 0.578f}};
  hull.upper.vertices_uv = {0, 0, 1, 0, 0, 1};
  hull.upper.node_triangles = {0, 1, 2, 0, 1, 2};
  hull.upper.child_offsets = {0, 0, 1};
  hull.upper.children = {0};
  hull.upper.leaf_planes = {3, -1};
  hull.upper.root_begin = 1;
  hull.upper.root_end = 2;
  hull.map.rows = 1;
  hull.map.cols = 2;
  hull.map.axis = {0, 1, 0};
  hull.map.reference = {1, 0, 0};
  hull.map.cell_offsets = {0, 2, 4};
  hull.map.cell_triangles = {0, 1, 2, 3};
  a.hulls.push_back(hull);
  a.joint_spheres.push_back({2, 1, {0.f, 0.9f, 0.f}, 0.05f});
  return a;
}

std::vector<uint8_t> Encode(const CharacterAsset& a) {
  std::vector<uint8_t> bytes;
  const Status s = EncodeAsset(a, &bytes);
  EXPECT_TRUE(s.ok()) << s.message();
  return bytes;
}

// Rewrites the payload and header checksums after a deliberate edit, so the decoder's later
// checks (versions, counts, indices) are the ones under test.
void FixChecksums(std::vector<uint8_t>& bytes) {
  auto put = [&](size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) bytes[at + i] = static_cast<uint8_t>(v >> (8 * i));
  };
  put(24, Crc32({bytes.data() + kAssetHeaderSize, bytes.size() - kAssetHeaderSize}));
  put(28, Crc32({bytes.data(), 28}));
}

std::vector<uint8_t> ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(AssetFile, RoundTripKeepsEveryField) {
  const CharacterAsset a = SmallAsset();
  const std::vector<uint8_t> bytes = Encode(a);
  CharacterAsset b;
  const Status s = DecodeAsset(bytes, "small.drape", &b);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(AssetToJson(a), AssetToJson(b));
  EXPECT_EQ(b.skeleton.joint_names[2], "head");
  EXPECT_EQ(b.body_maps.poses[0].depth_u16[1][3], 300);
  EXPECT_EQ(b.hulls[0].map.cell_triangles[3], 3u);
  // Encoding is deterministic: the same asset gives the same bytes.
  EXPECT_EQ(Encode(b), bytes);
}

TEST(AssetFile, EveryTruncationFailsCleanly) {
  const std::vector<uint8_t> bytes = Encode(SmallAsset());
  for (size_t length = 0; length < bytes.size(); ++length) {
    CharacterAsset out;
    const Status s = DecodeAsset({bytes.data(), length}, "cut.drape", &out);
    ASSERT_FALSE(s.ok()) << "length " << length;
    EXPECT_EQ(s.message().rfind("cut.drape: ", 0), 0u) << s.message();
    EXPECT_TRUE(out.skeleton.joint_names.empty()) << "half-loaded at length " << length;
  }
}

TEST(AssetFile, EverySingleByteFlipIsDetected) {
  const std::vector<uint8_t> bytes = Encode(SmallAsset());
  for (size_t at = 0; at < bytes.size(); ++at) {
    for (uint8_t flip : {uint8_t{0x01}, uint8_t{0x80}, uint8_t{0xFF}}) {
      std::vector<uint8_t> bad = bytes;
      bad[at] ^= flip;
      CharacterAsset out;
      const Status s = DecodeAsset(bad, "flip.drape", &out);
      ASSERT_FALSE(s.ok()) << "byte " << at << " ^ " << int(flip);
    }
  }
}

TEST(AssetFile, TrailingBytesAreRefused) {
  std::vector<uint8_t> bytes = Encode(SmallAsset());
  bytes.push_back(0);
  CharacterAsset out;
  const Status s = DecodeAsset(bytes, "long.drape", &out);
  EXPECT_EQ(s.code(), StatusCode::kTrailingBytes);
  EXPECT_NE(s.message().find("1 bytes after the payload"), std::string::npos) << s.message();
}

TEST(AssetFile, WrongMagicIsRefused) {
  const std::string text = "{\"asset\": {\"version\": \"2.0\"}}";
  CharacterAsset out;
  const Status s =
      DecodeAsset({reinterpret_cast<const uint8_t*>(text.data()), text.size()}, "model.gltf", &out);
  EXPECT_EQ(s.code(), StatusCode::kBadMagic);
  EXPECT_EQ(s.message(), "model.gltf: not a .drape file (wrong magic bytes)");
}

TEST(AssetFile, NewerAndOlderFormatVersionsAreRefusedByName) {
  for (uint32_t version : {0u, kAssetFormatVersion + 1}) {
    std::vector<uint8_t> bytes = Encode(SmallAsset());
    for (int i = 0; i < 4; ++i) bytes[8 + i] = static_cast<uint8_t>(version >> (8 * i));
    FixChecksums(bytes);
    CharacterAsset out;
    const Status s = DecodeAsset(bytes, "v.drape", &out);
    EXPECT_EQ(s.code(), StatusCode::kUnsupportedVersion);
    EXPECT_NE(s.message().find(version > kAssetFormatVersion ? "is newer" : "is older"),
              std::string::npos)
        << s.message();
  }
}

TEST(AssetFile, UnknownTypeVersionIsRefusedByTypeName) {
  std::vector<uint8_t> bytes = Encode(SmallAsset());
  // Payload: 1 byte of cereal endianness, then CharacterAsset's uint32 class version.
  ASSERT_EQ(bytes[kAssetHeaderSize + 1], 1);
  bytes[kAssetHeaderSize + 1] = 2;
  FixChecksums(bytes);
  CharacterAsset out;
  const Status s = DecodeAsset(bytes, "t.drape", &out);
  EXPECT_EQ(s.code(), StatusCode::kCorrupt);
  EXPECT_NE(s.message().find("unsupported version 2 of CharacterAsset"), std::string::npos)
      << s.message();
}

TEST(AssetFile, OutOfRangeIndicesAreRefusedWithTheField) {
  CharacterAsset a = SmallAsset();
  a.hulls[0].triangles[4] = 99;
  std::vector<uint8_t> invalid;
  EXPECT_FALSE(EncodeAsset(a, &invalid).ok()) << "the writer must refuse an invalid asset";
  const Status v = ValidateAsset(a);
  EXPECT_NE(v.message().find("hulls[0].triangles[4] = 99 is out of range [0, 4)"),
            std::string::npos)
      << v.message();

  CharacterAsset cyclic = SmallAsset();
  cyclic.hulls[0].upper.children[0] = 1;  // a node that is its own child: a walk would not end
  EXPECT_NE(ValidateAsset(cyclic).message().find("hulls[0].upper.children[0]"), std::string::npos);
  CharacterAsset parents = SmallAsset();
  parents.skeleton.parents[1] = 2;
  EXPECT_NE(ValidateAsset(parents).message().find("skeleton.parents[1] = 2"), std::string::npos);
  CharacterAsset skewed = SmallAsset();
  skewed.skeleton.rest_local[1].rotation = {0.f, 0.f, 0.f, 2.f};
  EXPECT_NE(ValidateAsset(skewed).message().find("not a finite unit quaternion"),
            std::string::npos);
  CharacterAsset tiny = SmallAsset();
  tiny.body_maps.poses[0].texel_size = 1e-30f;  // 1 / texel_size would be infinite
  EXPECT_NE(ValidateAsset(tiny).message().find("texel_size is not in"), std::string::npos);
  CharacterAsset flat = SmallAsset();
  flat.hulls[0].obb.axes[1] = {1, 0, 0};
  EXPECT_NE(ValidateAsset(flat).message().find("obb.axes are not orthonormal"), std::string::npos);
  CharacterAsset dup = SmallAsset();
  dup.skeleton.joint_names[2] = "root";
  EXPECT_NE(ValidateAsset(dup).message().find("'root' is a duplicate"), std::string::npos);
}

TEST(AssetFile, HugeCountWithValidChecksumDoesNotAllocate) {
  std::vector<uint8_t> bytes = Encode(SmallAsset());
  // The first array in the payload is info.source_name (a string); its uint64 size follows the
  // endianness byte and two uint32 class versions (CharacterAsset, AssetInfo).
  const size_t at = kAssetHeaderSize + 1 + 4 + 4;
  ASSERT_EQ(bytes[at], 10);  // strlen("small.gltf")
  // Lengths a resize would accept (16 GiB, 1 GiB) and one it would refuse (2^64 - 1): each must
  // be refused by the bound on the bytes left, before anything is allocated.
  for (uint64_t length : {uint64_t{1} << 34, uint64_t{1} << 30, ~uint64_t{0}}) {
    std::vector<uint8_t> bad = bytes;
    for (int i = 0; i < 8; ++i) bad[at + i] = static_cast<uint8_t>(length >> (8 * i));
    FixChecksums(bad);
    CharacterAsset out;
    const Status s = DecodeAsset(bad, "huge.drape", &out);
    EXPECT_EQ(s.code(), StatusCode::kCorrupt) << length;
    EXPECT_NE(s.message().find("payload bytes left"), std::string::npos) << s.message();
  }
}

TEST(AssetFile, WriterLeavesNoPartialFile) {
  const std::string dir = ::testing::TempDir() + "/drape_writer";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/a.drape";
  ASSERT_TRUE(WriteAssetFile(path, SmallAsset()).ok());
  CharacterAsset back;
  ASSERT_TRUE(ReadAssetFile(path, &back).ok());
  // A write into a missing directory fails and leaves nothing.
  const std::string bad = dir + "/missing/b.drape";
  const Status s = WriteAssetFile(bad, SmallAsset());
  EXPECT_EQ(s.code(), StatusCode::kIoError);
  EXPECT_NE(s.message().find(bad), std::string::npos);
  size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    files += entry.is_regular_file();
  EXPECT_EQ(files, 1u) << "only a.drape, no temporary left behind";
  const Status missing = ReadAssetFile(dir + "/none.drape", &back);
  EXPECT_EQ(missing.code(), StatusCode::kIoError);
}

// --- Body-map layouts (BodyMapPose class version 2, format version 2) ------------------------

// SmallAsset plus a second pose in the row-span layout: 6 x 3 texels, float32 depth and rgb8
// normals, two spans in row 0, one in row 1, none in row 2.
CharacterAsset SpansAsset() {
  CharacterAsset a = SmallAsset();
  BodyMapPose dense;
  dense.clip = 0;
  dense.time = 0.1f;
  dense.width = 6;
  dense.height = 3;
  dense.origin_x = -0.25f;
  dense.origin_y = 0.5f;
  dense.texel_size = 0.125f;
  dense.front_z = 0.5f;
  dense.depth_range = 1.f;
  dense.depth_encoding = DepthEncoding::kFloat32;
  dense.normal_encoding = NormalEncoding::kRgb8;
  const char* covered =
      "XX.XX."
      ".XXXX."
      "......";  // row 0 first
  for (int v = 0; v < 2; ++v) {
    dense.depth_f32[v].assign(18, dense.depth_range);
    dense.normal_rgb8[v].assign(54, 0);
    for (size_t k = 0; k < 18; ++k) {
      if (covered[k] != 'X') continue;
      dense.depth_f32[v][k] = 0.25f + 0.01f * static_cast<float>(k);
      dense.normal_rgb8[v][3 * k + 2] = v == 0 ? 255 : 0;
      dense.normal_rgb8[v][3 * k] = static_cast<uint8_t>(100 + k);
    }
  }
  BodyMapPose spans;
  EXPECT_TRUE(ConvertBodyMapLayout(dense, BodyMapLayout::kRowSpans, &spans).ok());
  a.body_maps.poses.push_back(spans);
  return a;
}

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
  // The writer writes format version 3 (BodyMapPose class version 3, one layer here).
  EXPECT_EQ(bytes[8], 3);
  EXPECT_EQ(kAssetFormatVersion, 3u);
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

// A format version 1 file holds only class version 1: a version 2 or 3 pose under a version 1
// header is refused, and an older class version of BodyMapPose is read as dense with one layer
// (the golden files).
TEST(BodyMapLayout, FormatVersion1HoldsOnlyDensePoses) {
  std::vector<uint8_t> bytes = Encode(SmallAsset());  // BodyMapPose version 3
  bytes[8] = 1;
  FixChecksums(bytes);
  CharacterAsset out;
  Status s = DecodeAsset(bytes, "v1.drape", &out);
  EXPECT_EQ(s.code(), StatusCode::kCorrupt);
  EXPECT_NE(s.message().find("BodyMapPose version 3 in a format version 1 file"), std::string::npos)
      << s.message();
  // mannequin_v2.drape holds a BodyMapPose version 2: under a version 1 header it is refused too.
  bytes = ReadBytes(test::GoldenDir() + "/mannequin_v2.drape");
  ASSERT_GT(bytes.size(), kAssetHeaderSize);
  bytes[8] = 1;
  FixChecksums(bytes);
  s = DecodeAsset(bytes, "v1.drape", &out);
  EXPECT_EQ(s.code(), StatusCode::kCorrupt);
  EXPECT_NE(s.message().find("BodyMapPose version 2 in a format version 1 file"), std::string::npos)
      << s.message();
  EXPECT_TRUE(out.body_maps.poses.empty());
  // mannequin_colliders_v1.drape was written by the format version 1 writer with a body-map pose.
  CharacterAsset golden;
  const Status g = ReadAssetFile(test::GoldenDir() + "/mannequin_colliders_v1.drape", &golden);
  ASSERT_TRUE(g.ok()) << g.message();
  ASSERT_EQ(golden.body_maps.poses.size(), 1u);
  const BodyMapPose& pose = golden.body_maps.poses[0];
  EXPECT_EQ(pose.layout, BodyMapLayout::kDense);
  EXPECT_EQ(pose.layers, 1);
  EXPECT_TRUE(pose.row_span_offsets.empty() && pose.span_begin.empty());
  EXPECT_EQ(BodyMapStoredTexels(pose), static_cast<size_t>(pose.width) * pose.height);
  EXPECT_EQ(pose.depth_u16[0].size(), static_cast<size_t>(pose.width) * pose.height);
}

// --- Depth layers (BodyMapPose class version 3, format version 3) ----------------------------

// The slab and the gaps of LayeredDensePose, a 5 x 3 rectangle (row 0 first): 'X' slab only,
// '1' slab and gap 1, '2' slab and gaps 1 and 2, '.' background in every layer.
constexpr const char* kLayeredTexels =
    "X21.X"
    ".X12."
    "2X...";

// Depth of `view` in layer k at dense texel n, in metres from that view's camera: boundaries in
// the order top > upper_1 > lower_1 > upper_2 > lower_2 > bottom (depth_range 1, so the back
// depth d is at z = front_z - 1 + d). Distinct per texel, so a misplaced value shows.
float LayerDepth(int view, size_t k, size_t n) {
  static const float kFront[3] = {0.10f, 0.30f, 0.50f};
  static const float kBack[3] = {0.10f, 0.60f, 0.40f};
  return (view == 0 ? kFront[k] : kBack[k]) + 0.001f * static_cast<float>(n);
}

// Layer k holds a surface at dense texel n.
bool HasLayer(size_t k, size_t n) {
  const char c = kLayeredTexels[n];
  return k == 0 ? c != '.' : (c == '2' || (c == '1' && k == 1));
}

// A dense pose with `layers` layers (1 to 3) of the texels above, in the given encodings, stored
// as the format stores them: layer 0 of every texel, then the gap layers of the texels with a
// gap ('1' and '2': gap_texels = {1, 2, 7, 8, 10}); background values everywhere a layer has
// no surface (as the bake writes).
BodyMapPose LayeredDensePose(DepthEncoding depth, NormalEncoding normal, uint8_t layers) {
  BodyMapPose p;
  p.clip = 0;
  p.time = 0.05f;
  p.width = 5;
  p.height = 3;
  p.origin_x = -0.3f;
  p.origin_y = 0.25f;
  p.texel_size = 0.125f;
  p.front_z = 0.5f;
  p.depth_range = 1.f;
  p.depth_encoding = depth;
  p.normal_encoding = normal;
  p.layers = layers;
  const size_t texels = 15;
  for (size_t n = 0; n < texels && layers > 1; ++n)
    if (HasLayer(1, n)) p.gap_texels.push_back(static_cast<uint32_t>(n));
  const size_t gaps = p.gap_texels.size();
  const size_t entries = texels + (layers - 1u) * gaps;
  for (int v = 0; v < 2; ++v) {
    if (depth == DepthEncoding::kFloat32) {
      p.depth_f32[v].assign(entries, p.depth_range);
    } else {
      p.depth_u16[v].assign(entries, 65535);
    }
    p.normal_f32[v].assign(normal == NormalEncoding::kFloat32 ? 3 * entries : 0, 0.f);
    p.normal_oct16[v].assign(normal == NormalEncoding::kOct16 ? 2 * entries : 0, 0);
    p.normal_rgb8[v].assign(normal == NormalEncoding::kRgb8 ? 3 * entries : 0, 0);
    for (size_t k = 0; k < layers; ++k) {
      for (size_t t = 0; t < (k == 0 ? texels : gaps); ++t) {
        const size_t n = k == 0 ? t : p.gap_texels[t];
        if (!HasLayer(k, n)) continue;
        const size_t e = k == 0 ? n : texels + (k - 1) * gaps + t;
        const float d = LayerDepth(v, k, n);
        if (depth == DepthEncoding::kFloat32) {
          p.depth_f32[v][e] = d;
        } else {
          p.depth_u16[v][e] = static_cast<uint16_t>(std::lround(d * 65535.f));
        }
        const size_t code = 40 * k + 2 * n + static_cast<size_t>(v);  // < 256, distinct
        for (size_t c = 0; c < 3; ++c) {
          if (normal == NormalEncoding::kFloat32)
            p.normal_f32[v][3 * e + c] = 0.001f * static_cast<float>(code + c);
          if (normal == NormalEncoding::kRgb8)
            p.normal_rgb8[v][3 * e + c] = static_cast<uint8_t>(code + c);
          if (normal == NormalEncoding::kOct16 && c < 2)
            p.normal_oct16[v][2 * e + c] = static_cast<uint16_t>(500 * code + c);
        }
      }
    }
  }
  return p;
}

// Every per-texel array and the span table of two poses are equal.
void ExpectSameMaps(const BodyMapPose& a, const BodyMapPose& b) {
  EXPECT_EQ(a.layout, b.layout);
  EXPECT_EQ(a.layers, b.layers);
  EXPECT_EQ(a.row_span_offsets, b.row_span_offsets);
  EXPECT_EQ(a.span_begin, b.span_begin);
  EXPECT_EQ(a.span_texel_offsets, b.span_texel_offsets);
  EXPECT_EQ(a.gap_texels, b.gap_texels);
  for (int v = 0; v < 2; ++v) {
    EXPECT_EQ(a.depth_f32[v], b.depth_f32[v]) << "view " << v;
    EXPECT_EQ(a.depth_u16[v], b.depth_u16[v]) << "view " << v;
    EXPECT_EQ(a.normal_f32[v], b.normal_f32[v]) << "view " << v;
    EXPECT_EQ(a.normal_oct16[v], b.normal_oct16[v]) << "view " << v;
    EXPECT_EQ(a.normal_rgb8[v], b.normal_rgb8[v]) << "view " << v;
  }
}

// SmallAsset plus a three-layer pose of the texels above, in row spans, float32 depth and oct16
// normals.
CharacterAsset LayeredAsset() {
  CharacterAsset a = SmallAsset();
  BodyMapPose spans;
  const Status s =
      ConvertBodyMapLayout(LayeredDensePose(DepthEncoding::kFloat32, NormalEncoding::kOct16, 3),
                           BodyMapLayout::kRowSpans, &spans);
  EXPECT_TRUE(s.ok()) << s.message();
  a.body_maps.poses.push_back(spans);
  return a;
}

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
  // texel_size, front_z, depth_range (float32), the encodings, layout (row spans), layers, then
  // row_span_offsets' uint64 count (height + 1 = 4).
  const std::vector<uint8_t> pattern = {
      0, 0, 0, 0x3E, 0, 0, 0, 0x3F, 0, 0, 0x80, 0x3F,  // 0.125f, 0.5f, 1.f, little-endian
      0, 1, 1, 3,    4, 0, 0, 0,    0, 0, 0,    0};
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
  const std::vector<uint8_t> pattern = {0, 1, 1, 3, 4, 0, 0, 0, 0, 0, 0, 0};  // encodings..count
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

// `bytes` (a file holding a BodyMapPose of class version `pose_version`) under a format
// `format_version` header, checksums fixed: refused as corrupt, naming both versions, no pose.
void ExpectPoseVersionRefused(std::vector<uint8_t> bytes, uint32_t format_version,
                              uint32_t pose_version) {
  bytes[8] = static_cast<uint8_t>(format_version);
  FixChecksums(bytes);
  CharacterAsset out;
  const std::string name = "v" + std::to_string(format_version) + ".drape";
  const Status s = DecodeAsset(bytes, name, &out);
  EXPECT_EQ(s.code(), StatusCode::kCorrupt);
  EXPECT_EQ(s.message(), name + ": BodyMapPose version " + std::to_string(pose_version) +
                             " in a format version " + std::to_string(format_version) + " file");
  EXPECT_TRUE(out.body_maps.poses.empty());
}

// Files of format versions 1 and 2 load with one layer; a BodyMapPose version 3 cannot be in
// them.
TEST(BodyMapLayers, OlderFormatsLoadWithOneLayerAndCannotHoldLayers) {
  CharacterAsset v2;
  ASSERT_TRUE(ReadAssetFile(test::GoldenDir() + "/mannequin_v2.drape", &v2).ok());
  ASSERT_EQ(v2.body_maps.poses.size(), 1u);
  EXPECT_EQ(v2.body_maps.poses[0].layers, 1);
  // Written again as format version 3, it reads the same.
  CharacterAsset again;
  ASSERT_TRUE(DecodeAsset(Encode(v2), "v3.drape", &again).ok());
  EXPECT_EQ(AssetToJson(again), AssetToJson(v2));
  // A version 3 pose under a format version 2 header.
  ExpectPoseVersionRefused(Encode(LayeredAsset()), 2, 3);
}

// A format version holds exactly its own BodyMapPose version. SmallAsset's pose rewritten as
// class version 2 (the layers byte removed) is a valid format version 2 file, and refused under
// a format version 3 header: no writer wrote it, and it would not re-encode to the same bytes.
TEST(BodyMapLayers, AFormatHoldsExactlyItsOwnPoseVersion) {
  const CharacterAsset small = SmallAsset();
  std::vector<uint8_t> bytes = Encode(small);
  // Class version 3, clip -1, time 0, width 2, height 2 (the pose's first fields).
  // clang-format off
  const std::vector<uint8_t> start = {3, 0, 0, 0,  0xFF, 0xFF, 0xFF, 0xFF,  0, 0, 0, 0,
                                      2, 0, 0, 0,  2, 0, 0, 0};
  // clang-format on
  const auto found = std::search(bytes.begin(), bytes.end(), start.begin(), start.end());
  ASSERT_NE(found, bytes.end());
  const size_t pose = static_cast<size_t>(found - bytes.begin());
  // 4 class version, 36 of clip .. depth_range, 2 encodings, 1 layout: then layers.
  const size_t layers_at = pose + 4 + 36 + 2 + 1;
  ASSERT_EQ(bytes[layers_at], 1);
  bytes[pose] = 2;
  bytes.erase(bytes.begin() + static_cast<std::ptrdiff_t>(layers_at));
  // The dense pose's empty span table (three uint64 counts), then gap_texels' count: remove it.
  const size_t gap_count_at = layers_at + 3 * 8;
  for (size_t i = 0; i < 8; ++i) ASSERT_EQ(bytes[gap_count_at + i], 0) << i;
  bytes.erase(bytes.begin() + static_cast<std::ptrdiff_t>(gap_count_at),
              bytes.begin() + static_cast<std::ptrdiff_t>(gap_count_at + 8));
  const uint64_t payload = bytes.size() - kAssetHeaderSize;
  for (int i = 0; i < 8; ++i) bytes[16 + i] = static_cast<uint8_t>(payload >> (8 * i));
  bytes[8] = 2;
  FixChecksums(bytes);
  CharacterAsset v2;
  const Status read = DecodeAsset(bytes, "v2.drape", &v2);
  ASSERT_TRUE(read.ok()) << read.message();
  EXPECT_EQ(v2.body_maps.poses[0].layers, 1);
  EXPECT_EQ(AssetToJson(v2), AssetToJson(small));
  ExpectPoseVersionRefused(bytes, 3, 2);
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

// The committed golden files of every format version this build reads load with their known
// content: mannequin_v1.drape (format 1, every class at version 1), mannequin_v2.drape (format 2:
// BodyMapPose version 2, a row-span pose) and mannequin_v3.drape (format 3: BodyMapPose version
// 3, four layers). Every truncation fails cleanly; flips are tried on every header byte and
// spread over the payload.
void ExpectMannequinContent(const CharacterAsset& a) {
  EXPECT_EQ(a.info.source_name, "mannequin.gltf");
  ASSERT_EQ(a.skeleton.joint_count(), 17u);
  EXPECT_EQ(a.skeleton.joint_names[0], "hips");
  EXPECT_EQ(a.skeleton.joint_names[16], "ankle_r");
  EXPECT_EQ(a.skeleton.parents[7], 6);  // elbow_l <- shoulder_l
  ASSERT_EQ(a.clips.size(), 1u);
  EXPECT_EQ(a.clips[0].name, "walk");
  EXPECT_FLOAT_EQ(a.clips[0].duration, 1.f);
  EXPECT_EQ(a.clips[0].frame_count, 31u);
  EXPECT_EQ(a.mesh.vertex_count(), 3810u);
  EXPECT_EQ(a.mesh.triangle_count(), 7584u);
  EXPECT_FLOAT_EQ(a.info.unit_scale, 1.f);
}

// Reads tests/golden/<name>, checking the format version its header declares.
void ReadGoldenFile(const std::string& name, uint8_t format_version, CharacterAsset* asset) {
  const std::string path = test::GoldenDir() + "/" + name;
  const std::vector<uint8_t> bytes = ReadBytes(path);
  ASSERT_GT(bytes.size(), kAssetHeaderSize);
  EXPECT_EQ(bytes[8], format_version) << "format version of " << name;
  const Status s = ReadAssetFile(path, asset);
  ASSERT_TRUE(s.ok()) << s.message();
}

TEST(GoldenFile, MannequinVersion1LoadsWithExpectedContent) {
  CharacterAsset a;
  ASSERT_NO_FATAL_FAILURE(ReadGoldenFile("mannequin_v1.drape", 1, &a));
  ExpectMannequinContent(a);
}

// tests/golden/mannequin_v2.json: N = 64, no hulls. Written once by the format version 2 writer;
// never regenerated (a later format gets a file of its own beside it).
TEST(GoldenFile, MannequinVersion2LoadsWithExpectedContent) {
  CharacterAsset a;
  ASSERT_NO_FATAL_FAILURE(ReadGoldenFile("mannequin_v2.drape", 2, &a));
  ExpectMannequinContent(a);
  ASSERT_EQ(a.body_maps.poses.size(), 1u);
  EXPECT_EQ(a.body_maps.resolution, 64u);
  const BodyMapPose& pose = a.body_maps.poses[0];
  EXPECT_EQ(pose.layout, BodyMapLayout::kRowSpans);
  EXPECT_EQ(pose.layers, 1);
  EXPECT_EQ(pose.width, 54u);
  EXPECT_EQ(pose.height, 66u);
  EXPECT_EQ(BodyMapStoredTexels(pose), 744u);
  EXPECT_EQ(pose.depth_u16[0].size(), 744u);
  EXPECT_EQ(pose.normal_oct16[1].size(), 2u * 744u);
  EXPECT_EQ(pose.row_span_offsets.size(), 67u);
  EXPECT_EQ(a.joint_spheres.size(), 16u);
  EXPECT_TRUE(a.hulls.empty());
}

// tests/golden/mannequin_v3.json: the walk at two poses (t = 0 and 1 s) at N = 192 with
// maps.layers = 4, joint spheres, no hulls. Written once by the format version 3 writer; never
// regenerated. At N = 192 the walking mannequin has air along z on 5 texels per pose (a hand
// passing before the thigh): the file carries a real gap list. Every listed texel holds gap 1,
// strictly nested in its slab after decoding, as the runtime's Build requires.
TEST(GoldenFile, MannequinVersion3LoadsWithExpectedContent) {
  CharacterAsset a;
  ASSERT_NO_FATAL_FAILURE(ReadGoldenFile("mannequin_v3.drape", 3, &a));
  ExpectMannequinContent(a);
  ASSERT_EQ(a.body_maps.poses.size(), 2u);
  EXPECT_EQ(a.body_maps.resolution, 192u);
  EXPECT_EQ(a.joint_spheres.size(), 16u);
  EXPECT_TRUE(a.hulls.empty());
  for (const BodyMapPose& pose : a.body_maps.poses) {
    SCOPED_TRACE(::testing::Message() << "t = " << pose.time);
    EXPECT_EQ(pose.clip, 0);
    EXPECT_EQ(pose.layout, BodyMapLayout::kRowSpans);
    EXPECT_EQ(pose.layers, 4);
    const size_t stored = BodyMapStoredTexels(pose);
    EXPECT_EQ(stored, 6593u);
    ASSERT_EQ(pose.gap_texels.size(), 5u);
    const size_t gaps = pose.gap_texels.size();
    ASSERT_EQ(pose.depth_u16[0].size(), stored + 3 * gaps);
    ASSERT_EQ(pose.normal_oct16[1].size(), 2 * (stored + 3 * gaps));
    const double range = pose.depth_range;
    for (size_t t = 0; t < gaps; ++t) {
      const size_t n = pose.gap_texels[t];
      // z of a front-view / back-view code (docs/FORMAT.md's decoder).
      const auto front = [&](uint16_t q) { return pose.front_z - q * range / 65535.0; };
      const auto back = [&](uint16_t q) { return pose.front_z - range + q * range / 65535.0; };
      const size_t gap1 = stored + t;
      ASSERT_NE(pose.depth_u16[0][gap1], 65535) << t;
      ASSERT_NE(pose.depth_u16[1][gap1], 65535) << t;
      const double top = front(pose.depth_u16[0][n]), bottom = back(pose.depth_u16[1][n]);
      const double upper = front(pose.depth_u16[0][gap1]), lower = back(pose.depth_u16[1][gap1]);
      EXPECT_GT(top, upper) << t;
      EXPECT_GT(upper, lower) << t;
      EXPECT_GT(lower, bottom) << t;
    }
  }
}

TEST(GoldenFile, EveryTruncationAndSampledFlipsFail) {
  for (const char* name : {"/mannequin_v1.drape", "/mannequin_v2.drape", "/mannequin_v3.drape"}) {
    SCOPED_TRACE(name);
    const std::vector<uint8_t> bytes = ReadBytes(test::GoldenDir() + name);
    ASSERT_GT(bytes.size(), kAssetHeaderSize);
    for (size_t length = 0; length < bytes.size(); ++length) {
      CharacterAsset out;
      ASSERT_FALSE(DecodeAsset({bytes.data(), length}, "golden", &out).ok()) << length;
    }
    const size_t stride = bytes.size() / 2000 + 1;
    for (size_t at = 0; at < bytes.size(); at += (at < kAssetHeaderSize ? 1 : stride)) {
      std::vector<uint8_t> bad = bytes;
      bad[at] ^= 0x20;
      CharacterAsset out;
      ASSERT_FALSE(DecodeAsset(bad, "golden", &out).ok()) << "byte " << at;
    }
  }
}

}  // namespace
}  // namespace drape

// The .drape container treats every file as untrusted: each way a file can be wrong gives a
// status with a message that names the file and the reason, and nothing crashes or half-loads.

#include <gtest/gtest.h>

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

// The committed golden file of the current version loads with its known content. Every
// truncation fails cleanly; flips are tried on every header byte and spread over the payload.
TEST(GoldenFile, MannequinVersion1LoadsWithExpectedContent) {
  const std::string path = test::GoldenDir() + "/mannequin_v1.drape";
  CharacterAsset a;
  const Status s = ReadAssetFile(path, &a);
  ASSERT_TRUE(s.ok()) << s.message();
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

TEST(GoldenFile, EveryTruncationAndSampledFlipsFail) {
  const std::vector<uint8_t> bytes = ReadBytes(test::GoldenDir() + "/mannequin_v1.drape");
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

}  // namespace
}  // namespace drape

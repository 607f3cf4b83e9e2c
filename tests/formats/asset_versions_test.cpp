// Format and class versions: a newer or older format version and an unknown class version are
// refused by name; each format version holds exactly its own BodyMapPose version; files of the
// older formats load as one-layer poses (dense ones for format 1).

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "asset_fixtures.h"
#include "drape/formats/asset_file.h"
#include "test_support.h"

namespace drape {
namespace {

using test::Encode;
using test::FixChecksums;
using test::LayeredAsset;
using test::ReadBytes;
using test::SmallAsset;

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
  ASSERT_EQ(bytes[kAssetHeaderSize + 1], 4);
  bytes[kAssetHeaderSize + 1] = 5;
  FixChecksums(bytes);
  CharacterAsset out;
  const Status s = DecodeAsset(bytes, "t.drape", &out);
  EXPECT_EQ(s.code(), StatusCode::kCorrupt);
  EXPECT_NE(s.message().find("unsupported version 5 of CharacterAsset"), std::string::npos)
      << s.message();
}

// Bytes of an empty render mesh at the end of a format 8 payload: its five arrays' counts (its
// class version went out with the bind mesh).
constexpr size_t kEmptyRenderMesh = 5 * 8;

// Sets the payload size of the header after bytes were cut off the end, and the checksums.
void FixPayloadSize(std::vector<uint8_t>& bytes) {
  const uint64_t payload = bytes.size() - kAssetHeaderSize;
  for (int i = 0; i < 8; ++i) bytes[16 + i] = static_cast<uint8_t>(payload >> (8 * i));
  FixChecksums(bytes);
}

// The render mesh arrived with format version 8 (CharacterAsset class version 4): a version 4
// asset under an older header is refused naming both, the older class version reads without it,
// and the validator names a bad one by its field.
TEST(AssetFile, RenderMeshNeedsFormatVersion8) {
  CharacterAsset small = SmallAsset();
  small.render_mesh = small.mesh;
  small.render_mesh.triangles.resize(9);  // three of the tetrahedron's four faces
  std::vector<uint8_t> bytes = Encode(small);
  CharacterAsset out;
  ASSERT_TRUE(DecodeAsset(bytes, "v8.drape", &out).ok());
  EXPECT_EQ(out.render_mesh.triangles, small.render_mesh.triangles);
  EXPECT_EQ(&RenderMeshOf(out), &out.render_mesh);
  bytes[8] = 7;
  FixChecksums(bytes);
  Status s = DecodeAsset(bytes, "v7.drape", &out);
  EXPECT_EQ(s.code(), StatusCode::kCorrupt);
  EXPECT_EQ(s.message(), "v7.drape: CharacterAsset version 4 in a format version 7 file");
  // As format 7 wrote it: class version 3, no render mesh at the end.
  small.render_mesh = MeshData{};
  bytes = Encode(small);
  bytes[8] = 7;
  bytes[kAssetHeaderSize + 1] = 3;
  bytes.resize(bytes.size() - kEmptyRenderMesh);
  FixPayloadSize(bytes);
  s = DecodeAsset(bytes, "v7.drape", &out);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(AssetToJson(out), AssetToJson(small));
  EXPECT_EQ(&RenderMeshOf(out), &out.mesh);  // none: the bind mesh is drawn
  // Render meshes the validator refuses, named by their field.
  small.render_mesh = small.mesh;
  small.render_mesh.triangles[4] = 9;
  s = EncodeAsset(small, &bytes);
  EXPECT_NE(s.message().find("render_mesh.triangles[4] = 9"), std::string::npos) << s.message();
  small.render_mesh = small.mesh;
  small.render_mesh.influence_joints[1] = 42;
  s = EncodeAsset(small, &bytes);
  EXPECT_NE(s.message().find("render_mesh.influence_joints[1]"), std::string::npos) << s.message();
  small.render_mesh = small.mesh;
  small.render_mesh.influence_offsets.clear();
  small.render_mesh.influence_joints.clear();
  small.render_mesh.influence_weights.clear();
  s = EncodeAsset(small, &bytes);
  EXPECT_NE(s.message().find("render_mesh.influence_offsets"), std::string::npos) << s.message();
}

// Capsules arrived with format version 6 (CharacterAsset class version 3): a version 3 asset
// under an older header is refused naming both, and the older class version reads without them.
TEST(AssetFile, CapsulesNeedFormatVersion6) {
  CharacterAsset small = SmallAsset();
  small.body_maps.poses.clear();  // a format 7 pose would be refused first under format 5
  small.capsules.push_back({0, {0.f, 0.1f, 0.f}, {0.f, 0.4f, 0.f}, 0.05f, 0.04f});
  std::vector<uint8_t> bytes = Encode(small);
  CharacterAsset out;
  ASSERT_TRUE(DecodeAsset(bytes, "v6.drape", &out).ok());
  ASSERT_EQ(out.capsules.size(), 1u);
  EXPECT_EQ(out.capsules[0].radius_to, 0.04f);
  bytes[8] = 5;
  FixChecksums(bytes);
  Status s = DecodeAsset(bytes, "v5.drape", &out);
  EXPECT_EQ(s.code(), StatusCode::kCorrupt);
  EXPECT_EQ(s.message(), "v5.drape: CharacterAsset version 4 in a format version 5 file");
  // As format 5 wrote it: class version 2, no capsules and no render mesh at the end (the
  // capsules' empty array: 8 bytes; the empty render mesh's five arrays: 5 * 8).
  small.capsules.clear();
  bytes = Encode(small);
  bytes[8] = 5;
  bytes[kAssetHeaderSize + 1] = 2;
  bytes.resize(bytes.size() - 8 - kEmptyRenderMesh);
  FixPayloadSize(bytes);
  s = DecodeAsset(bytes, "v5.drape", &out);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(AssetToJson(out), AssetToJson(small));
  // A capsule the validator refuses: named by its field.
  small.capsules.push_back({0, {0.f, 0.1f, 0.f}, {0.f, 0.4f, 0.f}, 0.05f, -1.f});
  EXPECT_FALSE(EncodeAsset(small, &bytes).ok());
  small.capsules[0].radius_to = 0.04f;
  small.capsules[0].joint = 99;
  s = EncodeAsset(small, &bytes);
  EXPECT_NE(s.message().find("capsules[0].joint"), std::string::npos) << s.message();
}

// Bone maps arrived with format version 5 (CharacterAsset class version 2): a version 2 asset
// under an older header is refused naming both, and the older class version reads without them.
TEST(AssetFile, BoneMapsNeedFormatVersion5) {
  CharacterAsset small = SmallAsset();
  small.body_maps.poses.clear();  // a format 7 pose would be refused first under format 4
  std::vector<uint8_t> bytes = Encode(small);
  bytes[8] = 4;
  FixChecksums(bytes);
  CharacterAsset out;
  Status s = DecodeAsset(bytes, "v4.drape", &out);
  EXPECT_EQ(s.code(), StatusCode::kCorrupt);
  EXPECT_EQ(s.message(), "v4.drape: CharacterAsset version 4 in a format version 4 file");
  // As format 4 wrote it: class version 1, no bone-map set and no capsules at the end (epsilon
  // and an empty array: 4 + 4 + 8 bytes; the capsules' empty array: 8).
  bytes[kAssetHeaderSize + 1] = 1;
  bytes.resize(bytes.size() - 16 - 8 - kEmptyRenderMesh);
  const uint64_t payload = bytes.size() - kAssetHeaderSize;
  for (int i = 0; i < 8; ++i) bytes[16 + i] = static_cast<uint8_t>(payload >> (8 * i));
  FixChecksums(bytes);
  s = DecodeAsset(bytes, "v4.drape", &out);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(AssetToJson(out), AssetToJson(small));
}

// A format version 1 file holds only class version 1: a version 2 or 3 pose under a version 1
// header is refused, and an older class version of BodyMapPose is read as dense with one layer
// (the golden files).
TEST(BodyMapLayout, FormatVersion1HoldsOnlyDensePoses) {
  std::vector<uint8_t> bytes = Encode(SmallAsset());  // BodyMapPose version 4
  bytes[8] = 1;
  FixChecksums(bytes);
  CharacterAsset out;
  Status s = DecodeAsset(bytes, "v1.drape", &out);
  EXPECT_EQ(s.code(), StatusCode::kCorrupt);
  EXPECT_NE(s.message().find("BodyMapPose version 4 in a format version 1 file"), std::string::npos)
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

// Where SmallAsset's pose starts in its encoding: class version 4, clip -1, time 0, width 2,
// height 2 (the pose's first fields).
size_t PoseStart(const std::vector<uint8_t>& bytes) {
  // clang-format off
  const std::vector<uint8_t> start = {4, 0, 0, 0,  0xFF, 0xFF, 0xFF, 0xFF,  0, 0, 0, 0,
                                      2, 0, 0, 0,  2, 0, 0, 0};
  // clang-format on
  const auto found = std::search(bytes.begin(), bytes.end(), start.begin(), start.end());
  EXPECT_NE(found, bytes.end());
  return static_cast<size_t>(found - bytes.begin());
}

// The view axis arrived with format version 7 (BodyMapPose class version 4, one byte after
// `layers`): a format 6 file reads with view axis z, a class version 3 pose under a format 7
// header is refused, and an unknown axis or a set of mixed axes is refused naming the field.
TEST(BodyMapViewAxis, ArrivedWithFormatVersion7) {
  CharacterAsset small = SmallAsset();
  small.hulls.clear();
  small.body_maps.poses[0].view_axis = BodyMapViewAxis::kY;
  std::vector<uint8_t> bytes = Encode(small);
  CharacterAsset out;
  ASSERT_TRUE(DecodeAsset(bytes, "v7.drape", &out).ok());
  EXPECT_EQ(out.body_maps.poses[0].view_axis, BodyMapViewAxis::kY);
  const size_t axis_at = PoseStart(bytes) + 4 + 36 + 2 + 1 + 1;
  ASSERT_EQ(bytes[axis_at], 2);
  // An unknown axis: corrupt, naming the field.
  std::vector<uint8_t> bad = bytes;
  bad[axis_at] = 3;
  FixChecksums(bad);
  Status s = DecodeAsset(bad, "axis.drape", &out);
  EXPECT_EQ(s.code(), StatusCode::kCorrupt);
  EXPECT_EQ(s.message(),
            "axis.drape: body_maps.poses[0].view_axis = 3 is not 0 (z), 1 (x) or 2 (y)");
  // As format 6 wrote it: pose class version 3, no axis byte (it reads as z); CharacterAsset
  // class version 3, no render mesh.
  std::vector<uint8_t> v6 = bytes;
  v6[PoseStart(v6)] = 3;
  v6.erase(v6.begin() + static_cast<std::ptrdiff_t>(axis_at));
  v6[kAssetHeaderSize + 1] = 3;
  v6.resize(v6.size() - kEmptyRenderMesh);
  const uint64_t payload = v6.size() - kAssetHeaderSize;
  for (int i = 0; i < 8; ++i) v6[16 + i] = static_cast<uint8_t>(payload >> (8 * i));
  v6[8] = 6;
  FixChecksums(v6);
  s = DecodeAsset(v6, "v6.drape", &out);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(out.body_maps.poses[0].view_axis, BodyMapViewAxis::kZ);
  small.body_maps.poses[0].view_axis = BodyMapViewAxis::kZ;
  EXPECT_EQ(AssetToJson(out), AssetToJson(small));
  ExpectPoseVersionRefused(v6, 7, 3);
  // Poses of one set share the axis.
  CharacterAsset mixed = SmallAsset();
  mixed.body_maps.poses.push_back(mixed.body_maps.poses[0]);
  mixed.body_maps.poses[1].view_axis = BodyMapViewAxis::kX;
  EXPECT_EQ(ValidateAsset(mixed).message(), "body_maps.poses[1].view_axis is x, pose 0's is z");
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
  ExpectPoseVersionRefused(Encode(LayeredAsset()), 2, 4);
}

// A format version holds exactly its own BodyMapPose version. SmallAsset's pose rewritten as
// class version 2 (the layers byte removed) is a valid format version 2 file, and refused under
// a format version 3 header: no writer wrote it, and it would not re-encode to the same bytes.
TEST(BodyMapLayers, AFormatHoldsExactlyItsOwnPoseVersion) {
  // Without hulls: the forged older file changes only the pose's bytes (HullColliderData is at
  // class version 2 from format version 4 on).
  CharacterAsset small = SmallAsset();
  small.hulls.clear();
  std::vector<uint8_t> bytes = Encode(small);
  const size_t pose = PoseStart(bytes);
  // 4 class version, 36 of clip .. depth_range, 2 encodings, 1 layout: then layers and the view
  // axis.
  const size_t layers_at = pose + 4 + 36 + 2 + 1;
  ASSERT_EQ(bytes[layers_at], 1);
  ASSERT_EQ(bytes[layers_at + 1], 0);
  bytes[pose] = 2;
  bytes.erase(bytes.begin() + static_cast<std::ptrdiff_t>(layers_at),
              bytes.begin() + static_cast<std::ptrdiff_t>(layers_at + 2));
  // The dense pose's empty span table (three uint64 counts), then gap_texels' count: remove it.
  const size_t gap_count_at = layers_at + 3 * 8;
  for (size_t i = 0; i < 8; ++i) ASSERT_EQ(bytes[gap_count_at + i], 0) << i;
  bytes.erase(bytes.begin() + static_cast<std::ptrdiff_t>(gap_count_at),
              bytes.begin() + static_cast<std::ptrdiff_t>(gap_count_at + 8));
  // As format 2 wrote it: CharacterAsset class version 1, without the bone-map set at the end
  // (its class version, epsilon and an empty array: 16 bytes) and the capsules' empty array (8).
  bytes[kAssetHeaderSize + 1] = 1;
  bytes.resize(bytes.size() - 16 - 8 - kEmptyRenderMesh);
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

// Bone maps round-trip, and the loader (and the writer) refuse a bone map naming a joint the
// skeleton lacks, a view frame that is not rigid, or a pose of a clip, naming the field.
TEST(AssetFile, BoneMapsRoundTripAndAreValidated) {
  CharacterAsset a = SmallAsset();
  a.bone_maps.epsilon = 0.004f;
  BoneMapData bone;
  bone.joint = 2;
  bone.view_from_bind.m[3] = 0.25f;  // a translation: rigid
  bone.pose = a.body_maps.poses[0];
  bone.pose.clip = -1;
  a.bone_maps.maps = {bone, bone};
  a.bone_maps.maps[1].joint = 1;
  CharacterAsset out;
  ASSERT_TRUE(DecodeAsset(Encode(a), "b.drape", &out).ok());
  EXPECT_EQ(AssetToJson(out), AssetToJson(a));
  ASSERT_EQ(out.bone_maps.maps.size(), 2u);
  EXPECT_EQ(out.bone_maps.maps[1].joint, 1);

  // The checks the loader and the writer share.
  const auto refused = [&](const CharacterAsset& bad, const std::string& expected) {
    const Status s = ValidateAsset(bad);
    EXPECT_EQ(s.code(), StatusCode::kCorrupt);
    EXPECT_NE(s.message().find(expected), std::string::npos) << s.message();
  };
  CharacterAsset bad = a;
  bad.bone_maps.maps[1].joint = 3;
  refused(bad, "bone_maps.maps[1].joint");
  bad = a;
  bad.bone_maps.maps[0].view_from_bind.m[0] = 2.f;  // a scale
  refused(bad, "bone_maps.maps[0].view_from_bind is not a finite rigid transform");
  bad = a;
  bad.bone_maps.maps[0].view_from_bind.m[0] = -1.f;  // a reflection
  refused(bad, "bone_maps.maps[0].view_from_bind");
  bad = a;
  bad.bone_maps.maps[1].pose.clip = 0;
  refused(bad, "bone_maps.maps[1].pose.clip is not -1");
  bad = a;
  bad.bone_maps.maps[1].pose.depth_u16[0].pop_back();
  refused(bad, "bone_maps.maps[1].pose.depth_u16_front");
  bad = a;
  bad.bone_maps.epsilon = -1.f;
  refused(bad, "bone_maps.epsilon");
}

}  // namespace
}  // namespace drape

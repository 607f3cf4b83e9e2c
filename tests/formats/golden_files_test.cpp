// The committed golden files of every format version this build reads (tests/golden/) load with
// their known content, and every truncation and sampled byte flip of them fails.

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "asset_fixtures.h"
#include "drape/formats/asset_file.h"
#include "test_support.h"

namespace drape {
namespace {

using test::ReadBytes;

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

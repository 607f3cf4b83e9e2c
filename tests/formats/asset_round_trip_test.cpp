// The .drape container round trip: every field survives encode and decode, the same asset gives
// the same bytes, and the writer leaves either the whole file or nothing.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "asset_fixtures.h"
#include "drape/formats/asset_file.h"

namespace drape {
namespace {

using test::Encode;
using test::SmallAsset;

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

}  // namespace
}  // namespace drape

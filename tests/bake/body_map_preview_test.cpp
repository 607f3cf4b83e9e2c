// The body-map previews: four PNGs per pose (depth and normals, front and back) and two more per
// gap layer; a missing directory is an I/O error.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <string>

#include "body_map_fixtures.h"
#include "body_map_gap_fixtures.h"
#include "drape/bake/body_map_baker.h"

namespace drape::bake {
namespace {

using namespace body_map_fixtures;

// `dir` holds exactly the named files (no other), each larger than `min_bytes`.
void ExpectExactlyTheseFiles(const std::filesystem::path& dir,
                             std::initializer_list<const char*> names, uintmax_t min_bytes) {
  for (const char* name : names) {
    const std::filesystem::path file = dir / name;
    ASSERT_TRUE(std::filesystem::exists(file)) << file;
    EXPECT_GT(std::filesystem::file_size(file), min_bytes) << file;
  }
  size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    files += entry.is_regular_file();
  EXPECT_EQ(files, names.size());
}

TEST(BodyMapBaker, PreviewWritesFourPngs) {
  const Mesh capsule = MakeCapsule({0.0, 0.0, 0.0}, 0.2, 0.3, 16, 32);
  BodyMapOptions o;
  o.resolution = 128;
  o.normal_encoding = NormalEncoding::kOct16;
  o.depth_encoding = DepthEncoding::kUnorm16;
  const BodyMapPose pose = BakeOrDie(capsule, o);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("drape_body_map_preview_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const Status status = WriteBodyMapPreview(pose, dir.string(), "capsule");
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectExactlyTheseFiles(dir,
                          {"capsule_front_depth.png", "capsule_back_depth.png",
                           "capsule_front_normal.png", "capsule_back_normal.png"},
                          100);
  std::filesystem::remove_all(dir);
  // A directory that does not exist is an I/O error, not a crash.
  EXPECT_EQ(WriteBodyMapPreview(pose, (dir / "missing" / "deeper").string(), "x").code(),
            StatusCode::kIoError);
}

TEST(BodyMapBaker, PreviewWritesGapLayerPngs) {
  const Mesh scene = GapScene();
  BodyMapOptions o;
  o.resolution = 128;
  o.depth_encoding = DepthEncoding::kUnorm16;
  o.layout = BodyMapLayout::kDense;
  o.layers = 3;
  const BodyMapPose pose = BakeOrDie(scene, o);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("drape_body_map_gap_preview_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const Status status = WriteBodyMapPreview(pose, dir.string(), "scene");
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectExactlyTheseFiles(
      dir,
      {"scene_front_depth.png", "scene_back_depth.png", "scene_front_normal.png",
       "scene_back_normal.png", "scene_gap1_front_depth.png", "scene_gap1_back_depth.png",
       "scene_gap2_front_depth.png", "scene_gap2_back_depth.png"},
      60);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace drape::bake

// A body without a skeleton is one region: the bake cuts it into convex pieces that fit it rather
// than one hull bridging the arms and the torso. Each case writes a posed copy of a rigged
// character as an OBJ (the skeleton removed), bakes it with the default config and checks the
// fit the bake measures.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "drape/bake/bake_pipeline.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"
#include "test_support.h"

namespace drape {
namespace {

struct StaticCase {
  const char* path;     // under shared/assets/characters, or "" for the built-in mannequin
  float clip_fraction;  // where in its longest clip the copy is posed
  // The copy's import.unit_scale, 0: the OBJ's metres. Animated_Human's file makes it 5.3 m
  // tall; the targets' millimetres are a person's, so its copy is read at 1.75 m.
  double unit_scale = 0.0;
};

class SkeletonRemoved : public ::testing::TestWithParam<StaticCase> {};

// The character posed at the case's clip time, written as an OBJ with no skeleton.
std::string WriteStaticCopy(const CharacterAsset& asset, float fraction, const std::string& out) {
  SkeletonPose pose;
  EXPECT_TRUE(pose.Init(asset.skeleton).ok());
  if (!asset.clips.empty()) {
    const ClipData& clip = asset.clips.front();
    EXPECT_TRUE(pose.SampleClip(clip, fraction * clip.duration, false).ok());
  }
  std::vector<Float3> posed(asset.mesh.vertex_count());
  EXPECT_TRUE(SkinMesh(asset.mesh, pose.skinning(), posed).ok());
  std::ofstream obj(out);
  for (const Float3& p : posed) obj << "v " << p.x << ' ' << p.y << ' ' << p.z << '\n';
  const std::vector<uint32_t>& t = asset.mesh.triangles;
  for (size_t i = 0; i + 2 < t.size(); i += 3)
    obj << "f " << t[i] + 1 << ' ' << t[i + 1] + 1 << ' ' << t[i + 2] + 1 << '\n';
  return out;
}

TEST_P(SkeletonRemoved, ConvexPiecesFitTheBody) {
  const std::string path =
      *GetParam().path ? test::CharacterPath(GetParam().path) : test::MannequinPath();
  DRAPE_REQUIRE_FILE(path);
  bake::BakeConfig config;
  config.maps_enabled = false;
  bake::BakeResult rigged;
  ASSERT_TRUE(bake::BakeCharacter(path, config, &rigged).ok());
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "drape_skeletonless";
  std::filesystem::create_directories(dir);
  const std::string obj = WriteStaticCopy(
      rigged.asset, GetParam().clip_fraction,
      (dir / (std::filesystem::path(path).stem().string() + "_static.obj")).string());
  bake::BakeResult result;
  config.import.unit_scale = GetParam().unit_scale;
  const Status s = bake::BakeCharacter(obj, config, &result);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(result.asset.skeleton.joint_count(), 1u) << "the copy has no skeleton";
  // One region, cut: more than one hull, within the budget of one bone.
  EXPECT_GT(result.asset.hulls.size(), 1u);
  EXPECT_LE(result.asset.hulls.size(), config.hull_max_pieces);
  // The capsules need bones: the whole body gets one, which the report measures.
  EXPECT_EQ(result.asset.capsules.size(), 1u);
  EXPECT_TRUE(result.report.contains("fit_capsules"));
  const nlohmann::json& fit = result.report["fit"];
  EXPECT_GE(fit["coverage"].get<double>(), 0.99);
  // One hull of the whole body bulged 104 mm on CesiumMan at rest. The pieces: 16.1 mm on the
  // walking mannequin, 14.4 mm on CesiumMan at its clip's first frame, 26.2 mm on Animated_Human
  // (the target: 30 mm; plane cuts alone: 21.2, 21.3 and 35.6 mm).
  EXPECT_LE(fit["bloat_max_mm"].get<double>(), 30.0);
  RecordProperty("bloat_p99_mm", std::to_string(fit["bloat_p99_mm"].get<double>()));
  RecordProperty("hulls", std::to_string(result.asset.hulls.size()));
}

INSTANTIATE_TEST_SUITE_P(
    HumanCopies, SkeletonRemoved,
    ::testing::Values(StaticCase{"", 0.5f}, StaticCase{"CesiumMan/CesiumMan.glb", 0.f},
                      StaticCase{"QuaterniusAnimatedHuman/Animated_Human.fbx", 0.f, 1.75 / 5.2594}),
    [](const auto& param_info) { return test::CharacterTestName(param_info.param.path); });

}  // namespace
}  // namespace drape

// The runtime's BodyMapRenderer against the bake's reference rasterizer: for a pose no bake saw
// (between a clip's keys), maps rendered at run time on the baked grid hold the same texels, the
// same depths (float against double arithmetic) and the same normals as the maps the bake makes
// of that posed mesh. On the mannequin and on every shared character present.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "body_map/body_map_collider_access.h"
#include "drape/bake/body_map_baker.h"
#include "drape/bake/importer.h"
#include "drape/runtime/body_map_renderer.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"
#include "test_support.h"

namespace drape::bake {
namespace {

struct Case {
  const char* name;
  const char* path;  // under ../shared/assets/characters; empty: the mannequin sample
};

class RenderedMaps : public ::testing::TestWithParam<Case> {};

TEST_P(RenderedMaps, AgreeWithTheBakeOnAPoseBetweenKeys) {
  const std::string path =
      *GetParam().path ? test::CharacterPath(GetParam().path) : test::MannequinPath();
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " is absent (../shared/assets)";
  Character character;
  ASSERT_TRUE(ImportCharacter(path, ImportOptions{}, &character).ok());
  SkeletonPose pose;
  ASSERT_TRUE(pose.Init(character.skeleton).ok());
  if (!character.clips.empty()) {
    const ClipData& clip = character.clips.front();
    // Between two keys: a pose the clip's resampled frames do not hold.
    const float time =
        (std::floor(0.37f * static_cast<float>(clip.frame_count)) + 0.43f) / clip.sample_rate;
    ASSERT_TRUE(pose.SampleClip(clip, std::min(time, clip.duration), false).ok());
  }
  std::vector<Float3> posed(character.mesh.vertex_count());
  ASSERT_TRUE(SkinMesh(character.mesh, pose.skinning(), posed).ok());

  BodyMapOptions bake_options;
  bake_options.resolution = 512;
  bake_options.layout = BodyMapLayout::kDense;
  BodyMapPose baked_pose;
  ASSERT_TRUE(BakeBodyMapPose(posed, character.mesh.triangles, bake_options, &baked_pose).ok());
  BodyMapCollider baked;
  ASSERT_TRUE(baked.Build(baked_pose).ok());

  BodyMapRenderOptions options;
  options.texel_size = baked_pose.texel_size;
  options.epsilon = bake_options.epsilon;
  options.grid_x = baked_pose.origin_x;
  options.grid_y = baked_pose.origin_y;
  BodyMapRenderer renderer;
  ASSERT_TRUE(renderer.Init(character.mesh, options).ok());
  BodyMapCollider rendered;
  ASSERT_TRUE(renderer.Render(pose.skinning(), &rendered).ok());

  // Texel (i, j) of the bake is texel (i + di, j + dj) of the render: one lattice.
  const long di =
      std::lround((double(baked.origin_x()) - rendered.origin_x()) / baked.texel_size());
  const long dj =
      std::lround((double(baked.origin_y()) - rendered.origin_y()) / baked.texel_size());
  size_t mismatched = 0, valid = 0;
  double max_depth = 0.0, max_angle = 0.0;
  for (uint32_t j = 0; j < baked.height(); ++j) {
    for (uint32_t i = 0; i < baked.width(); ++i) {
      float bt = 0.f, bb = 0.f, rt = 0.f, rb = 0.f;
      const bool in_bake = BodyMapColliderAccess::TexelSlab(baked, i, j, &bt, &bb);
      const long ri = long(i) + di, rj = long(j) + dj;
      const bool in_render =
          ri >= 0 && rj >= 0 &&
          BodyMapColliderAccess::TexelSlab(rendered, uint32_t(ri), uint32_t(rj), &rt, &rb);
      if (in_bake != in_render) ++mismatched;
      if (!(in_bake && in_render)) continue;
      ++valid;
      max_depth = std::max({max_depth, std::fabs(double(bt) - rt), std::fabs(double(bb) - rb)});
      for (bool back : {false, true}) {
        const Float3 a = BodyMapColliderAccess::TexelNormal(baked, i, j, back);
        const Float3 b =
            BodyMapColliderAccess::TexelNormal(rendered, uint32_t(ri), uint32_t(rj), back);
        const double cosine = std::clamp(double(Dot(a, b)), -1.0, 1.0);
        max_angle = std::max(max_angle, std::acos(cosine) * 180.0 / 3.14159265358979);
      }
    }
  }
  EXPECT_GT(valid, 10000u);
  // Texel centres exactly on a silhouette edge: the bake's top-left rule against inclusive edges.
  EXPECT_LE(mismatched, valid / 5000) << mismatched << " of " << valid;
  EXPECT_LT(max_depth, 2e-5) << "metres";  // float against double: 3 um measured
  EXPECT_LT(max_angle, 0.5) << "degrees";
}

INSTANTIATE_TEST_SUITE_P(Characters, RenderedMaps,
                         ::testing::Values(Case{"mannequin", ""},
                                           Case{"CesiumMan", "CesiumMan/CesiumMan.glb"},
                                           Case{"Fox", "Fox/Fox.glb"}),
                         [](const auto& param_info) { return std::string(param_info.param.name); });

}  // namespace
}  // namespace drape::bake

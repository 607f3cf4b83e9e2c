// The body maps that follow any pose. Per-bone local maps: baked once at the bind pose, they
// follow the joints; a rig bound in centimetres gets the texel and epsilon of its posed metres;
// the batch gives the same bits at any thread count; a bad pose is refused and keeps the previous
// one; and on the mannequin and the shared characters at a pose between a clip's keys, the
// points just inside the posed body are inside and the points clearly outside mostly outside.
// Maps rendered at run time (BodyMapRenderer) agree with the bake's reference rasterizer there.

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "body_map/body_map_collider_access.h"
#include "drape/bake/body_map_baker.h"
#include "drape/bake/bone_map_baker.h"
#include "drape/bake/importer.h"
#include "drape/bake/mesh_reference.h"
#include "drape/runtime/body_map_renderer.h"
#include "drape/runtime/bone_map_collider.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"
#include "skinned_spheres.h"
#include "test_support.h"

namespace drape::bake {
namespace {

constexpr float kRadius = 0.1f;  // metres

MeshData TwoSpheres(float scale = 1.f) { return test::TwoSkinnedSpheres(kRadius, scale); }

SkeletonData TwoJoints() {
  SkeletonData s;
  s.joint_names = {"a", "b"};
  s.parents = {-1, 0};
  s.rest_local.resize(2);
  s.inverse_bind.resize(2);
  return s;
}

Mat34 Moved() {  // joint 1: turned 90 degrees about z, then moved
  Mat34 m;
  m.m[0] = 0.f, m.m[1] = -1.f, m.m[4] = 1.f, m.m[5] = 0.f;
  return Multiply(TranslationMatrix({0.2f, 0.6f, 0.1f}), m);
}

TEST(BoneMaps, FollowTheJoints) {
  const MeshData mesh = TwoSpheres();
  BoneMapOptions options;
  options.texel_size = 0.002f;
  BoneMapSet set;
  std::vector<BoneMapStats> stats;
  ASSERT_TRUE(BakeBoneMaps(mesh, TwoJoints(), {}, options, &set, &stats).ok());
  ASSERT_EQ(set.maps.size(), 2u);
  EXPECT_EQ(stats[1].joint, 1);
  EXPECT_EQ(stats[1].triangles, mesh.triangle_count() / 2);
  BoneMapCollider bones;
  ASSERT_TRUE(bones.Build(set, 2).ok());
  EXPECT_TRUE(bones.IsInside({0.5f, 0.f, 0.f}));  // the bind pose until SetPose
  const Mat34 moved = Moved();
  const std::vector<Mat34> pose = {Mat34{}, moved};
  ASSERT_TRUE(bones.SetPose(pose, pose).ok());
  const Float3 centre = TransformPoint(moved, {0.5f, 0.f, 0.f});
  EXPECT_FALSE(bones.IsInside({0.5f, 0.f, 0.f}));
  EXPECT_TRUE(bones.IsInside(centre));
  EXPECT_TRUE(bones.IsInside(centre + Float3{0.f, 0.f, 0.09f}));
  EXPECT_FALSE(bones.IsInside(centre + Float3{0.f, 0.f, 0.11f}));
  EXPECT_TRUE(bones.IsInside({0.f, 0.f, 0.f}));  // joint 0 stayed
  // A motion down onto the moved sphere stops on its offset surface, the normal up.
  const ContactQuery c = bones.Query(centre + Float3{0.f, 0.f, 0.3f}, centre);
  ASSERT_TRUE(c.contact);
  EXPECT_NEAR(c.point.z, centre.z + kRadius + options.epsilon, 2.5e-3f);
  EXPECT_GT(c.normal.z, 0.97f);
  EXPECT_NEAR(c.point.x, centre.x, 3e-3f);
  EXPECT_NEAR(c.point.y, centre.y, 3e-3f);
}

// A rig bound in centimetres and posed in metres (its skinning matrices scale by 100): the
// texel and epsilon are the options' on the posed body, and contacts are in metres.
TEST(BoneMaps, ARigBoundInCentimetresGetsTheTexelOfItsPosedMetres) {
  const MeshData mesh = TwoSpheres(0.01f);
  Mat34 to_metres;
  for (int k : {0, 5, 10}) to_metres.m[k] = 100.f;
  const std::vector<Mat34> rest = {to_metres, to_metres};
  BoneMapOptions options;
  options.texel_size = 0.002f;
  BoneMapSet set;
  ASSERT_TRUE(BakeBoneMaps(mesh, TwoJoints(), rest, options, &set).ok());
  ASSERT_EQ(set.maps.size(), 2u);
  EXPECT_NEAR(set.maps[0].pose.texel_size * 100.f, options.texel_size, 2e-4f);
  BoneMapCollider bones;
  ASSERT_TRUE(bones.Build(set, 2).ok());
  ASSERT_TRUE(bones.SetPose(rest, rest).ok());
  EXPECT_TRUE(bones.IsInside({0.5f, 0.f, 0.09f}));
  EXPECT_FALSE(bones.IsInside({0.5f, 0.f, 0.11f}));
  const ContactQuery c = bones.Query({0.f, 0.f, 0.3f}, {0.f, 0.f, 0.09f});
  ASSERT_TRUE(c.contact);
  EXPECT_NEAR(c.point.z, kRadius + options.epsilon, 2.5e-3f);
  const ContactQuery inside = bones.Query({0.f, 0.f, 0.08f}, {0.f, 0.f, 0.08f});
  ASSERT_TRUE(inside.contact);
  EXPECT_NEAR(inside.depth, kRadius + options.epsilon - 0.08f, 2.5e-3f);  // metres, not cm
}

TEST(BoneMaps, TheBatchGivesTheSameBitsAtAnyThreadCountAndRefusesABadPose) {
  const MeshData mesh = TwoSpheres();
  BoneMapSet set;
  ASSERT_TRUE(BakeBoneMaps(mesh, TwoJoints(), {}, BoneMapOptions{}, &set).ok());
  BoneMapCollider bones;
  ASSERT_TRUE(bones.Build(set, 2).ok());
  const std::vector<Mat34> start = {Mat34{}, Mat34{}}, end = {Mat34{}, Moved()};
  ASSERT_TRUE(bones.SetPose(start, end).ok());
  std::mt19937 random(7);
  std::uniform_real_distribution<float> coordinate(-0.3f, 0.9f);
  std::vector<Float3> previous(3000), current(3000);
  for (size_t i = 0; i < previous.size(); ++i) {
    previous[i] = {coordinate(random), coordinate(random) * 0.5f, coordinate(random) * 0.3f};
    current[i] =
        previous[i] + Float3{coordinate(random), coordinate(random), coordinate(random)} * 0.2f;
  }
  previous[5].x = std::nanf("");
  const int saved = omp_get_max_threads();
  std::vector<Float3> reference;
  uint32_t reference_contacts = 0;
  for (int threads : {1, 2, 3}) {
    omp_set_num_threads(threads);
    std::vector<Float3> positions = current, velocities(current.size(), Float3{0.f, -1.f, 0.f});
    std::vector<uint8_t> flags(current.size());
    uint32_t contacts = 0;
    ASSERT_TRUE(
        bones.CollideBatch(previous, positions, velocities, flags, ResponseParams{}, &contacts)
            .ok());
    EXPECT_EQ(flags[5], kCollisionInvalidInput);
    if (reference.empty()) {
      reference = positions;
      reference_contacts = contacts;
      EXPECT_GT(contacts, 30u);
      continue;
    }
    EXPECT_EQ(contacts, reference_contacts);
    EXPECT_EQ(std::memcmp(positions.data(), reference.data(), positions.size() * sizeof(Float3)), 0)
        << threads << " threads";
  }
  omp_set_num_threads(saved);

  // A matrix that is not finite, or not invertible, is refused and the pose stays.
  const Float3 centre = TransformPoint(Moved(), {0.5f, 0.f, 0.f});
  ASSERT_TRUE(bones.IsInside(centre));
  Mat34 bad = Moved();
  bad.m[5] = std::nanf("");
  const std::vector<Mat34> nan_pose = {Mat34{}, bad};
  Status s = bones.SetPose(nan_pose, nan_pose);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("joint 1"), std::string::npos) << s.message();
  Mat34 flat;
  flat.m[10] = 0.f;
  const std::vector<Mat34> flat_pose = {flat, Mat34{}};
  EXPECT_FALSE(bones.SetPose(flat_pose, flat_pose).ok());
  EXPECT_FALSE(bones.SetPose(std::vector<Mat34>{Mat34{}}, std::vector<Mat34>{Mat34{}}).ok());
  EXPECT_TRUE(bones.IsInside(centre));
  // A bone map naming a joint the skeleton lacks.
  EXPECT_NE(bones.Build(set, 1).message().find("bone map 1: joint 1 of 1"), std::string::npos);
  EXPECT_TRUE(bones.empty());
}

struct Case {
  const char* name;
  const char* path;  // under ../shared/assets/characters; empty: the mannequin sample
};

// A character imported, its rest pose, and its skeleton posed between a clip's keys (a pose the
// clip's resampled frames do not hold).
struct PosedCharacter {
  Character character;
  SkeletonPose pose;
  std::vector<Float3> rest;          // the rest pose's vertices
  std::vector<Mat34> rest_skinning;  // bind -> rest
};

void PoseBetweenKeys(const Case& c, PosedCharacter* out) {
  const std::string path = *c.path ? test::CharacterPath(c.path) : test::MannequinPath();
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " is absent (../shared/assets)";
  Character& character = out->character;
  ASSERT_TRUE(ImportCharacter(path, ImportOptions{}, &character).ok());
  SkeletonPose& pose = out->pose;
  ASSERT_TRUE(pose.Init(character.skeleton).ok());
  pose.SetRest();
  out->rest.resize(character.mesh.vertex_count());
  ASSERT_TRUE(SkinMesh(character.mesh, pose.skinning(), out->rest).ok());
  out->rest_skinning.assign(pose.skinning().begin(), pose.skinning().end());
  if (!character.clips.empty()) {
    const ClipData& clip = character.clips.front();
    const float time =
        (std::floor(0.37f * static_cast<float>(clip.frame_count)) + 0.43f) / clip.sample_rate;
    ASSERT_TRUE(pose.SampleClip(clip, std::min(time, clip.duration), false).ok());
  }
}

class OnCharacters : public ::testing::TestWithParam<Case> {};

// At a pose between a clip's keys: points 3 mm inside the posed surface (along the vertex
// normals) are inside, points 20 mm outside mostly outside. The misses are the blended skin at
// bent joints, which each bone's maps take as rigid; the false insides are air a neighbouring
// part's slab covers in a concave corner (an armpit, the crotch).
TEST_P(OnCharacters, BoneMapsHoldThePosedBody) {
  PosedCharacter posed_character;
  PoseBetweenKeys(GetParam(), &posed_character);
  if (IsSkipped() || HasFatalFailure()) return;
  const Character& character = posed_character.character;
  const SkeletonPose& pose = posed_character.pose;
  const std::vector<Float3>& rest = posed_character.rest;
  const std::vector<Mat34>& rest_skinning = posed_character.rest_skinning;
  BoneMapOptions options;
  options.texel_size = AutomaticBoneMapTexel(rest);
  BoneMapSet set;
  ASSERT_TRUE(BakeBoneMaps(character.mesh, character.skeleton, rest_skinning, options, &set).ok());
  BoneMapCollider bones;
  ASSERT_TRUE(bones.Build(set, character.skeleton.joint_count()).ok());

  ASSERT_TRUE(bones.SetPose(pose.skinning(), pose.skinning()).ok());
  std::vector<Float3> posed(character.mesh.vertex_count());
  ASSERT_TRUE(SkinMesh(character.mesh, pose.skinning(), posed).ok());
  std::vector<Float3> normals(posed.size(), Float3{0.f, 0.f, 0.f});
  const std::vector<uint32_t>& tri = character.mesh.triangles;
  for (size_t t = 0; t + 2 < tri.size(); t += 3) {
    const Float3 n = Cross(posed[tri[t + 1]] - posed[tri[t]], posed[tri[t + 2]] - posed[tri[t]]);
    for (int k = 0; k < 3; ++k) normals[tri[t + k]] += n;
  }
  // The exact posed body decides which points are clearly inside or outside: a point near
  // where two overlapping parts of a mesh meet is inside the body whatever its normal says.
  const MeshReference reference(posed, tri);
  const float unit = options.texel_size / 0.003f;  // 1 on a 1.8 m person
  size_t inside_tested = 0, inside = 0, outside_tested = 0, outside_called_inside = 0;
  // Samples: every vertex (its area-weighted normal) and every triangle's centroid (its normal).
  std::vector<Float3> points = posed, directions = normals;
  for (size_t t = 0; t + 2 < tri.size(); t += 3) {
    const Float3 a = posed[tri[t]], b = posed[tri[t + 1]], c = posed[tri[t + 2]];
    points.push_back((a + b + c) * (1.f / 3.f));
    directions.push_back(Cross(b - a, c - a));
  }
  for (size_t k = 0; k < points.size(); ++k) {
    const Float3 n = NormalizeOr(directions[k], Float3{0.f, 0.f, 0.f});
    if (Length(n) == 0.f) continue;
    const Float3 below = points[k] - n * (0.003f * unit), above = points[k] + n * (0.02f * unit);
    const double b[3] = {below.x, below.y, below.z}, a[3] = {above.x, above.y, above.z};
    if (reference.Inside(b) && reference.Distance(b) > 0.002 * unit) {
      ++inside_tested;
      inside += bones.IsInside(below) ? 1 : 0;
    }
    if (!reference.Inside(a) && reference.Distance(a) > 0.015 * unit) {
      ++outside_tested;
      outside_called_inside += bones.IsInside(above) ? 1 : 0;
    }
  }
  ASSERT_GT(inside_tested, 50u);
  ASSERT_GT(outside_tested, 50u);
  EXPECT_GE(double(inside), 0.97 * double(inside_tested)) << inside << " of " << inside_tested;
  EXPECT_LE(double(outside_called_inside), 0.10 * double(outside_tested))
      << outside_called_inside << " of " << outside_tested;
}

// The runtime's BodyMapRenderer against the bake's reference rasterizer at the same pose: maps
// rendered on the baked grid hold the same texels, the same depths (float against double
// arithmetic) and the same normals as the maps the bake makes of the posed mesh; the rendered air
// gaps are the bake's (both keep up to three per texel, top down), and a gap the renderer
// misses is rare.
TEST_P(OnCharacters, RenderedMapsAgreeWithTheBake) {
  PosedCharacter posed_character;
  PoseBetweenKeys(GetParam(), &posed_character);
  if (IsSkipped() || HasFatalFailure()) return;
  const Character& character = posed_character.character;
  const SkeletonPose& pose = posed_character.pose;
  std::vector<Float3> posed(character.mesh.vertex_count());
  ASSERT_TRUE(SkinMesh(character.mesh, pose.skinning(), posed).ok());

  BodyMapOptions bake_options;
  bake_options.resolution = 512;
  bake_options.layout = BodyMapLayout::kDense;
  bake_options.layers = kMaxBodyMapLayers;
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
  size_t mismatched = 0, valid = 0, baked_gaps = 0, rendered_gaps = 0, false_gaps = 0;
  double max_depth = 0.0, max_angle = 0.0, max_gap_depth = 0.0;
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
      float bu[3], bl[3], ru[3], rl[3];
      const uint32_t bg = BodyMapColliderAccess::TexelGaps(baked, i, j, bu, bl);
      const uint32_t rg =
          BodyMapColliderAccess::TexelGaps(rendered, uint32_t(ri), uint32_t(rj), ru, rl);
      baked_gaps += bg;
      rendered_gaps += rg;
      if (rg > bg) false_gaps += rg - bg;
      // The same gaps, top down, where the bake kept all of its (it keeps the three thickest;
      // the renderer the three nearest the front).
      for (uint32_t g = 0; bg < 3 && g < std::min(rg, bg); ++g) {
        max_gap_depth = std::max(
            {max_gap_depth, std::fabs(double(bu[g]) - ru[g]), std::fabs(double(bl[g]) - rl[g])});
      }
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
  EXPECT_GE(rendered.layers(), 2u);
  EXPECT_LE(rendered.layers(), 4u);
  // No air the bake does not see; most of the bake's gaps found, at every depth.
  EXPECT_LE(false_gaps, valid / 5000) << false_gaps << " of " << rendered_gaps;
  EXPECT_GE(double(rendered_gaps), 0.98 * double(baked_gaps))
      << rendered_gaps << " of " << baked_gaps;
  EXPECT_LT(max_gap_depth, 2e-5) << "metres";
}

INSTANTIATE_TEST_SUITE_P(
    Characters, OnCharacters,
    ::testing::Values(Case{"mannequin", ""}, Case{"CesiumMan", "CesiumMan/CesiumMan.glb"},
                      Case{"Fox", "Fox/Fox.glb"},
                      Case{"RiggedFigure", "RiggedFigure/RiggedFigure.glb"},
                      Case{"Animated_Human", "QuaterniusAnimatedHuman/Animated_Human.fbx"},
                      Case{"RobotExpressive", "RobotExpressive/RobotExpressive.glb"}),
    [](const auto& param_info) { return std::string(param_info.param.name); });

}  // namespace
}  // namespace drape::bake

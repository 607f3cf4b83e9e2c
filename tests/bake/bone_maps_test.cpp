// Per-bone local maps: baked once at the bind pose, they follow the joints; a rig bound in
// centimetres gets the texel and epsilon of its posed metres; the batch gives the same bits at
// any thread count; a bad pose is refused and keeps the previous one; and on the mannequin and
// the shared characters at a pose between a clip's keys, the points just inside the posed body
// are inside and the points clearly outside are mostly outside.

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "drape/bake/bone_map_baker.h"
#include "drape/bake/importer.h"
#include "drape/bake/mesh_reference.h"
#include "drape/runtime/bone_map_collider.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"
#include "octahedron_sphere.h"
#include "test_support.h"

namespace drape::bake {
namespace {

constexpr float kRadius = 0.1f;  // metres

// Two spheres (radius kRadius * scale), the first at the origin on joint 0, the second at
// (0.5, 0, 0) * scale on joint 1, rigidly weighted.
MeshData TwoSpheres(float scale = 1.f) {
  const test::UnitSphereMesh unit = test::OctahedronSphere(4);
  MeshData mesh;
  for (int sphere = 0; sphere < 2; ++sphere) {
    const uint32_t base = static_cast<uint32_t>(mesh.positions.size());
    for (const auto& p : unit.positions) {
      mesh.positions.push_back(
          {(static_cast<float>(p[0]) * kRadius + 0.5f * static_cast<float>(sphere)) * scale,
           static_cast<float>(p[1]) * kRadius * scale, static_cast<float>(p[2]) * kRadius * scale});
    }
    for (const auto& t : unit.triangles)
      for (uint32_t k : t) mesh.triangles.push_back(base + k);
  }
  mesh.influence_offsets.push_back(0);
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    mesh.influence_joints.push_back(v < mesh.vertex_count() / 2 ? 0 : 1);
    mesh.influence_weights.push_back(1.f);
    mesh.influence_offsets.push_back(v + 1);
  }
  return mesh;
}

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

class BoneMapsOnCharacters : public ::testing::TestWithParam<Case> {};

// At a pose between a clip's keys: points 3 mm inside the posed surface (along the vertex
// normals) are inside, points 20 mm outside mostly outside. The misses are the blended skin at
// bent joints, which each bone's maps take as rigid; the false insides are air a neighbouring
// part's slab covers in a concave corner (an armpit, the crotch).
TEST_P(BoneMapsOnCharacters, HoldThePosedBody) {
  const std::string path =
      *GetParam().path ? test::CharacterPath(GetParam().path) : test::MannequinPath();
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " is absent (../shared/assets)";
  Character character;
  ASSERT_TRUE(ImportCharacter(path, ImportOptions{}, &character).ok());
  SkeletonPose pose;
  ASSERT_TRUE(pose.Init(character.skeleton).ok());
  pose.SetRest();
  std::vector<Float3> rest(character.mesh.vertex_count());
  ASSERT_TRUE(SkinMesh(character.mesh, pose.skinning(), rest).ok());
  const std::vector<Mat34> rest_skinning(pose.skinning().begin(), pose.skinning().end());
  BoneMapOptions options;
  options.texel_size = AutomaticBoneMapTexel(rest);
  BoneMapSet set;
  ASSERT_TRUE(BakeBoneMaps(character.mesh, character.skeleton, rest_skinning, options, &set).ok());
  BoneMapCollider bones;
  ASSERT_TRUE(bones.Build(set, character.skeleton.joint_count()).ok());

  if (!character.clips.empty()) {
    const ClipData& clip = character.clips.front();
    const float time =
        (std::floor(0.37f * static_cast<float>(clip.frame_count)) + 0.43f) / clip.sample_rate;
    ASSERT_TRUE(pose.SampleClip(clip, std::min(time, clip.duration), false).ok());
  }
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

INSTANTIATE_TEST_SUITE_P(Characters, BoneMapsOnCharacters,
                         ::testing::Values(Case{"mannequin", ""},
                                           Case{"CesiumMan", "CesiumMan/CesiumMan.glb"},
                                           Case{"Fox", "Fox/Fox.glb"},
                                           Case{"RiggedFigure", "RiggedFigure/RiggedFigure.glb"}),
                         [](const auto& param_info) { return std::string(param_info.param.name); });

}  // namespace
}  // namespace drape::bake

// The same character authored in centimetres, in millimetres, or 10 km from the origin gives the
// same colliders in metres, within float tolerance. The variants are the built-in
// mannequin with its root node scaled or moved.

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "drape/bake/bake_pipeline.h"
#include "drape/runtime/body_map_collider.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "test_support.h"

namespace drape {
namespace {

// Writes the mannequin with its root node ("mannequin", node 0) given this scale and translation.
std::string WriteVariant(const std::string& name, float scale, Float3 translation) {
  std::ifstream in(test::MannequinPath());
  nlohmann::json gltf = nlohmann::json::parse(in);
  nlohmann::json& root = gltf["nodes"][0];
  EXPECT_EQ(root["name"], "mannequin");
  root["scale"] = {scale, scale, scale};
  root["translation"] = {translation.x, translation.y, translation.z};
  const std::string path = ::testing::TempDir() + "/" + name + ".gltf";
  std::ofstream(path) << gltf.dump();
  return path;
}

// Hulls are compared unsimplified: the inflated hull is a continuous function of the input, while
// greedy simplification may take another collapse order on a rounding difference and end
// elsewhere within its growth bound (measured: 5-17 mm apart between the metre and centimetre
// bakes, both containing every rigid vertex's delta-ball). The cut into convex pieces is a greedy
// choice among candidate planes too (a near tie in hull volume can go either way on a rounding
// difference), so each bone keeps one hull here.
bake::BakeResult Bake(const std::string& path) {
  bake::BakeConfig config;
  config.maps.resolution = 256;
  config.hull.simplify = bake::SimplifyMode::kNone;
  config.hull_max_pieces = 1;
  bake::BakeResult result;
  const Status s = bake::BakeCharacter(path, config, &result);
  EXPECT_TRUE(s.ok()) << s.message();
  return result;
}

float MaxPlaneDistance(const HullColliderData& hull, Float3 p) {
  float worst = -INFINITY;
  for (const Plane& plane : hull.planes)
    worst = std::max(worst, Dot(plane.normal, p) - plane.offset);
  return worst;
}

// Hull surfaces (in their collider frames) within `tolerance` of each other both ways, joint
// spheres alike, and body maps with the same texel size and coverage.
void ExpectSameColliders(const CharacterAsset& a, const CharacterAsset& b, Float3 offset,
                         float tolerance) {
  ASSERT_EQ(a.hulls.size(), b.hulls.size());
  for (size_t h = 0; h < a.hulls.size(); ++h) {
    const std::string bone = a.skeleton.joint_names[a.hulls[h].joint];
    float worst = 0.f;
    for (const Float3& v : a.hulls[h].vertices)
      worst = std::max(worst, std::fabs(MaxPlaneDistance(b.hulls[h], v)));
    for (const Float3& v : b.hulls[h].vertices)
      worst = std::max(worst, std::fabs(MaxPlaneDistance(a.hulls[h], v)));
    EXPECT_LE(worst, tolerance) << bone;
  }
  // Sphere centres are stored in each file's bind frame, which a scaled root leaves in source
  // units; compare them where the runtime puts them, at the rest pose.
  SkeletonPose rest_a, rest_b;
  ASSERT_TRUE(rest_a.Init(a.skeleton).ok());
  ASSERT_TRUE(rest_b.Init(b.skeleton).ok());
  ASSERT_EQ(a.joint_spheres.size(), b.joint_spheres.size());
  for (size_t s = 0; s < a.joint_spheres.size(); ++s) {
    const JointSphereData &sa = a.joint_spheres[s], &sb = b.joint_spheres[s];
    EXPECT_NEAR(sa.radius, sb.radius, tolerance);
    const Float3 ca = TransformPoint(rest_a.skinning()[sa.joint], sa.center);
    const Float3 cb = TransformPoint(rest_b.skinning()[sb.joint], sb.center);
    EXPECT_LE(Length(ca + offset - cb), tolerance) << a.skeleton.joint_names[sa.joint];
  }
  ASSERT_EQ(a.body_maps.poses.size(), 1u);
  ASSERT_EQ(b.body_maps.poses.size(), 1u);
  BodyMapCollider ma, mb;
  ASSERT_TRUE(ma.Build(a.body_maps.poses[0]).ok());
  ASSERT_TRUE(mb.Build(b.body_maps.poses[0]).ok());
  EXPECT_NEAR(ma.texel_size(), mb.texel_size(), 1e-6f * ma.texel_size() + 1e-7f);
  const double coverage_a = ma.stats().valid_texels, coverage_b = mb.stats().valid_texels;
  EXPECT_NEAR(coverage_b / coverage_a, 1.0, 0.005);
}

TEST(Units, CentimetresAndMillimetresBakeLikeMetres) {
  const bake::BakeResult metres = Bake(test::MannequinPath());
  for (const auto& [name, scale] :
       {std::pair{"centimetres", 100.f}, std::pair{"millimetres", 1000.f}}) {
    const bake::BakeResult other = Bake(WriteVariant(name, scale, {}));
    EXPECT_NEAR(other.asset.info.unit_scale, 1.f / scale, 1e-9f) << name;
    // Coordinates pass through float at the source scale: a few ulps of 1.75 m.
    ExpectSameColliders(metres.asset, other.asset, {}, 1e-4f);
  }
}

TEST(Units, TenKilometresFromTheOriginBakesLikeAtIt) {
  const bake::BakeResult here = Bake(test::MannequinPath());
  const Float3 offset{10000.f, 0.f, 0.f};
  const bake::BakeResult far = Bake(WriteVariant("far", 1.f, offset));
  // Float spacing at 1e4 m is 1 mm: positions there carry half of that, and hull
  // simplification may then settle a millimetre apart.
  ExpectSameColliders(here.asset, far.asset, offset, 2.5e-3f);
}

}  // namespace
}  // namespace drape

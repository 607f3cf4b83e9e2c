// Golden colliders: today's bakes of the built-in mannequin and of the shared CesiumMan against
// the committed files tests/golden/<name>_colliders_v2.drape, compared with tolerances (not
// hashes), so a change of numerics that moves a surface is seen, and a change of rounding is not.
// CesiumMan's cases skip with a message when ../shared is absent.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "body_map/body_map_collider_access.h"
#include "drape/bake/bake_config.h"
#include "drape/bake/bake_pipeline.h"
#include "drape/formats/asset_file.h"
#include "drape/runtime/body_map_collider.h"
#include "drape/runtime/math.h"
#include "test_support.h"

namespace drape {
namespace {

float MaxPlaneDistance(const HullColliderData& hull, Float3 p) {
  float worst = -INFINITY;
  for (const Plane& plane : hull.planes)
    worst = std::max(worst, Dot(plane.normal, p) - plane.offset);
  return worst;
}

// Every vertex of `a` lies within `tolerance` of the surface of `b`: for a point inside a convex
// polytope the max plane distance is minus its distance to the boundary; outside it is a lower
// bound, so this is a necessary condition in both directions, and a sufficient one near the
// surface where the vertices are.
float WorstSurfaceGap(const HullColliderData& a, const HullColliderData& b) {
  float worst = 0.f;
  for (const Float3& v : a.vertices) worst = std::max(worst, std::fabs(MaxPlaneDistance(b, v)));
  return worst;
}

struct GoldenCase {
  std::string name;    // the golden file is tests/golden/<name>_colliders_v2.drape
  std::string source;  // the character file baked today
};

std::string PrintCase(const ::testing::TestParamInfo<GoldenCase>& info) { return info.param.name; }

struct GoldenBakes {
  CharacterAsset golden, today;
  Status golden_status, today_status;
};

// One bake per character for the whole suite; both with tests/golden/mannequin_colliders.json.
const GoldenBakes& BakesOf(const GoldenCase& c) {
  static std::map<std::string, GoldenBakes> cache;
  if (const auto found = cache.find(c.name); found != cache.end()) return found->second;
  GoldenBakes& bakes = cache[c.name];
  bakes.golden_status =
      ReadAssetFile(test::GoldenDir() + "/" + c.name + "_colliders_v2.drape", &bakes.golden);
  bake::BakeConfig config;
  bakes.today_status =
      bake::LoadBakeConfig(test::GoldenDir() + "/mannequin_colliders.json", &config);
  bake::BakeResult result;
  if (bakes.today_status.ok()) bakes.today_status = bake::BakeCharacter(c.source, config, &result);
  bakes.today = std::move(result.asset);
  return bakes;
}

class GoldenColliders : public ::testing::TestWithParam<GoldenCase> {
 protected:
  void SetUp() override {
    DRAPE_REQUIRE_FILE(GetParam().source);
    const GoldenBakes& bakes = BakesOf(GetParam());
    ASSERT_TRUE(bakes.golden_status.ok()) << bakes.golden_status.message();
    ASSERT_TRUE(bakes.today_status.ok()) << bakes.today_status.message();
    golden_ = &bakes.golden;
    today_ = &bakes.today;
  }
  const CharacterAsset* golden_ = nullptr;
  const CharacterAsset* today_ = nullptr;
};

INSTANTIATE_TEST_SUITE_P(
    Characters, GoldenColliders,
    ::testing::Values(GoldenCase{"mannequin", test::MannequinPath()},
                      GoldenCase{"CesiumMan", test::CharacterPath("CesiumMan/CesiumMan.glb")}),
    PrintCase);

TEST_P(GoldenColliders, HullsKeepTheirSurfaces) {
  ASSERT_EQ(today_->hulls.size(), golden_->hulls.size());
  for (size_t h = 0; h < golden_->hulls.size(); ++h) {
    const HullColliderData& g = golden_->hulls[h];
    const HullColliderData& t = today_->hulls[h];
    const std::string bone = golden_->skeleton.joint_names[g.joint];
    ASSERT_EQ(t.joint, g.joint);
    for (int k = 0; k < 12; ++k) EXPECT_NEAR(t.bind_frame.m[k], g.bind_frame.m[k], 1e-5f) << bone;
    const float tolerance = 1e-3f;  // metres: one mm of surface movement is a visible change
    EXPECT_LE(WorstSurfaceGap(g, t), tolerance) << bone << ": golden vertices off today's surface";
    EXPECT_LE(WorstSurfaceGap(t, g), tolerance)
        << bone << ": today's vertices off the golden surface";
    const double ratio =
        static_cast<double>(t.triangles.size()) / static_cast<double>(g.triangles.size());
    EXPECT_NEAR(ratio, 1.0, 0.1) << bone;
    EXPECT_EQ(t.map.kind, g.map.kind) << bone;
  }
}

TEST_P(GoldenColliders, JointSpheresKeepCentresAndRadii) {
  ASSERT_EQ(today_->joint_spheres.size(), golden_->joint_spheres.size());
  for (size_t s = 0; s < golden_->joint_spheres.size(); ++s) {
    const JointSphereData& g = golden_->joint_spheres[s];
    const JointSphereData& t = today_->joint_spheres[s];
    EXPECT_EQ(t.joint, g.joint);
    EXPECT_LE(Length(t.center - g.center), 1e-5f);
    EXPECT_NEAR(t.radius, g.radius, 1e-5f);
  }
}

TEST_P(GoldenColliders, BodyMapsKeepCoverageAndDepth) {
  ASSERT_EQ(today_->body_maps.poses.size(), golden_->body_maps.poses.size());
  BodyMapCollider g, t;
  ASSERT_TRUE(g.Build(golden_->body_maps.poses[0]).ok());
  ASSERT_TRUE(t.Build(today_->body_maps.poses[0]).ok());
  EXPECT_FLOAT_EQ(t.texel_size(), g.texel_size());
  // Compare texel by texel over the union of the two stored rectangles, in asset coordinates.
  const float s = g.texel_size();
  const float x0 = std::min(g.origin_x(), t.origin_x()), y0 = std::min(g.origin_y(), t.origin_y());
  auto extent = [s](uint32_t texels) { return s * static_cast<float>(texels); };
  const float x1 = std::max(g.origin_x() + extent(g.width()), t.origin_x() + extent(t.width()));
  const float y1 = std::max(g.origin_y() + extent(g.height()), t.origin_y() + extent(t.height()));
  size_t texels = 0, coverage_mismatch = 0;
  float worst_depth = 0.f;
  auto slab = [&](const BodyMapCollider& c, float x, float y, float* top, float* bottom) {
    const long i = std::lround(std::floor((x - c.origin_x()) / s));
    const long j = std::lround(std::floor((y - c.origin_y()) / s));
    if (i < 0 || j < 0 || i >= static_cast<long>(c.width()) || j >= static_cast<long>(c.height()))
      return false;
    return BodyMapColliderAccess::TexelSlab(c, static_cast<uint32_t>(i), static_cast<uint32_t>(j),
                                            top, bottom);
  };
  for (float y = y0 + 0.5f * s; y < y1; y += s) {
    for (float x = x0 + 0.5f * s; x < x1; x += s) {
      float gt = 0, gb = 0, tt = 0, tb = 0;
      const bool gv = slab(g, x, y, &gt, &gb), tv = slab(t, x, y, &tt, &tb);
      ++texels;
      if (gv != tv) {
        ++coverage_mismatch;
      } else if (gv) {
        worst_depth = std::max({worst_depth, std::fabs(gt - tt), std::fabs(gb - tb)});
      }
    }
  }
  EXPECT_LE(static_cast<double>(coverage_mismatch), 1e-4 * static_cast<double>(texels))
      << coverage_mismatch << " of " << texels << " texels changed coverage";
  // Two unorm16 quanta of the depth range (about 10 um here).
  EXPECT_LE(worst_depth, 2.f * golden_->body_maps.poses[0].depth_range / 65535.f);
}

}  // namespace
}  // namespace drape

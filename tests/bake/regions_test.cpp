// Joint spheres (BuildJointSpheres) on a two-bone body built by hand: paper B's radius over every
// flexible vertex, and spheres.cover left_by_hulls' radius over the flexible corners of the
// triangles no single hull holds.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "drape/bake/regions.h"

namespace drape {
namespace {

// A box collider [x_lo, x_hi] x [-half, half]^2 in its bone's frame (the identity here).
HullColliderData Box(int32_t joint, float x_lo, float x_hi, float half) {
  HullColliderData hull;
  hull.joint = joint;
  hull.planes = {{{1.f, 0.f, 0.f}, x_hi},  {{-1.f, 0.f, 0.f}, -x_lo}, {{0.f, 1.f, 0.f}, half},
                 {{0.f, -1.f, 0.f}, half}, {{0.f, 0.f, 1.f}, half},   {{0.f, 0.f, -1.f}, half}};
  return hull;
}

class JointSpheres : public ::testing::Test {
 protected:
  // Bone 0 (parent) along -x, bone 1 (child) along +x, the joint at the origin. Rest = bind.
  JointSpheres() {
    regions_.rest_positions = {
        {-0.5f, 0.f, 0.f},     // 0: rigid to bone 0
        {0.5f, 0.f, 0.f},      // 1: rigid to bone 1
        {0.05f, 0.1f, 0.f},    // 2: flexible, in both boxes
        {0.f, 0.5f, 0.f},      // 3: flexible, in neither box (0.5 m from the joint)
        {-0.05f, -0.1f, 0.f},  // 4: flexible, in both boxes
        {0.9f, 0.15f, 0.f},    // 5: flexible, in bone 1's box (0.9 m from the joint)
    };
    regions_.rest_skinning.assign(2, Mat34{});
    regions_.collider_frames.assign(2, Mat34{});
    regions_.rigid_vertices = {{0}, {1}};
    regions_.shaping_vertices = {{}, {}};
    bake::JointRegion joint;
    joint.child = 1;
    joint.parent = 0;
    joint.center = {0.f, 0.f, 0.f};
    joint.flexible_vertices = {2, 3, 4, 5};
    regions_.joints = {joint};
    hulls_ = {Box(0, -1.f, 0.1f, 0.2f), Box(1, -0.1f, 1.f, 0.2f)};
  }

  bake::Regions regions_;
  std::vector<HullColliderData> hulls_;
  static constexpr float kDelta = 0.005f;  // metres
};

TEST_F(JointSpheres, PaperBReachesEveryFlexibleVertex) {
  const std::vector<uint32_t> triangles = {0, 2, 4, 2, 3, 4, 1, 5, 2};
  const auto spheres = bake::BuildJointSpheres(regions_, kDelta, {}, triangles);
  ASSERT_EQ(spheres.size(), 1u);
  EXPECT_EQ(spheres[0].joint, 1);
  EXPECT_EQ(spheres[0].parent_joint, 0);
  EXPECT_NEAR(spheres[0].radius, std::hypot(0.9f, 0.15f) + kDelta, 1e-6f);
}

TEST_F(JointSpheres, LeftByHullsReachesTheFlexibleCornersOfUncoveredTriangles) {
  // Triangle (0, 2, 4) lies in bone 0's box and (1, 5, 2) in bone 1's; (2, 3, 4) in neither, so
  // its flexible corners 2, 3 and 4 set the radius, and vertex 5 does not.
  const std::vector<uint32_t> triangles = {0, 2, 4, 2, 3, 4, 1, 5, 2};
  const auto spheres = bake::BuildJointSpheres(regions_, kDelta, hulls_, triangles);
  ASSERT_EQ(spheres.size(), 1u);
  EXPECT_NEAR(spheres[0].radius, 0.5f + kDelta, 1e-6f);
  EXPECT_LE(spheres[0].radius, bake::BuildJointSpheres(regions_, kDelta, {}, triangles)[0].radius);
}

TEST_F(JointSpheres, LeftByHullsKeepsOnlyTheDeltaWhenTheHullsHoldEveryTriangle) {
  const std::vector<uint32_t> triangles = {0, 2, 4, 1, 5, 2};
  const auto spheres = bake::BuildJointSpheres(regions_, kDelta, hulls_, triangles);
  ASSERT_EQ(spheres.size(), 1u);
  EXPECT_NEAR(spheres[0].radius, kDelta, 1e-6f);
}

TEST_F(JointSpheres, LeftByHullsNeedsOneHullForTheWholeTriangle) {
  // Vertex 0 is only in bone 0's box and vertex 5 only in bone 1's: the triangle (0, 5, 2) lies in
  // neither box whole, though each corner is in one of them.
  const std::vector<uint32_t> triangles = {0, 5, 2};
  const auto spheres = bake::BuildJointSpheres(regions_, kDelta, hulls_, triangles);
  ASSERT_EQ(spheres.size(), 1u);
  EXPECT_NEAR(spheres[0].radius, std::hypot(0.9f, 0.15f) + kDelta, 1e-6f);
}

}  // namespace
}  // namespace drape

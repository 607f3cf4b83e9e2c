// Pose evaluation: clip sampling between keys, the shorter-arc rotation blend, the bind pose,
// and the engine path (joint world matrices handed in).

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"

namespace drape {
namespace {

Quat AxisAngleY(float radians) { return {0.f, std::sin(radians / 2), 0.f, std::cos(radians / 2)}; }

SkeletonData TwoBones() {
  SkeletonData s;
  s.joint_names = {"root", "child"};
  s.parents = {-1, 0};
  s.rest_local.resize(2);
  s.rest_local[1].translation = {1.f, 0.f, 0.f};
  s.inverse_bind.resize(2);
  s.inverse_bind[1].m[3] = -1.f;  // child bind at x = 1
  return s;
}

ClipData Turn(uint32_t joints, float end_angle) {
  ClipData clip;
  clip.name = "turn";
  clip.duration = 1.f;
  clip.sample_rate = 2.f;
  clip.frame_count = 3;
  clip.keys.assign(static_cast<size_t>(clip.frame_count) * joints, Transform{});
  for (uint32_t f = 0; f < 3; ++f) {
    clip.keys[f * joints + 1].translation = {1.f, 0.f, 0.f};
    clip.keys[f * joints + 0].rotation = AxisAngleY(end_angle * static_cast<float>(f) / 2.f);
  }
  return clip;
}

// Local transforms from the caller give what a clip giving them gives; a blend of two poses is
// halfway on the shorter arc; bad input is refused naming the joint.
TEST(SkeletonPose, LocalTransformsAndBlends) {
  const SkeletonData s = TwoBones();
  const ClipData clip = Turn(2, 1.5f);
  SkeletonPose sampled, local, rest;
  ASSERT_TRUE(sampled.Init(s).ok() && local.Init(s).ok() && rest.Init(s).ok());
  ASSERT_TRUE(sampled.SampleClip(clip, 1.f, false).ok());  // 1.5 rad about Y
  ASSERT_TRUE(local.SetLocalTransforms(sampled.local()).ok());
  for (size_t j = 0; j < 2; ++j)
    for (int k = 0; k < 12; ++k) EXPECT_EQ(local.skinning()[j].m[k], sampled.skinning()[j].m[k]);
  // Halfway between the rest pose (0 rad) and 1.5 rad: 0.75 rad.
  ASSERT_TRUE(rest.SampleClip(clip, 0.f, false).ok());
  ASSERT_TRUE(rest.BlendWith(sampled, 0.5f).ok());
  const Float3 child = {rest.world()[1].m[3], rest.world()[1].m[7], rest.world()[1].m[11]};
  EXPECT_NEAR(child.x, std::cos(0.75f), 1e-5f);
  EXPECT_NEAR(child.z, -std::sin(0.75f), 1e-5f);
  EXPECT_FALSE(rest.BlendWith(sampled, 1.5f).ok());
  std::vector<Transform> bad(sampled.local().begin(), sampled.local().end());
  bad[1].rotation.y = std::nanf("");
  const Status status = local.SetLocalTransforms(bad);
  EXPECT_EQ(status.message(), "local transform 1 is not finite");
  EXPECT_FALSE(local.SetLocalTransforms(std::span<const Transform>(bad).first(1)).ok());
}

TEST(SkeletonPose, RestAndBindPoses) {
  const SkeletonData s = TwoBones();
  SkeletonPose pose;
  ASSERT_TRUE(pose.Init(s).ok());
  EXPECT_FLOAT_EQ(pose.world()[1].m[3], 1.f);
  for (const Mat34& m : pose.skinning())
    for (int i = 0; i < 12; ++i) EXPECT_NEAR(m.m[i], Mat34{}.m[i], 1e-6f);
  pose.SetBind();
  EXPECT_NEAR(pose.world()[1].m[3], 1.f, 1e-6f);
}

TEST(SkeletonPose, SamplesBetweenKeysOnTheShorterArc) {
  const SkeletonData s = TwoBones();
  const ClipData clip = Turn(2, 1.5f);  // 0 -> 0.75 -> 1.5 rad about Y
  SkeletonPose pose;
  ASSERT_TRUE(pose.Init(s).ok());
  ASSERT_TRUE(pose.SampleClip(clip, 0.25f, false).ok());  // halfway between keys 0 and 1
  const Float3 child = {pose.world()[1].m[3], pose.world()[1].m[7], pose.world()[1].m[11]};
  EXPECT_NEAR(child.x, std::cos(0.375f), 2e-4f);
  EXPECT_NEAR(child.z, -std::sin(0.375f), 2e-4f);
  // A key stored as the negated quaternion (same rotation) must not spin the long way round.
  ClipData flipped = clip;
  Quat& q = flipped.keys[1 * 2 + 0].rotation;
  q = {-q.x, -q.y, -q.z, -q.w};
  ASSERT_TRUE(pose.SampleClip(flipped, 0.25f, false).ok());
  EXPECT_NEAR(pose.world()[1].m[3], std::cos(0.375f), 2e-4f);
  // Clamped and looped times.
  ASSERT_TRUE(pose.SampleClip(clip, 5.f, false).ok());
  EXPECT_NEAR(pose.world()[1].m[3], std::cos(1.5f), 1e-5f);
  ASSERT_TRUE(pose.SampleClip(clip, 1.25f, true).ok());
  EXPECT_NEAR(pose.world()[1].m[3], std::cos(0.375f), 2e-4f);
  EXPECT_FALSE(pose.SampleClip(clip, NAN, false).ok());
}

TEST(SkeletonPose, EngineMatricesDriveSkinning) {
  const SkeletonData s = TwoBones();
  SkeletonPose pose;
  ASSERT_TRUE(pose.Init(s).ok());
  std::vector<Mat34> world(2);
  world[1].m[3] = 1.f;
  world[1].m[7] = 2.f;  // the child lifted by 2 m
  ASSERT_TRUE(pose.SetJointWorldMatrices(world).ok());
  MeshData mesh;
  mesh.positions = {{1.f, 0.f, 0.f}, {0.f, 0.f, 0.f}};
  mesh.influence_offsets = {0, 1, 3};
  mesh.influence_joints = {1, 0, 1};
  mesh.influence_weights = {1.f, 0.5f, 0.5f};
  std::vector<Float3> posed(2);
  ASSERT_TRUE(SkinMesh(mesh, pose.skinning(), posed).ok());
  EXPECT_NEAR(posed[0].y, 2.f, 1e-6f);
  EXPECT_NEAR(posed[1].y, 1.f, 1e-6f);  // blended halfway
  std::vector<Mat34> wrong(1);
  EXPECT_EQ(pose.SetJointWorldMatrices(wrong).code(), StatusCode::kInvalidArgument);
  world[0].m[0] = NAN;
  EXPECT_EQ(pose.SetJointWorldMatrices(world).code(), StatusCode::kInvalidArgument);
  std::vector<Float3> small(1);
  EXPECT_FALSE(SkinMesh(mesh, pose.skinning(), small).ok());
}

TEST(Math, AffineInverseAndRigidInverseAgree) {
  Transform t;
  t.translation = {0.3f, -1.f, 2.f};
  t.rotation = Normalize(Quat{0.1f, 0.7f, -0.2f, 0.6f});
  const Mat34 m = ToMatrix(t);
  Mat34 inv;
  ASSERT_TRUE(InverseAffine(m, &inv));
  const Mat34 rigid = InverseRigid(m);
  for (int i = 0; i < 12; ++i) EXPECT_NEAR(inv.m[i], rigid.m[i], 1e-5f);
  const Mat34 identity = Multiply(m, inv);
  for (int i = 0; i < 12; ++i) EXPECT_NEAR(identity.m[i], Mat34{}.m[i], 1e-5f);
  Mat34 singular;
  singular.m[0] = 0.f;
  EXPECT_FALSE(InverseAffine(singular, &inv));
}

}  // namespace
}  // namespace drape

// BodyMapSequence: the nearest and the bracketing poses, and blends.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "body_map_test_fixtures.h"
#include "workers.h"

namespace drape {
namespace {

using namespace test;

TEST(BodyMapSequence, NearestAndBracketingPoses) {
  // The sphere raised by 0.1 m between t = 0 and t = 1.
  const auto raised = [](double dz) {
    return [dz](double x, double y) {
      SurfaceSample s = Sphere(x, y);
      s.top += dz;
      s.bottom += dz;
      return s;
    };
  };
  std::vector<BodyMapPose> poses = {MakePose(SphereGrid(), raised(0.0)),
                                    MakePose(SphereGrid(), raised(0.1))};
  poses[0].clip = poses[1].clip = 2;
  poses[0].time = 0.f;
  poses[1].time = 1.f;
  BodyMapSequence nearest;
  ASSERT_TRUE(nearest.Build(poses).ok());
  EXPECT_EQ(nearest.size(), 2u);
  EXPECT_EQ(&nearest.At(-5.f), &nearest.pose(0));
  EXPECT_EQ(&nearest.At(0.3f), &nearest.pose(0));
  EXPECT_EQ(&nearest.At(0.5f), &nearest.pose(0));  // ties go to the earlier pose
  EXPECT_EQ(&nearest.At(0.7f), &nearest.pose(1));
  EXPECT_EQ(&nearest.At(9.f), &nearest.pose(1));

  BodyMapSequence bracket;
  ASSERT_TRUE(bracket.Build(poses, DepthSampling::kNearest, PoseBlend::kBracket).ok());
  BodyMapCollider scratch;
  const BodyMapCollider& blended = bracket.At(0.25f, &scratch);
  EXPECT_EQ(&blended, &scratch);
  EXPECT_FLOAT_EQ(blended.time(), 0.25f);
  float top, bottom, top0, bottom0;
  ASSERT_TRUE(BodyMapColliderAccess::TexelSlab(blended, 44, 44, &top, &bottom));
  ASSERT_TRUE(BodyMapColliderAccess::TexelSlab(bracket.pose(0), 44, 44, &top0, &bottom0));
  EXPECT_NEAR(top, top0 + 0.025f, 1e-6);
  EXPECT_NEAR(bottom, bottom0 + 0.025f, 1e-6);
  const ContactQuery q = blended.Query({0.f, 0.f, 0.5f}, {0.f, 0.f, 0.f});
  ASSERT_TRUE(q.contact);
  EXPECT_NEAR(q.point.z, top, 1e-6);
  // Refilling the same scratch with another time does not allocate more.
  const size_t bytes = scratch.memory_bytes();
  bracket.At(0.75f, &scratch);
  EXPECT_EQ(scratch.memory_bytes(), bytes);
  EXPECT_EQ(&bracket.At(0.75f), &bracket.pose(1));          // no scratch: nearest
  EXPECT_EQ(&bracket.At(0.f, &scratch), &bracket.pose(0));  // on a key: that pose

  // Different grids: nearest.
  std::vector<BodyMapPose> mixed = poses;
  mixed[1] = MakePose(BoxGrid(), Box);
  mixed[1].clip = 2;
  mixed[1].time = 1.f;
  BodyMapSequence different;
  ASSERT_TRUE(different.Build(mixed, DepthSampling::kNearest, PoseBlend::kBracket).ok());
  EXPECT_EQ(&different.At(0.6f, &scratch), &different.pose(1));

  // Invalid sequences.
  BodyMapSequence bad;
  std::vector<BodyMapPose> unsorted = poses;
  std::swap(unsorted[0].time, unsorted[1].time);
  EXPECT_EQ(bad.Build(unsorted).code(), StatusCode::kInvalidArgument);
  std::vector<BodyMapPose> two_clips = poses;
  two_clips[1].clip = 3;
  EXPECT_EQ(bad.Build(two_clips).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(bad.Build({}).code(), StatusCode::kInvalidArgument);
  std::vector<BodyMapPose> broken = poses;
  broken[1].texel_size = 0.f;
  const Status status = bad.Build(broken);
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("pose 1"), std::string::npos) << status.message();
  EXPECT_TRUE(bad.At(0.f).empty());
}

}  // namespace
}  // namespace drape

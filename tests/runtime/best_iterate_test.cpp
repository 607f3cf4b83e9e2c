// When every Gauss-Seidel pass is used, the particle keeps the best iterate, not its input: one
// pass pushes a particle out of a box into the thin edge of a neighbour, which is still a contact
// (the pass count is exhausted) but far shallower than where it started.

#include <gtest/gtest.h>

#include <vector>

#include "drape/runtime/hull_collider_set.h"
#include "hull_fixtures.h"

namespace drape {
namespace {

using test::MakeBox;

TEST(BestIterate, ExhaustedPassesKeepTheShallowerIterate) {
  // A: x in [-0.05, 0.05]; the particle at x = 0.01 is 40 mm deep, nearest its +x face. C starts
  // at that face, so the push-out lands 0.1 mm inside C.
  HullColliderData a = MakeBox({0.05f, 0.1f, 0.1f}, {0.f, 0.f, 0.f});
  HullColliderData c = MakeBox({0.075f, 0.2f, 0.2f}, {0.125f, 0.f, 0.f});
  a.joint = c.joint = 0;
  HullColliderOptions options;
  options.gauss_seidel_passes = 1;
  HullColliderSet set;
  const std::vector<HullColliderData> hulls{a, c};
  ASSERT_TRUE(set.Build(hulls, {}, 1, options).ok());
  const Mat34 identity;
  ASSERT_TRUE(set.SetPose({&identity, 1}, {&identity, 1}).ok());
  const Float3 p{0.01f, 0.f, 0.f};
  ASSERT_NEAR(set.Query(p, p).depth, 0.04f, 1e-5f);
  std::vector<Float3> previous{p}, positions{p}, velocities{{0.f, 0.f, 0.f}};
  std::vector<uint8_t> flags(1);
  ASSERT_TRUE(set.CollideBatch(previous, positions, velocities, flags, {}).ok());
  EXPECT_TRUE(flags[0] & kCollisionContact);
  EXPECT_GT(positions[0].x, 0.05f) << "the pushed-out iterate, not the input";
  EXPECT_LT(set.Query(positions[0], positions[0]).depth, 1e-3f);
}

}  // namespace
}  // namespace drape

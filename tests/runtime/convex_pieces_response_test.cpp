// A bone cut into convex pieces: the faces along a cut lie inside the body (plane_internal). A
// particle inside a piece near its cut leaves through the piece's nearest outer face, not through
// the cut into the neighbouring piece, and the depth it reports is the distance to that face.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "drape/runtime/hull_collider_set.h"
#include "hull_fixtures.h"

namespace drape {
namespace {

using test::MakeBox;

// A 0.4 x 0.1 x 0.1 m bar cut at x = 0 into two boxes that overlap by 2 mm (their inflation);
// the faces at the cut are flagged internal when `flag_cuts`.
std::vector<HullColliderData> CutBar(bool flag_cuts) {
  HullColliderData left = MakeBox({0.101f, 0.05f, 0.05f}, {-0.1f, 0.f, 0.f});
  HullColliderData right = MakeBox({0.101f, 0.05f, 0.05f}, {0.1f, 0.f, 0.f});
  for (HullColliderData* h : {&left, &right}) {
    h->joint = 0;
    if (!flag_cuts) continue;
    h->plane_internal.assign(h->planes.size(), 0);
    const float facing = h == &left ? 1.f : -1.f;  // the face towards the other piece
    for (size_t p = 0; p < h->planes.size(); ++p) {
      if (h->planes[p].normal.x * facing > 0.99f) h->plane_internal[p] = 1;
    }
  }
  return {left, right};
}

HullColliderSet Build(const std::vector<HullColliderData>& hulls) {
  HullColliderSet set;
  EXPECT_TRUE(set.Build(hulls, {}, 1, {}).ok());
  const Mat34 identity;
  EXPECT_TRUE(set.SetPose({&identity, 1}, {&identity, 1}).ok());
  return set;
}

TEST(ConvexPieces, APointNearACutLeavesThroughAnOuterFace) {
  const Float3 p{-0.01f, 0.02f, 0.f};  // 9 mm from the left piece's cut, 30 mm from its top face
  const HullColliderSet flagged = Build(CutBar(true));
  const ContactQuery q = flagged.Query(p, p);
  ASSERT_TRUE(q.contact);
  EXPECT_NEAR(q.normal.y, 1.f, 1e-6f) << "the nearest outer face is the top";
  EXPECT_NEAR(q.point.y, 0.05f, 1e-5f);
  EXPECT_NEAR(q.depth, 0.03f, 1e-5f) << "the depth to the outer face, not to the cut";
  const Float3 off = q.point + q.normal * 1e-4f;  // just off the surface, as a response puts it
  EXPECT_FALSE(flagged.Query(off, off).inside_end) << "outside both pieces";

  // CollideBatch leaves through the top face too. Without the flags (below) the nearest face is
  // the cut: the exit lands in the other piece, whose nearest face is its own cut, and the
  // particle stays trapped.
  std::vector<Float3> previous{p}, positions{p}, velocities{{0.f, 0.f, 0.f}};
  std::vector<uint8_t> flags(1);
  ASSERT_TRUE(flagged.CollideBatch(previous, positions, velocities, flags, {}).ok());
  EXPECT_TRUE(flags[0] & kCollisionContact);
  EXPECT_FALSE(flagged.Query(positions[0], positions[0]).inside_end) << "batch: outside both";
  EXPECT_NEAR(positions[0].y, 0.05f + 1e-4f, 1e-5f);

  const HullColliderSet plain = Build(CutBar(false));
  std::vector<Float3> plain_positions{p}, plain_velocities{{0.f, 0.f, 0.f}};
  ASSERT_TRUE(plain.CollideBatch(previous, plain_positions, plain_velocities, flags, {}).ok());
  EXPECT_TRUE(plain.Query(plain_positions[0], plain_positions[0]).inside_end)
      << "without the flags the cut faces trap the particle";
}

TEST(ConvexPieces, FlagsChangeOnlyWhichFaceAPointLeavesThrough) {
  // A point nearer an outer face than the cut leaves the same way with and without flags.
  const Float3 p{-0.05f, 0.045f, 0.f};
  const ContactQuery plain = Build(CutBar(false)).Query(p, p);
  const ContactQuery flagged = Build(CutBar(true)).Query(p, p);
  ASSERT_TRUE(plain.contact && flagged.contact);
  EXPECT_EQ(plain.point.y, flagged.point.y);
  EXPECT_EQ(plain.depth, flagged.depth);
}

}  // namespace
}  // namespace drape

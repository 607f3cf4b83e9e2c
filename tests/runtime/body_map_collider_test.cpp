// BodyMapCollider on analytic bodies: classification for every encoding, the continuous walk
// against an exact reference, side walls, grazing and boundary cases, starts inside, the
// response, huge coordinates, bilinear depth, rejected data, the quick paths against the walk,
// and the row-span layout.
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

TEST(BodyMapCollider, SphereClassificationAtTexelCentresIsTheSameForEveryEncoding) {
  const GridSpec g = SphereGrid();
  // 0.1 mm from either surface: well above the unorm16 step (1 m / 65535 = 15 um).
  constexpr double kMargin = 1e-4;
  const DepthEncoding depths[2] = {DepthEncoding::kFloat32, DepthEncoding::kUnorm16};
  const NormalEncoding normals[3] = {NormalEncoding::kFloat32, NormalEncoding::kOct16,
                                     NormalEncoding::kRgb8};
  for (DepthEncoding de : depths) {
    for (NormalEncoding ne : normals) {
      const BodyMapCollider c = BuildOrDie(MakePose(g, Sphere, de, ne));
      int checked = 0;
      for (uint32_t j = 0; j < g.height; ++j) {
        for (uint32_t i = 0; i < g.width; ++i) {
          const double x = g.origin_x + (i + 0.5) * g.texel, y = g.origin_y + (j + 0.5) * g.texel;
          const double h = SphereHeight(x, y);
          const auto at = [&](double z) {
            return c.IsInside(
                {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
          };
          if (h < 0.0) {
            EXPECT_FALSE(at(0.0)) << i << "," << j;
            continue;
          }
          if (h < 2 * kMargin) continue;
          EXPECT_TRUE(at(h - kMargin)) << i << "," << j;
          EXPECT_FALSE(at(h + kMargin)) << i << "," << j;
          EXPECT_TRUE(at(-h + kMargin)) << i << "," << j;
          EXPECT_FALSE(at(-h - kMargin)) << i << "," << j;
          EXPECT_TRUE(at(0.0));
          ++checked;
        }
      }
      EXPECT_GT(checked, 4000);
      EXPECT_FALSE(c.IsInside({0.f, 0.f, 0.31f}));
      EXPECT_FALSE(c.IsInside({1.f, 0.f, 0.f}));  // outside the stored rectangle
      EXPECT_FALSE(c.IsInside({-1.f, -1.f, 0.f}));
      // Normals within the encoding's error (rgb8: 0.385 degrees, oct16: 0.004).
      const double tolerance = ne == NormalEncoding::kRgb8 ? 0.8 : 0.01;  // degrees
      for (uint32_t t : {20u, 44u, 60u}) {
        const SurfaceSample s =
            Sphere(g.origin_x + (t + 0.5) * g.texel, g.origin_y + (44 + 0.5) * g.texel);
        EXPECT_LT(AngleDegrees(BodyMapColliderAccess::TexelNormal(c, t, 44, false), s.front_normal),
                  tolerance);
        EXPECT_LT(AngleDegrees(BodyMapColliderAccess::TexelNormal(c, t, 44, true), s.back_normal),
                  tolerance);
      }
    }
  }
}

TEST(BodyMapCollider, StraightDownOnSphereGivesSurfacePointAndNormal) {
  const BodyMapCollider c = BuildOrDie(MakePose(SphereGrid(), Sphere));
  EXPECT_EQ(c.width(), 88u);
  EXPECT_FLOAT_EQ(c.texel_size(), kTexel);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> xy(-0.25f, 0.25f);
  int contacts = 0;
  for (int k = 0; k < 500; ++k) {
    const float x = xy(rng), y = xy(rng);
    if (std::sqrt(x * x + y * y) > 0.8 * kSphereRadius) continue;
    // Pure z motion: a zero-length 2D segment visits one texel.
    const ContactQuery q = c.Query({x, y, 0.5f}, {x, y, 0.f});
    ASSERT_TRUE(q.contact);
    ++contacts;
    EXPECT_TRUE(q.inside_end);
    EXPECT_EQ(q.flags, kCollisionNone);
    // Nearest sampling: the surface is the height at the texel centre, at most |grad h| * s/sqrt2
    // (slope <= 0.8/0.6 here) from the true height.
    const double slope_bound = 0.8 / 0.6 * kTexel * 0.7072 + 1e-6;
    EXPECT_NEAR(q.point.z, SphereHeight(x, y), slope_bound);
    EXPECT_FLOAT_EQ(q.point.x, x);
    EXPECT_FLOAT_EQ(q.point.y, y);
    EXPECT_NEAR(q.t, (0.5 - q.point.z) / 0.5, 1e-6);
    // Normal: the texel centre's analytic normal (oct16 re-encoded float: < 0.005 degrees).
    const double xc = c.origin_x() + (std::floor((x - c.origin_x()) / kTexel) + 0.5) * kTexel;
    const double yc = c.origin_y() + (std::floor((y - c.origin_y()) / kTexel) + 0.5) * kTexel;
    const Float3 expected = NormalizeOr(
        {static_cast<float>(xc), static_cast<float>(yc), static_cast<float>(SphereHeight(xc, yc))},
        {});
    EXPECT_LT(AngleDegrees(q.normal, expected), 0.01);
    EXPECT_NEAR(q.depth, q.point.z, 1e-6);  // p1 at z = 0, nearer surface is the front one
    // From below: enters through the back surface, back normal.
    const ContactQuery b = c.Query({x, y, -0.5f}, {x, y, 0.f});
    ASSERT_TRUE(b.contact);
    EXPECT_LT(b.point.z, 0.f);
    EXPECT_LT(b.normal.z, 0.f);
    EXPECT_NEAR(b.point.z, -q.point.z, 1e-6);
  }
  EXPECT_GT(contacts, 200);
}

// The walk against an exact brute-force reference over every texel column, for random segments
// of every length (short ones walk texel by texel, long ones use the 8x8 min/max blocks).
// Query against the brute-force first entry on `segments` random segments (RandomSegment) that
// start outside: contact, t, point on the segment and a unit normal. `start` sees each p0.
TEST(BodyMapCollider, WalkMatchesExactReferenceOnRandomSegments) {
  for (int shape = 0; shape < 2; ++shape) {
    const BodyMapCollider c = shape == 0 ? BuildOrDie(MakePose(SphereGrid(), Sphere))
                                         : BuildOrDie(MakePose(BoxGrid(), Box));
    const WalkCounts n = ExpectWalkMatchesReference(c, 11 + shape, 1200);
    std::printf("shape %d: %d hits (%d side walls), %d misses\n", shape, n.hits, n.side_walls,
                n.misses);
    EXPECT_GT(n.hits, 200) << shape;
    EXPECT_GT(n.misses, 50) << shape;
    EXPECT_GT(n.side_walls, 20) << shape;
  }
}

TEST(BodyMapCollider, FastParticleThroughThinSlabIsCaught) {
  const BodyMapCollider c = BuildOrDie(MakePose(SphereGrid(), ThinSlab));
  // 10 cm per step across a 2 mm slab: both end points are outside.
  const Float3 p0{0.01f, 0.02f, 0.05f}, p1{0.01f, 0.02f, -0.05f};
  EXPECT_FALSE(c.IsInside(p0));
  EXPECT_FALSE(c.IsInside(p1));  // an endpoint-only test (paper A literal) misses this one
  const ContactQuery q = c.Query(p0, p1);
  ASSERT_TRUE(q.contact);
  EXPECT_FALSE(q.inside_end);
  EXPECT_FLOAT_EQ(q.depth, 0.f);
  EXPECT_NEAR(q.t, (0.05 - kSlabThickness) / 0.1, 1e-6);
  EXPECT_NEAR(q.point.z, kSlabThickness, 1e-7);
  EXPECT_LT(AngleDegrees(q.normal, {0.f, 0.f, 1.f}), 0.01);
  // From below, entering through the back surface, with the back normal (-z), not an average.
  const ContactQuery b = c.Query(p1, p0);
  ASSERT_TRUE(b.contact);
  EXPECT_NEAR(b.t, 0.5, 1e-6);
  EXPECT_LT(AngleDegrees(b.normal, {0.f, 0.f, -1.f}), 0.01);
  // Diagonally across many texels: caught in the texel where z crosses the slab.
  const Float3 d0{-0.2f, -0.1f, 0.04f}, d1{0.2f, 0.15f, -0.04f};
  const ContactQuery diagonal = c.Query(d0, d1);
  ASSERT_TRUE(diagonal.contact);
  EXPECT_NEAR(diagonal.t, (0.04 - kSlabThickness) / 0.08, 1e-5);
  EXPECT_EQ(diagonal.flags, kCollisionNone);
}

TEST(BodyMapCollider, SideWallEntryIsFlaggedWithTheNearerSurfacesNormal) {
  const BodyMapCollider c = BuildOrDie(MakePose(BoxGrid(), Box));
  const float edge = -25.f * kTexel;  // the box's -x side, a texel edge
  const ContactQuery q = c.Query({-0.3f, 0.f, 0.03f}, {-0.1f, 0.f, 0.03f});
  ASSERT_TRUE(q.contact);
  EXPECT_TRUE(q.flags & kCollisionSideWall);
  EXPECT_NEAR(q.point.x, edge, kWallTolerance);
  EXPECT_LT(q.point.x, edge) << "the contact point is on the outer side of the wall";
  EXPECT_FALSE(c.IsInside(q.point)) << "a particle placed at the contact must not test inside";
  EXPECT_NEAR(q.t, (edge + 0.3) / 0.2, 1e-5);
  EXPECT_LT(AngleDegrees(q.normal, {0.f, 0.f, 1.f}), 0.01);  // z = 0.03 is nearer the front
  const ContactQuery low = c.Query({-0.3f, 0.f, -0.03f}, {-0.1f, 0.f, -0.03f});
  ASSERT_TRUE(low.contact);
  EXPECT_LT(AngleDegrees(low.normal, {0.f, 0.f, -1.f}), 0.01);
}

TEST(BodyMapCollider, GrazingSegments) {
  const BodyMapCollider c = BuildOrDie(MakePose(BoxGrid(), Box));
  // Sinking by 2 um over 40 texels: crosses the top surface half way, through the front.
  const ContactQuery q = c.Query({-0.15f, 0.f, kBoxTop + 1e-6f}, {0.15f, 0.f, kBoxTop - 1e-6f});
  ASSERT_TRUE(q.contact);
  EXPECT_EQ(q.flags, kCollisionNone);
  EXPECT_NEAR(q.t, 0.5, 0.02);
  EXPECT_FLOAT_EQ(q.point.z, kBoxTop);
  EXPECT_GE(q.t, 0.f);
  EXPECT_LE(q.t, 1.f);
  // Parallel, 1 um above: no contact. Parallel exactly on the surface (z = top is inside):
  // entered through the box's side wall.
  EXPECT_FALSE(c.Query({-0.3f, 0.f, kBoxTop + 1e-6f}, {0.3f, 0.f, kBoxTop + 1e-6f}).contact);
  const ContactQuery on = c.Query({-0.3f, 0.f, kBoxTop}, {0.3f, 0.f, kBoxTop});
  ASSERT_TRUE(on.contact);
  EXPECT_TRUE(on.flags & kCollisionSideWall);
  EXPECT_NEAR(on.point.x, -25.f * kTexel, kWallTolerance);
}

TEST(BodyMapCollider, PointsExactlyOnTexelBoundaries) {
  const BodyMapCollider c = BuildOrDie(MakePose(BoxGrid(), Box));
  // Texel (i) covers [x_i, x_i + s): the box's low edges belong to it, its high edges do not.
  const float lo = -25.f * kTexel, hi = 25.f * kTexel;
  EXPECT_TRUE(c.IsInside({lo, 0.f, 0.f}));
  EXPECT_FALSE(c.IsInside({hi, 0.f, 0.f}));
  EXPECT_TRUE(c.IsInside({0.f, -12.f * kTexel, 0.f}));
  EXPECT_FALSE(c.IsInside({0.f, 12.f * kTexel, 0.f}));
  EXPECT_TRUE(c.IsInside({0.f, 0.f, kBoxTop}));  // both surfaces are inside (closed slab)
  EXPECT_TRUE(c.IsInside({0.f, 0.f, kBoxBottom}));
  // Segments running exactly along a texel edge agree with the point test.
  EXPECT_FALSE(c.Query({hi, -0.2f, 0.f}, {hi, 0.2f, 0.f}).contact);
  const ContactQuery along = c.Query({lo, -0.2f, 0.f}, {lo, 0.2f, 0.f});
  ASSERT_TRUE(along.contact);
  EXPECT_NEAR(along.point.y, -12.f * kTexel, kWallTolerance);
  EXPECT_TRUE(along.flags & kCollisionSideWall);
  // Ending exactly on the high edge (just outside), coming along x: no contact.
  EXPECT_FALSE(c.Query({0.3f, 0.f, 0.f}, {hi, 0.f, 0.f}).contact);
  // Exactly through a texel corner of the box.
  const ContactQuery corner =
      c.Query({lo - 0.05f, -12.f * kTexel - 0.05f, 0.f}, {lo, -12.f * kTexel, 0.f});
  ASSERT_TRUE(corner.contact);
  EXPECT_NEAR(corner.t, 1.0, 1e-6);
}

TEST(BodyMapCollider, StartInsidePushesOutToTheNearerSurface) {
  const BodyMapCollider c = BuildOrDie(MakePose(BoxGrid(), Box));
  const ContactQuery up = c.Query({0.01f, 0.01f, 0.03f}, {0.02f, 0.01f, 0.03f});
  ASSERT_TRUE(up.contact);
  EXPECT_EQ(up.flags, kCollisionStartedInside);
  EXPECT_FLOAT_EQ(up.t, 0.f);
  EXPECT_FLOAT_EQ(up.point.x, 0.02f);  // p1 is pushed out along z
  EXPECT_FLOAT_EQ(up.point.z, kBoxTop);
  EXPECT_NEAR(up.depth, kBoxTop - 0.03f, 1e-7);
  EXPECT_LT(AngleDegrees(up.normal, {0.f, 0.f, 1.f}), 0.01);
  const ContactQuery down = c.Query({0.f, 0.f, -0.04f}, {0.f, 0.f, -0.04f});
  ASSERT_TRUE(down.contact);
  EXPECT_EQ(down.flags, kCollisionStartedInside);
  EXPECT_FLOAT_EQ(down.point.z, kBoxBottom);
  EXPECT_NEAR(down.depth, -0.04f - kBoxBottom, 1e-7);
  EXPECT_LT(AngleDegrees(down.normal, {0.f, 0.f, -1.f}), 0.01);
  // Leaving the body by itself: no contact.
  EXPECT_FALSE(c.Query({0.f, 0.f, 0.f}, {0.f, 0.f, 0.2f}).contact);
}

// Beside a side of the body, a point inside (a particle the body moved onto near its silhouette)
// is a fraction of a texel from the side and the body's half thickness from either surface along
// z: it leaves through the side, to just outside the nearest outside texel, with the push's
// direction as the normal; the batch gives the same answer. Farther than kSideExitTexels from any
// side, or less than a texel deep along z, it still goes along z.
TEST(BodyMapCollider, StartInsideBesideASideLeavesThroughTheSide) {
  const BodyMapCollider c = BuildOrDie(MakePose(BoxGrid(), Box));
  const Float3 beside{24.5f * kTexel, 0.3f * kTexel, 0.f};  // the side: x = 25 texels
  const ContactQuery q = c.Query(beside, beside);
  ASSERT_TRUE(q.contact);
  EXPECT_EQ(q.flags, kCollisionStartedInside | kCollisionSideWall);
  EXPECT_NEAR(q.point.x, 25.f * kTexel, kWallTolerance);
  EXPECT_GE(q.point.x, 25.f * kTexel);
  EXPECT_NEAR(q.point.y, beside.y, 1e-6f);
  EXPECT_FLOAT_EQ(q.point.z, beside.z);
  EXPECT_NEAR(q.depth, 0.5f * kTexel, kWallTolerance);
  EXPECT_LT(AngleDegrees(q.normal, {1.f, 0.f, 0.f}), 0.01);
  EXPECT_FALSE(c.IsInside(q.point));
  // Near a corner: the nearer of the two sides (y = -12 texels here).
  const Float3 corner{-23.2f * kTexel, -11.6f * kTexel, 0.01f};
  const ContactQuery qc = c.Query(corner, corner);
  ASSERT_TRUE(qc.contact);
  EXPECT_LT(AngleDegrees(qc.normal, {0.f, -1.f, 0.f}), 0.01);
  EXPECT_NEAR(qc.depth, 0.4f * kTexel, kWallTolerance);
  EXPECT_FALSE(c.IsInside(qc.point));
  // Too far from a side, or near the front surface: along z.
  const Float3 middle{19.5f * kTexel, 0.f, -0.01f};
  EXPECT_FLOAT_EQ(c.Query(middle, middle).point.z, kBoxBottom);
  const Float3 near_top{24.5f * kTexel, 0.f, kBoxTop - 0.5f * kTexel};
  const ContactQuery qt = c.Query(near_top, near_top);
  EXPECT_EQ(qt.flags, kCollisionStartedInside);
  EXPECT_FLOAT_EQ(qt.point.z, kBoxTop);
  // The batch: Query and the response, bit for bit, in every lane pack.
  ExpectEveryLanePackAnswersAsQuery(c, beside);
}

// The distance to the silhouette that spares the points far from one the side-exit search: on
// the sphere's maps (a round silhouette, the grid's edge beyond it) every texel's value is the
// brute-force Chebyshev distance to the nearest background texel, capped.
TEST(BodyMapCollider, AirReachIsTheDistanceToTheNearestBackgroundTexel) {
  const BodyMapCollider c = BuildOrDie(MakePose(SphereGrid(), Sphere));
  const int cap = BodyMapColliderAccess::kSideExitTexels + 1;
  const int w = static_cast<int>(c.width()), h = static_cast<int>(c.height());
  const auto background = [&](int i, int j) {
    float top = 0.f, bottom = 0.f;
    return i < 0 || j < 0 || i >= w || j >= h ||
           !BodyMapColliderAccess::TexelSlab(c, uint32_t(i), uint32_t(j), &top, &bottom);
  };
  size_t near = 0, far = 0;
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) {
      int want = cap;
      for (int d = 0; d < cap && want == cap; ++d) {
        for (int dj = -d; dj <= d && want == cap; ++dj) {
          for (int di = -d; di <= d; ++di) {
            if (std::max(std::abs(di), std::abs(dj)) == d && background(i + di, j + dj)) {
              want = d;
              break;
            }
          }
        }
      }
      ASSERT_EQ(BodyMapColliderAccess::AirReach(c, uint32_t(i), uint32_t(j)), uint32_t(want))
          << i << ", " << j;
      near += want > 0 && want < cap;
      far += want == cap;
    }
  }
  EXPECT_GT(near, 100u);
  EXPECT_GT(far, 1000u);
}

// A particle inside the shell that leaves the body through its far side crossed it (a resting
// particle the solver left within epsilon of a limb, pushed through it): it goes back out along
// z to the surface it started nearer to, through z or the side walls alike, the batch agreeing
// bit for bit; one that leaves through the side it started near is leaving: no contact.
TEST(BodyMapCollider, StartInsideTheShellThroughTheBodyIsACrossing) {
  const BodyMapCollider c = BuildOrDie(MakePose(BoxGrid(), Box));
  const float in_front = kBoxTop - 0.002f, in_back = kBoxBottom + 0.002f;
  struct Case {
    Float3 p0, p1;
    bool crossing;
    bool back;  // the surface it goes back to
  };
  const Case cases[] = {
      {{0.01f, 0.01f, in_front}, {0.01f, 0.01f, kBoxBottom - 0.01f}, true, false},  // one texel
      {{0.01f, 0.01f, in_front}, {0.06f, 0.02f, kBoxBottom - 0.01f}, true, false},  // a walk
      {{0.01f, 0.01f, in_back}, {-0.03f, 0.01f, kBoxTop + 0.02f}, true, true},
      {{0.01f, 0.01f, in_back}, {0.01f, 0.01f, kBoxBottom - 0.05f}, false, true},  // leaving
      {{0.01f, 0.01f, in_front}, {0.04f, 0.01f, kBoxTop + 0.05f}, false, false},
      // Along x through the whole box from half a texel inside its left wall, and out of it.
      {{-24.5f * kTexel, 0.01f, 0.f}, {0.3f, 0.01f, 0.f}, true, false},
      {{-24.5f * kTexel, 0.01f, 0.f}, {-0.3f, 0.01f, 0.f}, false, false},
  };
  std::vector<Float3> previous, positions, velocities;
  for (const Case& k : cases) {
    const ContactQuery q = c.Query(k.p0, k.p1);
    EXPECT_EQ(q.contact, k.crossing) << k.p1.x;
    EXPECT_FALSE(q.inside_end);
    if (k.crossing) {
      EXPECT_EQ(q.flags, kCollisionStartedInside);
      EXPECT_EQ(q.t, 0.f);
      EXPECT_FLOAT_EQ(q.point.x, k.p0.x);
      EXPECT_FLOAT_EQ(q.point.z, k.back ? kBoxBottom : kBoxTop);
      EXPECT_LT(AngleDegrees(q.normal, {0.f, 0.f, k.back ? -1.f : 1.f}), 0.01);
    }
    previous.push_back(k.p0);
    positions.push_back(k.p1);
    velocities.push_back({0.f, 0.f, -1.f});
  }
  // The batch (its lanes hand these to Query) gives Query + ApplyResponse's bits.
  ResponseParams params;
  std::vector<uint8_t> flags(positions.size());
  std::vector<Float3> batch = positions, batch_v = velocities;
  ASSERT_TRUE(c.CollideBatch(previous, batch, batch_v, flags, params).ok());
  for (size_t i = 0; i < positions.size(); ++i) {
    const ContactQuery q = c.Query(previous[i], positions[i]);
    Float3 p = positions[i], v = velocities[i];
    if (q.contact) ApplyResponse(q, params, &p, &v);
    EXPECT_EQ(std::memcmp(&p, &batch[i], sizeof(Float3)), 0) << i;
    EXPECT_EQ(std::memcmp(&v, &batch_v[i], sizeof(Float3)), 0) << i;
    EXPECT_EQ((flags[i] & kCollisionContact) != 0, q.contact) << i;
    EXPECT_EQ(flags[i] & kCollisionStartedInside, q.flags & kCollisionStartedInside) << i;
  }
}

TEST(BodyMapCollider, StartInsideThenReEnteringAnotherPartIsASweptContact) {
  // Two boxes with a 10-texel gap: x in [-25, -5) and [5, 25) texels.
  const auto two_boxes = [](double x, double y) {
    SurfaceSample s = Box(x, y);
    if (std::fabs(x) < 5 * kTexel) s.valid = false;
    return s;
  };
  const BodyMapCollider c = BuildOrDie(MakePose(BoxGrid(), two_boxes));
  const ContactQuery q = c.Query({-0.1f, 0.f, 0.f}, {0.1f, 0.f, 0.f});
  ASSERT_TRUE(q.contact);
  EXPECT_EQ(q.flags, kCollisionSideWall);  // not kCollisionStartedInside
  EXPECT_NEAR(q.point.x, 5.f * kTexel, kWallTolerance);
}

TEST(BodyMapCollider, ResponseFollowsPaperEquation5) {
  const BodyMapCollider c = BuildOrDie(MakePose(BoxGrid(), Box));
  ResponseParams params;
  params.friction = 0.3f;
  params.restitution = 0.5f;
  params.separation = 1e-4f;
  params.friction_model = FrictionModel::kPaperA;
  // 0: falls onto the top. 1: same motion but a separating velocity (+z). 2: free, untouched.
  // 3: NaN position. 4: infinite velocity.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<Float3> previous = {
      {0.f, 0.f, 0.1f}, {0.f, 0.f, 0.1f}, {0.f, 0.f, 0.3f}, {0.f, 0.f, 0.1f}, {0.f, 0.f, 0.1f}};
  std::vector<Float3> positions = {
      {0.f, 0.f, 0.f}, {0.f, 0.f, 0.f}, {0.f, 0.f, 0.2f}, {nan, 0.f, 0.f}, {0.f, 0.f, 0.f}};
  std::vector<Float3> velocities = {{1.f, 0.f, -2.f},
                                    {1.f, 0.f, 1.f},
                                    {1.f, 2.f, -3.f},
                                    {1.f, 0.f, -2.f},
                                    {std::numeric_limits<float>::infinity(), 0.f, 0.f}};
  std::vector<uint8_t> flags(5, 0xff);
  uint32_t contacts = 0;
  ASSERT_TRUE(c.CollideBatch(previous, positions, velocities, flags, params, &contacts).ok());
  EXPECT_EQ(contacts, 2u);
  // V.N = -2 < 0: V_n = (0, 0, -2), V' = (V - V_n)(1 - 0.3) - V_n * 0.5 = (0.7, 0, 1), up to the
  // oct16 normal (+z is 0.0012 degrees off: 65535 steps have no exact midpoint).
  EXPECT_EQ(flags[0], kCollisionContact);
  EXPECT_NEAR(positions[0].z, kBoxTop + params.separation, 1e-6);
  EXPECT_NEAR(velocities[0].x, 0.7f, 1e-4);
  EXPECT_NEAR(velocities[0].y, 0.f, 1e-4);
  EXPECT_NEAR(velocities[0].z, 1.f, 1e-4);
  {  // exactly eq. 5 with the contact's own normal
    const ContactQuery q = c.Query(previous[0], {0.f, 0.f, 0.f});
    const Float3 v{1.f, 0.f, -2.f};
    const Float3 vn = q.normal * Dot(v, q.normal);
    const Float3 expected = (v - vn) * (1.f - params.friction) - vn * params.restitution;
    EXPECT_NEAR(velocities[0].x, expected.x, 1e-6);
    EXPECT_NEAR(velocities[0].y, expected.y, 1e-6);
    EXPECT_NEAR(velocities[0].z, expected.z, 1e-6);
    EXPECT_NEAR(positions[0].x, q.point.x + q.normal.x * params.separation, 1e-7);
  }
  // Separating (V.N > 0): the position is put on the surface, the velocity is kept.
  EXPECT_EQ(flags[1], kCollisionContact);
  EXPECT_NEAR(positions[1].z, kBoxTop + params.separation, 1e-6);
  EXPECT_EQ(velocities[1].x, 1.f);
  EXPECT_EQ(velocities[1].z, 1.f);
  EXPECT_EQ(flags[2], kCollisionNone);
  EXPECT_EQ(positions[2].z, 0.2f);
  EXPECT_EQ(velocities[2].y, 2.f);
  EXPECT_EQ(flags[3], kCollisionInvalidInput);
  EXPECT_TRUE(std::isnan(positions[3].x));
  EXPECT_EQ(velocities[3].z, -2.f);
  EXPECT_EQ(flags[4], kCollisionInvalidInput);
  EXPECT_EQ(positions[4].z, 0.f);
  // A query with NaN reports invalid input and no contact.
  const ContactQuery bad = c.Query({nan, 0.f, 0.f}, {0.f, 0.f, 0.f});
  EXPECT_FALSE(bad.contact);
  EXPECT_EQ(bad.flags, kCollisionInvalidInput);
  // Mismatched spans are an error, not a crash.
  std::vector<uint8_t> short_flags(2);
  EXPECT_EQ(c.CollideBatch(previous, positions, velocities, short_flags, params).code(),
            StatusCode::kInvalidArgument);
}

TEST(BodyMapCollider, HugeCoordinatesAreClippedNotOverflowed) {
  const BodyMapCollider c = BuildOrDie(MakePose(BoxGrid(), Box));
  const ContactQuery q = c.Query({1e30f, 0.f, 0.f}, {-1e30f, 0.f, 0.f});
  ASSERT_TRUE(q.contact);
  EXPECT_TRUE(q.flags & kCollisionSideWall);
  EXPECT_NEAR(q.point.x, 25.f * kTexel, 2e-3);  // the +x side (float t resolution at 1e30)
  EXPECT_NEAR(q.t, 0.5, 1e-6);
  const float big = 3e38f;
  EXPECT_FALSE(c.Query({big, big, big}, {big, -big, big}).contact);
  // Through the origin from +-3e38: the double clip cannot place the crossing to the metre, but
  // the walk stays bounded by the map and the answer is well formed.
  const ContactQuery through = c.Query({big, big, big}, {-big, -big, -big});
  EXPECT_GE(through.t, 0.f);
  EXPECT_LE(through.t, 1.f);
  EXPECT_TRUE(IsFinite(through.point));
  EXPECT_FALSE(c.IsInside({big, 0.f, 0.f}));
  // Found by fuzzing: the exit parameter rounds to exactly 1 in double although p1 is 9e9 m
  // outside the box; the end must still be clamped (an unclamped end overflowed the walk).
  const ContactQuery far = c.Query({0.3f, 4.4e27f, 0.f}, {-0.39f, -8.9e9f, 0.45f});
  EXPECT_FALSE(far.inside_end);
  EXPECT_GE(far.t, 0.f);
  EXPECT_LE(far.t, 1.f);
  EXPECT_TRUE(IsFinite(far.point));
}

TEST(BodyMapCollider, BilinearDepthIsMoreAccurateThanNearestOnASphere) {
  const BodyMapPose pose = MakePose(SphereGrid(), Sphere);
  const BodyMapCollider nearest = BuildOrDie(pose, DepthSampling::kNearest);
  const BodyMapCollider bilinear = BuildOrDie(pose, DepthSampling::kBilinear);
  EXPECT_GT(bilinear.stats().bilinear_blocks, 3500u);  // of ~4600 texels on the disc
  EXPECT_EQ(nearest.stats().bilinear_blocks, 0u);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> xy(-0.25f, 0.25f);
  double sum[2] = {0, 0}, worst[2] = {0, 0}, normal_sum[2] = {0, 0};
  int n = 0;
  for (int k = 0; k < 2000; ++k) {
    const float x = xy(rng), y = xy(rng);
    const double h = SphereHeight(x, y);
    if (std::sqrt(x * x + y * y) > 0.8 * kSphereRadius) continue;
    const Float3 truth_normal{x, y, static_cast<float>(h)};
    const BodyMapCollider* colliders[2] = {&nearest, &bilinear};
    for (int m = 0; m < 2; ++m) {
      const ContactQuery q = colliders[m]->Query({x, y, 0.5f}, {x, y, 0.f});
      ASSERT_TRUE(q.contact);
      const double error = std::fabs(q.point.z - h);
      sum[m] += error;
      worst[m] = std::max(worst[m], error);
      normal_sum[m] += AngleDegrees(q.normal, truth_normal);
    }
    ++n;
  }
  ASSERT_GT(n, 500);
  // Nearest: error ~ slope * s / 2 (mm). Bilinear: ~ curvature * s^2 / 8 (um).
  std::printf("depth error mean/max: nearest %.3g/%.3g m, bilinear %.3g/%.3g m\n", sum[0] / n,
              worst[0], sum[1] / n, worst[1]);
  EXPECT_LT(sum[1], 0.1 * sum[0]) << "mean nearest " << sum[0] / n << " bilinear " << sum[1] / n;
  EXPECT_LT(worst[1], worst[0]);
  EXPECT_LT(worst[1], 4e-4);  // s^2 / 8 * |h''| * 2 at r = 0.8 R
  EXPECT_LT(normal_sum[1], normal_sum[0]);
}

TEST(BodyMapCollider, BilinearWalkAgreesWithBilinearPointTest) {
  const BodyMapCollider c = BuildOrDie(MakePose(SphereGrid(), Sphere), DepthSampling::kBilinear);
  std::mt19937 rng(21);
  int hits = 0;
  for (int k = 0; k < 600; ++k) {
    Float3 p0, p1;
    RandomSegment(rng, k, &p0, &p1);
    if (c.IsInside(p0)) continue;
    const ContactQuery q = c.Query(p0, p1);
    EXPECT_EQ(q.inside_end, c.IsInside(p1));
    EXPECT_TRUE(!q.inside_end || q.contact);
    // Dense sampling of the point test: the walk never reports its entry later than the first
    // inside sample, and every swept contact lies on the segment.
    constexpr int kSamples = 20000;
    int first = -1;
    for (int s = 0; s <= kSamples && first < 0; ++s) {
      if (c.IsInside(Lerp(p0, p1, static_cast<float>(s) / kSamples))) first = s;
    }
    if (first >= 0) {
      ASSERT_TRUE(q.contact) << k;
      EXPECT_LE(q.t, static_cast<double>(first) / kSamples + 1e-5) << k;
      ++hits;
    }
    if (q.contact) {
      const Float3 on_segment = Lerp(p0, p1, q.t);
      EXPECT_NEAR(q.point.x, on_segment.x, 1e-5);
      EXPECT_NEAR(q.point.y, on_segment.y, 1e-5);
      EXPECT_NEAR(q.point.z, on_segment.z, 1e-4);
      // On the true sphere within the bilinear error (the silhouette blocks are nearest).
      if (!(q.flags & kCollisionSideWall)) {
        EXPECT_NEAR(Length(q.point), kSphereRadius, 2.0 * kTexel) << k;
      }
    }
  }
  EXPECT_GT(hits, 150);
}

TEST(BodyMapCollider, BatchIsBitwiseIdenticalAtOneAndTwoThreads) {
  const BodyMapCollider c = BuildOrDie(MakePose(SphereGrid(), Sphere));
  std::mt19937 rng(9);
  constexpr size_t kCount = 20000;
  std::vector<Float3> previous(kCount), positions(kCount), velocities(kCount);
  for (size_t k = 0; k < kCount; ++k) {
    previous[k] = RandomPoint(rng, -0.35f, 0.35f, -0.35f, 0.35f);
    positions[k] = previous[k] + RandomPoint(rng, -0.05f, 0.05f, -0.05f, 0.05f);
    velocities[k] = RandomPoint(rng, -1.f, 1.f, -1.f, 1.f);
  }
  const ResponseParams params;
  std::vector<Float3> result_positions[2], result_velocities[2];
  std::vector<uint8_t> result_flags[2];
  uint32_t contacts[2] = {0, 0};
  for (int run = 0; run < 2; ++run) {
    test::UseWorkers(run + 1);
    result_positions[run] = positions;
    result_velocities[run] = velocities;
    result_flags[run].assign(kCount, 0);
    ASSERT_TRUE(c.CollideBatch(previous, result_positions[run], result_velocities[run],
                               result_flags[run], params, &contacts[run])
                    .ok());
  }
  test::UseDefaultWorkers();
  EXPECT_GT(contacts[0], 1000u);
  EXPECT_EQ(contacts[0], contacts[1]);
  EXPECT_EQ(0, std::memcmp(result_positions[0].data(), result_positions[1].data(),
                           kCount * sizeof(Float3)));
  EXPECT_EQ(0, std::memcmp(result_velocities[0].data(), result_velocities[1].data(),
                           kCount * sizeof(Float3)));
  EXPECT_EQ(result_flags[0], result_flags[1]);
  // And each equals the single query.
  for (size_t k = 0; k < kCount; k += 97) {
    const ContactQuery q = c.Query(previous[k], positions[k]);
    EXPECT_EQ(q.contact, (result_flags[0][k] & kCollisionContact) != 0);
  }
}

TEST(BodyMapCollider, BuildRejectsInconsistentData) {
  const BodyMapPose good = MakePose(BoxGrid(), Box);
  const auto expect_rejected = [](const BodyMapPose& pose, const char* what) {
    BodyMapCollider c;
    const Status status = c.Build(pose);
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << what;
    EXPECT_FALSE(status.message().empty()) << what;
    EXPECT_TRUE(c.empty()) << what;
    EXPECT_FALSE(c.IsInside({0.f, 0.f, 0.f})) << what;
    EXPECT_FALSE(c.Query({0.f, 0.f, 1.f}, {0.f, 0.f, -1.f}).contact) << what;
  };
  BodyMapPose p = good;
  p.depth_f32[1].pop_back();
  expect_rejected(p, "short back depth");
  p = good;
  p.normal_f32[0].push_back(0.f);
  expect_rejected(p, "long front normals");
  p = good;
  p.texel_size = 0.f;
  expect_rejected(p, "zero texel size");
  p = good;
  p.texel_size = std::numeric_limits<float>::quiet_NaN();
  expect_rejected(p, "NaN texel size");
  p = good;
  p.depth_range = -1.f;
  expect_rejected(p, "negative depth range");
  p = good;
  p.depth_f32[0][100] = std::numeric_limits<float>::quiet_NaN();
  expect_rejected(p, "NaN depth");
  p = good;
  p.depth_f32[1][7] = -0.5f;
  expect_rejected(p, "negative depth");
  p = good;
  p.normal_f32[1][5] = std::numeric_limits<float>::infinity();
  expect_rejected(p, "infinite normal");
  p = good;
  p.width = 0;
  expect_rejected(p, "zero width");
  p = good;
  p.origin_x = std::numeric_limits<float>::infinity();
  expect_rejected(p, "infinite origin");
  p = good;
  p.depth_u16[0].resize(p.depth_f32[0].size());
  expect_rejected(p, "an unchosen encoding filled");
  p = good;
  p.depth_encoding = static_cast<DepthEncoding>(9);
  expect_rejected(p, "unknown encoding");
  // Not built: the batch says so.
  BodyMapCollider unbuilt;
  std::vector<Float3> a(1), b(1), v(1);
  std::vector<uint8_t> f(1);
  EXPECT_EQ(unbuilt.CollideBatch(a, b, v, f, ResponseParams{}).code(), StatusCode::kInvalidState);
}

TEST(BodyMapCollider, SilhouetteDisagreementIsBackgroundAndCounted) {
  BodyMapPose p = MakePose(BoxGrid(), Box);
  const size_t k = 20 * 64 + 32;      // texel (32, 20): inside the box
  p.depth_f32[1][k] = p.depth_range;  // the back map says background there
  const BodyMapCollider c = BuildOrDie(p);
  EXPECT_EQ(c.stats().one_sided_texels, 1u);
  EXPECT_FALSE(c.IsInside({0.5f * kTexel, 0.5f * kTexel, 0.f}));
  EXPECT_TRUE(c.IsInside({1.5f * kTexel, 0.5f * kTexel, 0.f}));
  EXPECT_EQ(c.stats().valid_texels, 50u * 24u - 1u);
  // 17 bytes per texel plus small change.
  EXPECT_GE(c.memory_bytes(), 64u * 40u * 17u);
  EXPECT_LT(c.memory_bytes(), 64u * 40u * 17u + 2048u);
}

TEST(BodyMapCollider, QuickPathsAnswerBitForBitAsTheWalk) {
  const BodyMapCollider bodies[3] = {BuildOrDie(MakePose(SphereGrid(), Sphere)),
                                     BuildOrDie(MakePose(BoxGrid(), Box)),
                                     BuildOrDie(MakePose(SphereGrid(), ThinSlab))};
  std::mt19937 rng(20261123);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  for (int body = 0; body < 3; ++body) {
    for (DepthSampling sampling : {DepthSampling::kNearest, DepthSampling::kBilinear}) {
      SCOPED_TRACE(::testing::Message() << "body " << body << " sampling " << int(sampling));
      const BodyMapCollider& c =
          sampling == DepthSampling::kNearest
              ? bodies[body]
              : BuildOrDie(MakePose(body == 1 ? BoxGrid() : SphereGrid(), body == 0   ? Sphere
                                                                          : body == 1 ? Box
                                                                                      : ThinSlab),
                           sampling);
      const Float3 lo = c.bounds_min(), hi = c.bounds_max();
      const auto point = [&](float pad) {
        return Float3{lo.x - pad + unit(rng) * (hi.x - lo.x + 2.f * pad),
                      lo.y - pad + unit(rng) * (hi.y - lo.y + 2.f * pad),
                      lo.z - pad + unit(rng) * (hi.z - lo.z + 2.f * pad)};
      };
      int contacts = 0, started_inside = 0, single_texel = 0, clearly_free = 0;
      for (int k = 0; k < 48000; ++k) {
        Float3 p0 = point(0.02f), p1 = p0;
        const float texel = c.texel_size();
        switch (k % 6) {
          case 0:  // a point
            break;
          case 1:  // sub-texel, mostly along z through a surface
            p1 = p0 + Float3{(unit(rng) - 0.5f) * 0.5f * texel, (unit(rng) - 0.5f) * 0.5f * texel,
                             (unit(rng) - 0.5f) * 0.05f};
            break;
          case 2:  // one to three texels
            p1 = p0 + Float3{(unit(rng) - 0.5f) * 6.f * texel, (unit(rng) - 0.5f) * 6.f * texel,
                             (unit(rng) - 0.5f) * 0.02f};
            break;
          case 3:  // long, across the box
            p1 = point(0.1f);
            break;
          case 4:  // on a texel edge, moving along z only
            p0.x = c.origin_x() + std::floor((p0.x - c.origin_x()) / texel) * texel;
            p1 = Float3{p0.x, p0.y, p0.z + (unit(rng) - 0.5f) * 0.1f};
            break;
          default: {  // starting or ending exactly on a surface value of the texel's slab
            const float u = (p0.x - c.origin_x()) / texel, v = (p0.y - c.origin_y()) / texel;
            float top = 0.f, bottom = 0.f;
            if (u >= 0.f && v >= 0.f &&
                BodyMapColliderAccess::TexelSlab(c, static_cast<uint32_t>(u),
                                                 static_cast<uint32_t>(v), &top, &bottom)) {
              const float surface = unit(rng) < 0.5f ? top : bottom;
              if (unit(rng) < 0.5f) {
                p0.z = surface;
                p1 = Float3{p0.x, p0.y, surface + (unit(rng) - 0.5f) * 0.01f};
              } else {
                p1 = Float3{p0.x, p0.y, surface};
              }
            }
            break;
          }
        }
        const ContactQuery quick = c.Query(p0, p1);
        const ContactQuery walk = BodyMapColliderAccess::QueryWalk(c, p0, p1);
        ExpectSameAnswer(quick, walk, k);
        contacts += walk.contact;
        started_inside += (walk.flags & kCollisionStartedInside) != 0;
        const bool single = BodyMapColliderAccess::SingleTexelAnswers(c, p0, p1);
        single_texel += single;
        clearly_free += !single && BodyMapColliderAccess::ClearlyFree(c, p0, p1);
      }
      // The sets must exercise both quick paths and the walk.
      EXPECT_GT(contacts, 2000);
      EXPECT_GT(started_inside, 200);
      if (sampling == DepthSampling::kNearest) {
        EXPECT_GT(single_texel, 4000);  // the thin slab's 2 mm clip box sends most to the walk
      }
      EXPECT_GT(clearly_free, 2000);
    }
  }
}

TEST(BodyMapCollider, RowSpanLayoutAnswersExactlyAsDense) {
  const NormalEncoding normals[3] = {NormalEncoding::kFloat32, NormalEncoding::kOct16,
                                     NormalEncoding::kRgb8};
  for (const bool sphere : {true, false}) {
    for (DepthEncoding de : {DepthEncoding::kFloat32, DepthEncoding::kUnorm16}) {
      for (NormalEncoding ne : normals) {
        BodyMapPose dense =
            sphere ? MakePose(SphereGrid(), Sphere, de, ne) : MakePose(BoxGrid(), Box, de, ne);
        ZeroBackgroundNormals(dense);
        BodyMapPose spans;
        ASSERT_TRUE(ConvertBodyMapLayout(dense, BodyMapLayout::kRowSpans, &spans).ok());
        ASSERT_EQ(spans.layout, BodyMapLayout::kRowSpans);
        EXPECT_LT(BodyMapStoredTexels(spans), BodyMapStoredTexels(dense));
        // Back to dense: the very same arrays.
        BodyMapPose back;
        ASSERT_TRUE(ConvertBodyMapLayout(spans, BodyMapLayout::kDense, &back).ok());
        EXPECT_EQ(back.depth_f32[1], dense.depth_f32[1]);
        EXPECT_EQ(back.depth_u16[0], dense.depth_u16[0]);
        EXPECT_EQ(back.normal_f32[0], dense.normal_f32[0]);
        EXPECT_EQ(back.normal_oct16[1], dense.normal_oct16[1]);
        EXPECT_EQ(back.normal_rgb8[1], dense.normal_rgb8[1]);
        for (DepthSampling sampling : {DepthSampling::kNearest, DepthSampling::kBilinear}) {
          SCOPED_TRACE(::testing::Message()
                       << (sphere ? "sphere" : "box") << " depth " << int(de) << " normal "
                       << int(ne) << " sampling " << int(sampling));
          const BodyMapCollider a = BuildOrDie(dense, sampling);
          const BodyMapCollider b = BuildOrDie(spans, sampling);
          ExpectIdenticalColliders(a, b, 1000, 0.05f);
        }
      }
    }
  }
}

TEST(BodyMapCollider, BuildRejectsACorruptSpanTable) {
  BodyMapPose good;
  ASSERT_TRUE(ConvertBodyMapLayout(MakePose(BoxGrid(), Box), BodyMapLayout::kRowSpans, &good).ok());
  ASSERT_TRUE(BodyMapCollider().Build(good).ok());
  const auto expect_rejected = [](const BodyMapPose& pose, const char* field) {
    BodyMapCollider c;
    const Status status = c.Build(pose);
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << field;
    EXPECT_NE(status.message().find(field), std::string::npos) << status.message();
    EXPECT_TRUE(c.empty()) << field;
  };
  const size_t row = 10;  // a row of the box: one span [7, 57)
  const uint32_t s = good.row_span_offsets[row];
  BodyMapPose p = good;
  p.span_begin[s] = 20;  // the span now ends at 70 > width 64
  expect_rejected(p, "beyond width");
  p = good;
  p.row_span_offsets[row] = p.row_span_offsets[row + 1] + 1;
  expect_rejected(p, "row_span_offsets");
  p = good;
  p.row_span_offsets.pop_back();
  expect_rejected(p, "row_span_offsets");
  p = good;
  p.span_texel_offsets[s + 1] = p.span_texel_offsets[s];
  expect_rejected(p, "span_texel_offsets");
  p = good;
  p.depth_f32[0].pop_back();
  expect_rejected(p, "depth_f32_front");
  p = good;
  p.layout = static_cast<BodyMapLayout>(7);
  expect_rejected(p, "layout");
  p = good;
  p.layout = BodyMapLayout::kDense;  // a dense pose with a span table: inconsistent
  expect_rejected(p, "span");
}

}  // namespace
}  // namespace drape

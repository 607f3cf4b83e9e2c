// Body maps with air gaps (layers > 1): the inside set, entries across a gap, the walk against
// the exact reference, the quick paths and the batch, rejected data, the row-span layout, blends,
// and the gap flag the lanes read.
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

TEST(BodyMapGaps, InsideSetIsTheSlabMinusItsGaps) {
  const BodyMapCollider paper = BuildOrDie(LayeredPose(1, kStack));
  const BodyMapCollider two = BuildOrDie(LayeredPose(2, kStack));
  const BodyMapCollider three = BuildOrDie(LayeredPose(3, kStack));
  EXPECT_EQ(paper.layers(), 1u);
  EXPECT_EQ(three.layers(), 3u);
  EXPECT_EQ(paper.stats().gap_texels, 0u);
  EXPECT_EQ(three.stats().gap_texels, 40u * 40u);  // the plate's texels
  EXPECT_EQ(two.stats().gap_texels, 40u * 40u);
  // Stored compactly: two gap slots of 16 bytes per gap texel, and one bit per texel and a count
  // per 32 texels (which texels have gaps, and where theirs start).
  const size_t words = (size_t{three.width()} * three.height() + 31) / 32;
  EXPECT_LE(three.memory_bytes() - paper.memory_bytes(), 40u * 40u * 2 * 16 + words * 4 * 2 + 64);
  // Under the plate only (x < 0): one gap (0.05, 0.10).
  const Float3 plate_only{-0.05f, 0.01f, 0.f}, both_plates{0.03f, 0.01f, 0.f};
  const auto at = [](Float3 p, float z) { return Float3{p.x, p.y, z}; };
  for (const BodyMapCollider* c : {&two, &three}) {
    EXPECT_TRUE(c->IsInside(at(plate_only, 0.11f)));
    EXPECT_FALSE(c->IsInside(at(plate_only, 0.075f)));
    EXPECT_TRUE(c->IsInside(at(plate_only, 0.0f)));
    EXPECT_FALSE(c->IsInside(at(plate_only, 0.13f)));
    EXPECT_TRUE(c->IsInside(at(plate_only, 0.10f)));  // gap boundaries are inside
    EXPECT_TRUE(c->IsInside(at(plate_only, 0.05f)));
  }
  EXPECT_TRUE(paper.IsInside(at(plate_only, 0.075f)));  // paper A: the air counts as inside
  // Under both plates: gaps (0.075, 0.10) and (0.05, 0.065); with two layers only the wider,
  // upper one.
  EXPECT_TRUE(three.IsInside(at(both_plates, 0.07f)));
  EXPECT_FALSE(three.IsInside(at(both_plates, 0.09f)));
  EXPECT_FALSE(three.IsInside(at(both_plates, 0.06f)));
  EXPECT_FALSE(two.IsInside(at(both_plates, 0.09f)));
  EXPECT_TRUE(two.IsInside(at(both_plates, 0.06f)));
  float upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers];
  const uint32_t i = static_cast<uint32_t>((both_plates.x + 44 * kTexel) / kTexel);
  const uint32_t j = static_cast<uint32_t>((both_plates.y + 44 * kTexel) / kTexel);
  ASSERT_EQ(BodyMapColliderAccess::TexelGaps(three, i, j, upper, lower), 2u);
  EXPECT_NEAR(upper[0], 0.10f, 1e-6);
  EXPECT_NEAR(lower[0], 0.075f, 1e-6);
  EXPECT_NEAR(upper[1], 0.065f, 1e-6);
  EXPECT_NEAR(lower[1], 0.05f, 1e-6);
  EXPECT_EQ(BodyMapColliderAccess::TexelGaps(paper, i, j, upper, lower), 0u);
  // The batch and the bilinear sampling classify the same way (the gap texels stay nearest).
  const BodyMapCollider bilinear = BuildOrDie(LayeredPose(3, kStack), DepthSampling::kBilinear);
  std::mt19937 rng(31);
  std::vector<Float3> points(20000);
  for (Float3& p : points) p = RandomPoint(rng, -0.3f, 0.3f, -0.15f, 0.15f);
  std::vector<uint8_t> inside(points.size());
  ASSERT_TRUE(three.InsideBatch(points, inside).ok());
  int gap_points = 0;
  for (size_t k = 0; k < points.size(); ++k) {
    EXPECT_EQ(inside[k] != 0, three.IsInside(points[k])) << k;
    EXPECT_EQ(bilinear.IsInside(points[k]), three.IsInside(points[k])) << k;
    gap_points += paper.IsInside(points[k]) && !three.IsInside(points[k]);
  }
  EXPECT_GT(gap_points, 500);
}

TEST(BodyMapGaps, EntriesAcrossAGapUseTheGapsSurfaces) {
  const BodyMapCollider paper = BuildOrDie(LayeredPose(1, kStack));
  // Oct16 normals (the runtime's storage) are within 0.004 degrees.
  for (NormalEncoding ne : {NormalEncoding::kFloat32, NormalEncoding::kOct16}) {
    SCOPED_TRACE(::testing::Message() << "normal encoding " << int(ne));
    const BodyMapCollider c = BuildOrDie(LayeredPose(3, kStack, DepthEncoding::kFloat32, ne));
    const float x = -0.05f, y = 0.01f;  // under the plate only: one gap (0.05, 0.10)
    // From the gap down into the block: a front entry on the gap's lower boundary.
    ContactQuery q = c.Query({x, y, 0.09f}, {x, y, 0.03f});
    ASSERT_TRUE(q.contact);
    EXPECT_EQ(q.flags, kCollisionNone);
    EXPECT_NEAR(q.t, (0.09f - 0.05f) / 0.06f, 1e-5);
    EXPECT_NEAR(q.point.z, 0.05f, 1e-6);
    EXPECT_LT(AngleDegrees(q.normal, kGapLowerNormal), 0.01);
    EXPECT_NEAR(q.depth, 0.02f, 1e-6);  // below the block's top, in the block's interval
    // From the gap up into the plate: a back entry on the gap's upper boundary.
    q = c.Query({x, y, 0.06f}, {x, y, 0.105f});
    ASSERT_TRUE(q.contact);
    EXPECT_NEAR(q.point.z, 0.10f, 1e-6);
    EXPECT_LT(AngleDegrees(q.normal, kGapUpperNormal), 0.01);
    // Moving inside the gap: air, no contact. Paper A's slab calls it inside.
    q = c.Query({x, y, 0.06f}, {x + 0.01f, y, 0.09f});
    EXPECT_FALSE(q.contact);
    EXPECT_FALSE(q.inside_end);
    EXPECT_TRUE(paper.Query({x, y, 0.06f}, {x + 0.01f, y, 0.09f}).contact);
    // From inside the plate through the gap into the block: a swept entry into the block.
    q = c.Query({x, y, 0.11f}, {x, y, 0.04f});
    ASSERT_TRUE(q.contact);
    EXPECT_EQ(q.flags & kCollisionStartedInside, 0);
    EXPECT_NEAR(q.point.z, 0.05f, 1e-6);
    EXPECT_LT(AngleDegrees(q.normal, kGapLowerNormal), 0.01);
    // Deep in the plate and staying: pushed out to the plate's nearer surface, its lower one.
    q = c.Query({x, y, 0.105f}, {x, y, 0.102f});
    ASSERT_TRUE(q.contact);
    EXPECT_EQ(q.flags, kCollisionStartedInside);
    EXPECT_NEAR(q.point.z, 0.10f, 1e-6);
    EXPECT_NEAR(q.depth, 0.002f, 1e-6);
    EXPECT_LT(AngleDegrees(q.normal, kGapUpperNormal), 0.01);
    // From above through everything: the plate's front surface.
    q = c.Query({x, y, 0.2f}, {x, y, -0.2f});
    ASSERT_TRUE(q.contact);
    EXPECT_NEAR(q.point.z, 0.12f, 1e-6);
    EXPECT_LT(AngleDegrees(q.normal, Float3{0.f, 0.f, 1.f}), 0.01);
    // Sideways at gap height from beyond the plate (slab = the block only) in under it: air.
    // Paper A's slab grows there and reports a side wall.
    q = c.Query({-0.2f, y, 0.075f}, {-0.1f, y, 0.075f});
    EXPECT_FALSE(q.contact);
    q = paper.Query({-0.2f, y, 0.075f}, {-0.1f, y, 0.075f});
    ASSERT_TRUE(q.contact);
    EXPECT_NE(q.flags & kCollisionSideWall, 0);
    // Sideways in the gap into the edge of the mid plate (x = 0): a side wall, with the normal of
    // the nearer surface of the mid plate's interval, its top (gap 0's lower boundary).
    q = c.Query({-0.02f, y, 0.073f}, {0.02f, y, 0.073f});
    ASSERT_TRUE(q.contact);
    EXPECT_NE(q.flags & kCollisionSideWall, 0);
    EXPECT_NEAR(q.point.x, 0.f, kWallTolerance);
    EXPECT_LT(AngleDegrees(q.normal, kGapLowerNormal), 0.01);
  }
}

TEST(BodyMapGaps, WalkMatchesExactReferenceOnRandomSegments) {
  const BodyMapCollider paper = BuildOrDie(LayeredPose(1, kStack));
  for (uint8_t layers : {uint8_t{2}, uint8_t{3}}) {
    const BodyMapCollider c = BuildOrDie(LayeredPose(layers, kStack));
    int from_gap = 0;  // starts that paper A's slab would call inside
    const WalkCounts n = ExpectWalkMatchesReference(
        c, 17 + layers, 3000, [&](Float3 p0) { from_gap += paper.IsInside(p0); });
    std::printf("layers %d: %d hits (%d side walls), %d misses, %d starts in a gap\n", layers,
                n.hits, n.side_walls, n.misses, from_gap);
    EXPECT_GT(n.hits, 300);
    EXPECT_GT(n.misses, 100);
    EXPECT_GT(from_gap, 50);
  }
}

TEST(BodyMapGaps, QuickPathsAndBatchAnswerAsTheWalkAtAnyThreadCount) {
  for (DepthSampling sampling : {DepthSampling::kNearest, DepthSampling::kBilinear}) {
    SCOPED_TRACE(::testing::Message() << "sampling " << int(sampling));
    const BodyMapCollider c = BuildOrDie(LayeredPose(3, kStack), sampling);
    std::mt19937 rng(41);
    std::uniform_real_distribution<float> unit(0.f, 1.f);
    constexpr size_t kCount = 30000;
    std::vector<Float3> previous(kCount), positions(kCount), velocities(kCount);
    for (size_t k = 0; k < kCount; ++k) {
      previous[k] = RandomPoint(rng, -0.3f, 0.3f, -0.15f, 0.15f);
      const float reach = k % 3 == 0 ? 0.3f * kTexel : (k % 3 == 1 ? 3.f * kTexel : 0.1f);
      positions[k] = previous[k] + RandomPoint(rng, -reach, reach, -0.03f, 0.03f);
      velocities[k] = RandomPoint(rng, -1.f, 1.f, -1.f, 1.f);
    }
    int contacts = 0;
    for (size_t k = 0; k < kCount; ++k) {
      const ContactQuery walk = BodyMapColliderAccess::QueryWalk(c, previous[k], positions[k]);
      ExpectSameAnswer(c.Query(previous[k], positions[k]), walk, static_cast<int>(k));
      contacts += walk.contact;
    }
    EXPECT_GT(contacts, 3000);
    std::vector<Float3> out_positions[2], out_velocities[2];
    std::vector<uint8_t> flags[2];
    for (int run = 0; run < 2; ++run) {
      test::UseWorkers(run + 1);
      out_positions[run] = positions;
      out_velocities[run] = velocities;
      flags[run].assign(kCount, 0);
      ASSERT_TRUE(c.CollideBatch(previous, out_positions[run], out_velocities[run], flags[run],
                                 ResponseParams{})
                      .ok());
    }
    test::UseDefaultWorkers();
    EXPECT_EQ(
        0, std::memcmp(out_positions[0].data(), out_positions[1].data(), kCount * sizeof(Float3)));
    EXPECT_EQ(flags[0], flags[1]);
  }
}

TEST(BodyMapGaps, BuildRejectsGapsThatDoNotNest) {
  const GridSpec g = SphereGrid();
  const uint32_t i = 30, j = 44;  // under the plate only (x = -0.11 m)
  const size_t k = static_cast<size_t>(j) * g.width + i;
  const auto expect_rejected = [](const BodyMapPose& pose, const std::string& words) {
    BodyMapCollider c;
    const Status status = c.Build(pose);
    EXPECT_FALSE(status.ok()) << words;
    EXPECT_NE(status.message().find(words), std::string::npos) << status.message();
    EXPECT_TRUE(c.empty());
  };
  // The stack's own gaps with texel `texel`'s replaced by `gaps`.
  const auto with_gaps = [&](size_t texel, const std::vector<GapSpec>& gaps) {
    GapsByTexel all = BoxGaps(3, kStack);
    all[texel] = gaps;
    return PackLayered(3, kStack, all);
  };
  const auto with_gap = [&](size_t texel, bool front_valid, double upper, bool back_valid,
                            double lower) {
    return with_gaps(texel, {GapSpec{upper, lower, front_valid, back_valid}});
  };
  ASSERT_TRUE(BodyMapCollider().Build(with_gap(k, true, 0.09, true, 0.06)).ok());
  for (uint8_t layers : {uint8_t{0}, uint8_t{5}}) {
    BodyMapPose pose = LayeredPose(3, kStack);
    pose.layers = layers;
    expect_rejected(pose, "layers = " + std::to_string(layers));
  }
  {  // arrays sized for three layers, pose says two
    BodyMapPose pose = LayeredPose(3, kStack);
    pose.layers = 2;
    expect_rejected(pose, "2 layer(s)");
  }
  {  // a gap list with one layer
    BodyMapPose pose = LayeredPose(1, kStack);
    pose.gap_texels = {static_cast<uint32_t>(k)};
    expect_rejected(pose, "layers = 1 (no gap layers)");
  }
  {  // a gap list that does not increase
    BodyMapPose pose = LayeredPose(3, kStack);
    ASSERT_GE(pose.gap_texels.size(), 2u);
    std::swap(pose.gap_texels[0], pose.gap_texels[1]);
    expect_rejected(pose, "does not increase");
  }
  expect_rejected(with_gap(k, true, 0.09, false, 0.0), "only one of its two boundaries");
  expect_rejected(with_gap(k, true, 0.13, true, 0.06), "not strictly inside");  // above top
  expect_rejected(with_gap(k, true, 0.07, true, 0.09), "not strictly inside");  // inverted
  expect_rejected(with_gap(k, true, 0.09, true, -0.2), "not strictly inside");  // below bottom
  const size_t block_only = static_cast<size_t>(j) * g.width + 16;  // x = -0.215 m: no gap
  expect_rejected(with_gaps(block_only, {GapSpec{0, 0, false, false}, GapSpec{0.0, -0.05}}),
                  "has no gap 1");
  expect_rejected(with_gap(0, true, 0.09, true, 0.06), "background texel");
  // Gap 2 overlapping gap 1.
  expect_rejected(with_gaps(k, {GapSpec{0.10, 0.05}, GapSpec{0.07, 0.03}}), "gap layer 2");
}

TEST(BodyMapGaps, RowSpanLayoutAnswersExactlyAsDense) {
  for (DepthEncoding de : {DepthEncoding::kFloat32, DepthEncoding::kUnorm16}) {
    BodyMapPose dense = LayeredPose(3, kStack, de, NormalEncoding::kOct16);
    ZeroBackgroundNormals(dense);
    BodyMapPose spans, back;
    ASSERT_TRUE(ConvertBodyMapLayout(dense, BodyMapLayout::kRowSpans, &spans).ok());
    ASSERT_TRUE(ConvertBodyMapLayout(spans, BodyMapLayout::kDense, &back).ok());
    EXPECT_EQ(spans.gap_texels.size(), dense.gap_texels.size());
    EXPECT_NE(spans.gap_texels, dense.gap_texels);  // renumbered: spans store fewer texels
    EXPECT_EQ(back.gap_texels, dense.gap_texels);
    EXPECT_EQ(back.depth_f32[0], dense.depth_f32[0]);
    EXPECT_EQ(back.depth_u16[1], dense.depth_u16[1]);
    EXPECT_EQ(back.normal_oct16[0], dense.normal_oct16[0]);
    for (DepthSampling sampling : {DepthSampling::kNearest, DepthSampling::kBilinear}) {
      SCOPED_TRACE(::testing::Message() << "depth " << int(de) << " sampling " << int(sampling));
      const BodyMapCollider a = BuildOrDie(dense, sampling), b = BuildOrDie(spans, sampling);
      EXPECT_EQ(a.stats().gap_texels, b.stats().gap_texels);
      ExpectIdenticalColliders(a, b, 2000, 0.05f);
    }
  }
}

TEST(BodyMapGaps, SequenceBlendsGapsWhereBothPosesHaveThem) {
  // The plate rises by 0.04 m from t = 0 to t = 1; at t = 1 the mid plate is gone.
  ZBox raised = kPlate;
  raised.z_lo += 0.04f;
  raised.z_hi += 0.04f;
  std::vector<BodyMapPose> poses = {LayeredPose(3, kStack), LayeredPose(3, {kBlock, raised})};
  poses[0].time = 0.f;
  poses[1].time = 1.f;
  BodyMapSequence sequence;
  ASSERT_TRUE(sequence.Build(poses, DepthSampling::kNearest, PoseBlend::kBracket).ok());
  BodyMapCollider scratch;
  const BodyMapCollider& blended = sequence.At(0.25f, &scratch);
  ASSERT_EQ(&blended, &scratch);
  EXPECT_EQ(blended.layers(), 3u);
  float upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers];
  // Under the plate only: one gap in both poses, blended.
  ASSERT_EQ(BodyMapColliderAccess::TexelGaps(blended, 30, 44, upper, lower), 1u);
  EXPECT_NEAR(upper[0], 0.11f, 1e-6);
  EXPECT_NEAR(lower[0], 0.05f, 1e-6);
  // Under both plates at t = 0, the raised plate only at t = 1: the first gap is blended (the
  // mid plate's top at t = 0 with the block's top at t = 1), the second, which pose 1 lacks,
  // ends the list.
  ASSERT_EQ(BodyMapColliderAccess::TexelGaps(blended, 48, 44, upper, lower), 1u);
  EXPECT_NEAR(upper[0], 0.11f, 1e-6);
  EXPECT_NEAR(lower[0], 0.75f * 0.075f + 0.25f * 0.05f, 1e-6);
  EXPECT_FALSE(blended.IsInside({-0.05f, 0.01f, 0.08f}));
  EXPECT_TRUE(blended.IsInside({-0.05f, 0.01f, 0.115f}));

  // The batch's lanes find a blend's gap texels as Query does (the blend refreshes the per-texel
  // gap bits they test): motions in and across the plates, bit for bit, on every lane path.
  constexpr size_t kCount = 4000;
  std::mt19937 rng(20261123u);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  const auto in = [&](float lo, float hi) { return lo + (hi - lo) * unit(rng); };
  std::vector<Float3> previous(kCount), positions(kCount),
      velocities(kCount, Float3{0.f, 0.f, -1.f});
  for (size_t k = 0; k < kCount; ++k) {
    previous[k] = {in(-24.f, 24.f) * kTexel, in(-24.f, 24.f) * kTexel, in(-0.12f, 0.14f)};
    const float reach = k % 2 == 0 ? 1.f : 6.f;  // texels: short lanes, and walks
    positions[k] = {previous[k].x + in(-reach, reach) * kTexel,
                    previous[k].y + in(-reach, reach) * kTexel, previous[k].z + in(-0.04f, 0.04f)};
  }
  ResponseParams params;
  params.friction = 0.3f;
  const OneByOne want = QueryOneByOne(blended, previous, positions, velocities, params);
  // Contacts on a gap's upper boundary (a plate's underside, its normal facing down).
  const size_t gap_contacts =
      std::count_if(want.queries.begin(), want.queries.end(), [](const ContactQuery& q) {
        return q.contact && q.normal.z < 0.f && q.point.z > 0.f && q.point.z < 0.11f;
      });
  EXPECT_GT(gap_contacts, kCount / 50);
  for (InstructionSet lanes : kEveryLanes) {
    if (!UseLanes(&scratch, lanes)) continue;  // (scratch is the blend)
    SCOPED_TRACE(LanesName(lanes));
    std::vector<Float3> got_positions = positions, got_velocities = velocities;
    std::vector<uint8_t> got_flags(kCount);
    ASSERT_TRUE(
        scratch.CollideBatch(previous, got_positions, got_velocities, got_flags, params).ok());
    for (size_t k = 0; k < kCount; ++k) {
      ASSERT_EQ(got_flags[k], want.flags[k]) << k;
      ExpectSameBits(got_positions[k], want.positions[k], "position", static_cast<int>(k));
      ExpectSameBits(got_velocities[k], want.velocities[k], "velocity", static_cast<int>(k));
    }
  }
}

// With gap layers the lanes read whether a texel has gaps from its slab's top (its lowest mantissa
// bit, set by Finish), not from a second table: the bit must mark exactly the texels with gaps,
// after Build and after a blend, and move a top by at most one ulp, upward. Without gap layers
// the tops are the maps' own values.
TEST(BodyMapGaps, SlabTopsCarryTheGapFlagWithinOneUlp) {
  const auto flag = [](float top) { return (std::bit_cast<uint32_t>(top) & 1u) != 0u; };
  const auto check = [&](const BodyMapCollider& c, const BodyMapPose* pose) {
    float upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers];
    size_t valid = 0, with_gaps = 0, moved = 0, moved_below_zero = 0;
    for (uint32_t j = 0; j < c.height(); ++j) {
      for (uint32_t i = 0; i < c.width(); ++i) {
        float top = 0.f, bottom = 0.f;
        if (!BodyMapColliderAccess::TexelSlab(c, i, j, &top, &bottom)) continue;
        ++valid;
        const bool gaps = BodyMapColliderAccess::TexelGaps(c, i, j, upper, lower) != 0u;
        with_gaps += gaps;
        if (c.layers() > 1) {
          EXPECT_EQ(flag(top), gaps) << i << ", " << j;
        }
        if (pose == nullptr) continue;
        const float map_top = pose->front_z - pose->depth_f32[0][size_t{j} * c.width() + i];
        if (c.layers() == 1) {
          EXPECT_EQ(std::bit_cast<uint32_t>(top), std::bit_cast<uint32_t>(map_top));
        } else {
          EXPECT_TRUE(top == map_top || top == std::nextafter(map_top, 1.f)) << i << ", " << j;
        }
        moved += top != map_top;
        moved_below_zero += top != map_top && map_top < 0.f;
      }
    }
    return std::array<size_t, 4>{valid, with_gaps, moved, moved_below_zero};
  };
  // The stack, and eight stacks of two posts below z = 0 (a gap between them, tops a millimetre
  // apart): moving a negative top up is a step the other way in its bits.
  std::vector<ZBox> boxes = kStackAndPosts;
  for (int m = 0; m < 8; ++m) {
    const float y = static_cast<float>(10 + 4 * m) * kTexel;
    const float top = -0.15f - 0.001f * static_cast<float>(m);
    boxes.push_back({34 * kTexel, 38 * kTexel, y, y + 3 * kTexel, -0.2f, -0.18f});
    boxes.push_back({34 * kTexel, 38 * kTexel, y, y + 3 * kTexel, -0.17f, top});
  }
  const BodyMapPose paper_pose = LayeredPose(1, boxes);
  const BodyMapPose layered_pose = LayeredPose(3, boxes);
  const std::array<size_t, 4> paper = check(BuildOrDie(paper_pose), &paper_pose);
  EXPECT_EQ(paper[1], 0u);
  EXPECT_EQ(paper[2], 0u);
  const std::array<size_t, 4> layered = check(BuildOrDie(layered_pose), &layered_pose);
  EXPECT_EQ(layered[1], 40u * 40u + 8u * 4u * 3u);  // under the plate, and the posts
  // Tops that held the other bit are moved, some of them below z = 0 (a test that moved none
  // would test nothing).
  EXPECT_GT(layered[2], 0u);
  EXPECT_GT(layered[3], 0u);
  // A blend: the plate rises and the mid plate goes, so texels gain and lose gaps between poses.
  ZBox raised = kPlate;
  raised.z_lo += 0.04f;
  raised.z_hi += 0.04f;
  std::vector<BodyMapPose> poses = {layered_pose, LayeredPose(3, {kBlock, raised, kLowPost})};
  poses[0].time = 0.f;
  poses[1].time = 1.f;
  BodyMapSequence sequence;
  ASSERT_TRUE(sequence.Build(poses, DepthSampling::kNearest, PoseBlend::kBracket).ok());
  BodyMapCollider scratch;
  for (float t : {0.25f, 0.75f, 0.4f}) {
    SCOPED_TRACE(::testing::Message() << "t = " << t);
    const std::array<size_t, 4> blended = check(sequence.At(t, &scratch), nullptr);
    EXPECT_GT(blended[1], 0u);
  }
}

// CollideBatch answers every particle as Query and ApplyResponse do, bit for bit, whichever of
// its paths (four particles at once when they stay in one texel or cross one edge, or one by
// one) takes the particle: resting and sliding motions, points, starts inside, background,
// motions off the grid or beyond the clip box, longer motions, texels with gaps, and non-finite
// input in any of the three arrays.
// Query's long walks step 8x8 blocks; the batch's lanes step texels. A segment through a texel
// corner on a block's edge is where the block walk could begin a block in another texel than the
// texel walk (the crossing point's other coordinate rounds across an edge): both must visit the
// same texels, so the answers are the same bits. (Without 7497812, 190 of the sphere's 40 000
// differ.)

// Beside a gap that closes (the air between an arm and the torso, shut a texel further on by a
// wall of body), a point inside the wall at the gap's height is a fraction of a texel from the
// air and far from either surface along z: it leaves sideways into the gap, whatever its distance
// to the silhouette; the batch gives the same answer in every lane pack.
TEST(BodyMapGaps, StartInsideBesideAGapLeavesThroughIt) {
  // The stack's block and plate, and a wall from the block's bottom to the plate's top beside
  // the plate (the boxes stay disjoint: the block is cut around the wall).
  constexpr ZBox kBlockLeft{-30 * kTexel, 20 * kTexel, -30 * kTexel, 30 * kTexel, -0.10f, 0.05f};
  constexpr ZBox kBlockRight{22 * kTexel, 30 * kTexel, -30 * kTexel, 30 * kTexel, -0.10f, 0.05f};
  constexpr ZBox kWall{20 * kTexel, 22 * kTexel, -20 * kTexel, 20 * kTexel, -0.10f, 0.12f};
  const BodyMapCollider c = BuildOrDie(LayeredPose(3, {kBlockLeft, kBlockRight, kPlate, kWall}));
  const Float3 in_wall{20.3f * kTexel, 0.5f * kTexel, 0.075f};  // 10 texels from the background
  ASSERT_TRUE(c.IsInside(in_wall));
  ASSERT_FALSE(c.IsInside({19.5f * kTexel, in_wall.y, in_wall.z})) << "the gap's air";
  const ContactQuery q = c.Query(in_wall, in_wall);
  ASSERT_TRUE(q.contact);
  EXPECT_EQ(q.flags, kCollisionStartedInside | kCollisionSideWall);
  EXPECT_NEAR(q.point.x, 20.f * kTexel, kWallTolerance);
  EXPECT_LE(q.point.x, 20.f * kTexel);
  EXPECT_NEAR(q.depth, 0.3f * kTexel, kWallTolerance);
  EXPECT_LT(AngleDegrees(q.normal, {-1.f, 0.f, 0.f}), 0.01);
  EXPECT_FALSE(c.IsInside(q.point));
  ExpectEveryLanePackAnswersAsQuery(c, in_wall);
}

}  // namespace
}  // namespace drape

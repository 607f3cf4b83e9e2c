// BodyMapCollider::CollideBatch's lanes: every lane pack (the scalar reference, SSE2, AVX2)
// answers every particle bit for bit as Query and the response do, alone and through the batch,
// at one and two threads.
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

TEST(BodyMapBatch, LongWalksThroughBlockEdgeCornersAnswerAsQuery) {
  BodyMapCollider bodies[2] = {BuildOrDie(MakePose(SphereGrid(), Sphere)),
                               BuildOrDie(LayeredPose(3, kStack))};
  ResponseParams params;
  params.friction = 0.3f;
  params.restitution = 0.25f;
  params.separation = 2e-4f;
  std::mt19937 rng(20261124);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  for (BodyMapCollider& c : bodies) {
    const float texel = c.texel_size();
    const Float3 lo = c.bounds_min(), hi = c.bounds_max();
    const int blocks_u = static_cast<int>(c.width()) / 8,
              blocks_v = static_cast<int>(c.height()) / 8;
    ASSERT_GT(blocks_u, 2);
    ASSERT_GT(blocks_v, 2);
    constexpr size_t kCount = 40000;
    std::vector<Float3> previous(kCount), positions(kCount), velocities(kCount);
    for (size_t k = 0; k < kCount; ++k) {
      // Through a texel corner on a block's edge (a lattice point with u or v a multiple of 8),
      // at a random fraction of a 12-30 texel motion.
      const bool on_u_edge = unit(rng) < 0.5f;
      const auto lattice = [&](int blocks, bool block_edge) {
        const float block =
            static_cast<float>(1 + static_cast<int>(unit(rng) * static_cast<float>(blocks - 2)));
        return 8.f * block +
               (block_edge ? 0.f : static_cast<float>(static_cast<int>(unit(rng) * 8.f)));
      };
      const float corner_u = lattice(blocks_u, on_u_edge);
      const float corner_v = lattice(blocks_v, !on_u_edge);
      const float angle = unit(rng) * 6.2831853f, length = 12.f + 18.f * unit(rng);
      const float before = (0.2f + 0.6f * unit(rng)) * length;
      const float du = std::cos(angle), dv = std::sin(angle);
      const Float3 corner{c.origin_x() + corner_u * texel, c.origin_y() + corner_v * texel, 0.f};
      const float z0 = lo.z + (hi.z - lo.z) * (1.2f * unit(rng) - 0.1f);
      const float z1 = lo.z + (hi.z - lo.z) * (1.2f * unit(rng) - 0.1f);
      previous[k] = {corner.x - du * before * texel, corner.y - dv * before * texel, z0};
      positions[k] = {corner.x + du * (length - before) * texel,
                      corner.y + dv * (length - before) * texel, z1};
      velocities[k] = RandomPoint(rng, -1.f, 1.f, -1.f, 1.f);
    }
    const OneByOne want = QueryOneByOne(c, previous, positions, velocities, params);
    const size_t contacts = std::count_if(want.queries.begin(), want.queries.end(),
                                          [](const ContactQuery& q) { return q.contact; });
    EXPECT_GT(contacts, kCount / 10);
    for (InstructionSet lanes : kEveryLanes) {  // each the CPU has
      if (!UseLanes(&c, lanes)) continue;
      SCOPED_TRACE(LanesName(lanes));
      std::vector<Float3> got_positions = positions, got_velocities = velocities;
      std::vector<uint8_t> got_flags(kCount);
      ASSERT_TRUE(c.CollideBatch(previous, got_positions, got_velocities, got_flags, params).ok());
      size_t differing = 0;
      for (size_t k = 0; k < kCount; ++k) {
        differing += got_flags[k] != want.flags[k] ||
                     std::memcmp(&got_positions[k], &want.positions[k], sizeof(Float3)) != 0 ||
                     std::memcmp(&got_velocities[k], &want.velocities[k], sizeof(Float3)) != 0;
      }
      EXPECT_EQ(differing, 0u);
    }
  }
}

TEST(BodyMapBatch, AnswersAsQueryAndResponseBitForBit) {
  // The stack and posts with 3 and with 4 layers: groups whose lanes' texels have fewer gaps than
  // the collider has layers for gather only the layers some lane has (GatherGapLanes).
  constexpr int kBodies = 5;
  BodyMapCollider bodies[kBodies] = {
      BuildOrDie(MakePose(SphereGrid(), Sphere)), BuildOrDie(MakePose(BoxGrid(), Box)),
      BuildOrDie(MakePose(SphereGrid(), ThinSlab)), BuildOrDie(LayeredPose(3, kStackAndPosts)),
      BuildOrDie(LayeredPose(4, kStackAndPosts))};
  ResponseParams params;
  params.friction = 0.3f;
  params.restitution = 0.25f;
  params.separation = 2e-4f;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  std::mt19937 rng(20261123);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  size_t answered_walls = 0, answered_inside = 0, answered_entries = 0;  // scalar short lanes
  size_t answered_outside = 0, answered_gap_contacts = 0, answered_gap_inside = 0;
  size_t walked_answered = 0, walked_walls = 0, walked_inside = 0, walked_entries = 0;
  size_t walked_clipped_entries = 0, walked_z_face = 0, walked_long = 0;  // walking lanes
  size_t walked_gap_contacts = 0, walked_gap_starts = 0;
  size_t steep_short = 0, steep_walked = 0;  // from a gap through the start texel's whole slab
  size_t walks_answered[3] = {};             // by instruction set: the walks each pack answers
  for (int body = 0; body < kBodies; ++body) {
    SCOPED_TRACE(::testing::Message() << "body " << body);
    BodyMapCollider& c = bodies[body];
    const Float3 lo = c.bounds_min(), hi = c.bounds_max();
    const float texel = c.texel_size();
    const auto point = [&](float pad) {
      return Float3{lo.x - pad + unit(rng) * (hi.x - lo.x + 2.f * pad),
                    lo.y - pad + unit(rng) * (hi.y - lo.y + 2.f * pad),
                    lo.z - pad + unit(rng) * (hi.z - lo.z + 2.f * pad)};
    };
    constexpr size_t kCount = 40001;  // not a multiple of four: the one-by-one tail runs too
    std::vector<Float3> previous(kCount), positions(kCount), velocities(kCount);
    for (size_t k = 0; k < kCount; ++k) {
      Float3 p0 = point(0.01f), p1 = p0;
      switch (k % 8) {
        case 0:  // a point (a particle at rest)
          break;
        case 1: {  // cloth on the surface: from up to 2 mm above the front or below the back
                   // surface, a hundredth of a texel or up to 0.6 texel sideways, into it
          const float u = (p0.x - c.origin_x()) / texel, v = (p0.y - c.origin_y()) / texel;
          float top = 0.f, bottom = 0.f;
          if (u >= 0.f && v >= 0.f &&
              BodyMapColliderAccess::TexelSlab(c, static_cast<uint32_t>(u),
                                               static_cast<uint32_t>(v), &top, &bottom)) {
            const bool front = unit(rng) < 0.7f;
            p0.z = front ? top + 0.002f * unit(rng) : bottom - 0.002f * unit(rng);
            const float reach = (unit(rng) < 0.3f ? 0.02f : 1.2f) * texel;
            p1 = p0 + Float3{(unit(rng) - 0.5f) * reach, (unit(rng) - 0.5f) * reach,
                             (front ? -1.f : 1.f) * 0.004f * unit(rng)};
          }
          break;
        }
        case 2: {  // sliding: under half a texel, along z through a surface; a quarter of them
                   // steep, through a whole part
          const float rise = unit(rng) < 0.25f ? 1.f : 0.05f;
          p1 = p0 + Float3{(unit(rng) - 0.5f) * 0.8f * texel, (unit(rng) - 0.5f) * 0.8f * texel,
                           (unit(rng) - 0.5f) * rise};
          break;
        }
        case 3: {  // a few texels; a quarter of them steep, through a whole part in one texel
          const float rise = unit(rng) < 0.25f ? 1.f : 0.02f;
          p1 = p0 + Float3{(unit(rng) - 0.5f) * 6.f * texel, (unit(rng) - 0.5f) * 6.f * texel,
                           (unit(rng) - 0.5f) * rise};
          break;
        }
        case 4:  // beyond the clip box in z, or off the grid
          p0.z = unit(rng) < 0.5f ? hi.z + 0.01f : lo.z - 0.01f;
          p1 = unit(rng) < 0.5f ? Float3{p0.x, p0.y, 0.f} : point(0.3f);
          break;
        case 5: {  // starting or ending exactly on a surface value of the texel's slab
          const float u = (p0.x - c.origin_x()) / texel, v = (p0.y - c.origin_y()) / texel;
          float top = 0.f, bottom = 0.f;
          if (u >= 0.f && v >= 0.f &&
              BodyMapColliderAccess::TexelSlab(c, static_cast<uint32_t>(u),
                                               static_cast<uint32_t>(v), &top, &bottom)) {
            p0.z = unit(rng) < 0.5f ? top : bottom;
            p1 = Float3{p0.x, p0.y, p0.z + (unit(rng) - 0.5f) * 0.01f};
          }
          if (unit(rng) < 0.5f) {  // or ending exactly on one, 1-4 texels sideways
            const float angle = unit(rng) * 6.2831853f, reach = (1.f + 3.f * unit(rng)) * texel;
            p1 = p0 + Float3{reach * std::cos(angle), reach * std::sin(angle), 0.f};
            const float u1 = (p1.x - c.origin_x()) / texel, v1 = (p1.y - c.origin_y()) / texel;
            if (u1 >= 0.f && v1 >= 0.f &&
                BodyMapColliderAccess::TexelSlab(c, static_cast<uint32_t>(u1),
                                                 static_cast<uint32_t>(v1), &top, &bottom)) {
              bool front = unit(rng) < 0.5f;
              // In a texel with gaps, on a gap's boundary half the time (the lower one is the
              // top of the interval below it).
              float upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers];
              const uint32_t gaps = BodyMapColliderAccess::TexelGaps(
                  c, static_cast<uint32_t>(u1), static_cast<uint32_t>(v1), upper, lower);
              if (gaps > 0 && unit(rng) < 0.5f) {
                const uint32_t g =
                    static_cast<uint32_t>(unit(rng) * static_cast<float>(gaps)) % gaps;
                front = unit(rng) < 0.5f;
                top = lower[g];
                bottom = upper[g];
              }
              p1.z = front ? top : bottom;
              p0.z = p1.z + (front ? 1.f : -1.f) * 0.001f * unit(rng);
            }
            // Or starting exactly on a gap's boundary of its own texel, moving sideways.
            float upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers];
            const uint32_t gaps = u >= 0.f && v >= 0.f ? BodyMapColliderAccess::TexelGaps(
                                                             c, static_cast<uint32_t>(u),
                                                             static_cast<uint32_t>(v), upper, lower)
                                                       : 0u;
            if (gaps > 0 && unit(rng) < 0.5f) {
              const uint32_t g = static_cast<uint32_t>(unit(rng) * static_cast<float>(gaps)) % gaps;
              p0.z = unit(rng) < 0.5f ? upper[g] : lower[g];
              p1.z = p0.z + (unit(rng) - 0.5f) * 0.004f;
            }
          }
          break;
        }
        case 6: {  // non-finite input in one coordinate of one of the three arrays
          const float bad = unit(rng) < 0.5f ? nan : (unit(rng) < 0.5f ? inf : -inf);
          float* target[3] = {&p0.x, &p1.z, nullptr};
          const int which = static_cast<int>(unit(rng) * 3.f) % 3;
          if (target[which] != nullptr) *target[which] = bad;
          break;
        }
        default:  // long, across the box
          p1 = point(0.1f);
          break;
      }
      previous[k] = p0;
      positions[k] = p1;
      velocities[k] = RandomPoint(rng, -1.f, 1.f, -1.f, 1.f);
      if (k % 8 == 6 && k % 24 == 22) velocities[k].y = nan;
      // Motions from a gap out through the whole slab of their start texel, where that slab
      // ends inside the clip box (so the clipped motion leaves it too): the lanes must not take
      // a texel's slab for its gaps there.
      const float u = (p0.x - c.origin_x()) / texel, v = (p0.y - c.origin_y()) / texel;
      float upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers], top = 0.f, bottom = 0.f;
      // On the grid before the casts (p0 may be infinite: a float-to-integer cast of it is
      // undefined).
      if (u >= 0.f && v >= 0.f && u < static_cast<float>(c.width()) &&
          v < static_cast<float>(c.height()) && IsFinite(p1) &&
          BodyMapColliderAccess::TexelSlab(c, static_cast<uint32_t>(u), static_cast<uint32_t>(v),
                                           &top, &bottom)) {
        const uint32_t gaps = BodyMapColliderAccess::TexelGaps(
            c, static_cast<uint32_t>(u), static_cast<uint32_t>(v), upper, lower);
        bool in_gap = false;
        for (uint32_t g = 0; g < gaps; ++g) in_gap |= p0.z < upper[g] && p0.z > lower[g];
        if (in_gap && ((p1.z > top && top < hi.z) || (p1.z < bottom && bottom > lo.z))) {
          const float edges = std::fabs(std::floor((p1.x - c.origin_x()) / texel) - std::floor(u)) +
                              std::fabs(std::floor((p1.y - c.origin_y()) / texel) - std::floor(v));
          (edges <= 1.f ? steep_short : steep_walked) += 1;
        }
      }
    }
    // The reference: one particle at a time through the documented contract.
    std::vector<Float3> want_positions = positions, want_velocities = velocities;
    std::vector<uint8_t> want_flags(kCount);
    uint32_t want_contacts = 0;
    for (size_t k = 0; k < kCount; ++k) {
      if (!IsFinite(previous[k]) || !IsFinite(positions[k]) || !IsFinite(velocities[k])) {
        want_flags[k] = kCollisionInvalidInput;
        continue;
      }
      const ContactQuery q = c.Query(previous[k], positions[k]);
      if (!q.contact) {
        want_flags[k] = kCollisionNone;
        continue;
      }
      ApplyResponse(q, params, &want_positions[k], &want_velocities[k]);
      want_flags[k] = static_cast<uint8_t>(kCollisionContact | q.flags);
      ++want_contacts;
    }
    EXPECT_GT(want_contacts, kCount / 10);
    for (int run = 0; run < 6; ++run) {  // 1 and 2 threads; each lane path the CPU has
      const int threads = 1 + run % 2;
      const InstructionSet lanes = kEveryLanes[run / 2];
      if (!UseLanes(&c, lanes)) continue;
      SCOPED_TRACE(::testing::Message() << threads << " thread(s), " << LanesName(lanes));
      test::UseWorkers(threads);
      std::vector<Float3> got_positions = positions, got_velocities = velocities;
      std::vector<uint8_t> got_flags(kCount, 0xee);
      uint32_t got_contacts = 0;
      const Status status =
          c.CollideBatch(previous, got_positions, got_velocities, got_flags, params, &got_contacts);
      test::UseDefaultWorkers();
      ASSERT_TRUE(status.ok()) << status.message();
      EXPECT_EQ(got_contacts, want_contacts);
      int differing = 0;
      for (size_t k = 0; k < kCount && differing < 10; ++k) {
        const bool same = got_flags[k] == want_flags[k] &&
                          std::memcmp(&got_positions[k], &want_positions[k], sizeof(Float3)) == 0 &&
                          std::memcmp(&got_velocities[k], &want_velocities[k], sizeof(Float3)) == 0;
        if (!same) {
          ++differing;
          ADD_FAILURE() << "particle " << k << " (kind " << k % 8 << "): flags "
                        << int(got_flags[k]) << " want " << int(want_flags[k]);
        }
      }
    }
    // The short-motion lanes must carry a real share of these particles: points, resting and
    // sliding motions, surface starts, in one texel or across one texel edge. Every pack answers
    // the lanes the scalar reference does, with the same bits and the same long motions.
    size_t answered = 0;
    // Whether p's texel has gaps: the lanes solve those texels' intervals themselves.
    const auto has_gaps = [&](Float3 p) {
      const float u = (p.x - c.origin_x()) / texel, v = (p.y - c.origin_y()) / texel;
      float upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers];
      return u >= 0.f && v >= 0.f &&
             BodyMapColliderAccess::TexelGaps(c, static_cast<uint32_t>(u), static_cast<uint32_t>(v),
                                              upper, lower) > 0;
    };
    std::vector<Float3> scratch_positions = positions, scratch_velocities = velocities;
    std::vector<uint8_t> scratch_flags(kCount);
    std::vector<uint32_t> four_answered, four_long;
    for (InstructionSet kind : kEveryLanes) {
      if (!UseLanes(&c, kind)) {
        std::printf("this CPU lacks the %s: their short motions are not tested\n", LanesName(kind));
        continue;
      }
      const int width = BodyMapColliderAccess::LaneWidth(kind);
      SCOPED_TRACE(::testing::Message() << LanesName(kind) << ", short motions");
      scratch_positions = positions;
      scratch_velocities = velocities;
      for (size_t k = 0; k + static_cast<size_t>(width) <= kCount;
           k += static_cast<size_t>(width)) {
        uint32_t long_motions = 0;
        const uint32_t lanes = BodyMapColliderAccess::CollideShort(
            c, kind, &previous[k], &scratch_positions[k], &scratch_velocities[k], &scratch_flags[k],
            params, &long_motions);
        if (kind == InstructionSet::kScalar) {
          four_answered.push_back(lanes);
          four_long.push_back(long_motions);
        } else if (width == 4) {
          const size_t group = k / 4;
          ASSERT_EQ(lanes, four_answered[group]) << "group " << k;
          ASSERT_EQ(long_motions, four_long[group]) << "group " << k;
        } else {
          const size_t group = k / 4;
          ASSERT_EQ(lanes, four_answered[group] | four_answered[group + 1] << 4) << "group " << k;
          ASSERT_EQ(long_motions, four_long[group] | four_long[group + 1] << 4) << "group " << k;
        }
        for (int lane = 0; lane < width; ++lane) {
          const size_t q = k + static_cast<size_t>(lane);
          if (!((lanes >> lane) & 1u)) {
            // Not answered: written back, the same bits, for the walk to read.
            ASSERT_TRUE(std::memcmp(&scratch_positions[q], &positions[q], sizeof(Float3)) == 0 &&
                        std::memcmp(&scratch_velocities[q], &velocities[q], sizeof(Float3)) == 0)
                << "short-motion lane not answered, but changed: particle " << q;
            continue;
          }
          ASSERT_TRUE(scratch_flags[q] == want_flags[q] &&
                      std::memcmp(&scratch_positions[q], &want_positions[q], sizeof(Float3)) == 0 &&
                      std::memcmp(&scratch_velocities[q], &want_velocities[q], sizeof(Float3)) == 0)
              << "short-motion lane: particle " << q << " (kind " << q % 8 << ")";
          if (kind != InstructionSet::kScalar) continue;
          ++answered;
          answered_outside +=
              !(previous[q].x >= lo.x && previous[q].x <= hi.x && previous[q].y >= lo.y &&
                previous[q].y <= hi.y && previous[q].z >= lo.z && previous[q].z <= hi.z);
          const uint8_t f = scratch_flags[q];
          answered_walls += (f & kCollisionSideWall) != 0;
          answered_inside += (f & kCollisionStartedInside) != 0;
          answered_entries += f == kCollisionContact;
          const bool at_gaps = has_gaps(previous[q]) || has_gaps(positions[q]);
          answered_gap_contacts += at_gaps && (f & kCollisionContact) != 0;
          answered_gap_inside += at_gaps && (f & kCollisionStartedInside) != 0;
        }
      }
    }

    // (The thin slab's 2 mm clip box sends most motions to the walk.)
    EXPECT_GT(answered, kCount / (body == 2 ? 40 : 5));

    // The walking lanes alone, in every pack the CPU runs, on groups of particles
    // spread over the set (and on partial groups): every lane they answer is the reference bit
    // for bit, and lanes they do not answer (or that are not in the mask) are untouched. The
    // counts below are of the scalar pack.
    for (InstructionSet kind : kEveryLanes) {
      if (!UseLanes(&c, kind)) {
        std::printf("this CPU lacks the %s: their walks are not tested\n", LanesName(kind));
        continue;
      }
      const int width = BodyMapColliderAccess::LaneWidth(kind);
      SCOPED_TRACE(::testing::Message() << LanesName(kind) << ", walks");
      const bool count = kind == InstructionSet::kScalar;
      scratch_positions = positions;
      scratch_velocities = velocities;
      std::fill(scratch_flags.begin(), scratch_flags.end(), uint8_t{0xee});
      size_t answered_here = 0;
      const uint32_t all = (1u << width) - 1u;
      for (uint32_t k = 0; k + static_cast<uint32_t>(width) * 997 < kCount; ++k) {
        uint32_t index[8];
        for (int lane = 0; lane < width; ++lane)
          index[lane] = k + static_cast<uint32_t>(lane) * 997;
        const uint32_t mask =
            k % 7 == 3 ? 0x5u : (k % 7 == 5 ? 0x2u : (k % 7 == 6 ? 0xa6u & all : all));
        const uint32_t lanes = BodyMapColliderAccess::CollideWalks(
            c, kind, index, mask, previous.data(), scratch_positions.data(),
            scratch_velocities.data(), scratch_flags.data(), params);
        ASSERT_EQ(lanes & ~mask, 0u);
        for (int lane = 0; lane < width; ++lane) {
          const uint32_t q = index[lane];
          if (!((lanes >> lane) & 1u)) {
            ASSERT_EQ(scratch_flags[q], 0xee) << "particle " << q << " not answered but written";
            continue;
          }
          ++answered_here;
          const bool same =
              scratch_flags[q] == want_flags[q] &&
              std::memcmp(&scratch_positions[q], &want_positions[q], sizeof(Float3)) == 0 &&
              std::memcmp(&scratch_velocities[q], &want_velocities[q], sizeof(Float3)) == 0;
          ASSERT_TRUE(same) << "walking lane: particle " << q << " (kind " << q % 8 << "): flags "
                            << int(scratch_flags[q]) << " want " << int(want_flags[q]);
          if (!count) continue;
          const bool clipped = !(previous[q].z >= lo.z && previous[q].z <= hi.z &&
                                 positions[q].z >= lo.z && positions[q].z <= hi.z);
          const uint32_t texels =
              static_cast<uint32_t>(std::abs(std::floor((positions[q].x - c.origin_x()) / texel) -
                                             std::floor((previous[q].x - c.origin_x()) / texel)) +
                                    std::abs(std::floor((positions[q].y - c.origin_y()) / texel) -
                                             std::floor((previous[q].y - c.origin_y()) / texel)));
          const uint8_t f = want_flags[q];
          walked_walls += (f & kCollisionSideWall) != 0;
          walked_inside += (f & kCollisionStartedInside) != 0;
          walked_entries += f == kCollisionContact;
          walked_clipped_entries += clipped && f == kCollisionContact;
          walked_z_face += clipped && f == kCollisionContact && previous[q].x == positions[q].x &&
                           previous[q].y == positions[q].y;
          walked_long += texels >= 3 && (f & kCollisionContact) != 0;
          // Contacts where the motion starts or ends in a texel with gaps (the walk's own visit
          // and IntervalAt answer those inside the lanes).
          walked_gap_contacts +=
              (f & kCollisionContact) != 0 && (has_gaps(previous[q]) || has_gaps(positions[q]));
          // Starts strictly inside a gap, which the lanes' start test does not look for (their
          // answers must match anyway: the note at start_inside in body_map/lanes/walk_lanes.inl).
          const auto in_a_gap = [&](Float3 p) {
            const float u = (p.x - c.origin_x()) / texel, v = (p.y - c.origin_y()) / texel;
            float upper[kMaxBodyMapLayers], lower[kMaxBodyMapLayers];
            if (!(u >= 0.f && v >= 0.f)) return false;
            const uint32_t gaps = BodyMapColliderAccess::TexelGaps(
                c, static_cast<uint32_t>(u), static_cast<uint32_t>(v), upper, lower);
            for (uint32_t g = 0; g < gaps; ++g) {
              if (p.z < upper[g] && p.z > lower[g]) return true;
            }
            return false;
          };
          walked_gap_starts += in_a_gap(previous[q]);
        }
        // Restore what the lanes wrote, so later groups see the input.
        for (int lane = 0; lane < width; ++lane) {
          const uint32_t q = index[lane];
          scratch_positions[q] = positions[q];
          scratch_velocities[q] = velocities[q];
          scratch_flags[q] = 0xee;
        }
      }
      walks_answered[static_cast<int>(kind)] += answered_here;
    }
  }
  walked_answered = walks_answered[static_cast<int>(InstructionSet::kScalar)];
  // ... and every kind of contact it can give: side walls, surface entries, push-outs.
  EXPECT_GT(answered_walls, 200u);
  EXPECT_GT(answered_entries, 2000u);
  EXPECT_GT(answered_inside, 10000u);
  EXPECT_GT(answered_outside, 1000u);  // points that stay outside the clip box
  // ... in texels with gaps too (their intervals, gap surfaces' normals, push-outs among gaps).
  EXPECT_GT(answered_gap_contacts, 1000u);
  EXPECT_GT(answered_gap_inside, 500u);
  // The layered body's posts and the steep motions make these (see kStackAndPosts).
  EXPECT_GT(steep_short, 10u);
  EXPECT_GT(steep_walked, 50u);
  // ... and the walking lanes: most particles, every kind of contact, entries of motions clipped
  // to the box (through its top or bottom face among them), contacts three or more texels away.
  EXPECT_GT(walked_answered, 60000u);
  EXPECT_GT(walked_walls, 500u);
  EXPECT_GT(walked_entries, 5000u);
  EXPECT_GT(walked_inside, 5000u);
  EXPECT_GT(walked_clipped_entries, 500u);
  EXPECT_GT(walked_z_face, 500u);
  EXPECT_GT(walked_long, 500u);
  EXPECT_GT(walked_gap_contacts, 500u);
  EXPECT_GT(walked_gap_starts, 100u);
  // The SIMD packs answer about as many as the scalar one: the walks they give up on are the same.
  for (InstructionSet kind : {InstructionSet::kSse2, InstructionSet::kAvx2}) {
    if (UseLanes(&bodies[0], kind)) {
      EXPECT_GT(walks_answered[static_cast<int>(kind)], 300000u) << LanesName(kind);
    }
  }
  std::printf("short-motion lanes: %zu contacts at texels with gaps, %zu of them pushed out\n",
              answered_gap_contacts, answered_gap_inside);
  std::printf("motions from a gap through the whole slab: %zu within one texel edge, %zu walked\n",
              steep_short, steep_walked);
  std::printf(
      "walking lanes: %zu answered, %zu walls, %zu entries (%zu clipped, %zu through the "
      "box's z face), %zu pushed out, %zu contacts >= 3 texels away, %zu at texels with gaps, "
      "%zu starts in a gap; %zu answered with SSE2, %zu with AVX2\n",
      walked_answered, walked_walls, walked_entries, walked_clipped_entries, walked_z_face,
      walked_inside, walked_long, walked_gap_contacts, walked_gap_starts, walks_answered[1],
      walks_answered[2]);
}

}  // namespace
}  // namespace drape

// BodyMapCollider's batch calls: CollideBatch (particles through the short-motion lanes, then the
// walking lanes, the rest one by one) and InsideBatch.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <string>

#include "drape/runtime/body_map_collider.h"
#include "tasks/parallel_for.h"

namespace drape {
namespace {

// The set bits among the low eight of a lane mask, in a few operations: std::popcount is a
// library call where the baseline x86-64 lacks popcnt, and CollideRange counts once per group.
constexpr uint32_t CountLaneBits(uint32_t lanes) {
  lanes = lanes - ((lanes >> 1) & 0x55u);
  lanes = (lanes & 0x33u) + ((lanes >> 2) & 0x33u);
  return (lanes + (lanes >> 4)) & 0x0fu;
}
static_assert(CountLaneBits(0xffu) == 8 && CountLaneBits(0xa5u) == 4 && CountLaneBits(0) == 0);

}  // namespace

uint8_t BodyMapCollider::CollideOne(Float3 from, Float3* position, Float3* velocity,
                                    const ResponseParams& params) const {
  if (!IsFinite(from) || !IsFinite(*position) || !IsFinite(*velocity)) {
    return kCollisionInvalidInput;
  }
  const ContactQuery q = QueryView(from, *position);
  if (!q.contact) return kCollisionNone;
  ApplyResponse(q, params, position, velocity);
  return static_cast<uint8_t>(kCollisionContact | q.flags);
}

uint32_t BodyMapCollider::CollideRange(const Float3* previous, Float3* positions,
                                       Float3* velocities, uint8_t* flags, size_t count,
                                       const ResponseParams& params) const {
  size_t k = 0;
  if (sampling_ == DepthSampling::kNearest && stats_.valid_texels != 0) {
    // Groups of consecutive particles go through the short-motion lanes first; the particles
    // they do not answer queue for the walking lanes, and what those do not answer goes one by
    // one: eight lanes in AVX2, four in SSE2 or in the scalar pack. Where particles move a texel
    // or more per step the short lanes answer few and their work is wasted: after a group with
    // half or more of its motions across more than one texel edge, the next kScalarParticles
    // particles queue directly. Every path gives the same bits.
    constexpr uint32_t kScalarParticles = 16;
    const InstructionSet set = instruction_set();
    const LaneKernels& kernels = set == InstructionSet::kAvx2   ? Avx2LaneKernels()
                                 : set == InstructionSet::kSse2 ? Sse2LaneKernels()
                                                                : ScalarLaneKernels();
    const uint32_t width = kernels.width;
    const auto short_lanes = kernels.short_motions;
    const auto walk_lanes = kernels.walks;
    uint32_t skip_short = 0;  // groups
    // The particles waiting for the walking lanes: fewer than `width` between groups, so a group
    // adds at most `width` more.
    uint32_t queued[16] = {};
    uint32_t queued_count = 0;
    // Walks the first `width` queued particles (all of them, padded, for the last group).
    const auto walk_queued = [&] {
      const uint32_t walked = std::min(queued_count, width);
      for (uint32_t lane = walked; lane < width; ++lane) queued[lane] = queued[0];
      const uint32_t lanes = (1u << walked) - 1u;
      const uint32_t answered =
          (this->*walk_lanes)(queued, lanes, previous, positions, velocities, flags, params);
      for (uint32_t left = lanes & ~answered; left != 0; left &= left - 1u) {
        const uint32_t q = queued[std::countr_zero(left)];
        flags[q] = CollideOne(previous[q], &positions[q], &velocities[q], params);
      }
      // The rest (fewer than `width`) to the front: a fixed copy, not a loop of data-dependent
      // length (walked + 8 <= 16; entries past queued_count are never read).
      for (uint32_t i = 0; i < 8; ++i) queued[i] = queued[walked + i];  // forward: dest <= src
      queued_count -= walked;
    };
    for (; k + width <= count; k += width) {
      uint32_t answered = 0, long_motions = 0;
      if (skip_short > 0) {
        --skip_short;
      } else {
        answered = (this->*short_lanes)(previous + k, positions + k, velocities + k, flags + k,
                                        params, &long_motions);
        if (2 * CountLaneBits(long_motions) >= width) {
          skip_short = kScalarParticles / width;
        }
      }
      // The unanswered lanes join the queue without a branch each: which lanes a group answers
      // is data, and mispredicted branches here cost more than the stores.
      for (uint32_t lane = 0; lane < width; ++lane) {
        queued[queued_count] = static_cast<uint32_t>(k + lane);
        queued_count += ((answered >> lane) & 1u) ^ 1u;
      }
      if (queued_count >= width) walk_queued();
    }
    while (queued_count != 0) walk_queued();
  }
  for (; k < count; ++k) {
    flags[k] = CollideOne(previous[k], &positions[k], &velocities[k], params);
  }
  uint32_t contacts = 0;
  for (size_t i = 0; i < count; ++i) contacts += flags[i] & kCollisionContact;
  return contacts;
}

// A view axis other than z: the particles go through CollideRange in the view frame, in pieces
// that fit on the stack (no allocation), and come back. The permutation is exact, so this is the
// z-view answer of the permuted inputs.
uint32_t BodyMapCollider::CollideRangeInViewFrame(const Float3* previous, Float3* positions,
                                                  Float3* velocities, uint8_t* flags, size_t count,
                                                  const ResponseParams& params) const {
  constexpr size_t kPiece = 256;  // 3 x 3 KiB of stack
  Float3 view_previous[kPiece], view_positions[kPiece], view_velocities[kPiece];
  const BodyMapViewAxis axis = view_axis_;
  uint32_t contacts = 0;
  for (size_t begin = 0; begin < count; begin += kPiece) {
    const size_t n = std::min(kPiece, count - begin);
    for (size_t k = 0; k < n; ++k) {
      view_previous[k] = ToBodyMapView(axis, previous[begin + k]);
      view_positions[k] = ToBodyMapView(axis, positions[begin + k]);
      view_velocities[k] = ToBodyMapView(axis, velocities[begin + k]);
    }
    contacts +=
        CollideRange(view_previous, view_positions, view_velocities, flags + begin, n, params);
    for (size_t k = 0; k < n; ++k) {
      positions[begin + k] = FromBodyMapView(axis, view_positions[k]);
      velocities[begin + k] = FromBodyMapView(axis, view_velocities[k]);
    }
  }
  return contacts;
}

Status BodyMapCollider::CollideBatch(std::span<const Float3> previous, std::span<Float3> positions,
                                     std::span<Float3> velocities, std::span<uint8_t> flags,
                                     const ResponseParams& params, uint32_t* contact_count) const {
  if (contact_count != nullptr) *contact_count = 0;
  const size_t n = positions.size();
  if (previous.size() != n || velocities.size() != n || flags.size() != n) {
    return Status(StatusCode::kInvalidArgument,
                  "BodyMapCollider::CollideBatch: span sizes differ (previous " +
                      std::to_string(previous.size()) + ", positions " + std::to_string(n) +
                      ", velocities " + std::to_string(velocities.size()) + ", flags " +
                      std::to_string(flags.size()) + ")");
  }
  if (!ValidResponse(params)) {
    return Status(StatusCode::kInvalidArgument,
                  "BodyMapCollider::CollideBatch: response parameters out of range"
                  " (friction in [0, 1], static_friction in [0, 4], restitution in [0, 1], "
                  "separation finite and >= 0)");
  }
  if (empty()) {
    return Status(StatusCode::kInvalidState, "BodyMapCollider::CollideBatch: collider not built");
  }
  // Chunks through CollideRange, for the reason InsideBatch gives, taken by the threads as
  // they finish: a particle's cost runs from a few nanoseconds (free, resting) to hundreds (long
  // walks), and cloth groups them, so equal shares in order leave a thread idle. Each particle's
  // answer depends on that particle alone, so the schedule does not change a bit.
  const int64_t count = static_cast<int64_t>(n);
  constexpr int64_t kChunk = 1024;
  detail::ChunkSum contacts;  // an integer sum: the same at any thread count
  detail::ParallelRanges(count, kChunk, [&](int64_t begin, int64_t end) {
    contacts.Add(view_axis_ == BodyMapViewAxis::kZ
                     ? CollideRange(previous.data() + begin, positions.data() + begin,
                                    velocities.data() + begin, flags.data() + begin,
                                    static_cast<size_t>(end - begin), params)
                     : CollideRangeInViewFrame(previous.data() + begin, positions.data() + begin,
                                               velocities.data() + begin, flags.data() + begin,
                                               static_cast<size_t>(end - begin), params));
  });
  if (contact_count != nullptr) *contact_count = contacts.total();
  return Status::Ok();
}

void BodyMapCollider::InsideRange(const Float3* points, uint8_t* inside, size_t count) const {
  const float origin_x = origin_x_, origin_y = origin_y_, inv_texel = inv_texel_size_;
  const float width_f = width_f_, height_f = height_f_;
  const size_t width = width_;
  const Slab* const slabs = slabs_.data();
  const BodyMapViewAxis axis = view_axis_;
  for (size_t k = 0; k < count; ++k) {
    const Float3 p = ToBodyMapView(axis, points[k]);
    const float u = (p.x - origin_x) * inv_texel;
    const float v = (p.y - origin_y) * inv_texel;
    uint8_t result = 0;
    if (u >= 0.f && v >= 0.f && u < width_f && v < height_f) {
      const Slab& slab = slabs[static_cast<size_t>(v) * width + static_cast<size_t>(u)];
      result = static_cast<uint8_t>((p.z <= slab.top) & (p.z >= slab.bottom));
    }
    inside[k] = result;
  }
}

Status BodyMapCollider::InsideBatch(std::span<const Float3> points,
                                    std::span<uint8_t> inside) const {
  if (points.size() != inside.size()) {
    return Status(StatusCode::kInvalidArgument,
                  "BodyMapCollider::InsideBatch: " + std::to_string(points.size()) +
                      " points but " + std::to_string(inside.size()) + " result slots");
  }
  const int64_t count = static_cast<int64_t>(points.size());
  if (sampling_ != DepthSampling::kNearest || gap_layers_ != 0) {
    detail::ParallelFor(count, count > 16384 ? 4096 : count,
                        [&](int64_t k) { inside[k] = IsInside(points[k]) ? 1 : 0; });
    return Status::Ok();
  }
  // Chunks of 4096 points (one below 5 of them), each through InsideRange: in a loop over shared
  // variables the uint8_t stores may alias them, so a plain loop reloads the map's fields for
  // every point (measured 2x slower).
  constexpr int64_t kChunk = 4096;
  detail::ParallelRanges(
      count, count > 4 * kChunk ? kChunk : count, [&](int64_t begin, int64_t end) {
        InsideRange(points.data() + begin, inside.data() + begin, static_cast<size_t>(end - begin));
      });
  return Status::Ok();
}

}  // namespace drape

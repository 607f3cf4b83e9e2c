// The world-space entry points: the broad phase against the colliders' swept spheres, the batch
// over all particles of a step (groups of particles share one broad phase), and Query.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "drape/runtime/hull_collider_set.h"
#include "hull/plane_kernels.h"
#include "tasks/parallel_for.h"

namespace drape {
namespace {

// Particles per chunk of a parallel batch. Each chunk taken costs an atomic on a line the workers
// share: the walking skirt's 10 100 particles on 2 workers collide 5 % faster in chunks of 512
// than of 256 (40 chunks), and its contacts still spread over 20.
constexpr int64_t kBatchGrain = 512;

}  // namespace

uint32_t HullColliderSet::BroadPhase(Float3 p0, Float3 p1, float s0, float s1, bool active,
                                     uint32_t* out) const {
  // Sphere around the particle's segment against the colliders' swept spheres. The whole-step
  // spheres filter first when the fractions are not the selected ones; the candidates are then
  // tested against their swept sphere over [s0, s1] computed here, with the same arithmetic as
  // SelectSubstep's, so both paths keep exactly the same candidates: the lowest kMaxCandidates
  // indices that pass the swept test (the whole-step test runs in chunks until that many pass).
  const Float3 mid = (p0 + p1) * 0.5f;
  const float half = Length(p1 - p0) * 0.50001f;
  if (active) {
    return kernels_->spheres(sweep_x_.data(), sweep_y_.data(), sweep_z_.data(), sweep_r_.data(),
                             collider_count_, mid, half, out, kMaxCandidates);
  }
  constexpr uint32_t kChunk = 64;  // colliders per whole-step test, a multiple of kPlanePad
  uint32_t whole_step[kChunk];
  uint32_t kept = 0;
  for (uint32_t base = 0; base < collider_count_ && kept < kMaxCandidates; base += kChunk) {
    const uint32_t chunk = std::min(kChunk, collider_count_ - base);
    const uint32_t count = kernels_->spheres(&full_x_[base], &full_y_[base], &full_z_[base],
                                             &full_r_[base], chunk, mid, half, whole_step, kChunk);
    for (uint32_t i = 0; i < count && kept < kMaxCandidates; ++i) {
      const uint32_t k = base + whole_step[i];
      Float3 center;
      float radius;
      ComputeSweep(k, s0, s1, &center, &radius);
      const float dx = mid.x - center.x, dy = mid.y - center.y, dz = mid.z - center.z;
      const float rr = radius + half;
      if (dx * dx + dy * dy + dz * dz <= rr * rr) out[kept++] = k;
    }
  }
  return kept;
}

Status HullColliderSet::CollideBatch(std::span<const Float3> previous, std::span<Float3> positions,
                                     std::span<Float3> velocities, std::span<uint8_t> flags,
                                     const ResponseParams& params, float substep_start,
                                     float substep_end, uint32_t* contact_count) const {
  if (contact_count != nullptr) *contact_count = 0;
  const size_t n = positions.size();
  if (previous.size() != n || velocities.size() != n || flags.size() != n)
    return Status(
        StatusCode::kInvalidArgument,
        "HullColliderSet::CollideBatch: previous, positions, velocities and flags differ in size");
  if (!ValidResponse(params))
    return Status(StatusCode::kInvalidArgument,
                  "HullColliderSet::CollideBatch: response parameters out of range"
                  " (friction in [0, 1], static_friction in [0, 4], restitution in [0, 1], "
                  "separation finite and >= 0)");
  if (!(substep_start >= 0.f && substep_start <= substep_end && substep_end <= 1.f))
    return Status(StatusCode::kInvalidArgument,
                  "HullColliderSet::CollideBatch: substep fractions are not 0 <= s0 <= s1 <= 1");
  const bool active = substep_start == active_s0_ && substep_end == active_s1_;
  const int64_t count = static_cast<int64_t>(n);
  // Small batches stay on the calling thread: waking workers costs more than it saves, and on a
  // loaded machine far more (measured: a 961-particle sheet 25x slower with 2 threads). Larger
  // ones go in chunks of kBatchGrain particles, taken as the workers finish (contacts cluster).
  const bool parallel = count > 4096;
  detail::ChunkSum contacts;
  if (active && collider_count_ <= kMaxGroupedColliders) {
    // The first broad phase of a group of particles at once (four or eight: the kernels' lane
    // count; no branch per particle and collider); a particle without candidates is done
    // (ResolveParticle would leave it as it is).
    const uint32_t width = kernels_->group_width;
    const uint32_t words = (collider_count_ + 31) / 32;
    const uint32_t hull_count = static_cast<uint32_t>(hulls_.size());
    const int64_t groups = (count + width - 1) / width;
    const auto group_of_particles = [&](int64_t g) -> uint32_t {
      uint32_t group_contacts = 0;
      const size_t first = static_cast<size_t>(g) * width;
      const uint32_t lanes = static_cast<uint32_t>(std::min<size_t>(width, n - first));
      uint32_t masks[8 * kMaxGroupedColliders / 32];
      const uint32_t finite =
          kernels_->sphere_masks(&previous[first], &positions[first], &velocities[first], lanes,
                                 sweep_x_.data(), sweep_y_.data(), sweep_z_.data(), sweep_r_.data(),
                                 collider_count_, sweep_union_center_, sweep_union_radius_, masks);
      const auto lanes_with_candidates = [&] {
        uint32_t bits = 0;
        for (uint32_t l = 0; l < width; ++l) {
          uint32_t any = 0;
          for (uint32_t w = 0; w < words; ++w) any |= masks[l * words + w];
          bits |= any != 0 ? 1u << l : 0u;
        }
        return bits;
      };
      uint32_t candidates = lanes_with_candidates();
      if (candidates != 0 && hull_count > 0) {
        // Then the hulls' boxes, for the whole group at once: a candidate ColliderContact would
        // reject by its box is dropped here (most are: near a body a segment's sphere meets
        // several limbs' bounding spheres), and a particle left without one is done.
        kernels_->obb_masks(&previous[first], &positions[first], lanes, obb_start_.data(),
                            obb_end_.data(), obb_half_.data(), hull_count, collider_count_,
                            options_.continuous, kMaxCandidates, masks);
        candidates = lanes_with_candidates();
      }
      // Only the invalid lanes and those with candidates need more; the others are done.
      uint32_t work = ~finite | candidates;
      work &= (1u << lanes) - 1;
      std::memset(&flags[first], kCollisionNone, lanes);
      for (; work != 0; work &= work - 1) {
        const uint32_t l = static_cast<uint32_t>(__builtin_ctz(work));
        const size_t k = first + l;
        if (!((finite >> l) & 1u)) {
          flags[k] = kCollisionInvalidInput;
          continue;
        }
        ResolveParticle<true>(previous[k], &positions[k], &velocities[k], &flags[k], params,
                              substep_start, substep_end, &masks[l * words]);
        if (flags[k] & kCollisionContact) ++group_contacts;
      }
      return group_contacts;
    };
    detail::ParallelRanges(groups, parallel ? kBatchGrain / width : groups,
                           [&](int64_t begin, int64_t end) {
                             uint32_t chunk_contacts = 0;
                             for (int64_t g = begin; g < end; ++g)
                               chunk_contacts += group_of_particles(g);
                             contacts.Add(chunk_contacts);
                           });
    if (contact_count != nullptr) *contact_count = contacts.total();
    return Status::Ok();
  }
  const auto particle = [&](int64_t i) -> uint32_t {
    const size_t k = static_cast<size_t>(i);
    if (!IsFinite(previous[k]) || !IsFinite(positions[k]) || !IsFinite(velocities[k])) {
      flags[k] = kCollisionInvalidInput;
      return 0;
    }
    if (active) {
      ResolveParticle<true>(previous[k], &positions[k], &velocities[k], &flags[k], params,
                            substep_start, substep_end);
    } else {
      ResolveParticle<false>(previous[k], &positions[k], &velocities[k], &flags[k], params,
                             substep_start, substep_end);
    }
    return (flags[k] & kCollisionContact) != 0 ? 1u : 0u;
  };
  detail::ParallelRanges(count, parallel ? kBatchGrain : count, [&](int64_t begin, int64_t end) {
    uint32_t chunk_contacts = 0;
    for (int64_t i = begin; i < end; ++i) chunk_contacts += particle(i);
    contacts.Add(chunk_contacts);
  });
  if (contact_count != nullptr) *contact_count = contacts.total();
  return Status::Ok();
}

ContactQuery HullColliderSet::Query(Float3 p0, Float3 p1, uint8_t kinds) const {
  ContactQuery best;
  if (!IsFinite(p0) || !IsFinite(p1)) {
    best.flags = kCollisionInvalidInput;
    return best;
  }
  bool inside = false;
  float depth = 0.f;
  for (uint32_t k = 0; k < motions_.size(); ++k) {
    if (!HasKind(k, kinds)) continue;
    const ContactQuery c = ColliderContact(k, active_[k], p0, p1);
    inside = inside || c.inside_end;
    depth = std::max(depth, c.depth);
    if (!c.contact) continue;
    const bool better =
        !best.contact || c.depth > best.depth || (c.depth == best.depth && c.t < best.t);
    if (better) best = c;
  }
  // Inside overlapping colliders, the deepest one's exit may lie inside another (out through the
  // far side of a large joint sphere, into the torso hull): take the nearest exit of their union.
  if (best.contact && inside && InsideAny(ExitProbe(best), kinds)) {
    UnionExit(p0, p1, kinds, &best);
  }
  best.inside_end = inside;
  best.depth = depth;
  return best;
}

bool HullColliderSet::HasKind(uint32_t collider, uint8_t kinds) const {
  const bool is_hull = collider < hulls_.size();
  return (kinds & (is_hull ? kColliderHulls : kColliderSpheres)) != 0;
}

Float3 HullColliderSet::ExitProbe(const ContactQuery& c) {
  // Just off the surface the response puts the particle on (ResponseParams' default separation).
  return c.point + c.normal * 1e-4f;
}

bool HullColliderSet::InsideAny(Float3 x, uint8_t kinds) const {
  for (uint32_t k = 0; k < motions_.size(); ++k) {
    if (HasKind(k, kinds) && ColliderContact(k, active_[k], x, x).inside_end) return true;
  }
  return false;
}

}  // namespace drape

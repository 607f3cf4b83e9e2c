// The nearest exit of the union of overlapping colliders from a point inside them: where a
// particle inside a torso piece, its neighbouring piece and a joint sphere goes, rather than out
// of the deepest one into another (docs/ALGORITHMS.md §8.6). Query comes here when the deepest
// contact's exit lies inside another collider; CollideBatch for a particle that started inside
// and is still more than kUnionExitMinDepth inside after every pass.
#include <algorithm>
#include <cmath>

#include "drape/runtime/hull_collider_set.h"
#include "hull/nudge_out.h"

namespace drape {

using detail::NudgeOut;

uint32_t HullColliderSet::CollectExits(const ExitHolders& holders, ExitKey* keys) const {
  // Every outer face of every holder (its projection is on or outside that hull) and every
  // sphere's radial exit, at most kMaxExits (the rest are left out: a point inside that many
  // faces' worth of colliders is in a pinch the contact planes handle).
  const uint32_t hull_total = static_cast<uint32_t>(hulls_.size());
  uint32_t n = 0;
  for (uint32_t i = 0; i < holders.count && n < kMaxExits; ++i) {
    const uint32_t k = holders.colliders[i];
    const Float3 local = holders.local[i];
    if (k < hull_total) {
      const HullRecord& h = hulls_[k];
      for (uint32_t j = 0; j < h.plane_count && n < kMaxExits; ++j) {
        if (plane_internal_[h.plane_begin + j]) continue;
        keys[n++] = {-PlaneSignedDistance(planes_[h.plane_begin + j], local), k, j, i};
      }
    } else {
      keys[n++] = {spheres_[k - hull_total].radius - Length(local), k, kSphereExit, i};
    }
  }
  // Only the nearest kMaxExitTries are tried: a partial sort (the order is total: the same at
  // any thread count).
  const uint32_t tries = std::min(n, kMaxExitTries);
  std::partial_sort(keys, keys + tries, keys + n);
  return tries;
}

ContactQuery HullColliderSet::ExitContact(const ExitHolders& holders, const ExitKey& key) const {
  const Float3 local = holders.local[key.holder];
  ContactQuery c;
  c.contact = true;
  c.inside_end = true;
  c.t = 0.f;
  c.depth = std::max(key.distance, 0.f);
  if (key.plane == kSphereExit) {
    const float radius = spheres_[key.collider - hulls_.size()].radius;
    const Float3 n = NormalizeOr(local, Float3{0.f, 1.f, 0.f});
    c.normal = n;
    c.point = NudgeOut(n * radius, n, radius, [&](Float3 p) { return Length(p) - radius; });
  } else {
    const Plane& plane = planes_[hulls_[key.collider].plane_begin + key.plane];
    const Float3 projected = local - plane.normal * PlaneSignedDistance(plane, local);
    c.normal = plane.normal;
    c.point = NudgeOut(projected, plane.normal, 1.f + std::fabs(plane.offset),
                       [&](Float3 p) { return PlaneSignedDistance(plane, p); });
  }
  const ActiveFrames& f = *holders.frames[key.holder];
  c.point = TransformPoint(f.to_world_end, c.point);
  c.normal = TransformVector(f.to_world_end, c.normal);
  return c;
}

template <typename IsFree>
bool HullColliderSet::FirstFreeExit(Float3 p0, const ExitHolders& holders, double max_distance,
                                    IsFree is_free, ContactQuery* exit) const {
  ExitKey keys[kMaxExits];
  const uint32_t n = CollectExits(holders, keys);
  for (uint32_t e = 0; e < n; ++e) {
    const ContactQuery c = ExitContact(holders, keys[e]);
    const Float3 d = c.point - p0;  // in double: coordinates up to float's range
    if (std::sqrt(double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z) > max_distance)
      return false;  // nearest first: the others are beyond too (up to rounding)
    if (is_free(ExitProbe(c))) {
      *exit = c;
      return true;
    }
  }
  return false;
}

bool HullColliderSet::InsideAnyCandidate(Float3 x, const ContactFrames& candidates) const {
  for (uint32_t i = 0; i < candidates.count; ++i) {
    if (ColliderContact(candidates.candidates[i], *candidates.frames[i], x, x).inside_end)
      return true;
  }
  return false;
}

bool HullColliderSet::NearestUnionExit(Float3 p0, Float3 x, const ContactFrames& candidates,
                                       double max_distance, ContactQuery* exit) const {
  ExitHolders holders;
  const ContactQuery* contacts = candidates.contacts();
  for (uint32_t i = 0; i < candidates.count; ++i) {
    if (!contacts[i].inside_end) continue;
    const uint32_t h = holders.count++;
    holders.colliders[h] = candidates.candidates[i];
    holders.frames[h] = candidates.frames[i];
    holders.local[h] = TransformPoint(candidates.frames[i]->to_local_end, x);
  }
  return FirstFreeExit(
      p0, holders, max_distance,
      [&](Float3 probe) { return !InsideAnyCandidate(probe, candidates); }, exit);
}

void HullColliderSet::UnionExit(Float3 p0, Float3 p1, uint8_t kinds, ContactQuery* best) const {
  // Query's: the holders among every collider of `kinds`, an exit outside all of them, within
  // the particle's reach (its motion plus kUnionDepthFactor times the sum of its depths, from
  // p0: the bound every response keeps). None: the deepest contact stays.
  double reach = std::sqrt(double(Dot(p1 - p0, p1 - p0)));
  ExitHolders holders;
  for (uint32_t k = 0; k < motions_.size(); ++k) {
    if (!HasKind(k, kinds)) continue;
    const ContactQuery c = ColliderContact(k, active_[k], p1, p1);
    reach += kUnionDepthFactor * c.depth;
    if (c.inside_end && holders.count < kMaxCandidates) {
      const uint32_t h = holders.count++;
      holders.colliders[h] = k;
      holders.frames[h] = &active_[k];
      holders.local[h] = TransformPoint(active_[k].to_local_end, p1);
    }
  }
  ContactQuery exit;
  if (FirstFreeExit(
          p0, holders, reach, [&](Float3 probe) { return !InsideAny(probe, kinds); }, &exit)) {
    const uint8_t flags = best->flags;  // what the contact is (started inside) stays
    *best = exit;
    best->flags = flags;
  }
}

}  // namespace drape

// The nearest exit of the union of overlapping colliders from a point inside them: where a
// particle inside a torso piece, its neighbouring piece and a joint sphere goes, rather than out
// of the deepest one into another (docs/ALGORITHMS.md §8.6).
#include <algorithm>
#include <cmath>

#include "drape/runtime/hull_collider_set.h"
#include "hull/nudge_out.h"

namespace drape {

using detail::NudgeOut;

uint32_t HullColliderSet::CollectExits(Float3 x, const uint32_t* colliders,
                                       const ActiveFrames* const* frames, uint32_t count,
                                       ExitCandidate* exits) const {
  // Every outer face of every hull holding x (its projection there is on or outside that hull),
  // and every sphere's radial exit; the nearest kMaxExits, nearest first.
  uint32_t n = 0;
  const auto add = [&](ExitCandidate e) {
    if (n < kMaxExits) {
      exits[n++] = e;
      return;
    }
    uint32_t farthest = 0;
    for (uint32_t i = 1; i < n; ++i)
      farthest = exits[i].distance > exits[farthest].distance ? i : farthest;
    if (e.distance < exits[farthest].distance) exits[farthest] = e;
  };
  const uint32_t hull_total = static_cast<uint32_t>(hulls_.size());
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t k = colliders[i];
    const Float3 local = TransformPoint(frames[i]->to_local_end, x);
    if (k < hull_total) {
      const HullRecord& h = hulls_[k];
      float max_value = -INFINITY;
      for (uint32_t j = 0; j < h.plane_count; ++j)
        max_value = std::max(max_value, PlaneSignedDistance(planes_[h.plane_begin + j], local));
      if (max_value > 0.f) continue;  // not inside this hull
      for (uint32_t j = 0; j < h.plane_count; ++j) {
        if (plane_internal_[h.plane_begin + j]) continue;
        add({-PlaneSignedDistance(planes_[h.plane_begin + j], local), k, j, frames[i]});
      }
    } else {
      const float radius = spheres_[k - hull_total].radius;
      const float r = Length(local);
      if (r > radius) continue;
      add({radius - r, k, kSphereExit, frames[i]});
    }
  }
  // Ties keep the collider and plane order: identical at any thread count.
  std::sort(exits, exits + n, [](const ExitCandidate& a, const ExitCandidate& b) {
    return a.distance < b.distance ||
           (a.distance == b.distance &&
            (a.collider < b.collider || (a.collider == b.collider && a.plane < b.plane)));
  });
  return n;
}

ContactQuery HullColliderSet::ExitContact(Float3 x, const ExitCandidate& e) const {
  const Float3 local = TransformPoint(e.frames->to_local_end, x);
  ContactQuery c;
  c.contact = true;
  c.inside_end = true;
  c.t = 0.f;
  c.depth = std::max(e.distance, 0.f);
  if (e.plane == kSphereExit) {
    const float radius = spheres_[e.collider - hulls_.size()].radius;
    const Float3 n = NormalizeOr(local, Float3{0.f, 1.f, 0.f});
    c.normal = n;
    c.point = NudgeOut(n * radius, n, radius, [&](Float3 p) { return Length(p) - radius; });
  } else {
    const Plane& plane = planes_[hulls_[e.collider].plane_begin + e.plane];
    const Float3 projected = local - plane.normal * PlaneSignedDistance(plane, local);
    c.normal = plane.normal;
    c.point = NudgeOut(projected, plane.normal, 1.f + std::fabs(plane.offset),
                       [&](Float3 p) { return PlaneSignedDistance(plane, p); });
  }
  c.point = TransformPoint(e.frames->to_world_end, c.point);
  c.normal = TransformVector(e.frames->to_world_end, c.normal);
  return c;
}

bool HullColliderSet::InsideAnyCandidate(Float3 x, const ContactFrames& candidates) const {
  for (uint32_t i = 0; i < candidates.count; ++i) {
    if (ColliderContact(candidates.candidates[i], *candidates.frames[i], x, x).inside_end)
      return true;
  }
  return false;
}

bool HullColliderSet::NearestUnionExit(Float3 x, const ContactFrames& candidates,
                                       ContactQuery* exit) const {
  uint32_t holding[kMaxCandidates];
  const ActiveFrames* frames[kMaxCandidates];
  uint32_t count = 0;
  const ContactQuery* contacts = candidates.contacts();
  for (uint32_t i = 0; i < candidates.count; ++i) {
    if (!contacts[i].inside_end) continue;
    holding[count] = candidates.candidates[i];
    frames[count++] = candidates.frames[i];
  }
  ExitCandidate exits[kMaxExits];
  const uint32_t n = CollectExits(x, holding, frames, count, exits);
  for (uint32_t e = 0; e < std::min(n, kMaxExitTries); ++e) {
    const ContactQuery c = ExitContact(x, exits[e]);
    if (!InsideAnyCandidate(ExitProbe(c), candidates)) {
      *exit = c;
      return true;
    }
  }
  return false;
}

}  // namespace drape

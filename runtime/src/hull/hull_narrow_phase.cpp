// One collider against one particle segment: the hull's plane test or Kirkpatrick test, its
// push-out or map-table response, the continuous clip of the segment (docs/ALGORITHMS.md §8.3-8.5),
// and the world-space wrapper with the OBB rejection.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "drape/runtime/hull_collider_set.h"
#include "hull/nudge_out.h"
#include "hull/plane_kernels.h"

namespace drape {

using detail::ClipResult;
using detail::DualResult;
using detail::NudgeOut;
using detail::PlaneKernels;
using detail::PlaneSoa;

float HullColliderSet::PlaneMax(const HullRecord& h, Float3 p, uint32_t* arg) const {
  const uint32_t b = h.plane_begin;
  const PlaneSoa soa{&plane_nx_[b], &plane_ny_[b], &plane_nz_[b], &plane_d_[b], h.plane_padded};
  const PlaneKernels& k = *kernels_;
  const float m = k.max(soa, p);
  if (arg != nullptr) *arg = k.first_equal(soa, p, m);
  return m;
}

void HullColliderSet::PushOut(const HullRecord& h, Float3 p, float max_value,
                              ContactQuery* c) const {
  const uint32_t b = h.plane_begin;
  const PlaneSoa soa{&plane_nx_[b], &plane_ny_[b], &plane_nz_[b], &plane_d_[b], h.plane_padded};
  uint32_t j = kernels_->first_equal(soa, p, max_value);
  if (plane_internal_[b + j]) {
    // The nearest face is inside the body: leave through the nearest outer face instead (the
    // depth is then the distance to it). The outer planes' max: the internal ones padded.
    const PlaneSoa outer{&plane_nx_[b], &plane_ny_[b], &plane_nz_[b], &outer_plane_d_[b],
                         h.plane_padded};
    const float outer_max = kernels_->max(outer, p);
    if (outer_max > -1e37f) {  // some face is outer
      j = kernels_->first_equal(outer, p, outer_max);
      max_value = outer_max;
      c->depth = c->inside_end ? std::max(c->depth, -outer_max) : c->depth;
    }
  }
  const Plane& plane = planes_[b + j];
  const Float3 projected = p - plane.normal * max_value;
  c->point = NudgeOut(projected, plane.normal, 1.f + std::fabs(plane.offset),
                      [&](Float3 x) { return PlaneSignedDistance(plane, x); });
  c->normal = plane.normal;
}

ContactQuery HullColliderSet::HullNarrow(const HullRecord& h, Float3 a, Float3 b) const {
  ContactQuery c;
  const bool kirkpatrick = options_.inside_test == InsideTest::kKirkpatrick;
  const uint32_t base = h.plane_begin;
  const PlaneSoa soa{&plane_nx_[base], &plane_ny_[base], &plane_nz_[base], &plane_d_[base],
                     h.plane_padded};
  const PlaneKernels& kernels = *kernels_;
  float max_a = 1.f, max_b;
  if (options_.continuous) {
    // A particle at rest (or a point query) tests one point: the same answer for half the work.
    const DualResult dual = std::memcmp(&a, &b, sizeof(Float3)) == 0 ? kernels.dual_same(soa, a)
                                                                     : kernels.dual(soa, a, b);
    if (dual.separated) return c;  // one plane has both ends outside: no contact
    max_a = dual.max_a;
    max_b = dual.max_b;
  } else {
    max_b = kernels.max(soa, b);
  }
  const bool inside_b = kirkpatrick ? InsideKirkpatrick(h, b) : max_b <= 0.f;
  c.inside_end = inside_b;
  c.depth = inside_b ? std::max(0.f, -max_b) : 0.f;
  auto discrete = [&](float t, uint8_t flags) {
    c.contact = true;
    c.t = t;
    c.flags = flags;
    if (options_.response == HullResponse::kMapTableRay) {
      uint32_t plane;
      Float3 hit;
      if (MapRay(h, b, &hit, &plane)) {
        const Plane& pl = planes_[base + plane];
        c.point = NudgeOut(hit, pl.normal, 1.f + std::fabs(pl.offset),
                           [&](Float3 x) { return PlaneSignedDistance(pl, x); });
        c.normal = pl.normal;
        return;
      }
      c.flags |= kCollisionFallback;
    }
    PushOut(h, b, max_b, &c);
  };
  if (!options_.continuous) {
    if (inside_b) discrete(1.f, kCollisionNone);
    return c;
  }
  const bool inside_a = kirkpatrick ? InsideKirkpatrick(h, a) : max_a <= 0.f;
  if (inside_a) {
    if (inside_b) discrete(0.f, kCollisionStartedInside);
    return c;
  }
  // Cyrus-Beck clip of a -> b by the half-spaces (no plane has both ends outside here, so every
  // entering plane has fb <= 0 and fa - fb > 0).
  const ClipResult clip = kernels.clip(soa, a, b);
  if (clip.t_in >= 0.f && clip.t_in <= clip.t_out) {
    const Plane& pl = planes_[base + kernels.entry(soa, a, b, clip.t_in)];
    const Float3 target = options_.entry_response == EntryResponse::kProjectEnd
                              ? b - pl.normal * PlaneSignedDistance(pl, b)
                              : a + (b - a) * clip.t_in;
    c.contact = true;
    c.t = clip.t_in;
    c.point = NudgeOut(target, pl.normal, 1.f + std::fabs(pl.offset),
                       [&](Float3 x) { return PlaneSignedDistance(pl, x); });
    c.normal = pl.normal;
    return c;
  }
  if (inside_b) discrete(1.f, kCollisionNone);  // rounding: inside without a found entry
  return c;
}

ContactQuery HullColliderSet::ColliderContact(uint32_t collider, const ActiveFrames& f, Float3 p0,
                                              Float3 p1) const {
  ContactQuery c;
  const uint32_t hull_total = static_cast<uint32_t>(hulls_.size());
  if (collider < hull_total) {
    const HullRecord& h = hulls_[collider];
    // OBB rejection in the OBB frame: the end point, then (continuous) the segment.
    // Both ends are transformed and all compares evaluated without short circuits: one branch
    // on the whole test (whether the end is inside is a coin toss near the hull, and a
    // mispredicted branch costs more than the arithmetic).
    const Float3 bo = TransformPoint(f.to_obb_end, p1);
    const Float3 ao = TransformPoint(f.to_obb_start, p0);
    const Float3 half = h.obb_half;
    const Float3 bo_abs{std::fabs(bo.x), std::fabs(bo.y), std::fabs(bo.z)};
    const bool end_in = (bo_abs.x <= half.x) & (bo_abs.y <= half.y) & (bo_abs.z <= half.z);
    const bool beyond_one_face =
        ((ao.x > half.x) & (bo.x > half.x)) | ((ao.x < -half.x) & (bo.x < -half.x)) |
        ((ao.y > half.y) & (bo.y > half.y)) | ((ao.y < -half.y) & (bo.y < -half.y)) |
        ((ao.z > half.z) & (bo.z > half.z)) | ((ao.z < -half.z) & (bo.z < -half.z));
    const bool reject = !end_in && (!options_.continuous || beyond_one_face);
    if (reject) return c;
    const Float3 a = TransformPoint(f.to_local_start, p0);
    const Float3 b = TransformPoint(f.to_local_end, p1);
    c = HullNarrow(h, a, b);
  } else {
    const Float3 a = TransformPoint(f.to_local_start, p0);
    const Float3 b = TransformPoint(f.to_local_end, p1);
    c = SphereNarrow(spheres_[collider - hull_total].radius, a, b);
  }
  if (c.contact) {
    c.point = TransformPoint(f.to_world_end, c.point);
    c.normal = TransformVector(f.to_world_end, c.normal);
  }
  return c;
}

}  // namespace drape

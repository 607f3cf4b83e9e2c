#include "hull/hull_collider_set_access.h"

#include <algorithm>
#include <vector>

#include "hull/plane_kernels.h"

namespace drape {

bool HullColliderSetAccess::InsideLocal(const HullColliderSet& set, uint32_t hull, Float3 p,
                                        InsideTest test) {
  const HullColliderSet::HullRecord& h = set.hulls_[hull];
  if (test == InsideTest::kKirkpatrick) return h.has_hierarchy && set.InsideKirkpatrick(h, p);
  return set.PlaneMax(h, p, nullptr) <= 0.f;
}

float HullColliderSetAccess::MaxPlaneDistanceLocal(const HullColliderSet& set, uint32_t hull,
                                                   Float3 p, uint32_t* plane) {
  return set.PlaneMax(set.hulls_[hull], p, plane);
}

int32_t HullColliderSetAccess::LocateLocal(const HullColliderSet& set, uint32_t hull, Float3 p,
                                           bool upper, uint32_t* steps) {
  const HullColliderSet::HullRecord& h = set.hulls_[hull];
  if (steps != nullptr) *steps = 0;
  if (!h.has_hierarchy) return -1;
  return set.node_leaf_plane_[set.Locate(upper ? h.upper : h.lower,
                                         ProjectHullUv(p, h.uv_origin, h.uv_u, h.uv_v), steps)];
}

double HullColliderSetAccess::DepthSum(const HullColliderSet& set, Float3 p) {
  double sum = 0.0;
  for (uint32_t k = 0; k < set.motions_.size(); ++k) {
    sum += set.ColliderContact(k, set.active_[k], p, p).depth;
  }
  return sum;
}

ContactQuery HullColliderSetAccess::QueryHullLocal(const HullColliderSet& set, uint32_t hull,
                                                   Float3 a, Float3 b) {
  if (!IsFinite(a) || !IsFinite(b)) {
    ContactQuery c;
    c.flags = kCollisionInvalidInput;
    return c;
  }
  return set.HullNarrow(set.hulls_[hull], a, b);
}

bool HullColliderSetAccess::MapTableRayLocal(const HullColliderSet& set, uint32_t hull, Float3 p,
                                             Float3* point, Float3* normal) {
  const HullColliderSet::HullRecord& h = set.hulls_[hull];
  if (!h.has_map) return false;
  uint32_t plane;
  if (!set.MapRay(h, p, point, &plane)) return false;
  *normal = set.planes_[h.plane_begin + plane].normal;
  return true;
}

uint64_t HullColliderSetAccess::GroupBoxRejections(const HullColliderSet& set,
                                                   std::span<const Float3> previous,
                                                   std::span<const Float3> current) {
  const detail::PlaneKernels& k = *set.kernels_;
  const uint32_t words = (set.collider_count_ + 31) / 32;
  std::vector<uint32_t> masks(size_t{k.group_width} * words), before;
  uint64_t cleared = 0;
  for (size_t first = 0; first < current.size(); first += k.group_width) {
    const uint32_t lanes =
        static_cast<uint32_t>(std::min<size_t>(k.group_width, current.size() - first));
    k.sphere_masks(&previous[first], &current[first], &current[first], lanes, set.sweep_x_.data(),
                   set.sweep_y_.data(), set.sweep_z_.data(), set.sweep_r_.data(),
                   set.collider_count_, set.sweep_union_center_, set.sweep_union_radius_,
                   masks.data());
    before = masks;
    k.obb_masks(&previous[first], &current[first], lanes, set.obb_start_.data(),
                set.obb_end_.data(), set.obb_half_.data(), static_cast<uint32_t>(set.hulls_.size()),
                set.collider_count_, set.options_.continuous, HullColliderSet::kMaxCandidates,
                masks.data());
    for (size_t i = 0; i < size_t{lanes} * words; ++i)
      cleared += static_cast<uint64_t>(__builtin_popcount(before[i] & ~masks[i]));
  }
  return cleared;
}

}  // namespace drape

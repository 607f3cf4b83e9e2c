#include "hull/hull_collider_set_access.h"

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

}  // namespace drape

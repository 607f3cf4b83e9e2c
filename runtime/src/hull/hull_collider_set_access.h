#pragma once
// Test-only entry points of HullColliderSet: one collider at a time, in its collider frame, for
// the tests and the benchmarks that measure a kernel alone. Indices must be valid.

#include <cstdint>
#include <span>

#include "drape/runtime/hull_collider_set.h"

namespace drape {

struct HullColliderSetAccess {
  static bool InsideLocal(const HullColliderSet& set, uint32_t hull, Float3 p, InsideTest test);
  // max_i (n_i . p - d_i) and its plane (the first index attaining it).
  static float MaxPlaneDistanceLocal(const HullColliderSet& set, uint32_t hull, Float3 p,
                                     uint32_t* plane = nullptr);
  // The Kirkpatrick leaf's plane for p's projection, -1 outside the projected hull (or without a
  // hierarchy); steps (optional) receives the number of node tests.
  static int32_t LocateLocal(const HullColliderSet& set, uint32_t hull, Float3 p, bool upper,
                             uint32_t* steps = nullptr);
  // The OBB quick rejection: false means p is certainly outside the hull.
  static bool ObbMayContainLocal(const HullColliderSet& set, uint32_t hull, Float3 p) {
    const HullColliderSet::HullRecord& h = set.hulls_[hull];
    const Float3 d = p - h.obb_center;
    // The three compares first, then & (no short circuit, no branch per axis).
    const bool in_x = std::fabs(Dot(d, h.obb_axes[0])) <= h.obb_half.x;
    const bool in_y = std::fabs(Dot(d, h.obb_axes[1])) <= h.obb_half.y;
    const bool in_z = std::fabs(Dot(d, h.obb_axes[2])) <= h.obb_half.z;
    return in_x & in_y & in_z;
  }
  // The whole narrow phase of the collider-frame segment a -> b with the set's options.
  static ContactQuery QueryHullLocal(const HullColliderSet& set, uint32_t hull, Float3 a, Float3 b);
  // The sum over all colliders of the depth of world point p inside them (selected substep): the
  // bound a response inside overlapping colliders stays within, beside the motion.
  static double DepthSum(const HullColliderSet& set, Float3 p);
  // The batch's group box filter on the selected substep, over `previous` -> `current` in the
  // batch's groups: how many candidate bits of the sphere broad phase it clears.
  static uint64_t GroupBoxRejections(const HullColliderSet& set, std::span<const Float3> previous,
                                     std::span<const Float3> current);
  // The map-table response ray through p: false when it finds no listed triangle.
  static bool MapTableRayLocal(const HullColliderSet& set, uint32_t hull, Float3 p, Float3* point,
                               Float3* normal);
};

}  // namespace drape

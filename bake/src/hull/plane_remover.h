#pragma once
// Plane removal (dual collapse): the ablation simplifier. Drops the inflated hull's supporting
// planes one at a time, the one whose exposed cap grows the least first; containment holds by
// construction.

#include <cstdint>
#include <vector>

#include "hull/growth_reference.h"
#include "hull/hull_mesh.h"

namespace drape::bake::detail {

struct PlaneRemovalResult {
  Mesh mesh;
  std::vector<Vec3> kept_normals;    // unit, double
  std::vector<double> kept_offsets;  // planes the mesh's faces lie on (before the margin)
  uint32_t dropped = 0;
  bool budget_reached = false;
};

// h0's triangles grouped into planes by `groups` (GroupCoplanar). Drops planes while the mesh has
// more than max_triangles and the cap's growth stays within max_growth (metres). False when the
// dual hull degenerates; *result is then incomplete.
bool RemovePlanes(const Mesh& h0, const std::vector<uint32_t>& groups, uint32_t group_count,
                  const GrowthReference& reference, double max_growth, uint32_t max_triangles,
                  PlaneRemovalResult* result);

}  // namespace drape::bake::detail

#pragma once
// The runtime planes of a hull: coplanar triangles merged into one plane each, and float plane
// offsets that contain, in the runtime's float arithmetic, every collider vertex and every input
// delta-ball (header hull_builder.h, step 5).

#include <vector>

#include "drape/formats/hull_collider_data.h"
#include "hull/hull_mesh.h"

namespace drape::bake::detail {

struct PlaneGroups {
  std::vector<uint32_t> triangle_group;
  std::vector<Vec3> normals;  // unit, double (before rounding)
};

// Exact coplanar merging; with `hint` planes (plane removal) triangles lying on one hint plane
// within `hint_tolerance` also share it and take its normal.
PlaneGroups BuildPlaneGroups(const Mesh& mesh, const std::vector<Vec3>* hint_normals,
                             const std::vector<double>* hint_offsets, double hint_tolerance);

// Float plane offsets that contain, in the runtime's float arithmetic, every collider vertex
// and every float point within delta of an input point (header, step 5).
void FillPlanes(const Mesh& mesh, const PlaneGroups& groups, const std::vector<Vec3>& inputs,
                double delta, HullColliderData* collider);

}  // namespace drape::bake::detail

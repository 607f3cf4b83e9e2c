#pragma once
// Skinned spheres for the tests of colliders that follow joints: radius `radius * scale`, the
// first at the origin rigidly on joint 0, the second at (0.5, 0, 0) * scale on joint 1, and so
// on; an octahedron subdivided 4 times (facets within 1.2 % of the radius). Header-only.

#include "drape/formats/mesh_data.h"
#include "octahedron_sphere.h"

namespace drape::test {

// `count` spheres, sphere s centred at (0.5 s, 0, 0) * scale rigidly on joint s.
inline MeshData SkinnedSpheres(int count, float radius, float scale = 1.f) {
  const UnitSphereMesh unit = OctahedronSphere(4);
  MeshData mesh;
  for (int sphere = 0; sphere < count; ++sphere) {
    const uint32_t base = static_cast<uint32_t>(mesh.positions.size());
    for (const auto& p : unit.positions) {
      mesh.positions.push_back(
          {(static_cast<float>(p[0]) * radius + 0.5f * static_cast<float>(sphere)) * scale,
           static_cast<float>(p[1]) * radius * scale, static_cast<float>(p[2]) * radius * scale});
    }
    for (const auto& t : unit.triangles)
      for (uint32_t k : t) mesh.triangles.push_back(base + k);
  }
  const uint32_t per_sphere = static_cast<uint32_t>(unit.positions.size());
  mesh.influence_offsets.push_back(0);
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    mesh.influence_joints.push_back(static_cast<uint16_t>(v / per_sphere));
    mesh.influence_weights.push_back(1.f);
    mesh.influence_offsets.push_back(v + 1);
  }
  return mesh;
}

inline MeshData TwoSkinnedSpheres(float radius, float scale = 1.f) {
  return SkinnedSpheres(2, radius, scale);
}

}  // namespace drape::test

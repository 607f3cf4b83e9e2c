#pragma once
// A denser copy of a skinned mesh, for tests and benchmarks that need the same surface with more
// triangles (a densely meshed game character). Header-only.

#include <algorithm>
#include <cstdint>
#include <map>
#include <utility>

#include "drape/formats/mesh_data.h"
#include "drape/runtime/math.h"

namespace drape::test {

// Each triangle into four at its edges' midpoints, which lie on the surface; a midpoint takes the
// mean of its ends' influences, so it skins between them.
inline MeshData SubdividedMesh(const MeshData& mesh) {
  MeshData out = mesh;
  out.triangles.clear();
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;
  const auto midpoint = [&](uint32_t a, uint32_t b) {
    const auto [it, added] = midpoints.try_emplace(std::minmax(a, b), out.vertex_count());
    if (!added) return it->second;
    out.positions.push_back((mesh.positions[a] + mesh.positions[b]) * 0.5f);
    if (!mesh.influence_offsets.empty()) {
      std::map<uint16_t, float> weights;
      for (const uint32_t v : {a, b}) {
        for (uint32_t k = mesh.influence_offsets[v]; k < mesh.influence_offsets[v + 1]; ++k)
          weights[mesh.influence_joints[k]] += 0.5f * mesh.influence_weights[k];
      }
      for (const auto& [joint, weight] : weights) {
        out.influence_joints.push_back(joint);
        out.influence_weights.push_back(weight);
      }
      out.influence_offsets.push_back(static_cast<uint32_t>(out.influence_joints.size()));
    }
    return it->second;
  };
  for (size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
    const uint32_t a = mesh.triangles[t], b = mesh.triangles[t + 1], c = mesh.triangles[t + 2];
    const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
    out.triangles.insert(out.triangles.end(), {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca});
  }
  return out;
}

}  // namespace drape::test

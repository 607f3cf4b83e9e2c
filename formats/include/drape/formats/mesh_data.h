#pragma once
// The bind-pose body mesh: the exact surface every collider approximates.

#include <cstdint>
#include <vector>

#include "drape/formats/types.h"

namespace drape {

struct MeshData {
  std::vector<Float3> positions;    // bind pose, asset frame, metres; welded by position
  std::vector<uint32_t> triangles;  // 3 vertex indices per triangle, counter-clockwise outside
  // Skin influences in compressed rows: vertex v has influences [offsets[v], offsets[v+1]).
  // Weights of a vertex are > 0 and sum to 1 (renormalised at bake); all influences are kept.
  std::vector<uint32_t> influence_offsets;  // positions.size() + 1 entries, starts at 0
  std::vector<uint16_t> influence_joints;
  std::vector<float> influence_weights;

  uint32_t vertex_count() const { return static_cast<uint32_t>(positions.size()); }
  uint32_t triangle_count() const { return static_cast<uint32_t>(triangles.size() / 3); }
};

}  // namespace drape

#pragma once
// Private to the runtime: BuildCloth's stages for long-range tethers and skinned garments.

#include <cstdint>
#include <span>
#include <vector>

#include "drape/runtime/cloth.h"
#include "drape/runtime/math.h"

namespace drape::detail {

// One tether per dynamic particle connected through the mesh edges to a kinematic one: the
// geodesic distance (Dijkstra over the triangles' edges, in double, from every kinematic
// particle at once) to the nearest kinematic particle, times (1 + stretch of the particle).
// Ties go to the lower particle index, so the result depends on the mesh only. Sorted by
// particle. untethered: dynamic particles with no path.
std::vector<ClothTether> BuildTethers(std::span<const Float3> positions,
                                      std::span<const uint32_t> triangles,
                                      std::span<const uint8_t> kinematic,
                                      std::span<const float> stretch_per_particle, float stretch,
                                      uint32_t* untethered);

// Unit area-weighted vertex normals of the triangles (counter-clockwise winding faces out);
// +y for a particle in no triangle with area.
std::vector<Float3> VertexNormals(std::span<const Float3> positions,
                                  std::span<const uint32_t> triangles);

// The skinned position of a particle at one pose (linear blend skinning; the weights sum to 1).
inline Float3 SkinPoint(const ClothSkinWeights& w, const Mat34* skinning, Float3 p) {
  Float3 sum;
  for (int k = 0; k < 4; ++k)
    if (w.weights[k] != 0.f) sum += TransformPoint(skinning[w.joints[k]], p) * w.weights[k];
  return sum;
}
// The skinned direction of a normal (not normalised).
inline Float3 SkinVector(const ClothSkinWeights& w, const Mat34* skinning, Float3 v) {
  Float3 sum;
  for (int k = 0; k < 4; ++k)
    if (w.weights[k] != 0.f) sum += TransformVector(skinning[w.joints[k]], v) * w.weights[k];
  return sum;
}

}  // namespace drape::detail

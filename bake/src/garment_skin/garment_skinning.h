#pragma once
// Skin weights for a garment from the body it is worn on (drape-sim's skinned garments).

#include <span>
#include <string>
#include <vector>

#include "drape/formats/mesh_data.h"
#include "drape/formats/skeleton_data.h"
#include "drape/formats/status.h"
#include "drape/formats/types.h"
#include "drape/runtime/cloth.h"

namespace drape::bake::detail {

// Each garment particle takes the skin weights of the closest point of the body's surface: the
// barycentric blend of that triangle's corners' influences, the four largest kept and
// renormalised. body_positions: the body's vertices in the garment's frame (the bind positions,
// or the body posed at the rest pose for a garment authored there). distances (optional):
// metres from each particle to the body. kInvalidArgument when the body has no triangles or no
// skin influences.
Status TransferSkinWeights(const MeshData& body, std::span<const Float3> body_positions,
                           std::span<const Float3> garment, std::vector<ClothSkinWeights>* weights,
                           std::vector<float>* distances = nullptr);

// Reads a weights file: one line per garment vertex, in order, of `joint weight` pairs (joint
// names of the skeleton, weights >= 0, at least one > 0); blank lines and `#` comments skipped.
// The four heaviest are kept and renormalised. Errors name the file, the line and the reason
// (an unknown joint suggests the nearest names; a count that differs from `vertices`).
Status ReadSkinWeightsFile(const std::string& file, const SkeletonData& skeleton, size_t vertices,
                           std::vector<ClothSkinWeights>* weights);

// Averages each particle's weights with its mesh neighbours' `iterations` times (Jacobi, the four
// heaviest joints kept): a skirt's particles between the legs, which the closest body point gives
// to one thigh, get a blend of both thighs and the hips, so the skirt does not split like
// trousers when the legs stride.
void SmoothSkinWeights(std::span<const uint32_t> triangles, uint32_t iterations,
                       std::vector<ClothSkinWeights>* weights);

// Metres from each vertex to the nearest of `sources` along the mesh's edges (Dijkstra over the
// triangles' edges, rest lengths from `positions`); +inf where no edge path reaches. nearest
// (optional): that source's index in `sources` per vertex (UINT32_MAX where none reaches; ties:
// the path found first, the same on every machine).
std::vector<float> DistanceAlongEdges(std::span<const uint32_t> triangles,
                                      std::span<const Float3> positions,
                                      std::span<const uint32_t> sources,
                                      std::vector<uint32_t>* nearest = nullptr);

}  // namespace drape::bake::detail

#pragma once
// Points inside the body that the bones' hulls hold besides the surface they carry. The hulls of
// the surface patches the bones carry (or of the convex pieces of one) need not reach the body's
// middle: patches around a torso are orange segments whose hulls leave the centre empty, and a
// head cut into pieces is a shell of them. A particle there has no exit: it stays inside the
// body (docs/ALGORITHMS.md §2.3 has the measurements).

#include <cstdint>
#include <span>
#include <vector>

#include "drape/formats/types.h"

namespace drape::bake {

class MeshReference;
struct Regions;

// Per joint: points along the bone (joint to each child joint, rest pose, 8 per segment) inside
// the body by more than delta (metres). A fan from the bone to its patch fills a limb.
std::vector<std::vector<Float3>> BoneInteriorPoints(const Regions& regions,
                                                    std::span<const int32_t> parents,
                                                    const MeshReference& body, float delta);

// Per joint (`joints` of them): the points of a grid over the body's bounding box
// (kInteriorGridCells cells along its longest side) inside the body by more than delta, each given
// to the bone that carries the nearest surface triangle (`triangle_bones`: TriangleBones in
// regions.h, indexed as the body's triangles). `rest_positions`: the rest-pose mesh.
inline constexpr uint32_t kInteriorGridCells = 32;
std::vector<std::vector<Float3>> BodyInteriorPoints(std::span<const Float3> rest_positions,
                                                    std::span<const int32_t> triangle_bones,
                                                    uint32_t joints, const MeshReference& body,
                                                    float delta);

}  // namespace drape::bake

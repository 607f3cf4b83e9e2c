#pragma once
// Per-bone local maps (paper A's maps on paper B's skeleton): for every bone carrying part of the
// body, the front/back maps of that part baked once in a view frame fixed to the bone, along the
// axis most of the part's surface faces. The runtime (drape/runtime/bone_map_collider.h)
// maps each point into the frames of the bones whose bounds it reaches, so the maps follow any
// pose. How the parts and the axes are chosen: docs/ALGORITHMS.md §7.10.

#include <cstdint>
#include <span>
#include <vector>

#include "drape/bake/body_map_baker.h"
#include "drape/formats/body_map_data.h"
#include "drape/formats/mesh_data.h"
#include "drape/formats/skeleton_data.h"
#include "drape/formats/status.h"

namespace drape::bake {

struct BoneMapOptions {
  float texel_size = 0.003f;  // metres, [1e-4, 1] (the bake config's 0: the body's size / 600)
  float epsilon = 0.005f;     // metres the surface is offset along its normals, [0, 0.1]
  // A triangle joins a bone's part when the bone carries most of it, or when one of its corners
  // has at least this weight on the bone: the blended skin around a joint lies in the parts of
  // both bones, so the maps overlap where the skin bends. (0, 1].
  float min_weight = 0.2f;
  // Depth layers (1: the slab; more: air gaps inside it), as BodyMapOptions::layers. 3 by
  // default: a part's concave corners (a quadruped's hips with the tops of its legs) otherwise
  // fill with slab; on the Fox 10 % of the points 15 mm or more outside the body were called
  // inside with 1 layer.
  uint8_t layers = 3;
  DepthEncoding depth_encoding = DepthEncoding::kUnorm16;
};

// What BakeBoneMaps did for one bone that carries a part.
struct BoneMapStats {
  uint16_t joint = 0;
  uint32_t triangles = 0;          // of its part
  float facing = 0.f;              // share of the part's surface facing the view axis, [1/3, 1]
  uint32_t width = 0, height = 0;  // texels
  size_t bytes = 0;                // the pose's per-texel arrays and tables
};

// The automatic texel (the bake config's bone_maps.texel_size 0): the rest pose's longest side
// over 600 texels, 3 mm on a 1.8 m person; within [1e-4, 1] m.
float AutomaticBoneMapTexel(std::span<const Float3> rest_positions);

// Bakes the maps of every bone that carries part of `mesh` (bind pose, asset frame). The texel
// size and epsilon are metres of the posed body: a bone whose skinning matrix at the rest pose
// (rest_skinning, one per joint; empty: identity) scales the bind mesh (a rig bound in
// centimetres and posed in metres) is baked at the texel and epsilon divided by that scale.
// Bones carrying nothing get none. Deterministic. kInvalidArgument on bad options.
Status BakeBoneMaps(const MeshData& mesh, const SkeletonData& skeleton,
                    std::span<const Mat34> rest_skinning, const BoneMapOptions& options,
                    BoneMapSet* maps, std::vector<BoneMapStats>* stats = nullptr);

}  // namespace drape::bake

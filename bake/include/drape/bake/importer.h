#pragma once
// assimp -> Character. Measured pitfalls handled here are listed in ../shared/notes/algorithms.md
// §1: joints keyed by node name (preferring the node without meshes), rest != bind, unit scale and
// up axis chosen explicitly, weights renormalised by us (never LimitBoneWeights), no
// PreTransformVertices/OptimizeGraph, FBX pivots not preserved.
//
// Hard cases (tests/bake/import_hard_cases_test.cpp; assimp 5.2.5 measured):
// - Weights: every influence is kept (glTF JOINTS_n/WEIGHTS_n sets all arrive; 12 per vertex kept
//   as 12), renormalised to sum 1, with a counted warning when a raw sum is outside [0.9, 1.1].
//   assimp drops weights <= 0 and NaN; an infinite weight is an error naming the bone.
// - A vertex with no weight is rigid to its mesh node's nearest joint ancestor, else to joint 0,
//   with a counted warning. An unskinned mesh is rigid to its node's nearest joint ancestor; one
//   outside every joint becomes a joint of its own.
// - Joint names: unnamed glTF nodes are named "nodes[<node index>]" by assimp (unique, stable).
//   Two joints of one skin with one name fail assimp's validation (with or without
//   rename_duplicate_joints). A bone name that several nodes carry (two skins whose joints share
//   a name) is an error: bones are matched to nodes by name, so the binding would be a guess.
//   rename_duplicate_joints repairs only joints that can be told apart: a rigid mesh node named
//   like a joint, or a joint without a name ("joint_<joint index>").
// - Vertices at one position within a mesh are welded into one vertex whose skin is the average
//   of the copies' skins (counted when they differ); triangles with a repeated vertex or zero area
//   are dropped (counted). Non-finite positions, node transforms and offset matrices are errors
//   naming the file and the vertex, node or bone.

#include <string>

#include "drape/bake/character.h"
#include "drape/formats/status.h"

namespace drape::bake {

struct ImportOptions {
  // Metres per source unit. 0 = detect: FBX UnitScaleFactor metadata, glTF metres, then a
  // sanity check on the body height (a body taller than 20 m is taken to be in cm).
  double unit_scale = 0.0;
  // "auto" (FBX UpAxis metadata, +Y otherwise) or one of +X -X +Y -Y +Z -Z: the source axis
  // that becomes the asset's +Y.
  std::string up_axis = "auto";
  float clip_sample_rate = 30.f;  // Hz, (0, 1000]: the rate clips are resampled at
  // Duplicate joint names are an error unless this is set; then they get "#2", "#3" suffixes.
  bool rename_duplicate_joints = false;
};

Status ImportCharacter(const std::string& path, const ImportOptions& options, Character* character);

}  // namespace drape::bake

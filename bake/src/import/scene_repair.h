#pragma once
// What assimp's loaders produce but its ValidateDataStructure step refuses, repaired where a game
// engine or viewer would load the file anyway (header source_scene.h). It runs on the scene as
// the loader left it, before validation, so it trusts no count and no pointer. Each repair is
// one warning line for the bake report; what cannot be repaired stays for validation to refuse.
//
// Repaired: animation keys out of order or repeated (sorted, the last key of a time kept), keys
// past the clip's duration (the duration is extended: a Minetest .b3d's keys run one frame past
// it), zero or non-finite ticks per second (25, assimp's convention) or duration, channels with no
// key, clips with no channel; faces with no corner or a corner past the mesh's vertices (dropped,
// and a mesh left without faces with them); primitive-type flags that disagree with the faces;
// gaps between texture-coordinate or colour channels; tangents without bitangents; out-of-range
// material indices and broken materials; null bones and weights; node parent links.
// Dropped without a warning, as a character bake never reads them: lights, cameras, embedded
// textures and morph-target animation.
// Refused here (validation would recurse forever or crash on them): a cyclic node graph, a null
// mesh, a mesh without vertex or face arrays, a null bone array.

#include <assimp/scene.h>

#include <string>
#include <vector>

#include "drape/formats/status.h"

namespace drape::bake::detail {

// Repairs `scene` in place (assimp's own arrays, freed as assimp frees them); appends one line per
// repair to `warnings`.
Status RepairLoadedScene(const std::string& path, aiScene* scene,
                         std::vector<std::string>* warnings);

// After post-processing: weights naming a vertex past the mesh's vertices (what
// JoinIdenticalVertices leaves on a bone whose vertices it all removed) are dropped.
void DropStaleWeights(aiScene* scene, std::vector<std::string>* warnings);

}  // namespace drape::bake::detail

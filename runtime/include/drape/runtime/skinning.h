#pragma once
// Linear blend skinning of the stored body mesh: the posed surface the colliders approximate.

#include <span>

#include "drape/formats/mesh_data.h"
#include "drape/formats/status.h"
#include "drape/formats/types.h"

namespace drape {

// positions[v] = sum_k w_k * skinning[joint_k] * bind_position[v]. `posed` must hold
// mesh.vertex_count() entries. Vertices without influences keep their bind position.
// OpenMP over vertices; no allocation.
Status SkinMesh(const MeshData& mesh, std::span<const Mat34> skinning, std::span<Float3> posed);

}  // namespace drape

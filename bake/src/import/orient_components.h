#pragma once
// Outward winding of the imported mesh. Closed character meshes can be wound inward
// (docs/ALGORITHMS.md §1.4: winding number -1 inside).

#include <cstddef>

#include "drape/formats/mesh_data.h"

namespace drape::bake::detail {

// Orients every connected component (triangles sharing vertices) so that its signed volume about
// its centroid is positive. Returns how many components were flipped.
size_t OrientComponentsOutward(MeshData* mesh);

}  // namespace drape::bake::detail

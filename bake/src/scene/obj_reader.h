#pragma once
// The OBJ reader of OBJ garments: `v` and `f` lines, polygons fanned.

#include <cstdint>
#include <string>
#include <vector>

#include "drape/formats/status.h"
#include "drape/formats/types.h"

namespace drape::bake::detail {

// Reads the vertices and the triangles (0-based; negative OBJ indices count back from the
// vertices read so far) of `file`. Messages start with `where` (the scene and its JSON path) and
// name the file and line. colors (optional): the vertex colours of `v x y z r g b` lines, each
// channel in [0, 1]; empty unless every vertex has one.
Status ReadObj(const std::string& file, const std::string& where, std::vector<Float3>* positions,
               std::vector<uint32_t>* triangles, std::vector<Float3>* colors = nullptr);

}  // namespace drape::bake::detail

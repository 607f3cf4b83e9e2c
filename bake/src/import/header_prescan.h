#pragma once
// Before assimp reads a file: what it would otherwise take it seconds and gigabytes to refuse
// (header importer.h). assimp 5.2 allocates from the counts a header declares before it reads the
// data (a 300-byte OFF file that declares 353 billion faces makes it touch tens of GB), so the
// counts of the formats known to do so are checked against the bytes that could hold them. Also
// recognises a .drape asset given where a character model is expected.
//
// The bounds are sound: a file assimp would read in full is never refused. Checked: OFF (vertex
// and face counts, and lines longer than the 4096-byte buffer its reader overflows), PLY (element
// counts, and each list's length in binary data), B3D (every chunk inside its parent). Also
// counts what assimp drops without a word: OBJ `f` lines without a corner (warnings).

#include <string>
#include <vector>

#include "drape/formats/status.h"

namespace drape::bake::detail {

Status PrescanModelFile(const std::string& path, std::vector<std::string>* warnings);

}  // namespace drape::bake::detail

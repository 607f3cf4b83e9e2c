#pragma once
// The bind mesh of an import (header importer.h): every mesh instance's vertices in the asset
// frame, welded per source mesh, with every influence kept and renormalised; degenerate
// triangles dropped, components wound outward, and what was repaired reported.

#include <string>
#include <vector>

#include "drape/bake/character.h"
#include "import/asset_frame.h"
#include "import/skeleton_import.h"
#include "import/source_scene.h"

namespace drape::bake::detail {

// Fills character->mesh; inverse_bind_source is BuildSkeleton's. Refuses non-finite weights and
// vertices, faces naming missing vertices, and a mesh whose every triangle is degenerate.
Status ImportBindMesh(const std::string& path, const SourceScene& source, const JointNodes& joints,
                      const AssetFrame& frame, const std::vector<Mat4>& inverse_bind_source,
                      Character* character);

}  // namespace drape::bake::detail

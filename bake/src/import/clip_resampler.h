#pragma once
// The clips of an import (header importer.h): every animation resampled at a fixed rate into
// joint-local transforms, the root joints' in the asset frame.

#include <string>

#include "drape/bake/character.h"
#include "drape/bake/importer.h"
#include "import/asset_frame.h"
#include "import/skeleton_import.h"
#include "import/source_scene.h"

namespace drape::bake::detail {

// Appends one clip per animation to character->clips at options.clip_sample_rate; a clip with an
// unusable duration is skipped with a warning. Refuses a clip that produces a non-finite
// transform.
Status ResampleClips(const std::string& path, const ImportOptions& options,
                     const SourceScene& source, const JointNodes& joints, const AssetFrame& frame,
                     Character* character);

}  // namespace drape::bake::detail

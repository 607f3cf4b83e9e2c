#pragma once
// The asset frame of an import (header importer.h): which source axis becomes +Y and how many
// metres a source unit is, each with where it came from, and the matrix A = R_up * s that maps
// the source's scene-root frame to the asset frame.

#include <string>
#include <vector>

#include "drape/bake/importer.h"
#include "import/source_scene.h"

namespace drape::bake::detail {

struct AssetFrame {
  std::string up;            // the source axis that becomes the asset's +Y: +X -X +Y -Y +Z -Z
  std::string up_source;     // "config", "file metadata" or "format default"
  double scale = 1.0;        // metres per source unit
  std::string scale_source;  // how the scale was chosen, for the report
  Mat4 to_asset = Mat4::Identity();    // A = R_up * s
  Mat4 from_asset = Mat4::Identity();  // A^-1
};

// Up axis from the options or the file's metadata, unit scale from the options, the metadata or
// the rest-pose body's size. Refuses an unknown up axis and non-finite rest-pose vertices; warns
// when the body is not between 2 cm and 3 m tall after scaling.
Status ChooseAssetFrame(const std::string& path, const ImportOptions& options,
                        const SourceScene& source, AssetFrame* frame,
                        std::vector<std::string>* warnings);

}  // namespace drape::bake::detail

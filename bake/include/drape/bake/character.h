#pragma once
// The editable bake-side character: what the importer produces and every bake stage reads.

#include <string>
#include <vector>

#include "drape/formats/character_asset.h"

namespace drape::bake {

struct Character {
  AssetInfo info;               // source name, unit scale, up axis, source_to_asset
  SkeletonData skeleton;        // asset frame (metres, +Y up, facing +Z)
  std::vector<ClipData> clips;  // resampled at a fixed rate
  MeshData mesh;                // bind pose, welded, weights renormalised
  double source_to_asset[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};  // row-major 4x4
  std::vector<std::string> warnings;  // for the bake report
  // Where the unit scale and up axis came from (config, file metadata, format default): the
  // report's "frame". A warning too when it was assumed rather than read.
  std::string frame_provenance;
  // Every file the import read: the model, then what it names (buffers, materials, textures),
  // as the loader named them.
  std::vector<std::string> source_files;
};

}  // namespace drape::bake

#pragma once
// assimp -> Character: the bind mesh in metres, +Y up, facing +Z, welded and oriented, its skin
// with every influence kept and renormalised, the skeleton keyed by node name, and the clips
// resampled. Every refusal names the file and what is wrong. The measured pitfalls it handles
// (rest != bind, units and up axis, duplicate and unnamed joints, unweighted vertices):
// docs/ALGORITHMS.md §1; the hard cases are tests/bake/import_hard_cases_test.cpp.

#include <cstdint>
#include <string>
#include <vector>

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
  // The file is read in a child process first, so that a loader that crashes, hangs or allocates
  // from a hostile header costs an error naming the file rather than the caller's process.
  uint32_t memory_limit_mb = 8192;  // MiB the reading may add, [64, 1048576]
  float time_limit_s = 300.f;       // seconds the reading may take, (0, 86400]
};

Status ImportCharacter(const std::string& path, const ImportOptions& options, Character* character);

// Every file extension the import reads (".fbx", ".gltf", ...), lowercase, sorted.
std::vector<std::string> ReadableExtensions();

}  // namespace drape::bake

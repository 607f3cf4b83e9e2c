#pragma once
// One drape-sim run: load the scene, bake or reuse its asset, keep what the garments can reach,
// settle, simulate and write the frames, the animation and the figures.

#include <cstdint>
#include <string>

namespace drape::sim {

struct RunOptions {
  std::string scene_path, out_dir;
  int64_t frames = 0;     // > 0: overrides the scene's frame count
  int threads = 0;        // > 0: worker threads (the step's task pool, the bake's OpenMP team)
  std::string gltf_path;  // non-empty: also write the run as an animated glTF (.glb: binary)
  // Non-empty: also write each garment bound to the skeleton as <dir>/<garment>.glb.
  std::string garments_dir;
};

// Returns the process exit code: 0, or 1 after printing one line naming the input and the reason.
int RunScene(const RunOptions& options);

}  // namespace drape::sim

#pragma once
// Speed against error at the simulation level (DESIGN.md, "Speed against error": the peers in
// the same run): the same garment on the same walking character against the same colliders
// (the character's baked hulls and joint spheres), stepped by drape's ClothSolver and by
// Bullet's soft body. Every frame is timed, and after every frame each particle is tested
// against the exact posed mesh (linear blend skinning of the original mesh, fast winding
// number): how deep the cloth ends up inside the body, not inside the proxies.

#include <cstdint>
#include <string>
#include <vector>

#include "drape/bake/importer.h"

namespace drape::bench {

struct ClothComparisonRow {
  std::string solver;  // "drape ClothSolver (...)", "Bullet btSoftBody (...)"
  uint32_t particles = 0;
  uint32_t frames = 0;        // measured frames (after the settle frames)
  double ms_per_frame = 0.0;  // mean wall time of one frame (all substeps), one thread
  double ms_per_frame_max = 0.0;
  double inside_fraction = 0.0;     // particle-frames inside the exact mesh
  double penetration_p99_mm = 0.0;  // over particle-frames (outside counts 0)
  double penetration_max_mm = 0.0;
  bool finite = true;
  std::string error;  // non-empty: the solver could not run (the reason)
};

struct ClothComparisonOptions {
  uint32_t settle_frames = 30;  // held at the clip's start pose, not measured
  uint32_t frames = 120;        // 1/60 s each, the clip looping
  uint32_t segments = 100;      // skirt resolution (particles = segments x (rings + 1))
  uint32_t rings = 40;
  uint32_t substeps = 4;
  uint32_t iterations = 5;
};

// The character's first clip must exist and have a joint named "hips" (the built-in mannequin);
// otherwise returns no rows and says why in *note.
std::vector<ClothComparisonRow> CompareClothSolvers(const std::string& path,
                                                    const bake::ImportOptions& import,
                                                    const ClothComparisonOptions& options,
                                                    std::string* note);

}  // namespace drape::bench

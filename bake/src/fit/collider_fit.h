#pragma once
// How well the proxy colliders fit the body they stand for, measured against the exact rest-pose
// mesh (MeshReference: generalised winding number and distance) in double:
// - bloat: for points on a collider's surface, how far they lie outside the body beyond the
//   collider's own inflation delta, clamped at 0 (a point inside the body, or within delta of
//   it, has none). A hull that bridges two limbs, or a joint sphere of a limb's size, bloats.
// - coverage: the fraction of the body's surface (by area) that lies inside some collider or
//   at most delta + coverage_tolerance outside it. What no collider covers, cloth passes through.
// Samples come from fixed seeds, and every sample's answer is computed on its own: the figures
// are identical at any thread count. The fit only reads; it never changes what is baked.

#include <cstdint>
#include <span>
#include <vector>

#include "drape/formats/hull_collider_data.h"
#include "drape/formats/types.h"

namespace drape::bake {

struct ColliderFitOptions {
  double hull_delta = 0.005;    // metres: the hulls' inflation (hulls.delta)
  double sphere_delta = 0.005;  // metres: added to the joint spheres' radii (spheres.delta)
  // A body point counts as covered up to delta + this outside a collider, metres.
  double coverage_tolerance = 0.001;
  uint32_t hull_samples = 400;     // area-weighted points per hull (its vertices are added)
  uint32_t sphere_samples = 400;   // Fibonacci points per joint sphere
  uint32_t capsule_samples = 400;  // area-weighted points per capsule (which has no delta)
  uint32_t body_samples = 20000;   // area-weighted points on the body for the coverage
  // The winding number's accuracy (MeshReference's beta): 2 classifies every point farther than
  // 0.1 from w = 1/2 right, at a third of the cost of the reference's default.
  double winding_beta = 2.0;
};

// One collider's bloat, millimetres beyond its delta, >= 0.
struct ColliderBloat {
  double p99_mm = 0.0;  // 99th percentile (nearest rank) over its area-weighted samples
  double max_mm = 0.0;  // the largest over those samples and, for a hull, its vertices
  uint32_t samples = 0;
};

struct ColliderFit {
  std::vector<ColliderBloat> hulls;     // one per hull, in the order given
  std::vector<ColliderBloat> spheres;   // one per joint sphere, in the order given
  std::vector<ColliderBloat> capsules;  // one per capsule, in the order given
  double coverage = 0.0;                // [0, 1]; 0 when there is no collider
  double bloat_p99_mm = 0.0;            // over every collider's area-weighted samples
  double bloat_max_mm = 0.0;            // over every collider's samples
  uint32_t collider_samples = 0;        // bloat samples in all (hull vertices included)
  uint32_t body_samples = 0;            // coverage samples
};

// rest_positions / triangles: the body at rest, asset frame, metres. A hull is placed at
// rest_skinning[joint] * bind_frame, a sphere's centre at rest_skinning[joint] * center (as the
// runtime places them at the rest pose), a capsule's ends at rest_skinning[joint] * from, to. A
// collider whose joint has no skinning matrix is measured as having no samples.
ColliderFit MeasureColliderFit(std::span<const Float3> rest_positions,
                               std::span<const uint32_t> triangles,
                               std::span<const HullColliderData> hulls,
                               std::span<const JointSphereData> spheres,
                               std::span<const CapsuleColliderData> capsules,
                               std::span<const Mat34> rest_skinning,
                               const ColliderFitOptions& options = {});

}  // namespace drape::bake

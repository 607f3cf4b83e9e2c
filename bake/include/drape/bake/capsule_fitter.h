#pragma once
// Tapered capsules fitted to the body (capsules.* of the bake config): per bone, a round cone
// along the principal axis of the surface the bone carries, tapering as the cross-section's
// median radius does along it, wide enough to hold a given fraction of that surface, its caps
// reaching the ends of the surface. The shape engines' cloth
// colliders use (NvCloth, Unity, Chaos, Jolt); the runtime poses them into a ShapeColliderSet
// (drape/runtime/capsule_colliders.h).

#include <cstdint>
#include <span>
#include <vector>

#include "drape/bake/regions.h"
#include "drape/formats/hull_collider_data.h"
#include "drape/formats/mesh_data.h"

namespace drape::bake {

struct CapsuleFitOptions {
  // The fraction of the bone's surface vertices inside its capsule, (0, 1]: the taper follows
  // the median radius of slabs along the axis, raised until this fraction lies inside (1 bounds
  // them all, and bloats where the cross-section is not round).
  float radius_quantile = 0.95f;
  uint32_t slabs = 8;         // along the axis, >= 1
  uint32_t min_vertices = 8;  // a bone carrying fewer surface vertices gets no capsule
  float min_radius = 0.002f;  // metres, > 0
};

// One capsule per bone that carries triangles (TriangleBones), in joint order; a limb with one
// child joint runs from its joint to the child's (parents: the skeleton's); written as the
// format stores them (centres in the bind-pose frame through the inverse rest skinning, radii in
// rest-pose metres). Deterministic.
std::vector<CapsuleColliderData> FitCapsules(const Regions& regions, const MeshData& mesh,
                                             std::span<const int32_t> parents,
                                             const CapsuleFitOptions& options = {});

}  // namespace drape::bake

#pragma once
// Every method and setting the measurement compares, behind one small interface: the batch
// collision with response (what a cloth step calls, timed) and the single-motion query that
// gives the contact point and normal (for the accuracy metrics). Peers (the exact mesh query,
// FCL) answer the same calls with their own machinery.

#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "drape/bake/mesh_reference.h"
#include "drape/runtime/body_map_collider.h"
#include "drape/runtime/bone_map_collider.h"
#include "drape/runtime/capsule_colliders.h"
#include "drape/runtime/collision_types.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"
#include "drape/runtime/shape_collider_set.h"

namespace drape::peers {
class FclMeshPeer;
}

namespace drape::bench {

// One second at 60 Hz: the step the velocities of the query motions are derived from.
inline constexpr float kStepSeconds = 1.f / 60.f;

class Method {
 public:
  virtual ~Method() = default;
  // Moves every particle previous[i] -> positions[i] out of the collider, in place, with paper
  // A's response; flags[i] gets CollisionFlags. OpenMP inside as the method does it.
  virtual void Collide(std::span<const Float3> previous, std::span<Float3> positions,
                       std::span<Float3> velocities, std::span<uint8_t> flags) const = 0;
  // The contact of one motion, without response.
  virtual ContactQuery Query(Float3 p0, Float3 p1) const = 0;
  // Motions that enter the method's own collider surface (checked in double, 10 um deep) but got
  // no contact from Collide: must be 0 for a continuous proxy. -1 when not applicable.
  virtual long OwnSurfaceMisses(std::span<const Float3> previous, std::span<const Float3> current,
                                std::span<const uint8_t> flags) const {
    (void)previous, (void)current, (void)flags;
    return -1;
  }

  // Query + ApplyResponse one particle at a time (the hulls: their batch one particle at a time,
  // four planes per instruction), the answers Collide documents to equal bit for bit (with
  // kCollisionInvalidInput for non-finite input); false when the method documents no such
  // equality (then nothing is written).
  virtual bool QueryEachAndRespond(std::span<const Float3> previous, std::span<Float3> positions,
                                   std::span<Float3> velocities, std::span<uint8_t> flags) const {
    (void)previous, (void)positions, (void)velocities, (void)flags;
    return false;
  }

  std::string family;        // maps, hulls, spheres, hulls+spheres, maps+hulls, peer
  std::string setting;       // human-readable, unique within a character
  size_t baked_bytes = 0;    // bytes of baked data the method needs (0: computed at run time)
  size_t runtime_bytes = 0;  // bytes the runtime structure holds
  bool peer = false;         // a comparison point, not one of ours
  bool speed_only = false;   // no accuracy metrics (its answers do not classify inside)
};

// Paper A's body maps of one pose.
std::unique_ptr<Method> MakeBodyMapMethod(const BodyMapPose& pose, DepthSampling sampling,
                                          std::string setting, size_t baked_bytes,
                                          InstructionSet lanes = InstructionSet::kAvx2);

// Body maps already built (rendered at run time, or decoded), taken over.
std::unique_ptr<Method> MakeBodyMapMethod(BodyMapCollider&& collider, std::string setting,
                                          size_t baked_bytes);

// Per-bone local maps posed by `skinning` (at both ends of the step).
std::unique_ptr<Method> MakeBoneMapMethod(const BoneMapSet& maps, uint32_t joint_count,
                                          std::span<const Mat34> skinning, std::string setting,
                                          size_t baked_bytes);

// Paper B's colliders at one pose (skinning applied at the start and the end of the step).
// Either list may be empty (hulls alone, joint spheres alone).
std::unique_ptr<Method> MakeHullMethod(std::span<const HullColliderData> hulls,
                                       std::span<const JointSphereData> spheres,
                                       uint32_t joint_count, std::span<const Mat34> skinning,
                                       const HullColliderOptions& options, std::string family,
                                       std::string setting, size_t baked_bytes);

// The bake's tapered capsules at one pose (AddCapsuleColliders into a ShapeColliderSet).
std::unique_ptr<Method> MakeCapsuleMethod(std::span<const CapsuleColliderData> capsules,
                                          std::span<const Mat34> skinning, std::string setting);

// The body maps first, then the hulls and spheres (what a scene with both methods does).
std::unique_ptr<Method> MakeCombinedMethod(std::unique_ptr<Method> maps,
                                           std::unique_ptr<Method> hulls, std::string setting);

// The exact mesh query itself: winding number at both ends, the first crossing of the segment
// by CGAL's AABB tree, the closest point for a particle that ends inside.
std::unique_ptr<Method> MakeExactMeshPeer(const bake::MeshReference& reference);

// FCL's BVH point distance (the successor of RAPID, which paper A compares against): one
// distance query per particle; contact when closer than the separation. Unsigned distance does
// not tell inside from outside, so the peer is measured for speed only.
std::unique_ptr<Method> MakeFclPeer(std::span<const Float3> positions,
                                    std::span<const uint32_t> triangles);

ResponseParams BenchResponse();

}  // namespace drape::bench

#pragma once
// The bake's tapered capsules (CapsuleColliderData: one per bone that carries skin, fitted to the
// body's cross-section) posed from the skeleton into a ShapeColliderSet, where they collide with
// continuous detection and friction like the engine's own shapes:
//
//   ShapeColliderSet shapes;
//   shapes.Reserve(asset.capsules.size() + engine_shapes, 0);     // once
//   // every frame, from the skinning matrices at its start and end:
//   shapes.Clear();
//   AddCapsuleColliders(asset.capsules, skinning_start, skinning_end, &shapes);
//   shapes.AddPlane(floor, floor);                                 // the engine's, if any
//   // every substep: shapes.CollideBatch(...)
//
// A capsule's ends move with its bone (skinning(joint) * from, * to); its frame's x axis runs
// from `from` to `to` and turns with the bone, so the capsule does not spin about its axis.

#include <span>

#include "drape/formats/hull_collider_data.h"
#include "drape/formats/status.h"
#include "drape/formats/types.h"
#include "drape/runtime/shape_collider_set.h"

namespace drape {

// Adds every capsule at its bone's pose at the frame's start and end (skinning matrices per
// joint, finite). kInvalidArgument naming the capsule when its joint has no matrix or a posed
// capsule is not finite; the capsules before it stay added. No allocation within the set's
// reserved capacity.
Status AddCapsuleColliders(std::span<const CapsuleColliderData> capsules,
                           std::span<const Mat34> skinning_start,
                           std::span<const Mat34> skinning_end, ShapeColliderSet* shapes);

// The rigid frame AddCapsuleColliders gives a capsule at one pose (origin at the middle of its
// ends, x along from -> to, y and z turning with the bone) and its half length, metres.
Mat34 CapsuleFrame(const CapsuleColliderData& capsule, const Mat34& skinning, float* half_length);

}  // namespace drape

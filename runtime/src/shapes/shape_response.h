#pragma once
// Private to the runtime: the response to one engine-shape contact. The position is resolved in
// the shape's local frame (pushed out along the contact normal, then Coulomb friction on the
// displacement tangential to it, relative to the shape); the velocity in the world, relative to
// the shape's surface velocity (docs/ALGORITHMS.md §14).

#include "common/rigid_transform.h"
#include "drape/runtime/collision_types.h"
#include "shapes/shape_sweep.h"

namespace drape::detail {

// The resolved local position of a particle that moved q0 -> q1 relative to the shape. Within
// |q1 - q0| + c.end_depth + separation of q1, and outside the shape by the separation (the
// plane n . x = n . c.point + separation supports the shape, and friction slides along it).
Vec3D ResolvePosition(const LocalContact& c, const Vec3D& q0, const Vec3D& q1,
                      const ResponseParams& params);

// v' = v_surface + t keep - n (v_rel . n) restitution for v_rel = v - v_surface approaching the
// surface (v_rel . n < 0), t its tangential part and keep collision_types.h's TangentialKeep;
// a separating particle keeps v. normal: unit, world. m/s throughout.
Vec3D ResolveVelocity(const Vec3D& velocity, const Vec3D& surface_velocity, const Vec3D& normal,
                      const ResponseParams& params);

}  // namespace drape::detail

#pragma once
// Plain results and parameters shared by every collider kind (body maps, hulls, joint spheres).

#include <cstdint>

#include "drape/formats/types.h"

namespace drape {

// Paper A eq. 5: P' = C_p (+ separation * N), V_n = (V.N) N, V' = (V - V_n)(1 - friction) - V_n *
// restitution, applied only when V.N < 0 (a separating particle keeps its velocity).
struct ResponseParams {
  float friction = 0.2f;     // c_fric in [0, 1]
  float restitution = 0.0f;  // c_res in [0, 1]
  float separation = 1e-4f;  // metres the response point is placed outside the surface, >= 0
};

// Per-particle result flags of the batch collision calls.
enum CollisionFlags : uint8_t {
  kCollisionNone = 0,
  kCollisionContact = 1 << 0,        // a contact was found and the response applied
  kCollisionStartedInside = 1 << 1,  // the segment started inside: pushed out, not swept
  kCollisionSideWall = 1 << 2,       // body maps: entered through a texel side wall (staircase)
  kCollisionFallback = 1 << 3,       // hulls: the map-table ray missed; the push-out was used
  kCollisionInvalidInput = 1 << 7,   // a NaN or infinite position; the particle was left untouched
};

// The answer for one query segment p0 -> p1 (a point query is p0 == p1).
struct ContactQuery {       // 40 bytes
  bool inside_end = false;  // p1 is inside the collider (discrete test)
  bool contact = false;     // a contact was found (continuous test, or p1 inside)
  float t = 1.f;            // contact parameter along p0 -> p1 in [0, 1]
  Float3 point;             // contact point on the collider surface
  Float3 normal;            // unit outward surface normal at the contact
  float depth = 0.f;        // metres p1 lies inside the surface (0 when outside)
  uint8_t flags = kCollisionNone;
};

// Applies paper A eq. 5 to one particle given a contact. Returns the new position and velocity.
inline void ApplyResponse(const ContactQuery& c, const ResponseParams& params, Float3* position,
                          Float3* velocity) {
  position->x = c.point.x + c.normal.x * params.separation;
  position->y = c.point.y + c.normal.y * params.separation;
  position->z = c.point.z + c.normal.z * params.separation;
  const float vn = velocity->x * c.normal.x + velocity->y * c.normal.y + velocity->z * c.normal.z;
  if (vn < 0.f) {
    const Float3 normal_part{c.normal.x * vn, c.normal.y * vn, c.normal.z * vn};
    const float keep = 1.f - params.friction;
    velocity->x = (velocity->x - normal_part.x) * keep - normal_part.x * params.restitution;
    velocity->y = (velocity->y - normal_part.y) * keep - normal_part.y * params.restitution;
    velocity->z = (velocity->z - normal_part.z) * keep - normal_part.z * params.restitution;
  }
}

}  // namespace drape

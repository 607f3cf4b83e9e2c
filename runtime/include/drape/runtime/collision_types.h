#pragma once
// Plain results and parameters shared by every collider kind (body maps, hulls, joint spheres).

#include <cmath>
#include <cstdint>

#include "drape/formats/types.h"

namespace drape {

// How a contact removes tangential velocity.
enum class FrictionModel : uint8_t {
  // Coulomb's cone: with the normal velocity removed, dv_n = -V.N > 0, a tangential speed up to
  // static_friction * dv_n stops (the particle sticks), a faster one loses friction * dv_n.
  // What engines' cloth does; a particle at rest on a slope steeper than atan(static_friction)
  // slides, one on a gentler slope stays.
  kCoulomb = 0,
  // Paper A eq. 5: the tangential velocity is scaled by (1 - friction) at every contact, whatever
  // the normal speed (a resting particle creeps down any slope).
  kPaperA = 1,
};

// P' = C_p (+ separation * N), V_n = (V.N) N, then the friction model on V - V_n and
// V' = V_t' - V_n * restitution, applied only when V.N < 0 (a separating particle keeps its
// velocity).
struct ResponseParams {
  float friction = 0.2f;         // Coulomb: kinetic coefficient, paper A: c_fric; in [0, 1]
  float restitution = 0.0f;      // c_res in [0, 1]
  float separation = 1e-4f;      // metres the response point is placed outside the surface, >= 0
  float static_friction = 0.4f;  // Coulomb: static coefficient in [0, 4] (kPaperA ignores it)
  FrictionModel friction_model = FrictionModel::kCoulomb;
};

// The factor the tangential velocity keeps at a contact with normal speed `into` = -V.N > 0 and
// squared tangential speed `tangential_squared` (m^2/s^2).
inline float TangentialKeep(const ResponseParams& params, float into, float tangential_squared) {
  if (params.friction_model == FrictionModel::kPaperA) return 1.f - params.friction;
  const float stick = params.static_friction * into;
  if (tangential_squared <= stick * stick) return 0.f;
  const float keep = 1.f - params.friction * into / std::sqrt(tangential_squared);
  return keep > 0.f ? keep : 0.f;
}

// The response parameters are usable: every value finite and in its range.
inline bool ValidResponse(const ResponseParams& p) {
  return std::isfinite(p.friction) && p.friction >= 0.f && p.friction <= 1.f &&
         std::isfinite(p.static_friction) && p.static_friction >= 0.f && p.static_friction <= 4.f &&
         std::isfinite(p.restitution) && p.restitution >= 0.f && p.restitution <= 1.f &&
         std::isfinite(p.separation) && p.separation >= 0.f &&
         (p.friction_model == FrictionModel::kCoulomb ||
          p.friction_model == FrictionModel::kPaperA);
}

// Per-particle result flags of the batch collision calls.
enum CollisionFlags : uint8_t {
  kCollisionNone = 0,
  kCollisionContact = 1 << 0,        // a contact was found and the response applied
  kCollisionStartedInside = 1 << 1,  // the segment started inside: pushed out, not swept
  kCollisionSideWall = 1 << 2,       // body maps: through a texel side wall (staircase), on entry
                                     // or on a push-out beside air (with StartedInside)
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

// Applies the response to one particle given a contact. Returns the new position and velocity.
inline void ApplyResponse(const ContactQuery& c, const ResponseParams& params, Float3* position,
                          Float3* velocity) {
  position->x = c.point.x + c.normal.x * params.separation;
  position->y = c.point.y + c.normal.y * params.separation;
  position->z = c.point.z + c.normal.z * params.separation;
  const float vn = velocity->x * c.normal.x + velocity->y * c.normal.y + velocity->z * c.normal.z;
  if (vn < 0.f) {
    const Float3 normal_part{c.normal.x * vn, c.normal.y * vn, c.normal.z * vn};
    const Float3 tangential{velocity->x - normal_part.x, velocity->y - normal_part.y,
                            velocity->z - normal_part.z};
    const float keep = TangentialKeep(
        params, -vn,
        tangential.x * tangential.x + tangential.y * tangential.y + tangential.z * tangential.z);
    velocity->x = tangential.x * keep - normal_part.x * params.restitution;
    velocity->y = tangential.y * keep - normal_part.y * params.restitution;
    velocity->z = tangential.z * keep - normal_part.z * params.restitution;
  }
}

}  // namespace drape

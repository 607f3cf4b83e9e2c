#pragma once
// Round cones in double for the capsules' fit measure (fit/collider_fit.h): a surface to sample
// and a signed distance.

#include <cstdint>
#include <vector>

#include "drape/bake/capsule_fitter.h"

namespace drape::bake {

// The surface of a round cone (the convex hull of the spheres (a, radius_a) and (b, radius_b);
// the larger sphere when one holds the other) as triangles: `segments` around, `rings` along
// each cap's profile. positions: 3 doubles per vertex, metres.
void RoundConeMesh(const double a[3], double radius_a, const double b[3], double radius_b,
                   uint32_t segments, uint32_t rings, std::vector<double>* positions,
                   std::vector<uint32_t>* triangles);

// Signed distance from p to that round cone's surface, metres (negative inside).
double RoundConeDistance(const double p[3], const double a[3], double radius_a, const double b[3],
                         double radius_b);

}  // namespace drape::bake

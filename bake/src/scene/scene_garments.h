#pragma once
// What the garment resolution (scene_garments.cpp: ResolveGarment, PlaceGarment,
// NearestHeldParticles of drape/bake/scene.h) shares with the reach analysis.

#include "drape/formats/types.h"

namespace drape::bake::detail {

// The translation column of an affine matrix: a joint's position from its world or bind matrix.
inline Float3 Translation(const Mat34& m) { return {m.m[3], m.m[7], m.m[11]}; }

}  // namespace drape::bake::detail

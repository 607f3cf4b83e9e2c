#pragma once
// The garment's schema: the table of /garments/i and of the objects it holds (the shape of each
// garment type, the material and its springs, the attach and pin selections and their box).

#include "config/json_schema.h"
#include "drape/bake/scene.h"

namespace drape::bake::detail {

const JsonSchema<SceneGarment>& GarmentSchema();

}  // namespace drape::bake::detail

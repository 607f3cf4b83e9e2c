#pragma once
// The scene's schema: one table per JSON object of a scene file (/, /animation, /collision,
// /solver, /output and /output/camera; /garments/i is the garment's schema, garment_schema.h, and
// /bake the bake config's). ParseScene reads a scene through it and then applies the rules that
// span objects; the scenes reference (docs/SCENES.md) prints it.

#include "config/json_schema.h"
#include "drape/bake/bake_config.h"
#include "drape/bake/scene.h"

namespace drape::bake::detail {

const JsonSchema<Scene>& SceneSchema();

// A scene's /bake: drape-bake's parameters, without the collider kinds (from /collision/methods)
// and the maps' clip (from /animation/clip), read over *config.
Status ReadBakeOverrides(const JsonAt& at, BakeConfig* config);

}  // namespace drape::bake::detail

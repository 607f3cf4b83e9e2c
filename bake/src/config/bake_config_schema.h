#pragma once
// The bake config's schema: one table per section (import, maps, hulls, spheres). Read by
// ApplyBakeConfig and by a scene's /bake; printed by drape-bake --dump-config and in the scenes
// reference.

#include "config/json_schema.h"
#include "drape/bake/bake_config.h"

namespace drape::bake {

const JsonSchema<BakeConfig>& BakeConfigSchema();

}  // namespace drape::bake

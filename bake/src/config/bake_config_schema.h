#pragma once
// The bake config's schema: one table per section (import, maps, hulls, spheres). Read by
// ApplyBakeConfig and by a scene's /bake; printed by drape-bake --dump-config and in the scenes
// reference.

#include "drape/bake/bake_config.h"
#include "json_schema.h"  // beside this file: see json_schema.h on the fuzz target

namespace drape::bake {

const JsonSchema<BakeConfig>& BakeConfigSchema();

}  // namespace drape::bake

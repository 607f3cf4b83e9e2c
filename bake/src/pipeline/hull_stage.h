#pragma once
// The hull stage of the bake pipeline (bake_pipeline.cpp): per bone, its region split into convex
// pieces that fit the body (hulls.cut_fraction x hulls.max_bloat, hulls.max_pieces), one hull per
// piece with its OBB, Kirkpatrick hierarchies and map table, and the faces that lie inside the
// body marked.

#include <nlohmann/json.hpp>

#include "drape/bake/bake_config.h"
#include "drape/bake/character.h"
#include "drape/bake/regions.h"
#include "drape/formats/character_asset.h"
#include "drape/formats/status.h"

namespace drape::bake::detail {

// The hulls into asset->hulls; report: the hulls' entry (one per collider, those left out and
// why, the vertex fractions). A bone too small for a solid leaves its vertices to a joint sphere
// (regions' flexible vertices).
Status BakeHullStage(const BakeConfig& config, Regions& regions, const Character& character,
                     CharacterAsset* asset, nlohmann::json* report);

}  // namespace drape::bake::detail

#pragma once
// The body-map stage of the bake pipeline (bake_pipeline.cpp): the poses to bake, the view axis
// (maps.view_axis), the resolution and layers (maps.max_error), and the maps of every pose.

#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "drape/bake/bake_config.h"
#include "drape/bake/character.h"
#include "drape/bake/regions.h"
#include "drape/formats/character_asset.h"
#include "drape/formats/status.h"

namespace drape::bake::detail {

// The poses whose maps are baked: the rest pose, or every time of one clip at maps_clip_rate
// (0 = each of the clip's resampled frames).
struct MapPoseRequest {
  int32_t clip = -1;
  float time = 0.f;
};

const char* RendererName(MapRenderer r);

// The poses the maps are baked at; refuses a clip the character lacks, naming where the clip
// was named and listing the character's clips.
Status MapPoseRequests(const std::string& input, const BakeConfig& config,
                       const Character& character, std::vector<MapPoseRequest>* out);

// The maps of every requested pose into asset->body_maps: the view axis and, with
// maps.max_error, the setting chosen first; report: body_maps' entry (view axis, the setting's
// expected error, one entry per pose); warnings go to character.warnings. Previews of the first
// and last pose into preview_dir unless it is empty.
Status BakeMapStage(const BakeConfig& config, std::span<const MapPoseRequest> requests,
                    const Regions& regions, Character& character, const std::string& preview_dir,
                    CharacterAsset* asset, nlohmann::json* report);

// maps.asset_budget_mb: the whole encoded asset against the budget (report["size"]). Over it,
// the maps of every pose are baked again at the resolution that fits what the other sections
// leave (never below kMinBudgetResolution; at it when they leave nothing), up to three times,
// replacing report["body_maps"]'s poses; still over: a warning naming what takes the bytes.
// 0: no budget.
inline constexpr uint32_t kMinBudgetResolution = 256;
Status FitMapsToBudget(const BakeConfig& config, std::span<const MapPoseRequest> requests,
                       const Regions& regions, Character& character, const std::string& preview_dir,
                       CharacterAsset* asset, nlohmann::json* report);

}  // namespace drape::bake::detail

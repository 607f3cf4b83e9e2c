// The body-map stage of the bake: which poses, seen along which axis, at which resolution and
// layers (maps.max_error), baked into the asset, with the report's entries and previews.
#include "pipeline/map_stage.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

#include "body_map/map_error.h"
#include "config/clip_lookup.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"

namespace drape::bake::detail {
namespace {

using nlohmann::json;

json MapErrorToJson(const MapError& e) {
  return {{"error_p99_mm", e.p99_mm},
          {"error_max_mm", e.max_mm},
          {"misclassified_beyond_band", e.misclassified_beyond_band},
          {"samples", e.samples}};
}

// The maps' view axis: the configured one, or the rest pose's least-air axis (reported with the
// inside volume along each axis).
Status ChooseViewAxis(const BakeConfig& config, const Regions& regions, const Character& character,
                      BodyMapViewAxis* axis, json* report) {
  switch (config.maps_view_axis) {
    case BakeConfig::MapViewAxis::kX:
      *axis = BodyMapViewAxis::kX;
      break;
    case BakeConfig::MapViewAxis::kY:
      *axis = BodyMapViewAxis::kY;
      break;
    case BakeConfig::MapViewAxis::kZ:
      *axis = BodyMapViewAxis::kZ;
      break;
    case BakeConfig::MapViewAxis::kAuto: {
      ViewAxisChoice choice;
      if (Status s = ChooseBodyMapViewAxis(regions.rest_positions, character.mesh.triangles,
                                           config.maps, &choice);
          !s.ok()) {
        return Status(s.code(), "body maps: view axis: " + s.message());
      }
      *axis = choice.axis;
      (*report)["inside_litres_by_axis"] = {{"x", choice.inside_volume[1] * 1e3},
                                            {"y", choice.inside_volume[2] * 1e3},
                                            {"z", choice.inside_volume[0] * 1e3}};
      break;
    }
  }
  (*report)["view_axis"] = BodyMapViewAxisName(*axis);
  return Status::Ok();
}

// maps.max_error: the cheapest resolution and layers within the budget at the rest pose
// (body_map/map_error.h), every setting tried in the report, a warning when none is.
Status ChooseSettingForError(const BakeConfig& config, const Regions& regions, Character& character,
                             BodyMapOptions* options, json* report) {
  MapSettingChoice choice;
  if (Status s = ChooseMapSetting(regions.rest_positions, character.mesh.triangles, *options,
                                  config.maps_max_error_mm, &choice);
      !s.ok()) {
    return Status(s.code(), "body maps: maps.max_error: " + s.message());
  }
  options->resolution = choice.resolution;
  options->layers = choice.layers;
  json tried = json::array();
  for (const MapSettingTried& t : choice.tried) {
    json entry = MapErrorToJson(t.error);
    entry["resolution"] = t.resolution;
    entry["layers"] = t.layers;
    entry["bytes"] = t.bytes;
    tried.push_back(entry);
  }
  (*report)["max_error"] = {{"budget_mm", config.maps_max_error_mm},
                            {"within_budget", choice.within_budget},
                            {"resolution", choice.resolution},
                            {"layers", choice.layers},
                            {"tried", tried}};
  (*report)["expected_error"] = MapErrorToJson(choice.error);
  if (!choice.within_budget) {
    char what[200];
    std::snprintf(what, sizeof(what),
                  "maps.max_error %.2f mm is not reached by any setting up to N = 2048 with air "
                  "gaps: the best, N = %u with %u layer(s), errs %.2f mm (p99)",
                  config.maps_max_error_mm, choice.resolution, unsigned{choice.layers},
                  choice.error.p99_mm);
    character.warnings.push_back(what);
  }
  return Status::Ok();
}

}  // namespace

const char* RendererName(MapRenderer r) { return r == MapRenderer::kCpu ? "cpu" : "osmesa"; }

// The poses the maps are baked at; refuses a clip the character lacks, naming where the clip
// was named and listing the character's clips.
Status MapPoseRequests(const std::string& input, const BakeConfig& config,
                       const Character& character, std::vector<MapPoseRequest>* out) {
  out->clear();
  if (config.maps_clip.empty()) {
    out->push_back({});
    return Status::Ok();
  }
  int32_t c = -1;
  const std::string origin =
      config.maps_clip_origin.empty() ? std::string("/maps/clip") : config.maps_clip_origin;
  if (Status s = detail::FindClipNamed(character.clips, config.maps_clip, origin, input, &c);
      !s.ok())
    return s;
  const ClipData& clip = character.clips[static_cast<size_t>(c)];
  const float rate = config.maps_clip_rate > 0.f ? config.maps_clip_rate : clip.sample_rate;
  const uint32_t count = static_cast<uint32_t>(std::ceil(clip.duration * rate - 1e-3f)) + 1;
  for (uint32_t k = 0; k < count; ++k)
    out->push_back({c, std::min(static_cast<float>(k) / rate, clip.duration)});
  return Status::Ok();
}

Status BakeMapStage(const BakeConfig& config, std::span<const MapPoseRequest> requests,
                    const Regions& regions, Character& character, const std::string& preview_dir,
                    CharacterAsset* asset, json* report) {
  BodyMapOptions options = config.maps;
  if (Status s = ChooseViewAxis(config, regions, character, &options.view_axis, report); !s.ok())
    return s;
  if (config.maps_max_error_mm > 0.f) {
    if (Status s = ChooseSettingForError(config, regions, character, &options, report); !s.ok())
      return s;
  }
  SkeletonPose skeleton_pose;
  if (Status s = skeleton_pose.Init(character.skeleton); !s.ok()) return s;
  std::vector<Float3> posed(character.mesh.vertex_count());
  asset->body_maps.epsilon = config.maps.epsilon;
  asset->body_maps.resolution = options.resolution;
  asset->body_maps.fitted_window = config.maps.fitted_window;
  for (size_t r = 0; r < requests.size(); ++r) {
    const MapPoseRequest& request = requests[r];
    std::span<const Float3> positions = regions.rest_positions;
    if (request.clip >= 0) {
      if (Status s = skeleton_pose.SampleClip(character.clips[request.clip], request.time, false);
          !s.ok())
        return s;
      if (Status s = SkinMesh(character.mesh, skeleton_pose.skinning(), posed); !s.ok()) return s;
      positions = posed;
    }
    BodyMapPose pose;
    pose.clip = request.clip;
    pose.time = request.time;
    BodyMapPoseStats stats;
    if (Status s = BakeBodyMapPose(positions, character.mesh.triangles, options, &pose, &stats);
        !s.ok()) {
      return Status(s.code(), "body maps: " + s.message());
    }
    const std::string name =
        request.clip < 0 ? "rest"
                         : character.clips[request.clip].name + "@" + std::to_string(request.time);
    if (!preview_dir.empty() && (r == 0 || r + 1 == requests.size())) {
      std::string prefix = "maps_" + name;
      for (char& c : prefix)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
      if (Status s = WriteBodyMapPreview(pose, preview_dir, prefix); !s.ok()) return s;
    }
    asset->body_maps.poses.push_back(std::move(pose));
    (*report)["poses"].push_back(
        {{"pose", name},
         {"resolution", options.resolution},
         {"window_texels", {stats.window_width, stats.window_height}},
         {"rectangle_texels", {stats.width, stats.height}},
         {"layout", options.layout == BodyMapLayout::kRowSpans ? "spans" : "dense"},
         {"stored_texels", stats.stored_texels},
         {"texel_size_mm", stats.texel_size_mm},
         {"coverage", stats.coverage},
         {"bytes", stats.bytes},
         {"render_ms_front", stats.render_ms_front},
         {"render_ms_back", stats.render_ms_back},
         {"renderer", stats.renderer},
         {"silhouette_conflicts", stats.silhouette_conflicts},
         {"layers", stats.layers},
         {"gap_texels", stats.gap_texels},
         {"dropped_gaps", stats.dropped_gaps},
         {"gap_ms", stats.gap_ms}});
  }
  // The rest pose's error for the report (maps.max_error measured it already): about 60 ms.
  if (!report->contains("expected_error") && !requests.empty() && requests[0].clip < 0) {
    const MapErrorSamples samples =
        SampleMapError(regions.rest_positions, character.mesh.triangles);
    (*report)["expected_error"] =
        MapErrorToJson(MeasureMapError(asset->body_maps.poses[0], options.epsilon, samples));
  }
  return Status::Ok();
}

}  // namespace drape::bake::detail

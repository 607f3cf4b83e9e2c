// The body-map stage of the bake: which poses, seen along which axis, at which resolution and
// layers (maps.max_error), baked into the asset, with the report's entries and previews.
#include "pipeline/map_stage.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

#include "body_map/map_error.h"
#include "config/clip_lookup.h"
#include "drape/formats/asset_file.h"
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

namespace {

// Bytes of the asset as the writer encodes it (0 when it does not encode: CheckRuntimeAccepts
// says why later).
double EncodedBytes(const CharacterAsset& asset) {
  std::vector<uint8_t> bytes;
  return EncodeAsset(asset, &bytes).ok() ? static_cast<double>(bytes.size()) : 0.0;
}

// Bytes of the asset without its body-map poses: what the other sections take.
double BytesBesideMaps(CharacterAsset* asset) {
  std::vector<BodyMapPose> poses = std::move(asset->body_maps.poses);
  asset->body_maps.poses.clear();
  const double bytes = EncodedBytes(*asset);
  asset->body_maps.poses = std::move(poses);
  return bytes;
}

// Megabytes with two decimals, for messages.
std::string Megabytes(double bytes) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.2f MB", bytes * 1e-6);
  return text;
}

}  // namespace

Status FitMapsToBudget(const BakeConfig& config, std::span<const MapPoseRequest> requests,
                       const Regions& regions, Character& character, const std::string& preview_dir,
                       CharacterAsset* asset, json* report) {
  const double budget = 1e6 * static_cast<double>(config.maps_asset_budget_mb);  // bytes
  double bytes = EncodedBytes(*asset);
  const uint32_t first = asset->body_maps.resolution;
  for (int attempt = 0; attempt < 3 && budget > 0.0 && bytes > budget; ++attempt) {
    const double other = BytesBesideMaps(asset);
    const double maps = bytes - other;
    const uint32_t n = asset->body_maps.resolution;
    if (!(maps > 0.0) || n <= kMinBudgetResolution) break;
    // Bytes go with the texels, N^2; 3 % under, to a multiple of 16. The other sections alone
    // over the budget: the least resolution, the nearest the asset gets.
    const double scale = other < budget ? std::sqrt((budget - other) / maps) * 0.97 : 0.0;
    const uint32_t next =
        std::max(kMinBudgetResolution, static_cast<uint32_t>(n * scale) / 16u * 16u);
    if (next >= n) break;
    BakeConfig lower = config;
    lower.maps.resolution = next;
    lower.maps_max_error_mm = 0.f;  // the budget decides now (below)
    // The layers maps.max_error chose, else the configured ones (a pose holds only as many as
    // the gaps it found).
    const json& chosen = (*report)["body_maps"];
    if (chosen.contains("max_error"))
      lower.maps.layers = chosen["max_error"]["layers"].get<uint8_t>();
    json maps_report = {{"renderer", (*report)["body_maps"]["renderer"]}, {"poses", json::array()}};
    asset->body_maps.poses.clear();
    if (Status s =
            BakeMapStage(lower, requests, regions, character, preview_dir, asset, &maps_report);
        !s.ok())
      return s;
    for (const auto& [key, value] : (*report)["body_maps"].items())
      if (!maps_report.contains(key)) maps_report[key] = value;  // render mesh, max_error
    (*report)["body_maps"] = std::move(maps_report);
    bytes = EncodedBytes(*asset);
  }
  const uint32_t last = asset->body_maps.resolution;
  (*report)["size"] = {{"bytes", bytes}, {"budget_bytes", budget}};
  if (last != first) {
    (*report)["size"]["maps_resolution"] = {{"from", first}, {"to", last}};
    if (config.maps_max_error_mm > 0.f) {
      character.warnings.push_back(
          "maps.max_error chose N = " + std::to_string(first) +
          ", lowered to N = " + std::to_string(last) +
          " to keep the asset within maps.asset_budget_mb (" + Megabytes(budget) +
          "); the maps' expected error is the report's, at N = " + std::to_string(last));
    }
  }
  if (budget > 0.0 && bytes > budget) {
    const double other = BytesBesideMaps(asset);
    character.warnings.push_back(
        "the asset takes " + Megabytes(bytes) + ", over maps.asset_budget_mb (" +
        Megabytes(budget) + "): its " + std::to_string(asset->body_maps.poses.size()) +
        " body-map poses at N = " + std::to_string(last) + " take " + Megabytes(bytes - other) +
        " (N = " + std::to_string(kMinBudgetResolution) +
        " at least), the rest (colliders, mesh, clips) " + Megabytes(other));
  }
  return Status::Ok();
}

}  // namespace drape::bake::detail

#include "drape/bake/bake_pipeline.h"

#include <chrono>

#include "drape/bake/importer.h"
#include "drape/formats/asset_file.h"

namespace drape::bake {
namespace {

using Clock = std::chrono::steady_clock;
double MillisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace

Status BakeCharacter(const std::string& input, const BakeConfig& config, BakeResult* result) {
  nlohmann::json& report = result->report;
  report = nlohmann::json::object();
  report["input"] = input;
  report["tool_version"] = DRAPE_VERSION_STRING;
  report["format_version"] = kAssetFormatVersion;
  report["config"] = BakeConfigToJson(config);
  nlohmann::json timings = nlohmann::json::object();

  const auto import_start = Clock::now();
  Character character;
  if (Status s = ImportCharacter(input, config.import, &character); !s.ok()) return s;
  timings["import_ms"] = MillisecondsSince(import_start);

  CharacterAsset& asset = result->asset;
  asset = CharacterAsset{};
  asset.info = character.info;
  asset.skeleton = character.skeleton;
  asset.clips = character.clips;
  asset.mesh = character.mesh;

  report["unit_scale"] = character.info.unit_scale;
  report["up_axis"] = character.info.up_axis;
  nlohmann::json matrix = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) {
    matrix.push_back({character.source_to_asset[4 * r], character.source_to_asset[4 * r + 1],
                      character.source_to_asset[4 * r + 2], character.source_to_asset[4 * r + 3]});
  }
  report["source_to_asset"] = matrix;
  report["joint_count"] = asset.skeleton.joint_count();
  nlohmann::json clips = nlohmann::json::array();
  for (const ClipData& clip : asset.clips) {
    clips.push_back(
        {{"name", clip.name}, {"duration_s", clip.duration}, {"frames", clip.frame_count}});
  }
  report["clips"] = clips;
  report["mesh"] = {{"vertices", asset.mesh.vertex_count()},
                    {"triangles", asset.mesh.triangle_count()}};
  report["warnings"] = character.warnings;

  const auto validate_start = Clock::now();
  if (Status s = ValidateAsset(asset); !s.ok()) {
    return Status(s.code(), input + ": the baked asset does not validate: " + s.message());
  }
  timings["validate_ms"] = MillisecondsSince(validate_start);
  report["timings"] = timings;
  return Status::Ok();
}

}  // namespace drape::bake

#include "map_dump.h"

#include <cctype>
#include <filesystem>
#include <string>
#include <system_error>

#include "../replay_maps/motions_file.h"
#include "drape/formats/asset_file.h"
#include "methods.h"
#include "options.h"

namespace drape::bench {
namespace {

std::string Slug(std::string text) {  // letters and digits kept, the rest '_'
  for (char& c : text) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return text;
}

// DIR/replay/<character>, the directory made on first use.
std::string ReplayStem(const std::string& out_dir, const CharacterSpec& spec) {
  const std::filesystem::path dir = std::filesystem::path(out_dir) / "replay";
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) Fail(dir.string() + ": cannot create (" + error.message() + ")");
  return (dir / Slug(spec.label)).string();
}

}  // namespace

void DumpMotions(const std::string& out_dir, const CharacterSpec& spec, const QuerySet& mix) {
  const std::string path = ReplayStem(out_dir, spec) + "_mix.motions";
  if (const Status s = WriteFileAtomically(path, EncodeMotions(mix, kStepSeconds, BenchResponse()));
      !s.ok()) {
    Fail(s.message());
  }
}

void DumpMapPose(const std::string& out_dir, const CharacterSpec& spec, const MapSetting& m,
                 const BodyMapPose& pose) {
  CharacterAsset asset;
  asset.info.source_name = std::filesystem::path(spec.path).filename().string();
  asset.body_maps.resolution = m.resolution;
  asset.body_maps.epsilon = m.epsilon;
  asset.body_maps.fitted_window = m.fitted;
  asset.body_maps.poses.push_back(pose);
  const std::string path = ReplayStem(out_dir, spec) + "_" + Slug(Describe(m)) + ".drape";
  if (const Status s = WriteAssetFile(path, asset); !s.ok()) Fail(s.message());
}

}  // namespace drape::bench

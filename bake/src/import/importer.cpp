#include "drape/bake/importer.h"

#include <assimp/Importer.hpp>
#include <cmath>
#include <filesystem>

#include "import/asset_frame.h"
#include "import/clip_resampler.h"
#include "import/import_messages.h"
#include "import/mesh_import.h"
#include "import/skeleton_import.h"
#include "import/source_scene.h"

namespace drape::bake {
namespace {

using detail::SourceError;

// Refuses a missing, empty or directory path and options out of their documented range before
// assimp reads anything.
Status CheckImportInputs(const std::string& path, const ImportOptions& options) {
  std::error_code fs_error;
  if (!std::filesystem::exists(path, fs_error))
    return SourceError(path, StatusCode::kIoError, "file not found");
  if (std::filesystem::is_directory(path, fs_error))
    return SourceError(path, StatusCode::kIoError, "is a directory");
  if (std::filesystem::file_size(path, fs_error) == 0)
    return SourceError(path, StatusCode::kCorrupt, "file is empty");
  if (!(options.clip_sample_rate > 0.f && options.clip_sample_rate <= 1000.f)) {
    return SourceError(path, StatusCode::kInvalidArgument,
                       "clip_sample_rate must be in (0, 1000] Hz");
  }
  if (!(options.unit_scale >= 0.0 && std::isfinite(options.unit_scale))) {
    return SourceError(path, StatusCode::kInvalidArgument, "unit_scale must be >= 0 (0 = detect)");
  }
  return Status::Ok();
}

// The source's name, the tool version and the asset frame, with the frame's provenance as the
// first warning of the report.
void RecordSourceInfo(const std::string& path, const detail::AssetFrame& frame,
                      Character* character) {
  character->info.source_name = std::filesystem::path(path).filename().string();
  character->info.tool_version = DRAPE_VERSION_STRING;
  character->info.unit_scale = static_cast<float>(frame.scale);
  character->info.up_axis = frame.up;
  character->info.source_to_asset = detail::ToMat34(frame.to_asset);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) character->source_to_asset[4 * r + c] = frame.to_asset(r, c);
  character->warnings.insert(character->warnings.begin(), "unit scale " + detail::Fmt(frame.scale) +
                                                              " m/unit from " + frame.scale_source +
                                                              "; up axis " + frame.up + " from " +
                                                              frame.up_source);
}

}  // namespace

Status ImportCharacter(const std::string& path, const ImportOptions& options,
                       Character* character) {
  *character = Character{};
  if (Status s = CheckImportInputs(path, options); !s.ok()) return s;

  Assimp::Importer importer;  // owns the scene the stages read
  detail::SourceScene source;
  if (Status s = detail::ReadSourceScene(path, &importer, &source); !s.ok()) return s;

  detail::JointNodes joints;
  if (Status s = detail::SelectJointNodes(path, source, &joints); !s.ok()) return s;

  detail::AssetFrame frame;
  if (Status s = detail::ChooseAssetFrame(path, options, source, &frame, &character->warnings);
      !s.ok()) {
    return s;
  }

  std::vector<detail::Mat4> inverse_bind_source;  // per joint, source units
  if (Status s = detail::BuildSkeleton(path, options, source, joints, frame, character,
                                       &inverse_bind_source);
      !s.ok()) {
    return s;
  }

  if (Status s =
          detail::ImportBindMesh(path, source, joints, frame, inverse_bind_source, character);
      !s.ok()) {
    return s;
  }

  if (!joints.synthetic_root) {
    if (Status s = detail::ResampleClips(path, options, source, joints, frame, character);
        !s.ok()) {
      return s;
    }
  }

  RecordSourceInfo(path, frame, character);
  return Status::Ok();
}

}  // namespace drape::bake

#include "drape/bake/importer.h"

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <filesystem>

#include "import/asset_frame.h"
#include "import/child_process.h"
#include "import/clip_resampler.h"
#include "import/header_prescan.h"
#include "import/import_messages.h"
#include "import/mesh_import.h"
#include "import/recording_io_system.h"
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
  if (options.memory_limit_mb < 64 || options.memory_limit_mb > 1048576)
    return SourceError(path, StatusCode::kInvalidArgument,
                       "memory_limit_mb must be in [64, 1048576]");
  if (!(options.time_limit_s > 0.f && options.time_limit_s <= 86400.f))
    return SourceError(path, StatusCode::kInvalidArgument, "time_limit_s must be in (0, 86400] s");
  return Status::Ok();
}

// The source's name, the tool version and the asset frame with its provenance; the provenance is
// the report's first warning when it was assumed (a format that states no unit or up axis, or
// the size heuristic) rather than given by the config, the file, or the format's specification.
void RecordSourceInfo(const std::string& path, const detail::AssetFrame& frame,
                      Character* character) {
  character->info.source_name = std::filesystem::path(path).filename().string();
  character->info.tool_version = DRAPE_VERSION_STRING;
  character->info.unit_scale = static_cast<float>(frame.scale);
  character->info.up_axis = frame.up;
  character->info.source_to_asset = detail::ToMat34(frame.to_asset);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) character->source_to_asset[4 * r + c] = frame.to_asset(r, c);
  character->frame_provenance = "unit scale " + detail::Fmt(frame.scale) + " m/unit from " +
                                frame.scale_source + "; up axis " + frame.up + " from " +
                                frame.up_source;
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const bool specified = extension == ".gltf" || extension == ".glb";  // metres, +Y up by spec
  const bool assumed = frame.scale_source.find(", then x") != std::string::npos ||
                       (!specified && (frame.scale_source.rfind("format default", 0) == 0 ||
                                       frame.up_source == "format default"));
  if (assumed) {
    character->warnings.insert(character->warnings.begin(), character->frame_provenance);
  }
}

// The import's stages, in this process.
Status ImportStages(const std::string& path, const ImportOptions& options, Character* character) {
  Assimp::Importer importer;  // owns the scene the stages read
  importer.SetIOHandler(new detail::RecordingIOSystem(&character->source_files));  // it owns it
  detail::SourceScene source;
  if (Status s = detail::ReadSourceScene(path, &importer, &source, &character->warnings); !s.ok())
    return s;

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

}  // namespace

Status ImportCharacter(const std::string& path, const ImportOptions& options,
                       Character* character) {
  *character = Character{};
  if (Status s = CheckImportInputs(path, options); !s.ok()) return s;
  std::vector<std::string> prescan_warnings;
  if (Status s = detail::PrescanModelFile(path, &prescan_warnings); !s.ok()) return s;
  // A child process reads the file first: what would crash, hang or exhaust this process there
  // becomes an error here. Only a file it read cleanly is read again in this process.
  const detail::ChildLimits limits{static_cast<uint64_t>(options.memory_limit_mb) << 20,
                                   static_cast<double>(options.time_limit_s)};
  if (Status s = detail::RunInChildProcess(path, limits,
                                           [&] {
                                             Character probe;
                                             return ImportStages(path, options, &probe);
                                           });
      !s.ok()) {
    return s;
  }
  if (Status s = ImportStages(path, options, character); !s.ok()) return s;
  character->warnings.insert(character->warnings.end(), prescan_warnings.begin(),
                             prescan_warnings.end());
  return Status::Ok();
}

std::vector<std::string> ReadableExtensions() {
  std::string list;  // "*.3d;*.3ds;..."
  Assimp::Importer().GetExtensionList(list);
  std::vector<std::string> extensions;
  for (size_t at = 0; at < list.size();) {
    size_t end = list.find(';', at);
    if (end == std::string::npos) end = list.size();
    std::string pattern = list.substr(at, end - at);
    if (pattern.rfind("*.", 0) == 0) pattern.erase(0, 1);
    for (char& c : pattern) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (!pattern.empty()) extensions.push_back(pattern);
    at = end + 1;
  }
  std::sort(extensions.begin(), extensions.end());
  extensions.erase(std::unique(extensions.begin(), extensions.end()), extensions.end());
  return extensions;
}

}  // namespace drape::bake

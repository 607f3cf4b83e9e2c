#include "config/clip_lookup.h"

namespace drape::bake::detail {

Status FindClipNamed(std::span<const ClipData> clips, const std::string& name,
                     const std::string& origin, const std::string& character, int32_t* index) {
  *index = -1;
  std::string names;
  for (size_t c = 0; c < clips.size(); ++c) {
    if (clips[c].name == name) {
      *index = static_cast<int32_t>(c);
      return Status::Ok();
    }
    names += (names.empty() ? "" : " | ") + clips[c].name;
  }
  return Status(StatusCode::kInvalidArgument,
                origin + ": no clip named '" + name + "' in '" + character +
                    "' (clips: " + (names.empty() ? "none" : names) + ")");
}

}  // namespace drape::bake::detail

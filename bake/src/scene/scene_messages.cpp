#include "scene/scene_messages.h"

namespace drape::bake::detail {

Status Invalid(const std::string& message) { return Status(StatusCode::kInvalidArgument, message); }

std::string Quote(const std::string& s) { return "'" + s + "'"; }

std::string JoinNames(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : " | ") + n;
  return out;
}

}  // namespace drape::bake::detail

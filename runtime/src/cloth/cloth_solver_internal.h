#pragma once
// Private to the runtime: what the cloth solver's files share.

#include <cmath>
#include <cstdint>
#include <string>

#include "drape/formats/status.h"
#include "drape/formats/types.h"

namespace drape::detail {

inline Status InvalidArgument(const std::string& message) {
  return Status(StatusCode::kInvalidArgument, "ClothSolver: " + message);
}

inline bool Finite(const Mat34& m) {
  for (const float v : m.m)
    if (!std::isfinite(v)) return false;
  return true;
}

}  // namespace drape::detail

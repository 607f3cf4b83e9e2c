#pragma once
// Private to the runtime: what the cloth solver's files share.

#include <cmath>
#include <cstdint>
#include <string>

#include "drape/formats/status.h"
#include "drape/formats/types.h"

namespace drape::detail {

// Below this many particles a solver loop runs on one thread: forking costs more than it
// saves. The result is the same either way (per-index writes).
constexpr int64_t kParallelParticles = 2048;

inline Status InvalidArgument(const std::string& message) {
  return Status(StatusCode::kInvalidArgument, "ClothSolver: " + message);
}

inline bool Finite(const Mat34& m) {
  for (const float v : m.m)
    if (!std::isfinite(v)) return false;
  return true;
}

}  // namespace drape::detail

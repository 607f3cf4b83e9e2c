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

constexpr uint32_t kNoParticle = 0xffffffffu;

// Whether a position or velocity of particles [begin, end) is not finite. a - a is +0 for every
// finite a and NaN for infinities and NaN, so a particle's sum below is 0 exactly when its six
// components are finite (an integer OR: the same in any order).
inline bool AnyNonFinite(const Float3* x, const Float3* v, int64_t begin, int64_t end) {
  uint32_t bad = 0;
  for (int64_t i = begin; i < end; ++i) {
    const Float3 p = x[i], u = v[i];
    const float zero =
        (((p.x - p.x) + (p.y - p.y)) + ((p.z - p.z) + (u.x - u.x))) + ((u.y - u.y) + (u.z - u.z));
    bad |= static_cast<uint32_t>(!(zero == 0.f));
  }
  return bad != 0;
}

inline bool Finite(const Mat34& m) {
  for (const float v : m.m)
    if (!std::isfinite(v)) return false;
  return true;
}

}  // namespace drape::detail

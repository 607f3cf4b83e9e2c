#pragma once
// Private to the runtime: the last step of every hull and sphere response, which puts the
// response point on the outer side of its surface in the float arithmetic the inside tests use.

#include <algorithm>

#include "common/branchless.h"
#include "drape/runtime/math.h"

namespace drape::detail {

template <typename SignedDistance>
inline Float3 NudgeOut(Float3 p, Float3 n, float scale, SignedDistance signed_distance) {
  float f = signed_distance(p);
  float step = 1e-7f * scale;
  // The first step is taken unconditionally and kept by selects: a point projected onto a plane
  // lands on either side of it by rounding, so a branch here is mispredicted half of the time.
  // Same steps and values as the plain loop.
  const Float3 moved = p + n * std::max(-f, step);
  const float f_moved = signed_distance(moved);
  const bool needed = f < 0.f;
  p = {SelectIf(needed, moved.x, p.x), SelectIf(needed, moved.y, p.y),
       SelectIf(needed, moved.z, p.z)};
  f = SelectIf(needed, f_moved, f);
  step = SelectIf(needed, step * 2.f, step);
  for (int k = 1; f < 0.f && k < 24; ++k) {
    p = p + n * std::max(-f, step);
    f = signed_distance(p);
    step *= 2.f;
  }
  return p;
}

}  // namespace drape::detail

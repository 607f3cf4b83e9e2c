#pragma once
// Private to the runtime: a select without a branch, for conditions the branch predictor cannot
// learn (which side of a surface rounding lands on, the octant of an angle).

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace drape::detail {

// condition ? if_true : if_false without a branch (bit masks on SSE2; a plain select elsewhere).
inline float SelectIf(bool condition, float if_true, float if_false) {
#if defined(__SSE2__)
  const __m128 mask = _mm_castsi128_ps(_mm_set1_epi32(-static_cast<int>(condition)));
  return _mm_cvtss_f32(
      _mm_or_ps(_mm_and_ps(mask, _mm_set_ss(if_true)), _mm_andnot_ps(mask, _mm_set_ss(if_false))));
#else
  return condition ? if_true : if_false;
#endif
}

}  // namespace drape::detail

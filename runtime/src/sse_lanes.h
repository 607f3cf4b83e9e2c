#pragma once
// Private to the runtime: SSE2 lane helpers shared by the colliders' four-lane paths. Each gives
// lane by lane what the scalar expression gives (IEEE single precision per lane), so a lane path
// can be bit for bit its scalar twin.

#if defined(__SSE2__)
#include <emmintrin.h>

namespace drape::detail {

// mask ? a : b per lane (mask lanes all ones or all zeros).
inline __m128 SelectLanes(__m128 mask, __m128 a, __m128 b) {
  return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b));
}
// std::min / std::max per lane, with their operand order: the first argument on ties and when
// the second is NaN (minps / maxps return their second operand then).
inline __m128 StdMin(__m128 a, __m128 b) { return _mm_min_ps(b, a); }  // b < a ? b : a
inline __m128 StdMax(__m128 a, __m128 b) { return _mm_max_ps(b, a); }  // a < b ? b : a
inline __m128 AbsLanes(__m128 v) { return _mm_andnot_ps(_mm_set1_ps(-0.f), v); }
// mask ? a : b per 32-bit integer lane (mask lanes all ones or all zeros).
inline __m128i SelectLanesI(__m128 mask, __m128i a, __m128i b) {
  const __m128i m = _mm_castps_si128(mask);
  return _mm_or_si128(_mm_and_si128(m, a), _mm_andnot_si128(m, b));
}

}  // namespace drape::detail

#endif

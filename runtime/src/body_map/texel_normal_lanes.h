#pragma once
// Private to the runtime: the body-map renderer's texel normals four texels at a time (SSE2, the
// x86-64 baseline): TriangleShading::At and EncodeOct16 per lane, bit for bit their scalar
// twins. The renderer encodes the front and back normal of every covered texel each frame (a
// quarter of a render's time in scalar code at fine texels).

#include <cstdint>

#include "body_map/raster_triangle.h"

#if defined(__SSE2__)
#include <emmintrin.h>

namespace drape::detail {

// Four normals, one per lane.
struct NormalLanes {
  __m128 x, y, z;
};

// mask ? a : b per lane (mask lanes all ones or all zeros).
inline __m128 SelectNormalLanes(__m128 mask, __m128 a, __m128 b) {
  return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b));
}

// TriangleShading::At for four texel centres (px, py), each with its own triangle's shading.
inline NormalLanes ShadeLanes(const TriangleShading* const shading[4], __m128 px, __m128 py,
                              Float3 fallback) {
  static_assert(sizeof(TriangleShading) == 18 * sizeof(float), "18 packed floats");
  // The first 16 floats of each lane's shading as four rows, transposed into fields.
  const float* s[4] = {&shading[0]->x0, &shading[1]->x0, &shading[2]->x0, &shading[3]->x0};
  __m128 f[16];
  for (int row = 0; row < 4; ++row) {
    __m128 a = _mm_loadu_ps(s[0] + 4 * row), b = _mm_loadu_ps(s[1] + 4 * row);
    __m128 c = _mm_loadu_ps(s[2] + 4 * row), d = _mm_loadu_ps(s[3] + 4 * row);
    _MM_TRANSPOSE4_PS(a, b, c, d);
    f[4 * row] = a;
    f[4 * row + 1] = b;
    f[4 * row + 2] = c;
    f[4 * row + 3] = d;
  }
  // Fields: 0 x0, 1 y0, 2 b1_x, 3 b1_y, 4 b2_x, 5 b2_y, 6-8 n0, 9-11 n1, 12-14 n2, 15 face.x.
  const __m128 face_y = _mm_setr_ps(s[0][16], s[1][16], s[2][16], s[3][16]);
  const __m128 face_z = _mm_setr_ps(s[0][17], s[1][17], s[2][17], s[3][17]);
  const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.f);
  const auto clamp = [](__m128 v, __m128 lo, __m128 hi) {  // std::clamp: v < lo ? lo : ...
    return SelectNormalLanes(_mm_cmplt_ps(v, lo), lo,
                             SelectNormalLanes(_mm_cmplt_ps(hi, v), hi, v));
  };
  const __m128 dx = _mm_sub_ps(px, f[0]), dy = _mm_sub_ps(py, f[1]);
  const __m128 b1 = clamp(_mm_add_ps(_mm_mul_ps(f[2], dx), _mm_mul_ps(f[3], dy)), zero, one);
  const __m128 b2 =
      clamp(_mm_add_ps(_mm_mul_ps(f[4], dx), _mm_mul_ps(f[5], dy)), zero, _mm_sub_ps(one, b1));
  const __m128 w0 = _mm_sub_ps(_mm_sub_ps(one, b1), b2);
  const auto blend = [&](int k) {  // n0 * w0 + n1 * b1 + n2 * b2, one component
    return _mm_add_ps(_mm_add_ps(_mm_mul_ps(f[6 + k], w0), _mm_mul_ps(f[9 + k], b1)),
                      _mm_mul_ps(f[12 + k], b2));
  };
  const NormalLanes n{blend(0), blend(1), blend(2)};
  const __m128 sign_bit = _mm_set1_ps(-0.f);
  const auto abs = [&](__m128 v) { return _mm_andnot_ps(sign_bit, v); };
  const __m128 usable =
      _mm_cmpgt_ps(_mm_add_ps(_mm_add_ps(abs(n.x), abs(n.y)), abs(n.z)), _mm_set1_ps(1e-6f));
  const __m128 face_set =
      _mm_or_ps(_mm_or_ps(_mm_cmpneq_ps(f[15], zero), _mm_cmpneq_ps(face_y, zero)),
                _mm_cmpneq_ps(face_z, zero));
  const NormalLanes other{SelectNormalLanes(face_set, f[15], _mm_set1_ps(fallback.x)),
                          SelectNormalLanes(face_set, face_y, _mm_set1_ps(fallback.y)),
                          SelectNormalLanes(face_set, face_z, _mm_set1_ps(fallback.z))};
  return {SelectNormalLanes(usable, n.x, other.x), SelectNormalLanes(usable, n.y, other.y),
          SelectNormalLanes(usable, n.z, other.z)};
}

// EncodeOct16 per lane: lane l's code (first value in the low 16 bits) in codes[l].
inline void EncodeOct16Lanes(const NormalLanes& n, uint32_t codes[4]) {
  const __m128 sign_bit = _mm_set1_ps(-0.f);
  const auto abs = [&](__m128 v) { return _mm_andnot_ps(sign_bit, v); };
  const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.f), minus_one = _mm_set1_ps(-1.f);
  const __m128 l1 = _mm_add_ps(_mm_add_ps(abs(n.x), abs(n.y)), abs(n.z));
  // Finite and above 1e-30 (false for NaN); the others encode +z.
  const __m128 usable = _mm_and_ps(_mm_cmpgt_ps(l1, _mm_set1_ps(1e-30f)),
                                   _mm_cmplt_ps(l1, _mm_set1_ps(__builtin_huge_valf())));
  __m128 a = _mm_div_ps(n.x, l1), b = _mm_div_ps(n.y, l1);
  const __m128 sign_a = SelectNormalLanes(_mm_cmpge_ps(a, zero), one, minus_one);
  const __m128 sign_b = SelectNormalLanes(_mm_cmpge_ps(b, zero), one, minus_one);
  const __m128 fold = _mm_cmplt_ps(n.z, zero);
  const __m128 folded_a = _mm_mul_ps(_mm_sub_ps(one, abs(b)), sign_a);
  const __m128 folded_b = _mm_mul_ps(_mm_sub_ps(one, abs(a)), sign_b);
  a = SelectNormalLanes(fold, folded_a, a);
  b = SelectNormalLanes(fold, folded_b, b);
  // lround of unit * 65535 in [0, 65535]: the integer part, plus one where the fraction (exact
  // in float) is at least 1/2, as the scalar's truncation of the value plus 1/2 in double.
  const auto quantise = [&](__m128 c) {
    __m128 unit = _mm_add_ps(_mm_mul_ps(c, _mm_set1_ps(0.5f)), _mm_set1_ps(0.5f));
    unit = SelectNormalLanes(_mm_cmplt_ps(unit, zero), zero, unit);
    unit = SelectNormalLanes(_mm_cmpgt_ps(unit, one), one, unit);
    const __m128 x = _mm_mul_ps(unit, _mm_set1_ps(65535.f));
    const __m128i whole = _mm_cvttps_epi32(x);
    const __m128 fraction = _mm_sub_ps(x, _mm_cvtepi32_ps(whole));
    const __m128i up = _mm_castps_si128(_mm_cmpge_ps(fraction, _mm_set1_ps(0.5f)));
    return _mm_sub_epi32(whole, up);  // up is -1 where it rounds up
  };
  const __m128i code = _mm_or_si128(quantise(a), _mm_slli_epi32(quantise(b), 16));
  const __m128i plus_z = _mm_set1_epi32(32768 | (32768 << 16));
  const __m128i mask = _mm_castps_si128(usable);
  _mm_storeu_si128(reinterpret_cast<__m128i*>(codes),
                   _mm_or_si128(_mm_and_si128(mask, code), _mm_andnot_si128(mask, plus_z)));
}

}  // namespace drape::detail

#endif  // __SSE2__

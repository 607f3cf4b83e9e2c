#pragma once
// Private to the runtime: the lane operations on four SSE2 lanes. Each gives lane by lane what the
// scalar expression gives (IEEE single precision per lane), so a lane path can be bit for bit its
// scalar twin.
//
// The lane operations are named once for any width: the overloads here take __m128 / __m128i,
// those of scalar_lanes.h take ScalarF / ScalarI, those of avx2_lanes.inl __m256 / __m256i, and a
// pack type (ScalarLanes, Sse2Lanes, EightLanes) holds what only the width decides. A template
// written in these names (body_map/lanes/, hull/plane_kernels.inl) is one text for every pack,
// with the same bits per lane.

#if defined(__SSE2__)
#include <emmintrin.h>

#include <cstdint>

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

namespace lanes {

// Float lanes: IEEE single-precision arithmetic per lane; comparisons give all-ones masks (false
// on NaN, as the scalar comparison).
inline __m128 Add(__m128 a, __m128 b) { return _mm_add_ps(a, b); }
inline __m128 Sub(__m128 a, __m128 b) { return _mm_sub_ps(a, b); }
inline __m128 Mul(__m128 a, __m128 b) { return _mm_mul_ps(a, b); }
inline __m128 Div(__m128 a, __m128 b) { return _mm_div_ps(a, b); }
inline __m128 Sqrt(__m128 a) { return _mm_sqrt_ps(a); }
inline __m128 And(__m128 a, __m128 b) { return _mm_and_ps(a, b); }
inline __m128 Or(__m128 a, __m128 b) { return _mm_or_ps(a, b); }
inline __m128 AndNot(__m128 not_a, __m128 b) { return _mm_andnot_ps(not_a, b); }  // ~a & b
inline __m128 Less(__m128 a, __m128 b) { return _mm_cmplt_ps(a, b); }
inline __m128 LessEq(__m128 a, __m128 b) { return _mm_cmple_ps(a, b); }
inline __m128 Greater(__m128 a, __m128 b) { return _mm_cmpgt_ps(a, b); }
inline __m128 GreaterEq(__m128 a, __m128 b) { return _mm_cmpge_ps(a, b); }
inline __m128 Equal(__m128 a, __m128 b) { return _mm_cmpeq_ps(a, b); }
// Bit l = lane l's sign bit (a mask's lane l).
inline uint32_t LaneBits(__m128 mask) { return static_cast<uint32_t>(_mm_movemask_ps(mask)); }

// 32-bit integer lanes (wrapping arithmetic; comparisons signed).
inline __m128i Add(__m128i a, __m128i b) { return _mm_add_epi32(a, b); }
inline __m128i Sub(__m128i a, __m128i b) { return _mm_sub_epi32(a, b); }
inline __m128i And(__m128i a, __m128i b) { return _mm_and_si128(a, b); }
inline __m128i Or(__m128i a, __m128i b) { return _mm_or_si128(a, b); }
inline __m128i AndNot(__m128i not_a, __m128i b) { return _mm_andnot_si128(not_a, b); }
inline __m128i Less(__m128i a, __m128i b) { return _mm_cmplt_epi32(a, b); }
inline __m128i Greater(__m128i a, __m128i b) { return _mm_cmpgt_epi32(a, b); }
inline __m128i Equal(__m128i a, __m128i b) { return _mm_cmpeq_epi32(a, b); }
inline __m128i High16(__m128i a) { return _mm_srli_epi32(a, 16); }  // logical shift: 0 .. 65535
inline __m128i Abs(__m128i x) {  // SSE2 has no pabsd; wraps for INT32_MIN as |x| would
  const __m128i sign = _mm_srai_epi32(x, 31);
  return _mm_sub_epi32(_mm_xor_si128(x, sign), sign);
}

// Conversions: truncation toward zero (the cast), exact int -> float below 2^24, bit casts.
inline __m128i TruncateToInt(__m128 a) { return _mm_cvttps_epi32(a); }
inline __m128 ToFloat(__m128i a) { return _mm_cvtepi32_ps(a); }
inline __m128i AsInt(__m128 a) { return _mm_castps_si128(a); }
inline __m128 AsFloat(__m128i a) { return _mm_castsi128_ps(a); }

}  // namespace lanes

// What only the width decides: four lanes of SSE2.
struct Sse2Lanes {
  static constexpr int kCount = 4;
  using F = __m128;
  using I = __m128i;
  static F Splat(float x) { return _mm_set1_ps(x); }
  static F Zero() { return _mm_setzero_ps(); }
  static I SplatI(int32_t x) { return _mm_set1_epi32(x); }
  static I ZeroI() { return _mm_setzero_si128(); }
  static I LaneBitValues() { return _mm_setr_epi32(1, 2, 4, 8); }  // lane l holds 1 << l
  // Lane l = value(l), built from scalars (not stored and read back: four scalar stores read as
  // one vector would stall the store forwarding).
  template <class Value>
  static F FromLanes(const Value& value) {
    return _mm_setr_ps(value(0), value(1), value(2), value(3));
  }
  template <class Value>
  static I FromLanesI(const Value& value) {
    return _mm_setr_epi32(value(0), value(1), value(2), value(3));
  }
  static F Load(const float* unaligned) { return _mm_loadu_ps(unaligned); }
  static void Store(int32_t* aligned, I a) {
    _mm_store_si128(reinterpret_cast<__m128i*>(aligned), a);
  }
  static void Store(float* aligned, F a) { _mm_store_ps(aligned, a); }
  // The 16-byte aligned (x, y, z, w) rows at rows[0..3] as lanes (a 4x4 transpose), and back.
  static void LoadRows4(float* const rows[4], F* x, F* y, F* z, F* w) {
    *x = _mm_load_ps(rows[0]);
    *y = _mm_load_ps(rows[1]);
    *z = _mm_load_ps(rows[2]);
    *w = _mm_load_ps(rows[3]);
    _MM_TRANSPOSE4_PS(*x, *y, *z, *w);
  }
  static void StoreRows4(float* const rows[4], F x, F y, F z, F w) {
    _MM_TRANSPOSE4_PS(x, y, z, w);
    _mm_store_ps(rows[0], x);
    _mm_store_ps(rows[1], y);
    _mm_store_ps(rows[2], z);
    _mm_store_ps(rows[3], w);
  }
  // Four consecutive (x, y, z) float triples (48 packed bytes) as lanes: three loads and a
  // transpose.
  static void LoadFloat3s(const void* triples, F* x, F* y, F* z) {
    const float* f = static_cast<const float*>(triples);
    const __m128 a = _mm_loadu_ps(f);      // x0 y0 z0 x1
    const __m128 b = _mm_loadu_ps(f + 4);  // y1 z1 x2 y2
    const __m128 c = _mm_loadu_ps(f + 8);  // z2 x3 y3 z3
    const __m128 b2c1 = _mm_shuffle_ps(b, c, _MM_SHUFFLE(1, 1, 2, 2));
    const __m128 a1b0 = _mm_shuffle_ps(a, b, _MM_SHUFFLE(0, 0, 1, 1));
    const __m128 b3c2 = _mm_shuffle_ps(b, c, _MM_SHUFFLE(2, 2, 3, 3));
    const __m128 a2b1 = _mm_shuffle_ps(a, b, _MM_SHUFFLE(1, 1, 2, 2));
    const __m128 c0c3 = _mm_shuffle_ps(c, c, _MM_SHUFFLE(3, 3, 0, 0));
    *x = _mm_shuffle_ps(a, b2c1, _MM_SHUFFLE(2, 0, 3, 0));
    *y = _mm_shuffle_ps(a1b0, b3c2, _MM_SHUFFLE(2, 0, 2, 0));
    *z = _mm_shuffle_ps(a2b1, c0c3, _MM_SHUFFLE(2, 0, 2, 0));
  }
  // LoadFloat3s' inverse: the lanes as four consecutive triples, three stores.
  static void StoreFloat3s(void* triples, F x, F y, F z) {
    float* f = static_cast<float*>(triples);
    const __m128 x0y0x1y1 = _mm_unpacklo_ps(x, y);
    const __m128 x2y2x3y3 = _mm_unpackhi_ps(x, y);
    const __m128 z0x1 = _mm_shuffle_ps(z, x, _MM_SHUFFLE(1, 1, 0, 0));
    const __m128 y1z1 = _mm_shuffle_ps(y, z, _MM_SHUFFLE(1, 1, 1, 1));
    const __m128 z2x3 = _mm_shuffle_ps(z, x, _MM_SHUFFLE(3, 3, 2, 2));
    const __m128 y3z3 = _mm_shuffle_ps(y, z, _MM_SHUFFLE(3, 3, 3, 3));
    _mm_storeu_ps(f, _mm_shuffle_ps(x0y0x1y1, z0x1, _MM_SHUFFLE(2, 0, 1, 0)));      // x0 y0 z0 x1
    _mm_storeu_ps(f + 4, _mm_shuffle_ps(y1z1, x2y2x3y3, _MM_SHUFFLE(1, 0, 2, 0)));  // y1 z1 x2 y2
    _mm_storeu_ps(f + 8, _mm_shuffle_ps(z2x3, y3z3, _MM_SHUFFLE(2, 0, 2, 0)));      // z2 x3 y3 z3
  }
  // The slabs (two floats, 8 bytes: top then bottom; the normals' two codes load the same way)
  // at address(0..3) as lanes: 8-byte loads into halves and two shuffles. A function of the lane,
  // not an array of addresses, so that no array is stored only to be read back.
  template <class Address>
  static void LoadSlabsAt(const Address& address, F* top, F* bottom) {
    const auto pair = [&](int lane) {
      return static_cast<const __m64*>(static_cast<const void*>(address(lane)));
    };
    const __m128 slabs01 = _mm_loadh_pi(_mm_loadl_pi(_mm_setzero_ps(), pair(0)), pair(1));
    const __m128 slabs23 = _mm_loadh_pi(_mm_loadl_pi(_mm_setzero_ps(), pair(2)), pair(3));
    *top = _mm_shuffle_ps(slabs01, slabs23, _MM_SHUFFLE(2, 0, 2, 0));
    *bottom = _mm_shuffle_ps(slabs01, slabs23, _MM_SHUFFLE(3, 1, 3, 1));
  }
};

}  // namespace drape::detail

#endif

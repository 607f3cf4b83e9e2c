// Private to the runtime: the lane operations of sse2_lanes.h on eight lanes (__m256), and the
// lane pack EightLanes. Included, after every header, inside the AVX2 target region of
// body_map/lanes/lanes_avx2.cpp and hull/plane_kernels_avx2.cpp.
//
// Each definition here has internal linkage (static, or the unnamed namespace): a linker merging
// weak copies compiled for AVX2 with baseline ones could hand AVX2 code to a CPU without it.
// tests/runtime/check_lane_objects.sh fails if one is ever shared.
//
// No #include here, for the reason body_map/lanes/lanes.inl gives.

namespace drape::detail {

// The operations of sse2_lanes.h on eight lanes, beside their SSE2 overloads (where the lane walk's
// using-declarations find both); this file alone defines them. Comparisons use the predicates of
// the SSE2 instructions (cmpltps is LT_OS, cmpeqps EQ_OQ, ...): the same mask bits, NaN included.
// Every mask the lanes select by is all ones or all zeros per lane (a comparison, or And / Or /
// AndNot of comparisons), so one blend by the sign bit selects what the SSE2 and / andnot / or
// does, in one instruction instead of three.
static inline __m256 SelectLanes(__m256 mask, __m256 a, __m256 b) {
  return _mm256_blendv_ps(b, a, mask);
}
static inline __m256 StdMin(__m256 a, __m256 b) { return _mm256_min_ps(b, a); }  // b < a ? b : a
static inline __m256 StdMax(__m256 a, __m256 b) { return _mm256_max_ps(b, a); }  // a < b ? b : a
static inline __m256 AbsLanes(__m256 v) { return _mm256_andnot_ps(_mm256_set1_ps(-0.f), v); }
static inline __m256i SelectLanesI(__m256 mask, __m256i a, __m256i b) {
  return _mm256_castps_si256(
      _mm256_blendv_ps(_mm256_castsi256_ps(b), _mm256_castsi256_ps(a), mask));
}

namespace lanes {

static inline __m256 Add(__m256 a, __m256 b) { return _mm256_add_ps(a, b); }
static inline __m256 Sub(__m256 a, __m256 b) { return _mm256_sub_ps(a, b); }
static inline __m256 Mul(__m256 a, __m256 b) { return _mm256_mul_ps(a, b); }
static inline __m256 Div(__m256 a, __m256 b) { return _mm256_div_ps(a, b); }
static inline __m256 Sqrt(__m256 a) { return _mm256_sqrt_ps(a); }
static inline __m256 And(__m256 a, __m256 b) { return _mm256_and_ps(a, b); }
static inline __m256 Or(__m256 a, __m256 b) { return _mm256_or_ps(a, b); }
static inline __m256 AndNot(__m256 not_a, __m256 b) { return _mm256_andnot_ps(not_a, b); }
static inline __m256 Less(__m256 a, __m256 b) { return _mm256_cmp_ps(a, b, _CMP_LT_OS); }
static inline __m256 LessEq(__m256 a, __m256 b) { return _mm256_cmp_ps(a, b, _CMP_LE_OS); }
static inline __m256 Greater(__m256 a, __m256 b) { return _mm256_cmp_ps(a, b, _CMP_GT_OS); }
static inline __m256 GreaterEq(__m256 a, __m256 b) { return _mm256_cmp_ps(a, b, _CMP_GE_OS); }
static inline __m256 Equal(__m256 a, __m256 b) { return _mm256_cmp_ps(a, b, _CMP_EQ_OQ); }
static inline uint32_t LaneBits(__m256 mask) {
  return static_cast<uint32_t>(_mm256_movemask_ps(mask));
}

static inline __m256i Add(__m256i a, __m256i b) { return _mm256_add_epi32(a, b); }
static inline __m256i Sub(__m256i a, __m256i b) { return _mm256_sub_epi32(a, b); }
static inline __m256i And(__m256i a, __m256i b) { return _mm256_and_si256(a, b); }
static inline __m256i Or(__m256i a, __m256i b) { return _mm256_or_si256(a, b); }
static inline __m256i AndNot(__m256i not_a, __m256i b) { return _mm256_andnot_si256(not_a, b); }
static inline __m256i Less(__m256i a, __m256i b) { return _mm256_cmpgt_epi32(b, a); }
static inline __m256i Greater(__m256i a, __m256i b) { return _mm256_cmpgt_epi32(a, b); }
static inline __m256i Equal(__m256i a, __m256i b) { return _mm256_cmpeq_epi32(a, b); }
static inline __m256i High16(__m256i a) {
  return _mm256_srli_epi32(a, 16);
}  // logical shift: 0 .. 65535
static inline __m256i Abs(__m256i x) { return _mm256_abs_epi32(x); }  // INT32_MIN stays, as in SSE2

static inline __m256i TruncateToInt(__m256 a) { return _mm256_cvttps_epi32(a); }
static inline __m256 ToFloat(__m256i a) { return _mm256_cvtepi32_ps(a); }
static inline __m256i AsInt(__m256 a) { return _mm256_castps_si256(a); }
static inline __m256 AsFloat(__m256i a) { return _mm256_castsi256_ps(a); }

}  // namespace lanes

namespace {

// What only the width decides: eight lanes (Sse2Lanes' twin).
struct EightLanes {
  static constexpr int kCount = 8;
  using F = __m256;
  using I = __m256i;
  static F Splat(float x) { return _mm256_set1_ps(x); }
  static F Zero() { return _mm256_setzero_ps(); }
  static I SplatI(int32_t x) { return _mm256_set1_epi32(x); }
  static I ZeroI() { return _mm256_setzero_si256(); }
  static I LaneBitValues() { return _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128); }
  template <class Value>
  static F FromLanes(const Value& value) {
    return _mm256_setr_ps(value(0), value(1), value(2), value(3), value(4), value(5), value(6),
                          value(7));
  }
  template <class Value>
  static I FromLanesI(const Value& value) {
    return _mm256_setr_epi32(value(0), value(1), value(2), value(3), value(4), value(5), value(6),
                             value(7));
  }
  static F Load(const float* unaligned) { return _mm256_loadu_ps(unaligned); }
  static void Store(int32_t* aligned, I a) {
    _mm256_store_si256(reinterpret_cast<__m256i*>(aligned), a);
  }
  static void Store(float* aligned, F a) { _mm256_store_ps(aligned, a); }
  // Sse2Lanes::LoadFloat3s on triples 0-3 and 4-7 at once: the 256-bit shuffles work on each
  // 128-bit half alone.
  static void LoadFloat3s(const void* triples, F* x, F* y, F* z) {
    const float* f = static_cast<const float*>(triples);
    const __m256 a = _mm256_set_m128(_mm_loadu_ps(f + 12), _mm_loadu_ps(f));
    const __m256 b = _mm256_set_m128(_mm_loadu_ps(f + 16), _mm_loadu_ps(f + 4));
    const __m256 c = _mm256_set_m128(_mm_loadu_ps(f + 20), _mm_loadu_ps(f + 8));
    const __m256 b2c1 = _mm256_shuffle_ps(b, c, _MM_SHUFFLE(1, 1, 2, 2));
    const __m256 a1b0 = _mm256_shuffle_ps(a, b, _MM_SHUFFLE(0, 0, 1, 1));
    const __m256 b3c2 = _mm256_shuffle_ps(b, c, _MM_SHUFFLE(2, 2, 3, 3));
    const __m256 a2b1 = _mm256_shuffle_ps(a, b, _MM_SHUFFLE(1, 1, 2, 2));
    const __m256 c0c3 = _mm256_shuffle_ps(c, c, _MM_SHUFFLE(3, 3, 0, 0));
    *x = _mm256_shuffle_ps(a, b2c1, _MM_SHUFFLE(2, 0, 3, 0));
    *y = _mm256_shuffle_ps(a1b0, b3c2, _MM_SHUFFLE(2, 0, 2, 0));
    *z = _mm256_shuffle_ps(a2b1, c0c3, _MM_SHUFFLE(2, 0, 2, 0));
  }
  // Sse2Lanes::StoreFloat3s on each half, the halves then put in memory order.
  static void StoreFloat3s(void* triples, F x, F y, F z) {
    float* f = static_cast<float*>(triples);
    const __m256 x0y0x1y1 = _mm256_unpacklo_ps(x, y);
    const __m256 x2y2x3y3 = _mm256_unpackhi_ps(x, y);
    const __m256 z0x1 = _mm256_shuffle_ps(z, x, _MM_SHUFFLE(1, 1, 0, 0));
    const __m256 y1z1 = _mm256_shuffle_ps(y, z, _MM_SHUFFLE(1, 1, 1, 1));
    const __m256 z2x3 = _mm256_shuffle_ps(z, x, _MM_SHUFFLE(3, 3, 2, 2));
    const __m256 y3z3 = _mm256_shuffle_ps(y, z, _MM_SHUFFLE(3, 3, 3, 3));
    const __m256 a =
        _mm256_shuffle_ps(x0y0x1y1, z0x1, _MM_SHUFFLE(2, 0, 1, 0));  // triples 0-1, 4-5
    const __m256 b = _mm256_shuffle_ps(y1z1, x2y2x3y3, _MM_SHUFFLE(1, 0, 2, 0));
    const __m256 c = _mm256_shuffle_ps(z2x3, y3z3, _MM_SHUFFLE(2, 0, 2, 0));
    _mm256_storeu_ps(f, _mm256_permute2f128_ps(a, b, 0x20));       // low halves of a, b
    _mm256_storeu_ps(f + 8, _mm256_permute2f128_ps(c, a, 0x30));   // low of c, high of a
    _mm256_storeu_ps(f + 16, _mm256_permute2f128_ps(b, c, 0x31));  // high halves of b, c
  }
  // Sse2Lanes::LoadSlabsAt on each half.
  template <class Address>
  static void LoadSlabsAt(const Address& address, F* top, F* bottom) {
    const auto pair = [&](int lane) {
      return static_cast<const __m64*>(static_cast<const void*>(address(lane)));
    };
    const auto half = [&](int l, __m128* half_top, __m128* half_bottom) {
      const __m128 slabs01 = _mm_loadh_pi(_mm_loadl_pi(_mm_setzero_ps(), pair(l)), pair(l + 1));
      const __m128 slabs23 = _mm_loadh_pi(_mm_loadl_pi(_mm_setzero_ps(), pair(l + 2)), pair(l + 3));
      *half_top = _mm_shuffle_ps(slabs01, slabs23, _MM_SHUFFLE(2, 0, 2, 0));
      *half_bottom = _mm_shuffle_ps(slabs01, slabs23, _MM_SHUFFLE(3, 1, 3, 1));
    };
    __m128 top_low, bottom_low, top_high, bottom_high;
    half(0, &top_low, &bottom_low);
    half(4, &top_high, &bottom_high);
    *top = _mm256_set_m128(top_high, top_low);
    *bottom = _mm256_set_m128(bottom_high, bottom_low);
  }
};

}  // namespace
}  // namespace drape::detail

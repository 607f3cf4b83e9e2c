// The spring correction two blocks of four springs at a time: the particles stay rows (x, y, z,
// w), block k in the low 128 bits and block k + 1 in the high ones; only the differences b - a
// are transposed to x / y / z lanes (in-lane shuffles: one set for eight springs) and each end
// moves by its row times its lane's scale broadcast in-lane. Per x, y and z lane the operations
// of spring_kernels.cpp's CorrectBlock, in its order (no FMA: the project builds with
// -ffp-contract=off and the target below has none), so the same bits; the w lanes, which nothing
// reads, become w + (w_b - w_a) s.
//
// Only what is defined between the target pragmas below is compiled for AVX2 (see
// plane_kernels_avx2.cpp; tests/runtime/check_lane_objects.sh checks it).
#include <cstdint>

#include "cloth/spring_kernels.h"
#include "drape/runtime/cloth_solver.h"

#if defined(__SSE2__) && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include "common/lanes/avx2_region_begin.inl"

namespace drape::detail {
namespace {

using internal::Particle4;
using internal::SpringBlock;

__m256 LoadPair(const float* low, const float* high) {
  return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(low)), _mm_load_ps(high), 1);
}

template <SpringSide side>
void CorrectPair(const SpringBlock& b0, const SpringBlock& b1, float correction, float rest_scale,
                 Particle4* p) {
  __m256 ra[4], rb[4], rd[4];
  for (int k = 0; k < 4; ++k) {
    ra[k] = LoadPair(&p[b0.a[k]].x, &p[b1.a[k]].x);
    rb[k] = LoadPair(&p[b0.b[k]].x, &p[b1.b[k]].x);
    rd[k] = _mm256_sub_ps(rb[k], ra[k]);
  }
  const __m256 t0 = _mm256_unpacklo_ps(rd[0], rd[1]);  // x0 x1 y0 y1 per half
  const __m256 t1 = _mm256_unpacklo_ps(rd[2], rd[3]);  // x2 x3 y2 y3
  const __m256 t2 = _mm256_unpackhi_ps(rd[0], rd[1]);  // z0 z1 w0 w1
  const __m256 t3 = _mm256_unpackhi_ps(rd[2], rd[3]);  // z2 z3 w2 w3
  const __m256 dx = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 dy = _mm256_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
  const __m256 dz = _mm256_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 length = _mm256_sqrt_ps(_mm256_add_ps(
      _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz)));
  __m256 error = _mm256_sub_ps(
      length, _mm256_mul_ps(LoadPair(b0.rest_length, b1.rest_length), _mm256_set1_ps(rest_scale)));
  // std::max(0, e) / std::min(0, e) as the SSE2 pack's StdMax / StdMin: maxps / minps return
  // their second operand on NaN.
  if constexpr (side == SpringSide::kStretched) error = _mm256_max_ps(error, _mm256_setzero_ps());
  if constexpr (side == SpringSide::kCompressed) error = _mm256_min_ps(error, _mm256_setzero_ps());
  const __m256 valid = _mm256_cmp_ps(length, _mm256_set1_ps(1e-20f), _CMP_GT_OS);
  const __m256 scale =
      _mm256_and_ps(valid, _mm256_div_ps(_mm256_mul_ps(_mm256_set1_ps(correction), error), length));
  const __m256 sa = _mm256_mul_ps(scale, LoadPair(b0.weight_a, b1.weight_a));
  const __m256 sb = _mm256_mul_ps(scale, LoadPair(b0.weight_b, b1.weight_b));
  const __m256 sa_lane[4] = {_mm256_permute_ps(sa, 0x00), _mm256_permute_ps(sa, 0x55),
                             _mm256_permute_ps(sa, 0xAA), _mm256_permute_ps(sa, 0xFF)};
  const __m256 sb_lane[4] = {_mm256_permute_ps(sb, 0x00), _mm256_permute_ps(sb, 0x55),
                             _mm256_permute_ps(sb, 0xAA), _mm256_permute_ps(sb, 0xFF)};
  for (int k = 0; k < 4; ++k) {
    const __m256 a = _mm256_add_ps(ra[k], _mm256_mul_ps(rd[k], sa_lane[k]));
    const __m256 b = _mm256_sub_ps(rb[k], _mm256_mul_ps(rd[k], sb_lane[k]));
    _mm_store_ps(&p[b0.a[k]].x, _mm256_castps256_ps128(a));
    _mm_store_ps(&p[b1.a[k]].x, _mm256_extractf128_ps(a, 1));
    _mm_store_ps(&p[b0.b[k]].x, _mm256_castps256_ps128(b));
    _mm_store_ps(&p[b1.b[k]].x, _mm256_extractf128_ps(b, 1));
  }
}

template <SpringSide side>
void CorrectBlocks(const SpringBlock* blocks, uint32_t begin, uint32_t end, float correction,
                   float rest_scale, Particle4* p) {
  uint32_t k = begin;
  for (; k + 1 < end; k += 2)
    CorrectPair<side>(blocks[k], blocks[k + 1], correction, rest_scale, p);
  // An odd last block is paired with itself: its particles are loaded twice and written twice
  // with the same values.
  if (k < end) CorrectPair<side>(blocks[k], blocks[k], correction, rest_scale, p);
}

}  // namespace

void CorrectBlocksAvx2(const SpringBlock* blocks, uint32_t begin, uint32_t end, SpringSide side,
                       float correction, float rest_scale, Particle4* p) {
  switch (side) {
    case SpringSide::kBoth:
      return CorrectBlocks<SpringSide::kBoth>(blocks, begin, end, correction, rest_scale, p);
    case SpringSide::kStretched:
      return CorrectBlocks<SpringSide::kStretched>(blocks, begin, end, correction, rest_scale, p);
    case SpringSide::kCompressed:
      return CorrectBlocks<SpringSide::kCompressed>(blocks, begin, end, correction, rest_scale, p);
  }
}

}  // namespace drape::detail

#include "common/lanes/avx2_region_end.inl"

#else  // no AVX2 on this target: UsableInstructionSet never reports it

namespace drape::detail {

void CorrectBlocksAvx2(const internal::SpringBlock*, uint32_t, uint32_t, SpringSide, float, float,
                       internal::Particle4*) {}

}  // namespace drape::detail

#endif

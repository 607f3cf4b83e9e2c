// The spring-correction kernels (paper B eq. 2-3) the solver's spring passes run: the scalar
// reference over a four-lane pack, SSE2 and AVX2 with the particles kept as rows. All give the
// same bits per particle (tests/runtime/cloth_solver_test.cpp, SimdAndScalarKernelsAgree).
#include "cloth/spring_kernels.h"

#include "common/lanes/scalar_lanes.h"
#include "common/lanes/sse2_lanes.h"

namespace drape::detail {
namespace {

using internal::Particle4;
using internal::SpringBlock;

// Paper B eq. 2-3 for the four springs of a block at once (they share no particle, so the scatter
// does not overlap): each end moves by its share of correction * (L - R) along the spring, over
// a four-lane pack (common/lanes/): the scalar reference. The particles' (x, y, z, w) rows are
// transposed to x/y/z lanes and back.
// rest_scale multiplies the rest lengths (1 exactly for the spring iterations; 1 + max_stretch for
// the strain limit's pass, whose stretched-only springs act beyond that length).
template <class P, SpringSide side>
inline void CorrectBlock(const SpringBlock& block, float correction, float rest_scale,
                         Particle4* p) {
  using F = typename P::F;
  using namespace detail::lanes;
  float* a[4];
  float* b[4];
  for (int k = 0; k < 4; ++k) {
    a[k] = &p[block.a[k]].x;
    b[k] = &p[block.b[k]].x;
  }
  F ax, ay, az, aw, bx, by, bz, bw;
  P::LoadRows4(a, &ax, &ay, &az, &aw);
  P::LoadRows4(b, &bx, &by, &bz, &bw);
  const F dx = Sub(bx, ax), dy = Sub(by, ay), dz = Sub(bz, az);
  const F length = Sqrt(Add(Add(Mul(dx, dx), Mul(dy, dy)), Mul(dz, dz)));
  F error = Sub(length, Mul(P::Load(block.rest_length), P::Splat(rest_scale)));
  // Paper A's buckling model: stretch springs act only when stretched, bend springs only when
  // compressed (NaN and +-0 ties give 0, maxps / minps's second operand).
  if constexpr (side == SpringSide::kStretched) error = StdMax(P::Zero(), error);
  if constexpr (side == SpringSide::kCompressed) error = StdMin(P::Zero(), error);
  // A spring of length 0 has no direction: it waits for its neighbours to separate its ends.
  const F valid = Greater(length, P::Splat(1e-20f));
  const F scale = And(valid, Div(Mul(P::Splat(correction), error), length));
  const F sa = Mul(scale, P::Load(block.weight_a));
  const F sb = Mul(scale, P::Load(block.weight_b));
  ax = Add(ax, Mul(dx, sa));
  ay = Add(ay, Mul(dy, sa));
  az = Add(az, Mul(dz, sa));
  bx = Sub(bx, Mul(dx, sb));
  by = Sub(by, Mul(dy, sb));
  bz = Sub(bz, Mul(dz, sb));
  P::StoreRows4(a, ax, ay, az, aw);
  P::StoreRows4(b, bx, by, bz, bw);
}

#if defined(__SSE2__)
// CorrectBlock's operations for SSE2 with the particles kept as rows: the four differences
// b - a are formed row by row and only they are transposed to x/y/z lanes (7 shuffles), and each
// end moves by its row times its lane's scale broadcast (8 shuffles), where transposing the
// eight particles in and out takes 32: the shuffle port bounded the kernel. Per x, y and z lane
// the same IEEE operations in the same order as CorrectBlock, so the same bits (the w lanes,
// which nothing reads, become w + (w_b - w_a) s instead of staying as they were).
template <SpringSide side>
inline void CorrectBlockRows(const SpringBlock& block, float correction, float rest_scale,
                             Particle4* p) {
  __m128 ra[4], rb[4], rd[4];
  for (int k = 0; k < 4; ++k) {
    ra[k] = _mm_load_ps(&p[block.a[k]].x);
    rb[k] = _mm_load_ps(&p[block.b[k]].x);
    rd[k] = _mm_sub_ps(rb[k], ra[k]);
  }
  const __m128 t0 = _mm_unpacklo_ps(rd[0], rd[1]);  // x0 x1 y0 y1
  const __m128 t1 = _mm_unpacklo_ps(rd[2], rd[3]);  // x2 x3 y2 y3
  const __m128 t2 = _mm_unpackhi_ps(rd[0], rd[1]);  // z0 z1 w0 w1
  const __m128 t3 = _mm_unpackhi_ps(rd[2], rd[3]);  // z2 z3 w2 w3
  const __m128 dx = _mm_movelh_ps(t0, t1), dy = _mm_movehl_ps(t1, t0);
  const __m128 dz = _mm_movelh_ps(t2, t3);
  const __m128 length = _mm_sqrt_ps(
      _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz)));
  __m128 error =
      _mm_sub_ps(length, _mm_mul_ps(_mm_load_ps(block.rest_length), _mm_set1_ps(rest_scale)));
  if constexpr (side == SpringSide::kStretched) error = StdMax(_mm_setzero_ps(), error);
  if constexpr (side == SpringSide::kCompressed) error = StdMin(_mm_setzero_ps(), error);
  const __m128 valid = _mm_cmpgt_ps(length, _mm_set1_ps(1e-20f));
  const __m128 scale =
      _mm_and_ps(valid, _mm_div_ps(_mm_mul_ps(_mm_set1_ps(correction), error), length));
  const __m128 sa = _mm_mul_ps(scale, _mm_load_ps(block.weight_a));
  const __m128 sb = _mm_mul_ps(scale, _mm_load_ps(block.weight_b));
  const __m128 sa_lane[4] = {_mm_shuffle_ps(sa, sa, 0x00), _mm_shuffle_ps(sa, sa, 0x55),
                             _mm_shuffle_ps(sa, sa, 0xAA), _mm_shuffle_ps(sa, sa, 0xFF)};
  const __m128 sb_lane[4] = {_mm_shuffle_ps(sb, sb, 0x00), _mm_shuffle_ps(sb, sb, 0x55),
                             _mm_shuffle_ps(sb, sb, 0xAA), _mm_shuffle_ps(sb, sb, 0xFF)};
  for (int k = 0; k < 4; ++k) {
    _mm_store_ps(&p[block.a[k]].x, _mm_add_ps(ra[k], _mm_mul_ps(rd[k], sa_lane[k])));
    _mm_store_ps(&p[block.b[k]].x, _mm_sub_ps(rb[k], _mm_mul_ps(rd[k], sb_lane[k])));
  }
}
#endif

template <SpringSide side>
inline void CorrectFour(const SpringBlock& block, const SpringCorrection& c, Particle4* p) {
#if defined(__SSE2__)
  if (c.set != InstructionSet::kScalar) {
    CorrectBlockRows<side>(block, c.fraction, c.rest_scale, p);
    return;
  }
#endif
  CorrectBlock<ScalarLanes, side>(block, c.fraction, c.rest_scale, p);
}

// Blocks [begin, end) of one run: two at a time in AVX2, else one by one.
template <SpringSide side>
void CorrectBlockRange(const SpringBlock* blocks, uint32_t begin, uint32_t end,
                       const SpringCorrection& c, Particle4* p) {
  if (c.set == InstructionSet::kAvx2) {
    CorrectBlocksAvx2(blocks, begin, end, side, c.fraction, c.rest_scale, p);
    return;
  }
  for (uint32_t k = begin; k < end; ++k) CorrectFour<side>(blocks[k], c, p);
}

}  // namespace

void CorrectBlocks(const SpringBlock* blocks, uint32_t begin, uint32_t end, SpringSide side,
                   const SpringCorrection& c, Particle4* p) {
  switch (side) {
    case SpringSide::kBoth:
      return CorrectBlockRange<SpringSide::kBoth>(blocks, begin, end, c, p);
    case SpringSide::kStretched:
      return CorrectBlockRange<SpringSide::kStretched>(blocks, begin, end, c, p);
    case SpringSide::kCompressed:
      return CorrectBlockRange<SpringSide::kCompressed>(blocks, begin, end, c, p);
  }
}

}  // namespace drape::detail

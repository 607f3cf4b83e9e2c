// BodyMapCollider's eight lanes again, compiled for AVX2 with AVX-512 (F, VL, DQ, BW): the same
// text as body_map_collider_avx2.cpp (eight_lanes.inl, body_map_lane_walk.inl), still on 256-bit
// vectors, but with AVX-512VL's 32 vector registers instead of 16, where the walking lanes' loop
// spilled (see docs/PERFORMANCE.md). CollideRange calls them only when lane_kernel() is kAvx512;
// the answers are the bits of every other path. No 512-bit register is used (prefer-vector-width
// below; -mmove-max and -mstore-max from runtime/CMakeLists.txt keep GCC's struct copies to 256
// bits; tests/runtime/check_lane_objects.sh fails on a zmm register), so that CPUs which lower
// their clock for 512-bit instructions do not.
//
// As in the AVX2 file, only what is defined between the target pragmas is compiled for the
// target; every header comes before them.
#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

#include "drape/runtime/body_map_collider.h"
#include "body_map/lanes/sse2_lanes.h"

#if defined(__SSE2__) && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>

#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2,avx512f,avx512vl,avx512dq,avx512bw"))), \
                             apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx2,avx512f,avx512vl,avx512dq,avx512bw,prefer-vector-width=256")
#endif

// The lane operations first: the walk's templates find them where they are defined.
#include "body_map/lanes/avx2_lanes.inl"

#include "body_map/lanes/lane_walk.inl"

namespace drape {

uint32_t BodyMapCollider::CollideEightShortMotionsAvx512(const Float3* previous, Float3* positions,
                                                         Float3* velocities, uint8_t* flags,
                                                         const ResponseParams& params,
                                                         uint32_t* long_motions) const {
  return CollideShortLanes<detail::EightLanes>(previous, positions, velocities, flags, params,
                                               long_motions);
}

uint32_t BodyMapCollider::CollideEightWalksAvx512(const uint32_t* index, uint32_t lanes,
                                                  const Float3* previous, Float3* positions,
                                                  Float3* velocities, uint8_t* flags,
                                                  const ResponseParams& params) const {
  return CollideWalkLanes<detail::EightLanes>(index, lanes, previous, positions, velocities, flags,
                                              params);
}

}  // namespace drape

#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif

#else  // no AVX-512 on this target: CollideRange never calls it

namespace drape {

uint32_t BodyMapCollider::CollideEightShortMotionsAvx512(const Float3*, Float3*, Float3*, uint8_t*,
                                                         const ResponseParams&,
                                                         uint32_t* long_motions) const {
  *long_motions = 0;
  return 0;  // no lane answered
}

uint32_t BodyMapCollider::CollideEightWalksAvx512(const uint32_t*, uint32_t, const Float3*, Float3*,
                                                  Float3*, uint8_t*, const ResponseParams&) const {
  return 0;  // no lane answered: each goes one by one
}

}  // namespace drape

#endif

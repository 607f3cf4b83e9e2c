// BodyMapCollider's lanes eight at a time in AVX2: body_map_lane_walk.inl compiled for 256-bit
// lanes (eight_lanes.inl). CollideRange calls them only when lane_kernel() is kAvx2; the answers
// are the bits the four SSE2 lanes (and CollideOne) give.
//
// Only what is defined between the target pragmas below is compiled for AVX2. Every header comes
// before them, so the inline functions they define (also used by the SSE2 code, and merged with
// its copies by the linker) keep the baseline instruction set; the file therefore needs no
// -mavx2, which would compile those too.
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
#pragma clang attribute push(__attribute__((target("avx2"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx2")
#endif

// The lane operations first: the walk's templates find them where they are defined.
#include "body_map/lanes/avx2_lanes.inl"

#include "body_map/lanes/lane_walk.inl"

namespace drape {

uint32_t BodyMapCollider::CollideEightShortMotionsAvx2(const Float3* previous, Float3* positions,
                                                       Float3* velocities, uint8_t* flags,
                                                       const ResponseParams& params,
                                                       uint32_t* long_motions) const {
  return CollideShortLanes<detail::EightLanes>(previous, positions, velocities, flags, params,
                                               long_motions);
}

uint32_t BodyMapCollider::CollideEightWalksAvx2(const uint32_t* index, uint32_t lanes,
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

#else  // no AVX2 on this target: CollideRange never calls it

namespace drape {

uint32_t BodyMapCollider::CollideEightShortMotionsAvx2(const Float3*, Float3*, Float3*, uint8_t*,
                                                       const ResponseParams&,
                                                       uint32_t* long_motions) const {
  *long_motions = 0;
  return 0;  // no lane answered
}

uint32_t BodyMapCollider::CollideEightWalksAvx2(const uint32_t*, uint32_t, const Float3*, Float3*,
                                                Float3*, uint8_t*, const ResponseParams&) const {
  return 0;  // no lane answered: each goes one by one
}

}  // namespace drape

#endif

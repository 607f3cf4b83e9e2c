// BodyMapCollider's lanes eight at a time in AVX2: lanes.inl compiled for 256-bit lanes
// (common/lanes/avx2_lanes.inl). CollideRange takes them only for InstructionSet::kAvx2, which
// BestInstructionSet() reports only where the CPU and OS have AVX2; the answers are the bits the
// four-lane packs (and CollideOne) give.
//
// Only what is defined between the target pragmas below is compiled for AVX2. Every header comes
// before them, so the inline functions they define (also used by the baseline code, and merged
// with its copies by the linker) keep the baseline instruction set; the file therefore needs no
// -mavx2, which would compile those too. tests/runtime/check_lane_objects.sh checks it.
#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

#include "common/lanes/sse2_lanes.h"
#include "drape/runtime/body_map_collider.h"

#if defined(__SSE2__) && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include "common/lanes/avx2_region_begin.inl"

// The lane operations first: the lanes' templates find them where they are defined.
#include "common/lanes/avx2_lanes.inl"

#include "body_map/lanes/lanes.inl"

namespace drape {

const BodyMapCollider::LaneKernels& BodyMapCollider::Avx2LaneKernels() {
  static const LaneKernels kernels{8, &BodyMapCollider::CollideShortLanes<detail::EightLanes>,
                                   &BodyMapCollider::CollideWalkLanes<detail::EightLanes>};
  return kernels;
}

}  // namespace drape

#include "common/lanes/avx2_region_end.inl"

#else  // no AVX2 on this target: BestInstructionSet() never reports it

namespace drape {

const BodyMapCollider::LaneKernels& BodyMapCollider::Avx2LaneKernels() { return Sse2LaneKernels(); }

}  // namespace drape

#endif

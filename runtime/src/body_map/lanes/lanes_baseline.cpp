// BodyMapCollider's lanes in the baseline instruction set: four lanes of the scalar reference pack
// (any CPU) and four of SSE2 (every x86-64 CPU).
#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

#include "common/lanes/scalar_lanes.h"
#include "common/lanes/sse2_lanes.h"
#include "drape/runtime/body_map_collider.h"

#include "body_map/lanes/lanes.inl"

namespace drape {

const BodyMapCollider::LaneKernels& BodyMapCollider::ScalarLaneKernels() {
  static const LaneKernels kernels{4, &BodyMapCollider::CollideShortLanes<detail::ScalarLanes>,
                                   &BodyMapCollider::CollideWalkLanes<detail::ScalarLanes>};
  return kernels;
}

const BodyMapCollider::LaneKernels& BodyMapCollider::Sse2LaneKernels() {
#if defined(__SSE2__)
  static const LaneKernels kernels{4, &BodyMapCollider::CollideShortLanes<detail::Sse2Lanes>,
                                   &BodyMapCollider::CollideWalkLanes<detail::Sse2Lanes>};
  return kernels;
#else
  return ScalarLaneKernels();
#endif
}

}  // namespace drape

#include "hull/plane_kernels.h"

#include <cstdint>

#include "common/lanes/scalar_lanes.h"
#include "common/lanes/sse2_lanes.h"
#include "hull/plane_kernels.inl"

namespace drape::detail {

const PlaneKernels& PlaneKernelsFor(InstructionSet set) {
#if defined(__SSE2__)
  if (set == InstructionSet::kAvx2) return Avx2PlaneKernels();
  if (set == InstructionSet::kSse2) return PlaneLanes<Sse2Lanes>::Table();
#else
  (void)set;
#endif
  return PlaneLanes<ScalarLanes>::Table();
}

}  // namespace drape::detail

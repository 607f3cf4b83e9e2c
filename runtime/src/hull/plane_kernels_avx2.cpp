// The hull plane kernels eight lanes at a time in AVX2: plane_kernels.inl compiled for 256-bit
// lanes (common/lanes/avx2_lanes.inl). PlaneKernelsFor hands them out only for
// InstructionSet::kAvx2, which BestInstructionSet() reports only where the CPU and OS have AVX2.
//
// Only what is defined between the target pragmas below is compiled for AVX2. Every header comes
// before them, so the inline functions they define (which the baseline code also uses, and which
// the linker merges with its copies) keep the baseline instruction set;
// tests/runtime/check_lane_objects.sh checks it.
#include <cstdint>

#include "common/lanes/sse2_lanes.h"
#include "hull/plane_kernels.h"

#if defined(__SSE2__) && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include "common/lanes/avx2_region_begin.inl"

#include "common/lanes/avx2_lanes.inl"

#include "hull/plane_kernels.inl"

namespace drape::detail {

const PlaneKernels& Avx2PlaneKernels() { return PlaneLanes<EightLanes>::Table(); }

}  // namespace drape::detail

#include "common/lanes/avx2_region_end.inl"

#else  // no AVX2 on this target: BestInstructionSet() never reports it

namespace drape::detail {

const PlaneKernels& Avx2PlaneKernels() { return PlaneKernelsFor(InstructionSet::kSse2); }

}  // namespace drape::detail

#endif

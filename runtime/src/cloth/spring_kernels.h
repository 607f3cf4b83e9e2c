#pragma once
// Private to the runtime: the spring-correction kernels the solver's spring passes run, beyond
// the scalar reference and SSE2 ones in cloth_solver.cpp.

#include <cstdint>

#include "drape/runtime/cloth_solver.h"

namespace drape::detail {

// Which sign of the length error a spring acts on (paper A's buckling model restricts it).
enum class SpringSide : uint8_t { kBoth, kStretched, kCompressed };

// Corrects blocks [begin, end) of one run (springs pairwise disjoint) two blocks at a time in
// AVX2, with the same bits per particle as the scalar reference (cloth_solver.cpp's
// CorrectBlock). Only for InstructionSet::kAvx2 (the CPU and OS have it).
void CorrectBlocksAvx2(const internal::SpringBlock* blocks, uint32_t begin, uint32_t end,
                       SpringSide side, float correction, float rest_scale, internal::Particle4* p);

}  // namespace drape::detail

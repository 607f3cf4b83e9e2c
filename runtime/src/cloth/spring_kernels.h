#pragma once
// Private to the runtime: the spring-correction kernels the solver's spring passes run
// (spring_kernels.cpp; the AVX2 one in spring_kernels_avx2.cpp).

#include <cstdint>

#include "drape/runtime/cloth_solver.h"
#include "drape/runtime/instruction_set.h"

namespace drape::detail {

// Which sign of the length error a spring acts on (paper A's buckling model restricts it).
enum class SpringSide : uint8_t { kBoth, kStretched, kCompressed };

// How a run's blocks are corrected.
struct SpringCorrection {
  float fraction = 1.f;    // of the length error removed, in [0, 1]
  float rest_scale = 1.f;  // of the rest lengths (1 + max_stretch in the strain limit's pass)
  InstructionSet set = InstructionSet::kScalar;  // usable on this CPU
};

// Corrects blocks [begin, end) of one run (springs pairwise disjoint): the scalar reference, SSE2
// one block at a time, or AVX2 two at a time, all with the same bits.
void CorrectBlocks(const internal::SpringBlock* blocks, uint32_t begin, uint32_t end,
                   SpringSide side, const SpringCorrection& c, internal::Particle4* p);

// Corrects blocks [begin, end) of one run (springs pairwise disjoint) two blocks at a time in
// AVX2, with the same bits per particle as the scalar reference (spring_kernels.cpp's
// CorrectBlock). Only for InstructionSet::kAvx2 (the CPU and OS have it).
void CorrectBlocksAvx2(const internal::SpringBlock* blocks, uint32_t begin, uint32_t end,
                       SpringSide side, float correction, float rest_scale, internal::Particle4* p);

}  // namespace drape::detail

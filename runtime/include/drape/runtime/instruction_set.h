#pragma once
// The instruction sets the colliders' kernels are compiled for, and the switch that picks one.
// Every set gives the same bits; a narrower one is for measurement and for checking the wider
// ones against it (kScalar is the plain C++ reference every SIMD kernel is tested against).

#include <cstdint>

namespace drape {

enum class InstructionSet : uint8_t {
  kScalar = 0,  // plain C++, four lanes emulated: any CPU
  kSse2 = 1,    // four lanes: every x86-64 CPU
  kAvx2 = 2,    // eight lanes: CPUs (and OSes) with AVX2
};

// The widest set this CPU and OS run (kScalar off x86).
InstructionSet BestInstructionSet();

// `requested` narrowed to what this CPU runs.
inline InstructionSet UsableInstructionSet(InstructionSet requested) {
  const InstructionSet best = BestInstructionSet();
  return static_cast<uint8_t>(requested) < static_cast<uint8_t>(best) ? requested : best;
}

const char* ToString(InstructionSet set);  // "scalar", "sse2", "avx2"

}  // namespace drape

#include "drape/runtime/instruction_set.h"

namespace drape {

InstructionSet BestInstructionSet() {
#if defined(__SSE2__) && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
  // libgcc's check covers the OS side too (OSXSAVE and the YMM state in XCR0).
  static const InstructionSet best =
      __builtin_cpu_supports("avx2") ? InstructionSet::kAvx2 : InstructionSet::kSse2;
  return best;
#else
  return InstructionSet::kScalar;
#endif
}

const char* ToString(InstructionSet set) {
  switch (set) {
    case InstructionSet::kScalar:
      return "scalar";
    case InstructionSet::kSse2:
      return "sse2";
    case InstructionSet::kAvx2:
      return "avx2";
  }
  return "unknown";
}

}  // namespace drape

#include "common/cpu_features.h"

namespace drape::detail {

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
// libgcc's check covers the OS side too (OSXSAVE and the YMM state in XCR0; for AVX-512, the
// opmask and ZMM states as well).
bool CpuHasAvx2() { return __builtin_cpu_supports("avx2"); }
bool CpuHasAvx512() {
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
         __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw") &&
         __builtin_cpu_supports("avx2");
}
#else
bool CpuHasAvx2() { return false; }
bool CpuHasAvx512() { return false; }
#endif

}  // namespace drape::detail

#include "cpu_features.h"

namespace drape::detail {

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
// libgcc's check covers the OS side too (OSXSAVE and the YMM state in XCR0).
bool CpuHasAvx2() { return __builtin_cpu_supports("avx2"); }
#else
bool CpuHasAvx2() { return false; }
#endif

}  // namespace drape::detail

#pragma once
// Private to drape's command-line tools: OpenMP's threads sleep between parallel regions unless
// the user chose otherwise. With libgomp's default they spin for a while after each region, which
// on a shared or busy machine takes the cores other work (or a neighbour's bake) needs: a cloth
// step of many short regions ran 2-30x slower. libgomp reads OMP_WAIT_POLICY once, when it is
// loaded, before main, so a tool that finds it unset sets it to passive and runs itself again
// (the variable is then set: once). OMP_WAIT_POLICY=active keeps the spinning.

#include <unistd.h>

#include <cstdlib>

namespace drape::detail {

inline void PreferPassiveOpenMpWaits(char** argv) {
#if defined(__linux__)
  if (std::getenv("OMP_WAIT_POLICY") != nullptr) return;
  if (setenv("OMP_WAIT_POLICY", "passive", 1) != 0) return;
  execv("/proc/self/exe", argv);  // returns only when it failed: run on as we are
#else
  (void)argv;
#endif
}

}  // namespace drape::detail

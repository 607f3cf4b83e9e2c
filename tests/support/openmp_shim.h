#pragma once
// The OpenMP calls the tests make (thread counts for the same-bits-at-any-thread-count checks),
// also in a build without OpenMP (-DDRAPE_OPENMP=OFF), where there is one thread.

#if defined(_OPENMP)
#include <omp.h>
#else
inline int omp_get_max_threads() { return 1; }
inline void omp_set_num_threads(int) {}
#endif

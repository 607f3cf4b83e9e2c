// Private to the runtime: opens an AVX2 target region. A file that compiles kernels for AVX2
// includes this after every header, then the .inl files of its kernels, then
// avx2_region_end.inl: only what is defined between them is compiled for AVX2 (see
// docs/ARCHITECTURE.md, "SIMD: one kernel, several packs").
#include <immintrin.h>

#if defined(__clang__)
#pragma clang attribute push(__attribute__((target("avx2"))), apply_to = function)
#else
#pragma GCC push_options
#pragma GCC target("avx2")
#endif

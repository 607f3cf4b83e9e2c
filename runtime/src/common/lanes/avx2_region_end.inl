// Private to the runtime: closes the region avx2_region_begin.inl opened.
#if defined(__clang__)
#pragma clang attribute pop
#else
#pragma GCC pop_options
#endif

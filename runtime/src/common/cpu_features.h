#pragma once
// Private to the runtime: what the CPU running us can do, for the kernels that choose their
// instruction set at run time (hull plane loops, body-map walking lanes).

namespace drape::detail {

// AVX2 usable: the CPU has it and the OS saves the YMM registers (false off x86).
bool CpuHasAvx2();
// AVX-512 F, VL, DQ and BW usable, with AVX2 (the set body_map_collider_avx512.cpp is compiled
// for): the CPU has them and the OS saves their state (false off x86).
bool CpuHasAvx512();

}  // namespace drape::detail

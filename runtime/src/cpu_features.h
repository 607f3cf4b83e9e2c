#pragma once
// Private to the runtime: what the CPU running us can do, for the kernels that choose their
// instruction set at run time (hull plane loops, body-map walking lanes).

namespace drape::detail {

// AVX2 usable: the CPU has it and the OS saves the YMM registers (false off x86).
bool CpuHasAvx2();

}  // namespace drape::detail

#pragma once
// Private to the runtime: the first-fit spring colouring shared by the cloth builder (colour
// groups of each spring kind) and the solver (independent lanes within its SIMD blocks).

#include <cstdint>
#include <span>
#include <vector>

#include "drape/runtime/cloth.h"

namespace drape::detail {

// First-fit colouring of `springs` in order: each takes the smallest colour neither of its
// particles has yet (per-particle bitsets: O(springs * colours / 64)). Deterministic, at most
// 2 * max_valence - 1 colours. `used` holds one bitset per particle, all zero on entry and on
// return. Writes each spring's colour and returns the colour count.
uint32_t FirstFitColours(std::span<const ClothSpring> springs,
                         std::vector<std::vector<uint64_t>>* used,
                         std::vector<uint32_t>* colour_of);

}  // namespace drape::detail

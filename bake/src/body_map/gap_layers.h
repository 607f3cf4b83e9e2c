#pragma once
// Private to the body map baker: step 8, the air gaps inside paper A's slab (docs/ALGORITHMS.md
// §6), from the CPU fragment pass whichever renderer drew layer 0. Per texel the fragments are
// sorted front to back and swept with a winding count; the thickest gaps that stay strictly
// nested after encoding are stored as layers 1 .. layers - 1.

#include <cstddef>
#include <cstdint>
#include <span>

#include "body_map/cpu_rasterizer.h"
#include "drape/bake/body_map_baker.h"

namespace drape::bake {

struct GapCounts {
  size_t gap_texels = 0;
  size_t dropped_gaps = 0;
};

// Step 8 over the cropped rectangle of a dense pose whose layer 0 is encoded (its arrays hold
// exactly its width * height texels): fills pose->gap_texels and appends the gap layers' entries
// to every array. `valid` is layer 0's validity per raster texel (after step 6); crop_i0/crop_j0
// place the pose's texel (0, 0) in the raster. kInvalidArgument when the fragments would not fit
// in 32-bit offsets.
Status BakeGapLayers(const MapRasterInput& input, std::span<const uint8_t> valid, uint32_t crop_i0,
                     uint32_t crop_j0, BodyMapPose* pose, GapCounts* out);

}  // namespace drape::bake

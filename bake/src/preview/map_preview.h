#pragma once
// Private to the body map baker: PNG writing for the map previews (WriteBodyMapPreview in
// drape/bake/body_map_baker.h). stb_image_write is compiled into map_preview.cpp only.

#include <cstdint>
#include <span>
#include <string>

#include "drape/formats/status.h"

namespace drape::bake {

// Writes an 8-bit PNG of width x height pixels with `channels` (1 grey, 3 RGB) interleaved
// values per pixel. `pixels` is row-major with row 0 at the BOTTOM (the maps' j increases with
// y); the file stores row 0 at the top, so the rows are flipped on the way out.
Status WritePreviewPng(const std::string& path, uint32_t width, uint32_t height, int channels,
                       std::span<const uint8_t> pixels);

}  // namespace drape::bake

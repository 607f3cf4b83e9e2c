#pragma once
// Paper A's image-space body collider: front and back orthographic depth and normal maps of the
// posed body, offset by epsilon. The view axis is the asset frame's z (the body faces +z).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "drape/formats/status.h"

namespace drape {

enum class DepthEncoding : uint8_t {
  kFloat32 = 0,  // metres from the camera plane; background is exactly depth_range (test >=)
  kUnorm16 = 1,  // min(round(depth / depth_range * 65535), 65534); 65535 is background
};

enum class NormalEncoding : uint8_t {
  kFloat32 = 0,  // 3 floats per texel, unit length (0,0,0 on background)
  kOct16 = 1,    // octahedral, 2 x uint16 per texel (about 0.004 degrees); the exact
                 // encode/decode is documented in bake/include/drape/bake/body_map_baker.h
  kRgb8 = 2,     // paper A's colour encoding, 3 x uint8 per texel (about 0.4 degrees)
};

// How the per-texel arrays of a pose are laid out (BodyMapPose class version 2; version 1 is
// always dense).
enum class BodyMapLayout : uint8_t {
  kDense = 0,     // width * height texels, row-major j * width + i
  kRowSpans = 1,  // only the texels inside the row spans, row by row, span by span
};

// One pose's maps. Texel (i, j) covers asset-frame x in [origin_x + i*texel_size, +texel_size)
// and y in [origin_y + j*texel_size, +texel_size). Only the rectangle around the covered texels
// exists; everything outside it is background. Inside it, `layout` says which texels the
// per-texel arrays hold: all of them row-major (j * width + i), or only those in the row spans
// (everything outside the spans is background).
struct BodyMapPose {
  int32_t clip = -1;   // clip index, or -1 for the rest pose as authored (see docs/FORMAT.md)
  float time = 0.f;    // seconds into the clip
  uint32_t width = 0;  // texels
  uint32_t height = 0;
  float origin_x = 0.f, origin_y = 0.f;  // metres, asset frame
  float texel_size = 0.f;                // metres, > 0
  float front_z = 0.f;                   // asset-frame z of the front camera plane
  float depth_range = 0.f;  // metres between the front and back planes (paper's W'), > 0
  DepthEncoding depth_encoding = DepthEncoding::kFloat32;
  NormalEncoding normal_encoding = NormalEncoding::kFloat32;
  BodyMapLayout layout = BodyMapLayout::kDense;
  // kRowSpans only (empty when dense), compressed rows: row j's spans are the entries
  // [row_span_offsets[j], row_span_offsets[j + 1]) of the span arrays (height + 1 entries, from
  // 0, non-decreasing). Span s covers texels i in [span_begin[s], span_begin[s] + length) of its
  // row, length = span_texel_offsets[s + 1] - span_texel_offsets[s] >= 1, and its texels are
  // entries [span_texel_offsets[s], span_texel_offsets[s + 1]) of the per-texel arrays (span
  // count + 1 entries, from 0, strictly increasing, ending at the stored texel count). A row's
  // spans are sorted by begin, do not overlap and end within width. Storing the texel offset
  // rather than the length makes texel (i, j) a binary search within its row.
  std::vector<uint32_t> row_span_offsets;
  std::vector<uint16_t> span_begin;  // texel column, < width (width <= 16384)
  std::vector<uint32_t> span_texel_offsets;
  // Index 0 is the front view (looking along -z), 1 the back view (looking along +z). The back
  // map is not mirrored: the same texel covers the same (x, y) in both. Depth is measured from
  // each view's own camera plane. Exactly the arrays of the chosen encodings are filled, each
  // with one value (or 2 or 3 per texel, as noted) per stored texel.
  std::vector<float> depth_f32[2];
  std::vector<uint16_t> depth_u16[2];
  std::vector<float> normal_f32[2];       // 3 per texel
  std::vector<uint16_t> normal_oct16[2];  // 2 per texel
  std::vector<uint8_t> normal_rgb8[2];    // 3 per texel
};

struct BodyMapSet {
  float epsilon = 0.f;      // metres the surface was offset along its normals before rendering
  uint32_t resolution = 0;  // N of the N x N window the maps were rendered in
  bool fitted_window =
      false;  // true: the window was fitted to the body's L x H (not the paper's square)
  std::vector<BodyMapPose> poses;
};

// Texels the per-texel arrays hold: width * height (dense) or the spans' total (row spans;
// 0 when the span table is empty). Assumes a span table that CheckBodyMapLayout accepts.
size_t BodyMapStoredTexels(const BodyMapPose& pose);

// Checks the layout and the span table against width and height, without trusting any count:
// returns "" or the first problem as "<field> <reason>", e.g.
// "span_begin[7] = 3 overlaps the previous span of row 2 (ends at 5)".
std::string CheckBodyMapLayout(const BodyMapPose& pose);

// Position of texel (i, j) in the per-texel arrays, or -1 when it is outside the rectangle or
// (row spans) outside every span, i.e. background. O(log spans in row j). Assumes a span table
// that CheckBodyMapLayout accepts.
int64_t BodyMapTexelIndex(const BodyMapPose& pose, uint32_t i, uint32_t j);

// Copies `in` into `out` in `layout`. To row spans: keeps every texel that is valid (depth not
// background) in either view, in maximal runs. To dense: texels outside the spans get the
// background values (depth: depth_range or 65535; normals: zeros). Dense -> spans -> dense gives
// back the same arrays when every background texel holds those values (as the bake writes).
// kInvalidArgument (and `out` untouched) when `in`'s layout or array sizes are inconsistent.
Status ConvertBodyMapLayout(const BodyMapPose& in, BodyMapLayout layout, BodyMapPose* out);

}  // namespace drape

#pragma once
// Paper A's image-space body collider: front and back orthographic depth and normal maps of the
// posed body, offset by epsilon, seen along one of the asset frame's axes (z unless the pose
// says otherwise: a quadruped is seen from above).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "drape/formats/status.h"
#include "drape/formats/types.h"

namespace drape {

enum class DepthEncoding : uint8_t {
  kFloat32 = 0,  // metres from the camera plane; background is exactly depth_range (test >=)
  kUnorm16 = 1,  // min(round(depth / depth_range * 65535), 65534); 65535 is background
};

enum class NormalEncoding : uint8_t {
  kFloat32 = 0,  // 3 floats per texel, unit length (0,0,0 on background)
  kOct16 = 1,    // octahedral, 2 x uint16 per texel (about 0.004 degrees); the exact
                 // encode/decode: drape/runtime/normal_encoding.h
  kRgb8 = 2,     // paper A's colour encoding, 3 x uint8 per texel (about 0.4 degrees)
};

// How the per-texel arrays of a pose are laid out (BodyMapPose class version 2; version 1 is
// always dense).
enum class BodyMapLayout : uint8_t {
  kDense = 0,     // width * height texels, row-major j * width + i
  kRowSpans = 1,  // only the texels inside the row spans, row by row, span by span
};

// The asset-frame axis a pose is seen along (BodyMapPose class version 4; older poses are z).
// Every other field of the pose lives in its view frame (x', y', z'), a cyclic permutation of the
// asset frame whose z' is the view axis: kZ (x, y, z), kX (y, z, x), kY (z, x, y). A rotation,
// so the front view looks along -z' as before, and exact in floating point. The bake picks the
// axis whose slab holds the least air (docs/ALGORITHMS.md §6.9).
enum class BodyMapViewAxis : uint8_t { kZ = 0, kX = 1, kY = 2 };

// asset frame -> the view frame of `axis`, and back.
constexpr Float3 ToBodyMapView(BodyMapViewAxis axis, Float3 p) {
  return axis == BodyMapViewAxis::kX   ? Float3{p.y, p.z, p.x}
         : axis == BodyMapViewAxis::kY ? Float3{p.z, p.x, p.y}
                                       : p;
}
constexpr Float3 FromBodyMapView(BodyMapViewAxis axis, Float3 v) {
  return axis == BodyMapViewAxis::kX   ? Float3{v.z, v.x, v.y}
         : axis == BodyMapViewAxis::kY ? Float3{v.y, v.z, v.x}
                                       : v;
}
const char* BodyMapViewAxisName(BodyMapViewAxis axis);  // "x", "y", "z" or "unknown"

// One pose's maps. Texel (i, j) covers view-frame x' in [origin_x + i*texel_size, +texel_size)
// and y' in [origin_y + j*texel_size, +texel_size). Only the rectangle around the covered texels
// exists; everything outside it is background. Inside it, `layout` says which texels the
// per-texel arrays hold: all of them row-major (j * width + i), or only those in the row spans
// (everything outside the spans is background).
inline constexpr uint8_t kMaxBodyMapLayers = 4;  // the slab and up to three air gaps

struct BodyMapPose {
  int32_t clip = -1;   // clip index, or -1 for the rest pose as authored (see docs/FORMAT.md)
  float time = 0.f;    // seconds into the clip
  uint32_t width = 0;  // texels
  uint32_t height = 0;
  float origin_x = 0.f, origin_y = 0.f;  // metres, view frame
  float texel_size = 0.f;                // metres, > 0
  float front_z = 0.f;                   // view-frame z' of the front camera plane
  float depth_range = 0.f;  // metres between the front and back planes (paper's W'), > 0
  DepthEncoding depth_encoding = DepthEncoding::kFloat32;
  NormalEncoding normal_encoding = NormalEncoding::kFloat32;
  BodyMapLayout layout = BodyMapLayout::kDense;
  // Depth layers per texel, 1 to kMaxBodyMapLayers (class version 3; older poses have 1).
  // Layer 0 is paper A's slab: each view's nearest surface. Layer k >= 1 is the k-th air gap
  // inside that slab, counted from the front (an arm held before the chest leaves air between the
  // two; paper A's slab counts it as inside): the front arrays hold the depth from the front
  // camera of the gap's upper boundary (where the body is left going along -z), the back arrays
  // the depth from the back camera of its lower boundary (where the body is entered again).
  // Normals are the body's outward normals at those surfaces, so a gap's upper normal points
  // into the gap (-z side). Gap layers are stored only for the texels in gap_texels. At one
  // texel the gaps are filled in order and nested strictly inside the slab without touching:
  // top > upper_1 > lower_1 > upper_2 > lower_2 > ... > bottom (view-frame z').
  uint8_t layers = 1;
  BodyMapViewAxis view_axis = BodyMapViewAxis::kZ;  // class version 4; the same in a whole set
  // The stored texels that hold at least one gap (positions n within layer 0, strictly
  // increasing, each with gap 1 present; empty when layers = 1; class version 3). Layer k >= 1
  // of the t-th of them is entry stored_texels + (k - 1) * gap_texels.size() + t of every
  // per-texel array (times 2 or 3 for normals); a listed texel without gap k holds background
  // there. On a character a few percent of the texels have a gap, so the gap layers cost a few
  // percent of the slab's bytes, not `layers` times them.
  std::vector<uint32_t> gap_texels;
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
  // with BodyMapArrayEntries() values (times 2 or 3, as noted): layer 0 of every stored texel
  // (entry n), then the gap layers of the texels in gap_texels (see there).
  std::vector<float> depth_f32[2];
  std::vector<uint16_t> depth_u16[2];
  std::vector<float> normal_f32[2];       // 3 per texel
  std::vector<uint16_t> normal_oct16[2];  // 2 per texel
  std::vector<uint8_t> normal_rgb8[2];    // 3 per texel
};

// Per-bone local maps (CharacterAsset class version 2, format 5): one bone's part of the body (what
// it carries and the blended skin it shares with its neighbours) baked once, in a view frame
// fixed to the bone whose z is the view axis chosen for that part. At run time a point maps into
// the view frame through the bone's skinning matrix, so the maps follow any pose the skeleton
// takes; the blended skin near a joint is taken as rigid to each bone holding it.
struct BoneMapData {
  uint16_t joint = 0;    // the bone (skeleton joint index)
  Mat34 view_from_bind;  // rigid: bind-pose asset frame -> the view frame the pose is baked in
  BodyMapPose pose;      // front/back maps in the view frame; clip -1, time 0
};

struct BodyMapSet {
  float epsilon = 0.f;      // metres the surface was offset along its normals before rendering
  uint32_t resolution = 0;  // N of the N x N window the maps were rendered in
  bool fitted_window =
      false;  // true: the window was fitted to the body's L x H (not the paper's square)
  std::vector<BodyMapPose> poses;
};

struct BoneMapSet {
  float epsilon = 0.f;  // metres the surface was offset along its normals before rendering
  std::vector<BoneMapData> maps;
};

// Texels layer 0 of the per-texel arrays holds: width * height (dense) or the spans' total
// (row spans; 0 when the span table is empty). Assumes a span table that CheckBodyMapLayout
// accepts.
size_t BodyMapStoredTexels(const BodyMapPose& pose);

// Values of one component in each per-texel array: the stored texels (layer 0) plus
// (layers - 1) * gap_texels.size() gap entries.
size_t BodyMapArrayEntries(const BodyMapPose& pose);

// Checks the layout and the span table against width and height, without trusting any count:
// returns "" or the first problem as "<field> <reason>", e.g.
// "span_begin[7] = 3 overlaps the previous span of row 2 (ends at 5)".
std::string CheckBodyMapLayout(const BodyMapPose& pose);

// Position n of texel (i, j) in layer 0 of the per-texel arrays (and in gap_texels), or -1 when
// it is outside the rectangle or (row spans) outside every span, i.e. background in every layer.
// O(log spans in row j). Assumes a span table that CheckBodyMapLayout accepts.
int64_t BodyMapTexelIndex(const BodyMapPose& pose, uint32_t i, uint32_t j);

// Copies `in` into `out` in `layout`, every layer. To row spans: keeps every texel whose slab
// (layer 0) is valid (depth not background) in either view, in maximal runs (a gap lies inside
// its texel's slab, so no gap is lost; gap_texels is renumbered, the gap entries keep their
// order). To dense: texels outside the spans get the background values (depth: depth_range or
// 65535; normals: zeros). Dense -> spans -> dense gives back the same arrays when every texel
// without a slab holds those values (as the bake writes). kInvalidArgument (and `out`
// untouched) when `in`'s layers, layout, gap list or array sizes are inconsistent, or a gap lies
// outside the slab or out of order (the presence checks of ValidateAsset; not the depth order).
Status ConvertBodyMapLayout(const BodyMapPose& in, BodyMapLayout layout, BodyMapPose* out);

}  // namespace drape

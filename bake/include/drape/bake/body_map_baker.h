#pragma once
// Bakes one pose of paper A's image-space body collider: the front and back orthographic depth
// and normal maps of the posed body offset by epsilon along its normals, and optionally the air
// gaps inside that slab, as a drape::BodyMapPose (drape/formats/body_map_data.h). The camera box
// and window, the views, normals, gap layers and renderers: docs/ALGORITHMS.md §6; what each
// encoded value means to a decoder: docs/FORMAT.md (body-map encodings).

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "drape/formats/body_map_data.h"
#include "drape/formats/status.h"
#include "drape/formats/types.h"

namespace drape::bake {

enum class MapRenderer : uint8_t {
  kCpu,     // in-house orthographic rasterizer (double edge functions, top-left rule): the
            // deterministic reference, always available
  kOsMesa,  // paper A's GL path: OSMesa 3.3+ core context on llvmpipe, FBO with float targets
};

struct BodyMapOptions {
  uint32_t resolution = 1024;  // N: texels along the square window's side (texel budget N*N
                               // for the fitted window), 16..8192
  bool fitted_window = false;  // false: paper's square window; true: L' x H' window, same budget
  float epsilon = 0.005f;      // metres the surface is offset along its vertex normals, >= 0
  float margin = 0.01f;        // metres the camera box is enlarged beyond the offset surface, >= 0
  DepthEncoding depth_encoding = DepthEncoding::kFloat32;
  NormalEncoding normal_encoding = NormalEncoding::kOct16;
  MapRenderer renderer = MapRenderer::kCpu;
  // kRowSpans: store only the covered texels (the mannequin at N = 512 is 18 % of its
  // rectangle); kDense: the whole rectangle, as format version 1 did. Same maps either way.
  BodyMapLayout layout = BodyMapLayout::kRowSpans;
  // Depth layers per texel, 1..kMaxBodyMapLayers: 1 is paper A's slab alone; k adds up to k - 1
  // air gaps inside it (step 8), at the cost of a CPU fragment pass and (k - 1) entries more
  // per texel that has a gap (a few percent of a character's texels).
  uint8_t layers = 1;
  // The asset axis the body is seen along (body_map_data.h); ChooseBodyMapViewAxis picks it.
  BodyMapViewAxis view_axis = BodyMapViewAxis::kZ;
};

// Gaps thinner than this (metres) are not stored: the body counts as inside there. 0.1 mm is far
// below the cloth's collision scale (epsilon, 5 mm by default; a texel, 1-2 mm), so no real air
// is lost, while the ranges it drops are numerical: touching parts whose surfaces (nearly)
// coincide, slivers between folded offset triangles. It is also >= 3 unorm16 codes at
// a depth range up to 2 m, so quantisation cannot turn a stored gap inside out.
inline constexpr double kMinBodyMapGap = 1e-4;

struct BodyMapPoseStats {
  uint32_t width = 0, height = 0;                // the cropped rectangle, texels
  uint32_t window_width = 0, window_height = 0;  // the full window, texels (N x N when square)
  float texel_size_mm = 0.f;                     // millimetres
  float coverage = 0.f;                          // fraction of window texels that are valid, [0, 1]
  size_t valid_texels = 0;                       // texels valid in both views
  size_t stored_texels = 0;  // texels the arrays hold: width*height, or the spans' total
  size_t bytes = 0;  // bytes stored: the per-texel arrays (both views, depth + normals, every
                     // layer) plus the span table (row spans: 4 per row + 1, 6 per span + 4) and
                     // the gap list (4 per texel with a gap)
  double render_ms_front = 0.0;       // wall time of rendering the view (CPU: both views share one
  double render_ms_back = 0.0;        // pass, each is charged half of it: rasterize + normals;
                                      // OSMesa: upload + clear + draw + finish + readback), plus
                                      // half of gap_ms each
  const char* renderer = "";          // "cpu" or "osmesa (<GL_RENDERER>)"; static storage
  uint32_t silhouette_conflicts = 0;  // texels covered in exactly one view, made background
  uint8_t layers = 1;                 // options.layers: the slab plus up to layers - 1 gaps
  size_t gap_texels = 0;              // texels with at least one stored gap
  size_t dropped_gaps = 0;  // gaps found but not stored: beyond layers - 1 at their texel, or
                            // failing the nesting check after encoding (step 8)
  double gap_ms = 0.0;      // wall time of step 8: fragment pass, sweep, encoding; 0 if layers 1
};

// Bakes the maps of one pose. positions: the posed mesh in the asset frame (metres); triangles:
// 3 vertex indices each. On success fills every field of *pose except clip and time (left as the
// caller set them); stats may be null. On error returns kInvalidArgument (bad options, no
// triangles, an index out of range, a non-finite position, nothing covered) or kInvalidState (the
// OSMesa renderer failed or is not available in this build) and leaves *pose unchanged.
Status BakeBodyMapPose(std::span<const Float3> positions, std::span<const uint32_t> triangles,
                       const BodyMapOptions& options, BodyMapPose* pose,
                       BodyMapPoseStats* stats = nullptr);

// The view axis whose slab holds the least air: the body baked along x, y and z at
// min(options.resolution, kViewAxisProbeResolution) with options' epsilon and one layer, and
// the inside volume of each slab compared (with gap layers every axis holds about the body's
// volume). The air under a quadruped's belly, or between a human's legs seen from the front, is
// inside the slab; seen from above or from the side it is not. z is kept unless another axis
// holds at least kViewAxisMinGain less volume, so near-ties keep the paper's view.
// docs/ALGORITHMS.md §6.9.
inline constexpr uint32_t kViewAxisProbeResolution = 128;
inline constexpr double kViewAxisMinGain = 0.03;  // fraction of z's inside volume
struct ViewAxisChoice {
  BodyMapViewAxis axis = BodyMapViewAxis::kZ;
  double inside_volume[3] = {0.0, 0.0, 0.0};  // m^3, indexed by BodyMapViewAxis (z, x, y)
};
// Errors as BakeBodyMapPose's (options.view_axis is ignored).
Status ChooseBodyMapViewAxis(std::span<const Float3> positions, std::span<const uint32_t> triangles,
                             const BodyMapOptions& options, ViewAxisChoice* choice);

// The volume inside the pose's maps (m^3): per valid texel, the slab's thickness less its gaps',
// times the texel's area.
double BodyMapInsideVolume(const BodyMapPose& pose);

// Writes 4 PNGs into `directory` (which must exist): <prefix>_front_depth.png,
// <prefix>_back_depth.png (grey, nearer is brighter, background black) and
// <prefix>_front_normal.png, <prefix>_back_normal.png (colour (n*0.5+0.5)*255, background
// black), and for each gap layer k = 1 .. layers - 1 two more: <prefix>_gap<k>_front_depth.png
// (the gaps' upper boundaries) and <prefix>_gap<k>_back_depth.png (their lower boundaries), grey
// as above. Image rows are flipped so that +y is up.
Status WriteBodyMapPreview(const BodyMapPose& pose, const std::string& directory,
                           const std::string& prefix);

// True when this build has the OSMesa renderer (libOSMesa was found at configure time). Creating
// the context can still fail at run time (then the bake returns kInvalidState saying why). The
// first OSMesa bake sets GALLIUM_DRIVER=llvmpipe with setenv(), before creating the context.
bool OsMesaRendererAvailable();

// --- Codecs of the encodings above (bake-side reference; the runtime has its own decoder). ---
struct OctNormal16 {
  uint16_t u = 0, v = 0;
};
OctNormal16 EncodeNormalOct16(Float3 unit_normal);
Float3 DecodeNormalOct16(OctNormal16 code);  // unit length
void EncodeNormalRgb8(Float3 unit_normal, uint8_t rgb[3]);
Float3 DecodeNormalRgb8(const uint8_t rgb[3]);                // unit length
uint16_t EncodeDepthUnorm16(float depth, float depth_range);  // valid depth -> 0..65534
float DecodeDepthUnorm16(uint16_t code, float depth_range);

// One decoded texel of a baked pose; view 0 = front, 1 = back; (i, j) inside width x height.
// Layer 0 is the slab; layer k >= 1 the k-th gap (front: its upper boundary, back: its lower).
struct BodyMapTexel {
  bool valid = false;
  float depth = 0.f;  // metres from the view's plane (depth_range on background)
  Float3 normal;      // unit length when valid, (0,0,0) on background
};
// Either layout; a texel outside the spans (or the rectangle), or a layer >= pose.layers, reads
// as background.
BodyMapTexel ReadBodyMapTexel(const BodyMapPose& pose, int view, uint32_t i, uint32_t j,
                              uint32_t layer = 0);

}  // namespace drape::bake

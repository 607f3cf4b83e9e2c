#pragma once
// Bakes one pose of paper A's image-space body collider (Lin et al. 2015, section 2): the front
// and back orthographic depth maps and normal maps of the posed body mesh, offset by epsilon
// along its normals, and optionally the air gaps inside that slab (step 8). The result is a
// drape::BodyMapPose (formats/body_map_data.h); this header documents exactly how each of its
// fields is filled.
//
// Geometry (asset frame, metres; the view axis is z and the body faces +z):
//  1. Area-weighted vertex normals n_v = normalize(sum over incident triangles of
//     (b - a) x (c - a)), computed in double from the posed triangles. Triangles are taken as
//     counter-clockwise seen from outside (the importer orients each component by its signed
//     volume), so n_v points outward. A vertex whose sum is zero keeps n_v = 0.
//  2. Offset surface: q_v = p_v + epsilon * n_v (paper A, section 3). Fold-overs in concave or
//     thin regions are harmless: each view keeps the extreme surface. Thin features (fingers)
//     merge once they are closer than 2 epsilon.
//  3. Box: the AABB of the q_v of every vertex a triangle uses, enlarged by `margin` on all six
//     sides, so neither the near planes nor the window clip the offset surface (notes section
//     4.1, fix 1). front_z = box max z, depth_range = box extent in z (paper's W'), both rounded
//     up to float so that nothing is clipped in the stored float values either.
//  4. Window (the x,y rectangle the N-texel image spans), centred on the box:
//     - square (paper A section 2.1, default): side S' = max(L', H') of the box, N x N texels,
//       texel_size = S' / N.
//     - fitted: the box's own L' x H' rectangle with the same texel budget N*N, i.e.
//       texel_size = sqrt(L' * H') / N, window ceil(L'/t) x ceil(H'/t) texels. A tall body gets
//       smaller texels (H54: about 1.0 mm instead of 1.77 mm at N = 1024). This departs from the
//       paper, so it is an option.
//     Only the rectangle of covered texels plus a one-texel background border exists
//     (width x height); origin_x/origin_y are the asset-frame x,y of the lower-left corner of
//     stored texel (0,0). Texel (i,j) covers x in [origin_x + i*t, origin_x + (i+1)*t), y
//     likewise with j; its sample point is the centre (i + 1/2, j + 1/2). Storage is row-major,
//     index j*width + i, j increasing with y (the lower row first). With layout kRowSpans (the
//     default) only the texels valid in either view (after step 6) are stored, as maximal runs
//     per row (body_map_data.h): the same maps as the dense layout, whose texels outside the
//     spans all hold the background values below; ConvertBodyMapLayout turns one into the other.
//  5. Views: index 0 = front (camera plane z = front_z, looking along -z), depth
//     d = front_z - z. Index 1 = back (camera plane z = front_z - depth_range, looking along +z),
//     depth d = z - (front_z - depth_range). The back map is NOT mirrored: texel (i,j) covers the
//     same x,y in both maps. Each view keeps the minimum depth per texel (the surface nearest to
//     its camera), no face culling (character meshes are open and inconsistently wound).
//  6. Consistency: a texel is valid in both maps or in neither. A texel covered in exactly one
//     view (a silhouette pixel where the renderers' rounding differs) is made background in both
//     and counted in BodyMapPoseStats::silhouette_conflicts.
//  7. Normals: the outward normal of the offset surface at the visible point: the winning
//     triangle's vertex normals n_v interpolated with its barycentrics at the texel centre, then
//     normalised (for an exact offset surface the normal at p + eps*n is n). The front map's
//     normals mostly have n.z > 0, the back map's n.z < 0. A zero interpolated normal falls back to
//     the triangle's face normal, then to (0,0,+1) front / (0,0,-1) back.
//  8. Gap layers (options.layers > 1; layer 0 is steps 5-7, paper A's slab). Paper A counts all
//     the air between a texel's front and back surfaces as inside (an arm before the chest,
//     fingers over a palm). A CPU fragment pass, run whichever renderer drew layer 0 (OSMesa
//     too), collects at every texel centre every fragment of every offset triangle covering it,
//     with the coverage rule and barycentric front depth of the CPU rasterizer (the same code,
//     so the nearest fragment is bit for bit the CPU's layer 0). Each fragment gets a facing sign
//     from the z of its triangle's geometric normal (triangles are counter-clockwise seen from
//     outside): z > 0: a ray along -z enters the body there, +1; z < 0: it leaves, -1. The
//     fragments are sorted front to back (equal depths: entering first, then by triangle index)
//     and a winding count swept over them; the body is where the count is > 0. A texel's gaps
//     are the depth ranges strictly between its first and last fragment where the count is 0,
//     from the fragment that leaves (the gap's upper boundary) to the next one, which enters
//     (its lower boundary), thicker than kMinBodyMapGap. If the count ever goes negative or does
//     not end at 0 (an open mesh: a ray through a sleeve or neck opening; inconsistent winding),
//     the texel gets no gap: paper A's slab, the conservative answer. At most layers - 1 gaps
//     are kept per texel, the thickest (equal thickness: the nearer), stored front to back:
//     dropping a gap only makes more of the slab count as inside. Layer k holds the k-th kept
//     gap: front arrays the front depth of its upper boundary (the leaving fragment's depth),
//     back arrays the back depth of its lower boundary (the entering triangle's back-view
//     barycentric depth, as step 5), normals by step 7's rule on those triangles (upper: mostly
//     n.z < 0, into the gap, fallback (0,0,-1); lower: mostly n.z > 0, fallback (0,0,+1)).
//     After encoding, each gap is checked with the decoded values (in double, and in float as
//     asset z = front_z - d and (front_z - depth_range) + d, with either unorm16 decoder): top
//     > upper > lower > bottom, and upper below the previous kept gap's lower. A gap failing it
//     (or at a texel that is background in layer 0, possible with OSMesa) is dropped and the
//     later gaps move up, so a texel's layers are filled in order. The texels left with at
//     least one gap form pose.gap_texels (their layer-0 entries, increasing); the gap layers
//     are stored for them only. Layer 0 alone decides the row spans.
//
// Encodings (what a decoder must do; formats/body_map_data.h). Texel k below is j*width+i in
// the dense layout and BodyMapTexelIndex(pose, i, j) in the row-span layout; it is the entry of
// layer 0 in every array (times 2 or 3 for normals). Gap layer l >= 1 of a texel k listed in
// gap_texels, at position t of that list, is entry stored_texels + (l - 1) * gap_texels.size()
// + t (stored_texels = BodyMapStoredTexels(pose)); a texel not listed has no gap, a listed one
// without gap l holds background in every array there. The rules below apply to every layer.
//  - Depth kFloat32: depth_f32[view][k] in metres from that view's plane.
//    Valid texels hold a value in [0, depth_range); background holds exactly depth_range
//    (a decoder tests `d >= depth_range`).
//  - Depth kUnorm16: depth_u16 = min(round(d / depth_range * 65535), 65534) for valid texels,
//    65535 for background. Decode d = code * depth_range / 65535; error <= depth_range / 65535.
//  - Normal kFloat32: normal_f32 3 floats per texel, unit length; (0,0,0) on background.
//  - Normal kOct16: normal_oct16 2 x uint16 per texel (u, v). Decode:
//      p = (u, v) / 65535 * 2 - 1;  n = (p.x, p.y, 1 - |p.x| - |p.y|);
//      if (n.z < 0) n.xy = ((1 - |n.y|) * sign(n.x), (1 - |n.x|) * sign(n.y));  // sign(0) = +1
//      n = normalize(n).
//    The encoder folds n the same way (p = n.xy / (|x|+|y|+|z|), wrapped when n.z < 0) and
//    rounds (p * 0.5 + 0.5) * 65535 to the nearest code: angle error <= 0.004 degrees.
//    Background holds (0, 0).
//  - Normal kRgb8: normal_rgb8 3 x uint8 per texel, c = round((n * 0.5 + 0.5) * 255) (paper A
//    eq. 2). Decode n = normalize(c / 255 * 2 - 1); error <= 0.4 degrees. Background (0,0,0).
//  Validity comes from depth alone: background normal codes decode to arbitrary directions.

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

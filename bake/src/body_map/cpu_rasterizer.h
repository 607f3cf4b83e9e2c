#pragma once
// Private to the body map baker: the render request both renderers take, and the in-house
// orthographic rasterizer (docs/ALGORITHMS.md §6.7), the deterministic reference.

#include <cstdint>
#include <span>
#include <vector>

namespace drape::bake {

// The offset mesh expressed in the frame of the raster rectangle (the part of the window that
// is rendered): texel (i, j) covers [i, i+1) x [j, j+1) and is sampled at its centre.
struct MapRasterInput {
  uint32_t width = 0, height = 0;         // texels of the raster rectangle, > 0
  double depth_range = 0.0;               // metres between the two camera planes, > 0
  std::span<const double> window_x;       // per vertex, texel units
  std::span<const double> window_y;       // per vertex, texel units, increasing with asset y
  std::span<const double> view_depth[2];  // per vertex, metres from view 0 (front) / 1 (back) plane
  std::span<const double> normals;        // 3 per vertex, unit length or zero
  std::span<const double> positions;      // 3 per vertex, offset surface (for face normals)
  std::span<const uint32_t> triangles;    // 3 indices each, all < vertex count
};

// One rendered view over the raster rectangle, row-major j * width + i.
struct MapViewImage {
  std::vector<uint8_t> valid;  // 1 where some triangle covers the texel centre
  std::vector<float> depth;    // metres from the view's plane; meaningful where valid
  std::vector<float> normal;   // 3 per texel, unit length where valid, 0 elsewhere
};

// Rasterizes view `view` (0 front, 1 back): double-precision edge functions evaluated at texel
// centres, canonical per-edge evaluation plus the top-left rule (a texel centre on an edge shared
// by two triangles belongs to exactly one), no culling, barycentric depth, the minimum depth wins
// (ties: the lower triangle index, like GL_LESS). Normals are the winning triangle's vertex
// normals interpolated with its barycentrics, normalised. Single-threaded and deterministic.
// The image is resized to the raster and every texel written (its normal storage holds the
// working depths during the pass, so no other buffer is allocated): an image reused from an
// earlier call, of any size, keeps no stale texel and allocates nothing if it does not grow.
// `face`, when not null, receives the winning triangle index per texel (~0u where none).
void RasterizeViewCpu(const MapRasterInput& input, int view, MapViewImage* image,
                      std::vector<uint32_t>* face = nullptr);

// Both views (images[0] front, images[1] back) in one pass, bit-identical to two
// RasterizeViewCpu() calls: the edge tests, most of the work, run once for both.
void RasterizeViewsCpu(const MapRasterInput& input, MapViewImage images[2]);

// Every fragment of the raster rectangle (the gap layers of body_map_baker.h step 8): for each
// texel, every triangle that covers its centre, with the coverage rule and the barycentric depth
// of RasterizeViewCpu() (the same code), so a texel's nearest fragment is exactly the depth and
// triangle view 0 keeps. Texel n = j * width + i owns entries [offsets[n], offsets[n + 1]).
struct MapFragments {
  std::vector<uint32_t> offsets;   // width * height + 1 entries, from 0, non-decreasing
  std::vector<double> depth;       // metres from the front (view 0) plane, as RasterizeViewCpu
  std::vector<uint32_t> triangle;  // the covering triangle; a texel's entries ascend by it
  // +1 where the triangle's geometric normal has z > 0 (counter-clockwise in the window: a ray
  // along -z enters the body there), -1 where z < 0 (it leaves). Computed from the sign of the
  // twice signed window area, the normal's z up to the positive factor 1 / texel_size^2; a
  // triangle with zero window area covers no texel centre, so no fragment has normal z = 0.
  std::vector<int8_t> facing;
};

// Fills *fragments (resizing its vectors; reused storage is not reallocated when big enough),
// keeping only the texels covered by at least `min_fragments` triangles (the others get an empty
// range; 1 keeps every fragment). Two passes over the triangles: count per texel, prefix sum,
// fill. Single-threaded and deterministic: the order within a texel is the triangle order.
// Returns false (and *fragments unspecified) when the kept fragments would exceed 2^32 - 1.
bool CollectFragmentsCpu(const MapRasterInput& input, uint32_t min_fragments,
                         MapFragments* fragments);

// The depth in view `view` of triangle `triangle` at the centre of texel (i, j), bit-identical to
// the value the rasterizer computes there (meaningful where the triangle covers that centre).
double FragmentDepth(const MapRasterInput& input, int view, uint32_t triangle, uint32_t i,
                     uint32_t j);

// The normal rule of RasterizeViewCpu() for triangle `triangle` at the centre of texel (i, j):
// vertex normals interpolated with the clamped barycentrics, else the offset triangle's face
// normal, else (0, 0, fallback_z); unit length.
void FragmentNormal(const MapRasterInput& input, uint32_t triangle, uint32_t i, uint32_t j,
                    double fallback_z, float normal[3]);

}  // namespace drape::bake

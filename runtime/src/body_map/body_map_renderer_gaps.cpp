// BodyMapRenderer's air gap (options.air_gaps): the first air below each texel's front surface.
// The first raster pass found the highest surface leaving the body going along -z (the gap's
// upper boundary); this pass counts the surfaces above it, each texel centre on a shared edge
// counted once, and finds the highest surface entering the body below it (the lower boundary).
// The range between them is air when as many surfaces enter as leave above the upper boundary
// (the winding count is 0 just below it) and along the whole ray (the count ends at 0, as the
// bake's sweep requires), and none lies within kMinGap below it. Surfaces enter where the drawn
// (offset) triangle runs counter-clockwise in the window, as in the bake. Otherwise the texel
// keeps its slab, the conservative answer (docs/ALGORITHMS.md §7.9).
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>

#include "body_map/raster_triangle.h"
#include "drape/runtime/body_map_renderer.h"
#include "drape/runtime/normal_encoding.h"

namespace drape {
namespace {

using detail::kNoFace;
using detail::RasterTriangle;

// Gaps thinner than this (metres) are not kept, as the bake's (kMinBodyMapGap): touching parts
// and folded offset slivers, far below epsilon and a texel.
constexpr float kMinGap = 1e-4f;

}  // namespace

// Stage 4b: the texels where a gap may lie (the highest surface leaving the body lies above
// the back surface), then the entering and leaving surfaces around their upper gap boundary.
void BodyMapRenderer::RasterizeGapSurfaces(const Window& window, const BodyMapCollider& maps) {
  const size_t width = window.width, height = window.height;
  gap_tiles_.assign(detail::TileMask::TileCount(window.width, window.height), 0);
  detail::TileMask tiles{(static_cast<int64_t>(width) + 7) >> detail::TileMask::kShift, gap_tiles_};
  for (size_t j = 0; j < height; ++j) {
    for (size_t i = 0; i < width; ++i) {
      const size_t k = j * width + i;
      // No room for a gap of kMinGap and its two boundaries above the back surface.
      if (exit_face_[k] != kNoFace && !(exit_z_[k] > maps.slabs_[k].bottom + 2.f * kMinGap)) {
        exit_face_[k] = kNoFace;
      }
      if (exit_face_[k] != kNoFace) tiles.Mark(static_cast<int64_t>(i), static_cast<int64_t>(j));
    }
  }
  detail::RasterizeInBands(
      drawn_, raster_, raster_rows_, RasterWindowOf(window), &tiles,
      [&](uint32_t t, const RasterTriangle& r, size_t k, double px, double py, bool once) {
        if (exit_face_[k] == kNoFace) return;  // no gap to bound here
        // Counted once per shared edge; searched for the lower boundary inclusively, so that a
        // texel centre on a seam (vertices split at the same position, whose edge values are
        // not exactly negated) can only spoil the count, which keeps the slab.
        const float z = r.Depth(px, py), upper = exit_z_[k];
        if (!r.entering) {  // the drawn triangle's winding, as the bake's sweep
          if (once) ++exits_total_[k];
          if (z >= upper && once) ++exits_above_[k];
          return;
        }
        if (once) ++entries_total_[k];
        if (z > upper) {
          if (once) ++entries_above_[k];
        } else if (z > upper - kMinGap) {
          crowded_[k] = 1;
        } else if (z > entry_z_[k]) {
          entry_z_[k] = z;
          entry_face_[k] = t;
        }
      });
}

// Stage 4c: the gaps that pass, in row-major order, into the collider's compact gap storage,
// with their boundaries' normals (the upper one faces down into the gap, the lower one up).
void BodyMapRenderer::PublishGaps(const Window& window, BodyMapCollider* maps) {
  const size_t texels = static_cast<size_t>(window.width) * window.height;
  const size_t capacity = maps->gaps_.capacity();
  maps->gap_texel_bits_.assign((texels + 31) / 32, 0u);
  maps->gaps_.clear();
  maps->gap_normals_.clear();
  for (size_t k = 0; k < texels; ++k) {
    const BodyMapCollider::Slab slab = maps->slabs_[k];
    const float upper = exit_z_[k], lower = entry_z_[k];
    const bool air = exit_face_[k] != kNoFace && entry_face_[k] != kNoFace && !crowded_[k] &&
                     entries_above_[k] != 0 && entries_above_[k] == exits_above_[k] &&
                     entries_total_[k] == exits_total_[k] && upper < slab.top - kMinGap &&
                     lower > slab.bottom + kMinGap && upper - lower > kMinGap;
    if (!air) continue;
    maps->gap_texel_bits_[k >> 5] |= 1u << (k & 31u);
    maps->gaps_.push_back({upper, lower});
    const float px = static_cast<float>(k % window.width) + 0.5f;
    const float py = static_cast<float>(k / window.width) + 0.5f;
    const std::array<uint16_t, 2> a =
        EncodeOct16(shading_[exit_face_[k]].At(px, py, Float3{0.f, 0.f, -1.f}));
    const std::array<uint16_t, 2> b =
        EncodeOct16(shading_[entry_face_[k]].At(px, py, Float3{0.f, 0.f, 1.f}));
    maps->gap_normals_.push_back({{a[0], a[1]}, {b[0], b[1]}});
  }
  if (maps->gaps_.capacity() != capacity) ++stats_.grew;  // more gap texels than reserved
  maps->CountGapsBeforeWords();
}

}  // namespace drape

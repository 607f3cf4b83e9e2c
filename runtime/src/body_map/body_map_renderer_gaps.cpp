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
using detail::NormalInterpolator;
using detail::RasterTriangle;

// Gaps thinner than this (metres) are not kept, as the bake's (kMinBodyMapGap): touching parts
// and folded offset slivers, far below epsilon and a texel.
constexpr float kMinGap = 1e-4f;

}  // namespace

// Stage 4b: the entering and leaving surfaces around each texel's upper gap boundary.
void BodyMapRenderer::RasterizeGapSurfaces(const Window& window) {
  detail::RasterizeInBands(
      offset_.data(), mesh_->triangles.data(), drawn_, RasterWindowOf(window),
      [&](uint32_t t, const RasterTriangle& r, size_t k, double px, double py, const double* row) {
        if (exit_face_[k] == kNoFace) return;  // nothing leaves here: no gap to bound
        // Counted once per shared edge; searched for the lower boundary inclusively, so that a
        // texel centre on a seam (vertices split at the same position, whose edge values are
        // not exactly negated) can only spoil the count, which keeps the slab.
        const bool once = r.edge[0].InsideOnce(row[0], px) && r.edge[1].InsideOnce(row[1], px) &&
                          r.edge[2].InsideOnce(row[2], px);
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
  const double inverse_texel = 1.0 / static_cast<double>(options_.texel_size);
  const uint32_t* tri = mesh_->triangles.data();
  NormalInterpolator upper_normal, lower_normal;
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
    const double px = static_cast<double>(k % window.width) + 0.5;
    const double py = static_cast<double>(k / window.width) + 0.5;
    if (upper_normal.triangle() != exit_face_[k]) {
      upper_normal.SetUp(offset_.data(), normals_.data(), tri, exit_face_[k],
                         face_normals_[exit_face_[k]], window.origin_x, window.origin_y,
                         inverse_texel, Float3{0.f, 0.f, -1.f});
    }
    if (lower_normal.triangle() != entry_face_[k]) {
      lower_normal.SetUp(offset_.data(), normals_.data(), tri, entry_face_[k],
                         face_normals_[entry_face_[k]], window.origin_x, window.origin_y,
                         inverse_texel, Float3{0.f, 0.f, 1.f});
    }
    const std::array<uint16_t, 2> a = EncodeOct16(upper_normal.At(px, py));
    const std::array<uint16_t, 2> b = EncodeOct16(lower_normal.At(px, py));
    maps->gap_normals_.push_back({{a[0], a[1]}, {b[0], b[1]}});
  }
  if (maps->gaps_.capacity() != capacity) ++stats_.grew;  // more gap texels than reserved
  maps->CountGapsBeforeWords();
}

}  // namespace drape

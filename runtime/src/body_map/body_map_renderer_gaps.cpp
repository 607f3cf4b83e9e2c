// BodyMapRenderer's air gaps (options.air_gaps): the air below each texel's front surface, gap
// by gap going down. The first raster pass found the highest surface leaving the body going
// along -z (the first gap's upper boundary); a gap pass counts the surfaces above it, each texel
// centre on a shared edge counted once, and finds the highest surface entering the body below it
// (the lower boundary). The range between them is air when as many surfaces enter as leave above
// the upper boundary (the winding count is 0 just below it) and along the whole ray (the count
// ends at 0, as the bake's sweep requires), and none lies within kMinGap below it. The next gap's
// upper boundary is the highest surface leaving below that lower boundary (one more raster pass,
// over the texels that had a gap), and so on. Surfaces enter where the drawn (offset) triangle
// runs counter-clockwise in the window, as in the bake. Where a test fails the texel keeps what
// it has above, the conservative answer (docs/ALGORITHMS.md §7.9).
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <span>

#include "body_map/raster_triangle.h"
#include "drape/runtime/body_map_renderer.h"
#include "drape/runtime/normal_encoding.h"

namespace drape {
namespace {

using detail::kNoFace;
using detail::RasterTriangle;

constexpr float kInf = std::numeric_limits<float>::infinity();
// Gaps thinner than this (metres) are not kept, as the bake's (kMinBodyMapGap): touching parts
// and folded offset slivers, far below epsilon and a texel.
constexpr float kMinGap = 1e-4f;

}  // namespace

// Stage 4b: the air gaps, level by level, into found_ (level order, row-major in a level). The
// first level looks at every texel; each deeper one only at the texels where the level above
// found a gap (found_[begin, end)).
void BodyMapRenderer::FindGaps(const Window& window, const BodyMapCollider& maps) {
  found_.clear();
  const size_t texels = static_cast<size_t>(window.width) * window.height;
  std::fill(below_z_.begin(), below_z_.begin() + static_cast<std::ptrdiff_t>(texels), -kInf);
  size_t begin = 0, end = 0;
  for (uint32_t level = 0; level < options_.air_gaps; ++level) {
    const bool first = level == 0;
    if (!first) FindUpperBoundariesBelow(window, begin, end);
    RasterizeGapSurfaces(window, maps, first, begin, end);
    const size_t found = CollectGaps(window, maps, level, first, begin, end);
    begin = end;
    end = found;
    if (begin == end) break;  // nothing at this level: nothing deeper either
  }
}

// Calls visit(k) for every texel of a level: all of them, or those of found_[begin, end).
template <class Visit>
void ForLevelTexels(size_t texels, bool all, std::span<const BodyMapRenderer::FoundGap> above,
                    Visit&& visit) {
  if (all) {
    for (size_t k = 0; k < texels; ++k) visit(k);
  } else {
    for (const BodyMapRenderer::FoundGap& g : above) visit(size_t{g.texel});
  }
}

// The next level's upper boundaries: per texel whose gap above has its lower boundary at
// below_z_, the highest surface leaving the body below it.
void BodyMapRenderer::FindUpperBoundariesBelow(const Window& window, size_t begin, size_t end) {
  const int64_t width = window.width;
  gap_tiles_.assign(detail::TileMask::TileCount(window.width, window.height), 0);
  detail::TileMask tiles{(width + 7) >> detail::TileMask::kShift, gap_tiles_};
  for (size_t n = begin; n < end; ++n) {
    const size_t k = found_[n].texel;
    exit_z_[k] = -kInf;
    exit_face_[k] = kNoFace;
    tiles.Mark(static_cast<int64_t>(k) % width, static_cast<int64_t>(k) / width);
  }
  detail::RasterizeInBands(
      drawn_, raster_, raster_rows_, RasterWindowOf(window), &tiles,
      [&](uint32_t t, const RasterTriangle& r, size_t k, double px, double py, bool) {
        if (r.entering) return;  // below_z_ is -inf but at candidates
        const float z = r.Depth(px, py);
        if (z < below_z_[k] - kMinGap && z > exit_z_[k]) {
          exit_z_[k] = z;
          exit_face_[k] = t;
        }
      });
}

// At the level's texels, where a gap may lie below the upper boundary in exit_z_ (it lies above
// the back surface); then the entering and leaving surfaces around it. Texels outside the level
// have no exit face (CollectGaps clears it), so the pass leaves them alone.
void BodyMapRenderer::RasterizeGapSurfaces(const Window& window, const BodyMapCollider& maps,
                                           bool all, size_t begin, size_t end) {
  const int64_t width = window.width;
  const size_t texels = static_cast<size_t>(window.width) * window.height;
  gap_tiles_.assign(detail::TileMask::TileCount(window.width, window.height), 0);
  detail::TileMask tiles{(width + 7) >> detail::TileMask::kShift, gap_tiles_};
  const std::span<const FoundGap> above(found_.data() + begin, end - begin);
  ForLevelTexels(texels, all, above, [&](size_t k) {
    // No room for a gap of kMinGap and its two boundaries above the back surface.
    if (exit_face_[k] != kNoFace && !(exit_z_[k] > maps.slabs_[k].bottom + 2.f * kMinGap)) {
      exit_face_[k] = kNoFace;
    }
    if (exit_face_[k] == kNoFace) return;
    entry_z_[k] = -kInf;
    entry_face_[k] = kNoFace;
    entries_above_[k] = exits_above_[k] = entries_total_[k] = exits_total_[k] = 0;
    crowded_[k] = 0;
    tiles.Mark(static_cast<int64_t>(k) % width, static_cast<int64_t>(k) / width);
  });
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

// The level's gaps that pass the tests, appended to found_; below_z_ keeps their lower
// boundaries for the next level, and the texels without one lose their exit face (-inf and
// none: out of the next level). Returns found_'s new size.
size_t BodyMapRenderer::CollectGaps(const Window& window, const BodyMapCollider& maps,
                                    uint32_t level, bool all, size_t begin, size_t end) {
  const size_t texels = static_cast<size_t>(window.width) * window.height;
  // By index: found_ grows below (within its reserve, or counted as growth at publication).
  for (size_t n = all ? 0 : begin; n < (all ? texels : end); ++n) {
    const size_t k = all ? n : size_t{found_[n].texel};
    const BodyMapCollider::Slab slab = maps.slabs_[k];
    const float upper = exit_z_[k], lower = entry_z_[k];
    const bool air = exit_face_[k] != kNoFace && entry_face_[k] != kNoFace && !crowded_[k] &&
                     entries_above_[k] != 0 && entries_above_[k] == exits_above_[k] &&
                     entries_total_[k] == exits_total_[k] && upper < slab.top - kMinGap &&
                     lower > slab.bottom + kMinGap && upper - lower > kMinGap;
    below_z_[k] = air ? lower : -kInf;
    if (!air) {
      exit_face_[k] = kNoFace;
      continue;
    }
    found_.push_back(
        {static_cast<uint32_t>(k), level, upper, lower, exit_face_[k], entry_face_[k]});
  }
  return found_.size();
}

// Stage 4c: the gaps found, per texel in level order (top down), into the collider's compact gap
// storage, as many layers per gap texel as the deepest level found (absent ones -inf / +inf), with
// their boundaries' normals (the upper one faces down into the gap, the lower one up).
void BodyMapRenderer::PublishGaps(const Window& window, BodyMapCollider* maps) {
  const size_t texels = static_cast<size_t>(window.width) * window.height;
  const size_t capacity = maps->gaps_.capacity();
  uint32_t layers = 1;
  for (const FoundGap& g : found_) layers = std::max(layers, g.level + 1);
  // In place (no allocation): level order within a texel, row-major across texels.
  std::sort(found_.begin(), found_.end(), [](const FoundGap& a, const FoundGap& b) {
    return a.texel != b.texel ? a.texel < b.texel : a.level < b.level;
  });
  maps->gap_layers_ = layers;
  maps->gap_texel_bits_.assign((texels + 31) / 32, 0u);
  maps->gaps_.clear();
  maps->gap_normals_.clear();
  const std::array<uint16_t, 2> up = EncodeOct16({0.f, 0.f, 1.f});
  for (size_t first = 0; first < found_.size();) {
    const uint32_t k = found_[first].texel;
    maps->gap_texel_bits_[k >> 5] |= 1u << (k & 31u);
    const float px = static_cast<float>(k % window.width) + 0.5f;
    const float py = static_cast<float>(k / window.width) + 0.5f;
    size_t next = first;
    for (uint32_t level = 0; level < layers; ++level) {
      if (next < found_.size() && found_[next].texel == k && found_[next].level == level) {
        const FoundGap& g = found_[next++];
        maps->gaps_.push_back({g.upper, g.lower});
        const std::array<uint16_t, 2> a =
            EncodeOct16(shading_[g.upper_face].At(px, py, Float3{0.f, 0.f, -1.f}));
        const std::array<uint16_t, 2> b =
            EncodeOct16(shading_[g.lower_face].At(px, py, Float3{0.f, 0.f, 1.f}));
        maps->gap_normals_.push_back({{a[0], a[1]}, {b[0], b[1]}});
      } else {
        maps->gaps_.push_back({-kInf, kInf});  // no gap at this level
        maps->gap_normals_.push_back({{up[0], up[1]}, {up[0], up[1]}});
      }
    }
    first = next;
  }
  if (maps->gaps_.capacity() != capacity) ++stats_.grew;  // more gap texels than reserved
  maps->CountGapsBeforeWords();
}

}  // namespace drape

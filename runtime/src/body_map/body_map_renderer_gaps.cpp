// BodyMapRenderer's air gaps (options.air_gaps): the air below each texel's front surface, gap
// by gap going down. The first raster pass found the highest surface leaving the body going
// along -z (the first candidate upper boundary); a gap pass counts the surfaces above it, each
// texel centre on a shared edge counted once, and finds the highest surface entering the body
// below it (the lower boundary). The range between them is air when as many surfaces enter as
// leave above the upper boundary (the winding count is 0 just below it) and along the whole ray
// (the count ends at 0, as the bake's sweep requires), and none lies within kMinGap below it.
// The next candidate is the highest surface leaving below that lower boundary, or below the
// candidate itself when another part still encloses it (one more raster pass over the texels
// still searching), and so on. Surfaces enter where the drawn (offset) triangle runs
// counter-clockwise in the window, as in the bake. Where the ray does not balance the texel
// keeps what it has, the conservative answer (docs/ALGORITHMS.md §7.9). A part thinner than
// kMinGap at either end of the ray (a texel centre on the silhouette of a part seen edge-on,
// whose two sides meet at one depth) is no body: the slab ends at the air next to it instead of
// taking that air in.
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
// gap_flags_ bits: a surface lies within kMinGap below the candidate; one enters above it (a
// seam texel can leave the counts balanced with nothing counted above).
constexpr uint8_t kCrowded = 1, kEnteredAbove = 2;

}  // namespace

// Stage 4b: the air gaps into found_, pass by pass going down. The first pass looks at every
// texel; each later one only at the texels still searching (searching_): those that found a gap
// and may hold more, and those whose candidate was not one because another part encloses it (an
// arm sunk into the torso leaves the body below its exit) and whose ray has deeper surfaces.
void BodyMapRenderer::FindGaps(const Window& window, BodyMapCollider* maps) {
  found_.clear();
  searching_.clear();
  const size_t texels = static_cast<size_t>(window.width) * window.height;
  std::fill(below_z_.begin(), below_z_.begin() + static_cast<std::ptrdiff_t>(texels), -kInf);
  std::fill(gap_count_.begin(), gap_count_.begin() + static_cast<std::ptrdiff_t>(texels), 0);
  // Each pass rasterizes the searching texels' tiles twice; a ray with more nested parts than
  // this keeps what the passes found.
  const uint32_t max_passes = 2 * options_.air_gaps;
  for (uint32_t pass = 0; pass < max_passes; ++pass) {
    const bool first = pass == 0;
    if (!first) FindUpperBoundariesBelow(window);
    RasterizeGapSurfaces(window, *maps, first);
    CollectGaps(maps);
    if (searching_.empty()) break;
  }
}

// The next candidate upper boundaries: per searching texel, the highest surface leaving the body
// below below_z_ (its last gap's lower boundary, or the candidate that failed).
void BodyMapRenderer::FindUpperBoundariesBelow(const Window& window) {
  const int64_t width = window.width;
  gap_tiles_.assign(detail::TileMask::TileCount(window.width, window.height), 0);
  detail::TileMask tiles{(width + 7) >> detail::TileMask::kShift, gap_tiles_};
  for (const uint32_t k : searching_) {
    exit_z_[k] = -kInf;
    exit_face_[k] = kNoFace;
    tiles.Mark(int64_t{k} % width, int64_t{k} / width);
  }
  detail::RasterizeInBands(
      drawn_, raster_, raster_rows_, RasterWindowOf(window), &tiles,
      [&](uint32_t t, const RasterTriangle& r, size_t k, double px, double py, bool) {
        if (r.entering) return;  // below_z_ is -inf but where searching
        const float z = r.Depth(px, py);
        if (z < below_z_[k] - kMinGap && z > exit_z_[k]) {
          exit_z_[k] = z;
          exit_face_[k] = t;
        }
      });
}

// At the pass's texels, where a gap may lie below the candidate upper boundary in exit_z_ (it
// lies above the back surface); then the entering and leaving surfaces around it. Texels out of
// the pass have no exit face (CollectGaps clears it), so the pass leaves them alone.
void BodyMapRenderer::RasterizeGapSurfaces(const Window& window, const BodyMapCollider& maps,
                                           bool all) {
  const int64_t width = window.width;
  const size_t texels = static_cast<size_t>(window.width) * window.height;
  gap_tiles_.assign(detail::TileMask::TileCount(window.width, window.height), 0);
  detail::TileMask tiles{(width + 7) >> detail::TileMask::kShift, gap_tiles_};
  // The candidates, ascending: on the first pass every texel with one, later the searching
  // texels that still have one. Only they are reset, drawn and collected.
  const auto keep = [&](size_t k) {
    // No room for a gap of kMinGap and its two boundaries above the back surface.
    if (exit_face_[k] != kNoFace && !(exit_z_[k] > maps.slabs_[k].bottom + 2.f * kMinGap)) {
      exit_face_[k] = kNoFace;
    }
    if (exit_face_[k] == kNoFace) return false;
    entry_z_[k] = -kInf;
    entry_face_[k] = kNoFace;
    winding_above_[k] = winding_total_[k] = 0;
    gap_flags_[k] = 0;
    tiles.Mark(static_cast<int64_t>(k) % width, static_cast<int64_t>(k) / width);
    return true;
  };
  if (all) {
    searching_.clear();
    for (size_t k = 0; k < texels; ++k) {
      if (keep(k)) searching_.push_back(static_cast<uint32_t>(k));  // reserved for every texel
    }
  } else {
    searching_.erase(std::remove_if(searching_.begin(), searching_.end(),
                                    [&](uint32_t k) { return !keep(size_t{k}); }),
                     searching_.end());
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
          if (once) --winding_total_[k];
          if (z >= upper && once) --winding_above_[k];
          return;
        }
        if (once) ++winding_total_[k];
        // A candidate within kMinGap of the slab's front: what enters as close below it is the
        // other side of the same sliver, above the air rather than crowding it.
        const bool sliver_front = upper >= maps.slabs_[k].top - kMinGap;
        if (z > upper || (sliver_front && z > upper - kMinGap)) {
          if (once) {
            ++winding_above_[k];
            gap_flags_[k] |= kEnteredAbove;
          }
        } else if (z > upper - kMinGap) {
          gap_flags_[k] |= kCrowded;
        } else if (z > entry_z_[k]) {
          entry_z_[k] = z;
          entry_face_[k] = t;
        }
      });
}

// The pass's gaps that pass the tests, appended to found_, and the texels to search on
// (searching_, ascending): below a gap while the texel holds fewer than air_gaps, or below a
// candidate that was no gap because the body continues under it (the surfaces above it do not
// balance, or one lies within kMinGap below it) while the whole ray balances. The others lose
// their exit face (out of the next pass). Air whose only body above or below is thinner than
// kMinGap (a sliver at the slab's top or bottom) moves that end of the slab instead.
void BodyMapRenderer::CollectGaps(BodyMapCollider* maps) {
  next_searching_.clear();
  for (const uint32_t k : searching_) {
    BodyMapCollider::Slab& slab = maps->slabs_[k];
    const float upper = exit_z_[k], lower = entry_z_[k];
    const bool candidate = exit_face_[k] != kNoFace && winding_total_[k] == 0;
    const bool enclosed = winding_above_[k] != 0 || (gap_flags_[k] & kCrowded) != 0;
    const bool bounded = candidate && !enclosed && entry_face_[k] != kNoFace &&
                         (gap_flags_[k] & kEnteredAbove) != 0 && upper - lower > kMinGap;
    const bool body_above = upper < slab.top - kMinGap;
    const bool body_below = lower > slab.bottom + kMinGap;
    bool search_on = false;
    if (bounded && body_above && body_below) {
      found_.push_back(
          {static_cast<uint32_t>(k), gap_count_[k]++, upper, lower, exit_face_[k], entry_face_[k]});
      below_z_[k] = lower;
      search_on = gap_count_[k] < options_.air_gaps;
    } else if (bounded && !body_below) {
      slab.bottom = upper;  // below the air only a sliver: the slab's back is the air's top
      bottom_face_[k] = exit_face_[k];
    } else if (bounded) {
      slab.top = lower;  // above the air only a sliver: the slab's front is the air's bottom
      top_face_[k] = entry_face_[k];
      below_z_[k] = lower;
      search_on = true;
    } else if (candidate && enclosed) {
      below_z_[k] = upper;  // the next exit below this one may open the gap
      search_on = true;
    }
    if (search_on) {
      next_searching_.push_back(static_cast<uint32_t>(k));
    } else {
      below_z_[k] = -kInf;
      exit_face_[k] = kNoFace;
    }
  }
  searching_.swap(next_searching_);
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

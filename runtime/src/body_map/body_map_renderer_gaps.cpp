// BodyMapRenderer's air gaps (options.air_gaps): the air below each texel's front surface, gap
// by gap going down. The raster pass found the highest surface leaving the body going along -z
// (the first candidate upper boundary) and counted the surfaces on each ray. Where that surface
// lies above the back one a gap may lie: one more raster pass collects every surface on those
// texels' rays, in draw order, and the search then walks each texel's list. It counts the
// surfaces above the candidate, each texel centre on a shared edge counted once, and finds the
// highest surface entering the body below it (the lower boundary). The range between them is air
// when as many surfaces enter as leave above the upper boundary (the winding count is 0 just
// below it) and along the whole ray (the count ends at 0, as the bake's sweep requires), and none
// lies within kMinGap below it. The next candidate is the highest surface leaving below that
// lower boundary, or below the candidate itself when another part still encloses it, and so on.
// Surfaces enter where the drawn (offset) triangle runs counter-clockwise in the window, as in
// the bake. Where the ray does not balance the texel keeps what it has, the conservative answer
// (docs/ALGORITHMS.md §7.9). A part thinner than kMinGap at either end of the ray (a texel centre
// on the silhouette of a part seen edge-on, whose two sides meet at one depth) is no body: the
// slab ends at the air next to it instead of taking that air in.
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
// GapFragment::face_flags: the triangle below kMaxRasterTriangles, and two flags above it.
constexpr uint32_t kEnteringBit = 1u << 31, kCountsOnceBit = 1u << 30;
constexpr uint32_t kFaceMask = kCountsOnceBit - 1u;
// Gap texels per chunk of the search.
constexpr int64_t kGapTexelGrain = 256;
// Bounds on what the search collects, against hostile meshes (a human's gap texels cross 4-8
// surfaces): a texel whose ray crosses more surfaces, or whose surfaces would take the array
// past the total, is not searched and keeps its slab (the conservative answer).
constexpr uint32_t kMaxSurfacesPerGapTexel = 1024;
constexpr uint32_t kMaxGapFragments = 1u << 24;  // 128 MiB

}  // namespace

// Stage 4b: the air gaps of each gap texel into its slots of texel_gaps_, top down.
void BodyMapRenderer::FindGaps(const Window& window, BodyMapCollider* maps) {
  SelectGapTexels(*maps, static_cast<size_t>(window.width) * window.height);
  CollectGapFragments(window);
  const uint32_t slots = options_.air_gaps;
  const int64_t count = static_cast<int64_t>(gap_texels_.size());
  gaps_per_texel_.resize(gap_texels_.size());
  texel_gaps_.resize(gap_texels_.size() * slots);
  detail::ParallelFor(count, kGapTexelGrain, [&](int64_t c) {
    const uint32_t n = static_cast<uint32_t>(c);
    gaps_per_texel_[n] =
        static_cast<uint8_t>(SearchTexelGaps(n, maps, &texel_gaps_[size_t{n} * slots]));
  });
}

// The texels where a gap may lie (the first candidate lies above the back surface, with room for
// a gap of kMinGap and its two boundaries, and a surface enters the body below it) within the
// bounds above, ascending, and where each one's surfaces go. The other texels collect nothing
// (their count drops to 0).
void BodyMapRenderer::SelectGapTexels(const BodyMapCollider& maps, size_t texels) {
  gap_texels_.clear();
  fragment_offsets_.clear();
  uint32_t total = 0;
  for (size_t k = 0; k < texels; ++k) {
    // Background: no fragment, and its entries were never set (nor are they collected).
    const BodyMapCollider::Slab& slab = maps.slabs_[k];
    if (!(slab.top >= slab.bottom)) continue;
    // A gap's lower boundary is a surface entering the body below its upper one, which lies at
    // or below the first candidate: none there, no gap (parts sunk into each other).
    TexelRaster& e = texel_raster_[k];
    const bool room = e.exit_face != kNoFace && e.exit_z > slab.bottom + 2.f * kMinGap &&
                      e.lowest_entry_z < e.exit_z;
    const uint32_t surfaces = e.fragment_count;
    if (!room || surfaces > kMaxSurfacesPerGapTexel || surfaces > kMaxGapFragments - total) {
      e.fragment_count = 0;
      continue;
    }
    gap_texels_.push_back(static_cast<uint32_t>(k));
    fragment_offsets_.push_back(total);
    fragment_cursor_[k] = total;
    total += surfaces;
  }
  fragment_offsets_.push_back(total);
  fragments_.resize(total);
}

// One raster pass over the tiles that hold gap texels: every surface on their rays, in draw
// order (a texel's triangles are drawn in `drawn` order by one row band).
void BodyMapRenderer::CollectGapFragments(const Window& window) {
  const int64_t width = window.width;
  gap_tiles_.assign(detail::TileMask::TileCount(window.width, window.height), 0);
  detail::TileMask tiles{(width + 7) >> detail::TileMask::kShift, gap_tiles_};
  for (const uint32_t k : gap_texels_) tiles.Mark(int64_t{k} % width, int64_t{k} / width);
  if (gap_texels_.empty()) return;
  const detail::RasterWindow w = RasterWindowOf(window);
  detail::TrianglesOnTiles(RasterBoxes(), tiles, &gap_triangles_);
  detail::RasterizeInBands(
      RasterFaces(), RasterSetUps(), RasterBoxes(), w, &gap_triangles_,
      [&](uint32_t t, const RasterTriangle& r, size_t k, double px, double py, bool once) {
        // The same coverage as the raster pass counted.
        uint32_t& left = texel_raster_[k].fragment_count;
        if (left == 0) return;
        --left;
        const uint32_t flags = (r.entering ? kEnteringBit : 0u) | (once ? kCountsOnceBit : 0u);
        fragments_[fragment_cursor_[k]++] = {r.Depth(px, py), t | flags};
      });
}

// The search down one gap texel's ray (gap_texels_[candidate]): up to air_gaps gaps into found
// (level order), and the slab's ends moved past slivers. Returns the gaps found. Each step looks
// at the candidate upper boundary: where it bounds air, the next candidate is the highest leaving
// surface below the air; where another part encloses it, the highest leaving surface below it.
uint32_t BodyMapRenderer::SearchTexelGaps(uint32_t candidate, BodyMapCollider* maps,
                                          FoundGap* found) {
  const uint32_t k = gap_texels_[candidate];
  const GapFragment* begin = fragments_.data() + fragment_offsets_[candidate];
  const GapFragment* end = fragments_.data() + fragment_offsets_[candidate + 1];
  BodyMapCollider::Slab& slab = maps->slabs_[k];
  float upper = texel_raster_[k].exit_z;
  uint32_t upper_face = texel_raster_[k].exit_face;
  uint32_t gaps = 0;
  for (uint32_t step = 0; step < 2 * options_.air_gaps; ++step) {
    // No room for a gap of kMinGap and its two boundaries above the back surface.
    if (upper_face == kNoFace || !(upper > slab.bottom + 2.f * kMinGap)) break;
    // The surfaces around the candidate. Counted once per shared edge; searched for the lower
    // boundary inclusively, so that a texel centre on a seam (vertices split at the same
    // position, whose edge values are not exactly negated) can only spoil the count, which
    // keeps the slab.
    float lower = -kInf;
    uint32_t lower_face = kNoFace;
    int32_t winding_above = 0, winding_total = 0;
    bool crowded = false, entered_above = false;
    // A candidate within kMinGap of the slab's front: what enters as close below it is the
    // other side of the same sliver, above the air rather than crowding it.
    const bool sliver_front = upper >= slab.top - kMinGap;
    for (const GapFragment* f = begin; f != end; ++f) {
      const float z = f->z;
      const bool once = (f->face_flags & kCountsOnceBit) != 0;
      if ((f->face_flags & kEnteringBit) == 0) {  // the drawn triangle's winding, as the bake's
        if (once) --winding_total;
        if (z >= upper && once) --winding_above;
        continue;
      }
      if (once) ++winding_total;
      if (z > upper || (sliver_front && z > upper - kMinGap)) {
        if (once) {
          ++winding_above;
          entered_above = true;
        }
      } else if (z > upper - kMinGap) {
        crowded = true;
      } else if (z > lower) {
        lower = z;
        lower_face = f->face_flags & kFaceMask;
      }
    }
    // Air when the counts balance above it and along the ray and it is thick enough; a sliver at
    // the slab's top or bottom moves that end of the slab instead.
    const bool balanced = winding_total == 0;
    const bool enclosed = winding_above != 0 || crowded;
    const bool bounded =
        balanced && !enclosed && lower_face != kNoFace && entered_above && upper - lower > kMinGap;
    const bool body_above = upper < slab.top - kMinGap;
    const bool body_below = lower > slab.bottom + kMinGap;
    float below;  // where the next candidate is searched
    if (bounded && body_above && body_below) {
      found[gaps] = {upper, lower, upper_face, lower_face};
      if (++gaps == options_.air_gaps) break;
      below = lower;
    } else if (bounded && !body_below) {
      slab.bottom = upper;  // below the air only a sliver: the slab's back is the air's top
      texel_raster_[k].bottom_face = upper_face;
      break;
    } else if (bounded) {
      slab.top = lower;  // above the air only a sliver: the slab's front is the air's bottom
      texel_raster_[k].top_face = lower_face;
      below = lower;
    } else if (balanced && enclosed) {
      below = upper;  // the next exit below this one may open the gap
    } else {
      break;
    }
    // The next candidate: the highest surface leaving the body below `below`.
    upper = -kInf;
    upper_face = kNoFace;
    for (const GapFragment* f = begin; f != end; ++f) {
      if ((f->face_flags & kEnteringBit) != 0) continue;
      if (f->z < below - kMinGap && f->z > upper) {
        upper = f->z;
        upper_face = f->face_flags & kFaceMask;
      }
    }
  }
  return gaps;
}

// Stage 4c: the gaps found, per texel in level order (top down), into the collider's compact gap
// storage, as many layers per gap texel as the deepest level found (absent ones -inf / +inf), with
// their boundaries' normals (the upper one faces down into the gap, the lower one up).
void BodyMapRenderer::PublishGaps(const Window& window, BodyMapCollider* maps) {
  const size_t texels = static_cast<size_t>(window.width) * window.height;
  const size_t capacity = maps->gaps_.capacity();
  uint32_t layers = 1;
  for (const uint8_t gaps : gaps_per_texel_) layers = std::max<uint32_t>(layers, gaps);
  maps->gap_layers_ = layers;
  maps->gap_texel_bits_.assign((texels + 31) / 32, 0u);
  maps->gaps_.clear();
  maps->gap_normals_.clear();
  const std::array<uint16_t, 2> up = EncodeOct16({0.f, 0.f, 1.f});
  for (size_t c = 0; c < gap_texels_.size(); ++c) {  // ascending texels
    if (gaps_per_texel_[c] == 0) continue;
    const uint32_t k = gap_texels_[c];
    maps->gap_texel_bits_[k >> 5] |= 1u << (k & 31u);
    const float px = static_cast<float>(k % window.width) + 0.5f;
    const float py = static_cast<float>(k / window.width) + 0.5f;
    for (uint32_t level = 0; level < layers; ++level) {
      if (level < gaps_per_texel_[c]) {
        const FoundGap& g = texel_gaps_[c * options_.air_gaps + level];
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
  }
  if (maps->gaps_.capacity() != capacity) grew_ = true;  // more gap texels than reserved
  maps->CountGapsBeforeWords();
}

}  // namespace drape

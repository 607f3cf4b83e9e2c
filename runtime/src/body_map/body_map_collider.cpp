// BodyMapCollider's layout: what Build derives from the decoded slabs (bounds, the clip box,
// bilinear eligibility, the 8x8 min/max level, the gap flags), the compact gap storage, and
// per-texel access.
#include "drape/runtime/body_map_collider.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "drape/runtime/normal_encoding.h"
#include "tasks/parallel_for.h"

namespace drape {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
// Rows per chunk of the derived-data passes on the workers (a chunk's work is a few microseconds
// at the smallest; the chunking depends on the grid alone).
constexpr int64_t kFinishRowGrain = 32;

// `top` with its lowest mantissa bit equal to `has_gaps` (0 or 1): itself, or the next float up
// (out of the body, above any gap), or down from the largest float. Without a branch on the
// bit, which is data. In bits: + 0.f makes -0 into +0, whose next float up is the least
// denormal (bits 1).
float WithGapFlag(float top, uint32_t has_gaps) {
  const uint32_t bits = std::bit_cast<uint32_t>(top + 0.f);
  const uint32_t up = static_cast<int32_t>(bits) >= 0 ? bits + 1u : bits - 1u;
  const uint32_t down = static_cast<int32_t>(bits) >= 0 ? bits - 1u : bits + 1u;
  const uint32_t moved = up == std::bit_cast<uint32_t>(kInf) ? down : up;
  const bool keep = (std::bit_cast<uint32_t>(top) & 1u) == has_gaps;
  return std::bit_cast<float>(keep ? std::bit_cast<uint32_t>(top) : moved);
}
// Bilinear depth only where the four corner depths spread less than this many texel sizes
// (docs/ALGORITHMS.md §7.3): larger spreads are silhouettes or steps, where bilinear
// would invent a slope through air.
constexpr float kBilinearSpreadTexels = 3.f;

}  // namespace

void BodyMapCollider::Clear() {
  width_ = height_ = 0;
  width_f_ = height_f_ = 0.f;
  origin_x_ = origin_y_ = 0.f;
  texel_size_ = inv_texel_size_ = 0.f;
  clip_ = -1;
  time_ = 0.f;
  view_axis_ = BodyMapViewAxis::kZ;
  bounds_min_ = {1.f, 1.f, 1.f};
  bounds_max_ = {-1.f, -1.f, -1.f};
  for (int k = 0; k < 3; ++k) {
    clip_lo_[k] = 0.0;
    clip_hi_[k] = -1.0;
  }
  for (int k = 0; k < 2; ++k) {
    clip_lo_float_[k] = 0.f;
    clip_hi_float_[k] = -1.f;
  }
  blocks_w_ = blocks_h_ = 0;
  stats_ = BodyMapStats{};
  slabs_.clear();
  normals_.clear();
  bilinear_ok_.clear();
  blocks_.clear();
  gap_layers_ = 0;
  gap_texel_bits_.clear();
  gap_word_first_.clear();
  gaps_.clear();
  gap_normals_.clear();
  air_reach_.clear();
}

void BodyMapCollider::PackGaps(std::vector<GapTexel>* texels) {
  const size_t layers = gap_layers_;
  blocks_w_ = static_cast<uint32_t>((width_ + kBlockTexels - 1) >> kBlockShift);
  blocks_h_ = static_cast<uint32_t>((height_ + kBlockTexels - 1) >> kBlockShift);
  gap_texel_bits_.clear();
  gap_word_first_.clear();
  gaps_.clear();
  gap_normals_.clear();
  if (layers == 0) return;
  gap_texel_bits_.assign((static_cast<size_t>(width_) * height_ + 31) / 32, 0u);
  const auto texel_of = [&](const GapTexel& t) { return static_cast<size_t>(t.j) * width_ + t.i; };
  std::sort(texels->begin(), texels->end(),
            [&](const GapTexel& a, const GapTexel& b) { return texel_of(a) < texel_of(b); });
  gaps_.reserve(texels->size() * layers);  // exactly: memory_bytes() reports what gaps need
  gap_normals_.reserve(texels->size() * layers);
  for (const GapTexel& t : *texels) {
    const size_t k = texel_of(t);
    gap_texel_bits_[k / 32] |= 1u << (k % 32);
    gaps_.insert(gaps_.end(), t.gaps, t.gaps + layers);
    gap_normals_.insert(gap_normals_.end(), t.normals, t.normals + layers);
  }
  CountGapsBeforeWords();
}

void BodyMapCollider::CountGapsBeforeWords() {
  // No allocation once a blend's scratch held this grid (assign keeps the capacity).
  gap_word_first_.assign(gap_texel_bits_.size(), 0u);
  uint32_t before = 0;
  for (size_t word = 0; word < gap_texel_bits_.size(); ++word) {
    gap_word_first_[word] = before;
    before += static_cast<uint32_t>(std::popcount(gap_texel_bits_[word]));
  }
}

namespace {
// Row j's texels that may be valid: [first, second) of `row_spans`, or the whole row.
std::pair<size_t, size_t> RowSpan(std::span<const uint32_t> row_spans, size_t j, size_t width) {
  if (row_spans.empty()) return {0, width};
  return {row_spans[2 * j], row_spans[2 * j + 1]};
}
}  // namespace

void BodyMapCollider::Finish(std::span<const uint32_t> row_spans) {
  FinishBounds(row_spans);
  FinishBilinearBlocks();
  FinishMinMaxBlocks(row_spans);
  FinishAirReach(row_spans);
}

// Per texel, the Chebyshev distance in texels to the nearest texel with air inside the grid's
// box: background (beyond the grid counts as background) or a texel with air gaps in its slab
// (the narrow air between an arm and the torso, which closes a texel further on), capped at
// kSideExitTexels + 1: a point inside whose texel lies farther from all air has no side exit to
// look for (NearerSideExit). The distances along each row first, then down each column over
// them, in place (the rows above a texel already hold their final values, so their row
// distances wait in a small ring); no allocation once the grid's size was seen.
void BodyMapCollider::FinishAirReach(std::span<const uint32_t> row_spans) {
  const int64_t w = width_, h = height_;
  constexpr int kCap = kSideExitTexels + 1;
  air_reach_.resize(static_cast<size_t>(w * h));
  uint8_t* reach = air_reach_.data();
  detail::ParallelFor(h, kFinishRowGrain, [&](int64_t j) {
    uint8_t* row = reach + j * w;
    const Slab* slab = slabs_.data() + j * w;
    // Outside the row's span every texel is background (distance 0), and each end of the span
    // borders background or the grid's edge, so the runs start there.
    const auto [lo, hi] = RowSpan(row_spans, static_cast<size_t>(j), static_cast<size_t>(w));
    const int64_t begin = static_cast<int64_t>(lo), end = static_cast<int64_t>(hi);
    std::fill(row, row + begin, uint8_t{0});
    std::fill(row + end, row + w, uint8_t{0});
    int run = 0;  // texels since the last one with air (the grid's edge is one)
    for (int64_t i = begin; i < end; ++i) {
      const bool solid =
          slab[i].top >= slab[i].bottom && !TexelHasGaps(static_cast<size_t>(j * w + i));
      run = solid ? std::min(run + 1, kCap) : 0;
      row[i] = static_cast<uint8_t>(run);
    }
    run = 0;
    for (int64_t i = end - 1; i >= begin; --i) {
      run = row[i] == 0 ? 0 : std::min(run + 1, kCap);
      row[i] = static_cast<uint8_t>(std::min<int>(row[i], run));
    }
  });
  // Then down each column over them, in strips of kStrip columns so that the loops run along
  // the rows (a column walk strides a whole row per texel) and the strips on separate workers:
  // each strip's rows above the current one keep their row distances in a small ring, as they
  // are overwritten.
  constexpr int64_t kStrip = 64;
  static constexpr uint8_t kBeyond[kStrip] = {};  // rows beyond the grid: background, distance 0
  detail::ParallelFor((w + kStrip - 1) / kStrip, 1, [&](int64_t strip) {
    const int64_t i0 = strip * kStrip;
    const int64_t n = std::min(kStrip, w - i0);
    uint8_t above[kCap][kStrip];  // the row distances of rows j - 1 .. j - kCap + 1, by j % kCap
    for (int64_t j = 0; j < h; ++j) {
      uint8_t* row = reach + j * w + i0;
      uint8_t best[kStrip];
      for (int64_t i = 0; i < n; ++i) best[i] = std::min<uint8_t>(row[i], kCap);
      for (int d = 1; d < kCap; ++d) {  // d rows away, above and below
        const uint8_t* up = j - d >= 0 ? above[(j - d) % kCap] : kBeyond;
        const uint8_t* down = j + d < h ? reach + (j + d) * w + i0 : kBeyond;
        const uint8_t far = static_cast<uint8_t>(d);
        for (int64_t i = 0; i < n; ++i) {
          best[i] = std::min({best[i], std::max(far, up[i]), std::max(far, down[i])});
        }
      }
      std::copy(row, row + n, above[j % kCap]);
      std::copy(best, best + n, row);
    }
  });
}

// Marks the texels with gaps in their slabs' tops (WithGapFlag: the lanes read the flag from the
// slab they load anyway), counts the valid texels, and sets the bounds and the clip box.
void BodyMapCollider::FinishBounds(std::span<const uint32_t> row_spans) {
  const size_t w = width_, h = height_;
  // Row chunks on the workers, each with its own counts and bounds, joined in chunk order: the
  // same bits as one pass in row order (the first of equal z values kept, as std::min keeps it).
  struct Partial {
    uint32_t valid = 0;
    size_t i_lo = SIZE_MAX, i_hi = 0, j_lo = SIZE_MAX, j_hi = 0;  // valid texel range, [lo, hi)
    float z_lo = kInf, z_hi = -kInf;
  };
  constexpr int64_t kMaxChunks = 64;
  const int64_t rows_per_chunk =
      std::max<int64_t>(kFinishRowGrain, (static_cast<int64_t>(h) + kMaxChunks - 1) / kMaxChunks);
  Partial partials[kMaxChunks];
  detail::ParallelRanges(static_cast<int64_t>(h), rows_per_chunk, [&](int64_t begin, int64_t end) {
    Partial& p = partials[begin / rows_per_chunk];
    for (size_t j = static_cast<size_t>(begin); j < static_cast<size_t>(end); ++j) {
      const auto [lo, hi] = RowSpan(row_spans, j, w);
      for (size_t i = lo; i < hi; ++i) {
        Slab& s = slabs_[j * w + i];
        if (!(s.top >= s.bottom)) continue;  // background: top -inf, no gaps, its low bit clear
        if (gap_layers_ != 0) s.top = WithGapFlag(s.top, TexelHasGaps(j * w + i) ? 1u : 0u);
        ++p.valid;
        p.i_lo = std::min(p.i_lo, i);
        p.i_hi = std::max(p.i_hi, i + 1);
        p.j_lo = std::min(p.j_lo, j);
        p.j_hi = std::max(p.j_hi, j + 1);
        p.z_lo = std::min(p.z_lo, s.bottom);
        p.z_hi = std::max(p.z_hi, s.top);
      }
    }
  });
  uint32_t valid = 0;
  size_t i_lo = w, i_hi = 0, j_lo = h, j_hi = 0;
  float z_lo = kInf, z_hi = -kInf;
  const int64_t chunks = (static_cast<int64_t>(h) + rows_per_chunk - 1) / rows_per_chunk;
  for (int64_t c = 0; c < chunks; ++c) {
    const Partial& p = partials[c];
    if (p.valid == 0) continue;
    valid += p.valid;
    i_lo = std::min(i_lo, p.i_lo);
    i_hi = std::max(i_hi, p.i_hi);
    j_lo = std::min(j_lo, p.j_lo);
    j_hi = std::max(j_hi, p.j_hi);
    z_lo = std::min(z_lo, p.z_lo);
    z_hi = std::max(z_hi, p.z_hi);
  }
  stats_.valid_texels = valid;
  stats_.gap_texels = gap_layers_ == 0 ? 0u : static_cast<uint32_t>(gaps_.size() / gap_layers_);
  const double s = texel_size_;
  if (valid == 0) {
    bounds_min_ = {1.f, 1.f, 1.f};
    bounds_max_ = {-1.f, -1.f, -1.f};
    for (int k = 0; k < 3; ++k) {
      clip_lo_[k] = 0.0;
      clip_hi_[k] = -1.0;
    }
  } else {
    bounds_min_ = {static_cast<float>(origin_x_ + static_cast<double>(i_lo) * s),
                   static_cast<float>(origin_y_ + static_cast<double>(j_lo) * s), z_lo};
    bounds_max_ = {static_cast<float>(origin_x_ + static_cast<double>(i_hi) * s),
                   static_cast<float>(origin_y_ + static_cast<double>(j_hi) * s), z_hi};
    // The clip box is one texel wider in x and y than the valid texels, so the float texel
    // coordinate used by IsInside and the double box can never disagree about a valid texel.
    clip_lo_[0] = origin_x_ + (static_cast<double>(i_lo) - 1.0) * s;
    clip_hi_[0] = origin_x_ + (static_cast<double>(i_hi) + 1.0) * s;
    clip_lo_[1] = origin_y_ + (static_cast<double>(j_lo) - 1.0) * s;
    clip_hi_[1] = origin_y_ + (static_cast<double>(j_hi) + 1.0) * s;
    clip_lo_[2] = z_lo;
    clip_hi_[2] = z_hi;
  }
  // The same box in x and y for float coordinates: the least float >= lo and the greatest
  // float <= hi, so that x >= clip_lo_float_[0] exactly when x >= clip_lo_[0].
  for (int k = 0; k < 2; ++k) {
    float lo = static_cast<float>(clip_lo_[k]), hi = static_cast<float>(clip_hi_[k]);
    if (static_cast<double>(lo) < clip_lo_[k]) lo = std::nextafter(lo, kInf);
    if (static_cast<double>(hi) > clip_hi_[k]) hi = std::nextafter(hi, -kInf);
    clip_lo_float_[k] = lo;
    clip_hi_float_[k] = hi;
  }
}

// Bilinear eligibility per 2x2 block (lower corner texel (i, j)), kBilinear only.
void BodyMapCollider::FinishBilinearBlocks() {
  const size_t w = width_, h = height_;
  stats_.bilinear_blocks = 0;
  if (sampling_ == DepthSampling::kBilinear) {
    bilinear_ok_.assign(w * h, 0);
    const float max_spread = kBilinearSpreadTexels * texel_size_;
    for (size_t j = 0; j + 1 < h; ++j) {
      for (size_t i = 0; i + 1 < w; ++i) {
        const Slab q[4] = {slabs_[j * w + i], slabs_[j * w + i + 1], slabs_[(j + 1) * w + i],
                           slabs_[(j + 1) * w + i + 1]};
        float top_lo = kInf, top_hi = -kInf, bottom_lo = kInf, bottom_hi = -kInf;
        // Texels with air gaps stay nearest: their inside set is not one slab to interpolate.
        const uint32_t i0 = static_cast<uint32_t>(i), j0 = static_cast<uint32_t>(j);
        bool all_valid =
            gap_layers_ == 0 || (GapBase(i0, j0) < 0 && GapBase(i0 + 1, j0) < 0 &&
                                 GapBase(i0, j0 + 1) < 0 && GapBase(i0 + 1, j0 + 1) < 0);
        for (const Slab& c : q) {
          all_valid = all_valid && c.top >= c.bottom;
          top_lo = std::min(top_lo, c.top);
          top_hi = std::max(top_hi, c.top);
          bottom_lo = std::min(bottom_lo, c.bottom);
          bottom_hi = std::max(bottom_hi, c.bottom);
        }
        if (all_valid && top_hi - top_lo < max_spread && bottom_hi - bottom_lo < max_spread) {
          bilinear_ok_[j * w + i] = 1;
          ++stats_.bilinear_blocks;
        }
      }
    }
  } else {
    bilinear_ok_.clear();
  }
}

// The min/max level: 8x8 texel blocks, bounds over the block widened by one texel on each side,
// padded by 10 um per metre of |z| (+ 10 um) against the float rounding of the walk's Z(s).
void BodyMapCollider::FinishMinMaxBlocks(std::span<const uint32_t> row_spans) {
  const size_t w = width_, h = height_;
  blocks_w_ = static_cast<uint32_t>((w + kBlockTexels - 1) >> kBlockShift);
  blocks_h_ = static_cast<uint32_t>((h + kBlockTexels - 1) >> kBlockShift);
  blocks_.resize(static_cast<size_t>(blocks_w_) * blocks_h_);
  const auto block_row = [&](int64_t row) {  // every block of block row `row`
    const size_t bj = static_cast<size_t>(row);
    for (size_t bi = 0; bi < blocks_w_; ++bi) {
      const size_t i_begin = bi * kBlockTexels > 0 ? bi * kBlockTexels - 1 : 0;
      const size_t j_begin = bj * kBlockTexels > 0 ? bj * kBlockTexels - 1 : 0;
      const size_t i_end = std::min(w, (bi + 1) * kBlockTexels + 1);
      const size_t j_end = std::min(h, (bj + 1) * kBlockTexels + 1);
      float max_top = -kInf, min_bottom = kInf;
      for (size_t j = j_begin; j < j_end; ++j) {
        const auto [lo, hi] = RowSpan(row_spans, j, w);
        for (size_t i = std::max(i_begin, lo); i < std::min(i_end, hi); ++i) {
          const Slab& c = slabs_[j * w + i];
          if (!(c.top >= c.bottom)) continue;
          max_top = std::max(max_top, c.top);
          min_bottom = std::min(min_bottom, c.bottom);
        }
      }
      if (max_top >= min_bottom) {
        max_top += 1e-5f * (1.f + std::fabs(max_top));
        min_bottom -= 1e-5f * (1.f + std::fabs(min_bottom));
      }
      blocks_[bj * blocks_w_ + bi] = {max_top, min_bottom};
    }
  };
  detail::ParallelFor(blocks_h_, std::max<int64_t>(1, kFinishRowGrain / kBlockTexels), block_row);
}

InstructionSet BodyMapCollider::instruction_set() const {
  return UsableInstructionSet(instruction_set_limit_);
}

size_t BodyMapCollider::memory_bytes() const {
  return sizeof(*this) + (slabs_.capacity() + gaps_.capacity()) * sizeof(Slab) +
         (normals_.capacity() + gap_normals_.capacity()) * sizeof(TexelNormals) +
         (gap_texel_bits_.capacity() + gap_word_first_.capacity()) * sizeof(uint32_t) +
         bilinear_ok_.capacity() + blocks_.capacity() * sizeof(BlockBounds) + air_reach_.capacity();
}

Float3 BodyMapCollider::TexelNormal(uint32_t i, uint32_t j, bool back) const {
  if (i >= width_ || j >= height_) return Float3{0.f, 0.f, back ? -1.f : 1.f};
  const TexelNormals& n = normals_[static_cast<size_t>(j) * width_ + i];
  const uint16_t* q = back ? n.back : n.front;
  return DecodeOct16(q[0], q[1]);
}

int BodyMapCollider::TexelIntervals(uint32_t i, uint32_t j, Interval* intervals) const {
  const Slab& slab = slabs_[static_cast<size_t>(j) * width_ + i];
  if (!(slab.top >= slab.bottom)) return 0;
  int count = 0;
  intervals[0] = {slab.top, slab.bottom, kFrontSlot, kBackSlot};
  const int64_t base = gap_layers_ == 0 ? -1 : GapBase(i, j);
  if (base < 0) return 1;
  const Slab* gaps = gaps_.data() + base;
  for (uint32_t g = 0; g < gap_layers_ && gaps[g].top > gaps[g].bottom; ++g) {
    // Gap g splits the last interval: its upper boundary ends it, its lower one starts the next.
    const int slot = 2 + 2 * static_cast<int>(g);
    intervals[count].bottom = gaps[g].top;
    intervals[count].bottom_slot = slot;
    ++count;
    intervals[count] = {gaps[g].bottom, slab.bottom, slot + 1, kBackSlot};
  }
  return count + 1;
}

BodyMapCollider::Interval BodyMapCollider::IntervalAmongGaps(uint32_t i, uint32_t j,
                                                             float z) const {
  Interval intervals[kMaxBodyMapLayers];
  const int count = TexelIntervals(i, j, intervals);
  for (int k = 0; k < count; ++k) {
    if (z <= intervals[k].top && z >= intervals[k].bottom) return intervals[k];
  }
  const Slab& slab = slabs_[static_cast<size_t>(j) * width_ + i];
  return {slab.top, slab.bottom, kFrontSlot, kBackSlot};
}

Float3 BodyMapCollider::SlotNormal(uint32_t i, uint32_t j, int slot) const {
  if (slot < 2) return TexelNormal(i, j, slot == kBackSlot);
  const uint16_t* q = SlotCode(j * width_ + i, slot);
  return DecodeOct16(q[0], q[1]);
}

const uint16_t* BodyMapCollider::SlotCode(uint32_t texel, int slot) const {
  if (slot < 2) {
    const TexelNormals& n = normals_[texel];
    return slot == kBackSlot ? n.back : n.front;
  }
  const TexelNormals& n = gap_normals_[static_cast<size_t>(GapBaseAt(texel)) + (slot - 2) / 2];
  return slot % 2 == 1 ? n.back : n.front;
}

}  // namespace drape

#pragma once
// Paper A's image-space collider at run time: the front/back depth and normal maps of one posed
// body (drape/formats/body_map_data.h) as a per-texel slab along the view axis, tested discretely,
// continuously along each particle's motion, and in batches with the response. How it works:
// docs/ALGORITHMS.md §7; figures: docs/PERFORMANCE.md.
//
//   BodyMapCollider maps;
//   maps.Build(asset.body_maps[0]);                                   // once: allocates
//   maps.CollideBatch(previous, positions, velocities, flags, params); // per step
//
// Points, motions, contacts and velocities are in the asset frame. The maps live in the pose's
// view frame (x', y', z'), the cyclic permutation of the asset axes that puts the view axis in z'
// (BodyMapViewAxis; z' = z unless the bake chose x or y): texel (i, j) covers x' in
// [origin_x + i s, + s), y' in [origin_y + j s, + s) (s = texel size). A point is inside when
// both maps are valid at its texel and its z' lies between the back and front surfaces
// (boundaries included) and in none of the texel's air gaps (poses with layers > 1). Points
// outside the stored rectangle are outside.

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "drape/formats/body_map_data.h"
#include "drape/formats/status.h"
#include "drape/formats/types.h"
#include "drape/runtime/collision_types.h"
#include "drape/runtime/instruction_set.h"
#include "drape/runtime/math.h"

namespace drape {

namespace detail {
struct BodyMapWalk;
}  // namespace detail

// How depth between texel centres is reconstructed.
//  kNearest: constant over each texel (paper A); the segment test is exact per texel.
//  kBilinear: bilinear inside 2x2 blocks whose corners are valid and spread less than 3 texels,
//    nearest elsewhere; over 10x less depth error on smooth bodies, about 3.5x the query time.
enum class DepthSampling : uint8_t { kNearest = 0, kBilinear = 1 };

// What Build found in the maps (texel counts over the stored rectangle).
struct BodyMapStats {
  uint32_t valid_texels = 0;      // both maps valid and top >= bottom
  uint32_t one_sided_texels = 0;  // exactly one map valid (silhouette disagreement): background
  uint32_t inverted_texels = 0;   // front surface below the back surface: background
  uint32_t bilinear_blocks = 0;   // 2x2 blocks eligible for bilinear depth (kBilinear only)
  uint32_t gap_texels = 0;        // valid texels with at least one air gap (layers > 1)
};

// One pose's collider. Immutable after Build; queries are const, allocation-free and thread-safe.
// Memory per texel of the pose's rectangle: 17 bytes (slab, oct16 normals and the distance to the
// silhouette), + 1 with kBilinear, + 8 bytes per 8x8 block; with gap layers, 2
// bits per texel and 16 bytes per gap layer of each texel that has a gap. memory_bytes() reports
// the exact figure.
class BodyMapCollider {
 public:
  // Validates the untrusted pose and decodes it (allocates). A row-span pose is expanded into its
  // dense rectangle first, so both layouts of one bake answer alike. Any bad size, float, encoding,
  // array length, span table or gap is kInvalidArgument naming the pose and the reason; on error
  // the collider is empty (every point outside).
  Status Build(const BodyMapPose& pose, DepthSampling sampling = DepthSampling::kNearest);

  // Discrete test at one point.
  bool IsInside(Float3 p) const { return IsInsideView(ToBodyMapView(view_axis_, p)); }

  // Continuous test of the motion p0 -> p1 (a point query is p0 == p1), no response. The first
  // entry wins: through the front or back surface, or a texel's side wall
  // (kCollisionSideWall); t is its parameter, point is on the surface or wall. A motion that
  // starts inside and never leaves is pushed out to its nearest exit (t = 0,
  // kCollisionStartedInside): along the view axis to the nearer surface, or, when that is more
  // than a texel away, beside a silhouette through a neighbouring texel's side if nearer (also
  // kCollisionSideWall; the normal is the push's direction). depth: p1's penetration, the
  // distance to that exit. Non-finite input: no contact, kCollisionInvalidInput.
  ContactQuery Query(Float3 p0, Float3 p1) const;

  // Query and the response (collision_types.h) for every particle moving previous[i] ->
  // positions[i], in place on positions[i] and velocities[i]; flags[i] is always written. A
  // non-finite input is flagged kCollisionInvalidInput and left untouched. Spans of one size,
  // params finite. Bitwise identical at any thread count. With view axis z also bitwise Query +
  // ApplyResponse per particle; with x or y the response's sums run in view-frame order, which
  // may differ from that in the last bit.
  Status CollideBatch(std::span<const Float3> previous, std::span<Float3> positions,
                      std::span<Float3> velocities, std::span<uint8_t> flags,
                      const ResponseParams& params, uint32_t* contact_count = nullptr) const;

  // Discrete batch: inside[i] = IsInside(points[i]) ? 1 : 0. Sizes must match.
  Status InsideBatch(std::span<const Float3> points, std::span<uint8_t> inside) const;

  // The widest instruction set CollideBatch may use (kAvx2 by default; narrowed to the CPU's).
  // Every set gives the same bits. Kept across Build and sequence blending.
  void LimitInstructionSet(InstructionSet widest) { instruction_set_limit_ = widest; }
  InstructionSet instruction_set() const;  // the set CollideBatch uses

  bool empty() const { return width_ == 0; }
  uint32_t width() const { return width_; }         // texels
  uint32_t height() const { return height_; }       // texels
  float texel_size() const { return texel_size_; }  // metres
  float origin_x() const { return origin_x_; }      // metres, view frame (x')
  float origin_y() const { return origin_y_; }      // metres, view frame (y')
  BodyMapViewAxis view_axis() const { return view_axis_; }
  DepthSampling sampling() const { return sampling_; }
  uint32_t layers() const { return gap_layers_ + 1; }  // the slab and its gap layers
  int32_t clip() const { return clip_; }
  float time() const { return time_; }
  // Asset-frame box of the valid texels; every inside point lies in it. Empty map: min > max.
  Float3 bounds_min() const { return FromBodyMapView(view_axis_, bounds_min_); }
  Float3 bounds_max() const { return FromBodyMapView(view_axis_, bounds_max_); }
  const BodyMapStats& stats() const { return stats_; }
  size_t memory_bytes() const;

 private:
  friend class BodyMapSequence;
  friend class BodyMapRenderer;
  friend struct detail::BodyMapWalk;
  friend struct BodyMapColliderAccess;  // tests and tools: body_map/body_map_collider_access.h
  struct Decoder;                       // body_map/body_map_decode.cpp

  // IsInside and Query in the view frame.
  bool IsInsideView(Float3 p) const {
    if (sampling_ != DepthSampling::kNearest) return IsInsideBilinear(p);
    const float u = (p.x - origin_x_) * inv_texel_size_;
    const float v = (p.y - origin_y_) * inv_texel_size_;
    if (!(u >= 0.f && v >= 0.f && u < width_f_ && v < height_f_)) return false;  // also NaN
    const uint32_t i = static_cast<uint32_t>(u), j = static_cast<uint32_t>(v);
    const Slab& s = slabs_[static_cast<size_t>(j) * width_ + i];
    const bool in_slab =
        (p.z <= s.top) & (p.z >= s.bottom);  // no branch: a coin toss near a surface
    return gap_layers_ == 0 ? in_slab : in_slab && !InGap(GapBase(i, j), p.z);
  }
  ContactQuery QueryView(Float3 p0, Float3 p1) const;

  struct Slab {    // 8 bytes
    float top;     // z of the front surface; -inf on background
    float bottom;  // z of the back surface; +inf on background
  };
  struct TexelNormals {  // 8 bytes
    uint16_t front[2];   // oct16
    uint16_t back[2];
  };
  struct BlockBounds {  // 8 bytes: one 8x8 block of texels, widened by one texel on every side
    float max_top;      // padded up; -inf when no valid texel
    float min_bottom;   // padded down; +inf when no valid texel
  };
  // The z interval of a texel's inside set that holds a point and the surfaces bounding it:
  // slot 0/1 = the slab's front/back surface, 2 + 2g / 3 + 2g = gap g's upper/lower boundary.
  struct Interval {  // 16 bytes
    float top, bottom;
    int top_slot, bottom_slot;
  };
  static constexpr int kFrontSlot = 0, kBackSlot = 1;
  // Gaps are stored compactly: one bit per texel in row-major order, per 32-bit word the gap
  // texels before it, and gap_layers_ entries per gap texel. GapBaseAt: the index of row-major
  // texel k's first gap, or -1.
  int64_t GapBaseAt(uint32_t texel) const {
    const uint32_t word = gap_texel_bits_[texel >> 5];
    const uint32_t bit = 1u << (texel & 31u);
    if (!(word & bit)) return -1;
    return (static_cast<int64_t>(gap_word_first_[texel >> 5]) + std::popcount(word & (bit - 1u))) *
           gap_layers_;
  }
  int64_t GapBase(uint32_t i, uint32_t j) const { return GapBaseAt(j * width_ + i); }
  bool TexelHasGaps(size_t texel) const {
    return gap_layers_ != 0 && ((gap_texel_bits_[texel >> 5] >> (texel & 31u)) & 1u) != 0;
  }
  bool InGap(int64_t base, float z) const {
    if (base < 0) return false;
    const Slab* g = gaps_.data() + base;
    bool in = false;
    for (uint32_t k = 0; k < gap_layers_; ++k) in |= (z < g[k].top) & (z > g[k].bottom);
    return in;
  }
  int TexelIntervals(uint32_t i, uint32_t j, Interval* intervals) const;  // from the top
  // The interval holding z at texel (i, j); the slab itself when none does.
  Interval IntervalAt(uint32_t i, uint32_t j, float z) const {
    if (gap_layers_ == 0) {
      const Slab& s = slabs_[static_cast<size_t>(j) * width_ + i];
      return {s.top, s.bottom, kFrontSlot, kBackSlot};
    }
    return IntervalAmongGaps(i, j, z);
  }
  Interval IntervalAmongGaps(uint32_t i, uint32_t j, float z) const;
  Float3 SlotNormal(uint32_t i, uint32_t j, int slot) const;
  const uint16_t* SlotCode(uint32_t texel, int slot) const;  // the oct16 code of a slot
  Float3 TexelNormal(uint32_t i, uint32_t j, bool back) const;
  // One texel's gaps while they are decoded (absent gaps: top = -inf, bottom = +inf).
  struct GapTexel {
    uint32_t i, j;
    Slab gaps[kMaxBodyMapLayers - 1];
    TexelNormals normals[kMaxBodyMapLayers - 1];
  };
  void PackGaps(std::vector<GapTexel>* texels);  // compact storage, sorts *texels

  static constexpr uint32_t kBlockShift = 3;  // 8x8 texels per min/max block
  static constexpr uint32_t kBlockTexels = 1u << kBlockShift;

  // A motion's ends in texel units (the expressions the walk and IsInside use).
  struct TexelCoords {
    float u0, v0, u1, v1;
  };
  TexelCoords ToTexels(Float3 p0, Float3 p1) const {
    return {(p0.x - origin_x_) * inv_texel_size_, (p0.y - origin_y_) * inv_texel_size_,
            (p1.x - origin_x_) * inv_texel_size_, (p1.y - origin_y_) * inv_texel_size_};
  }
  bool ClearlyFree(Float3 p0, Float3 p1, const TexelCoords& t) const;  // quick path: air
  static constexpr int kFreeTestMaxTexels = 9;  // texels (or blocks) ClearlyFree reads at most
  // A motion clipped to the clip box: the walked segment q0 -> q1 and its parameters on p0 -> p1.
  struct ClippedMotion {
    Float3 q0, q1;
    double t_start, t_end;
    bool start_on_z_face;  // entered through the box's top or bottom face (t_start > 0)
  };
  bool ClipMotion(Float3 p0, Float3 p1, ClippedMotion* out) const;  // false: misses the box
  ContactQuery QueryWalk(Float3 p0, Float3 p1) const;               // Query without its quick paths
  void WalkInto(Float3 p0, Float3 p1, ContactQuery* out) const;
  bool QuerySingleTexel(Float3 p0, Float3 p1, const TexelCoords& t, ContactQuery* result) const;
  // A point inside more than a texel deep along z: its exit through a texel's side within this
  // many texels, when nearer (body_map_query.cpp). 4 cost 3.5x the maps' time per particle on
  // the mannequin's motion sets (docs/ALGORITHMS.md §7.4).
  static constexpr int kSideExitTexels = 1;
  bool NearerSideExit(Float3 p, float* depth, Float3* exit) const;
  void PlaceOnSideExit(Float3 p, Float3 exit, ContactQuery* result) const;
  bool IsInsideBilinear(Float3 p) const;
  void InsideRange(const Float3* points, uint8_t* inside, size_t count) const;  // kNearest
  uint8_t CollideOne(Float3 from, Float3* position, Float3* velocity,
                     const ResponseParams& params) const;
  uint32_t CollideRange(const Float3* previous, Float3* positions, Float3* velocities,
                        uint8_t* flags, size_t count, const ResponseParams& params) const;
  uint32_t CollideRangeInViewFrame(const Float3* previous, Float3* positions, Float3* velocities,
                                   uint8_t* flags, size_t count,
                                   const ResponseParams& params) const;

  // The lanes (body_map/lanes/), written once over a lane pack and instantiated per instruction
  // set. CollideShortLanes answers the motions within a texel or across one edge, CollideWalkLanes
  // walks longer ones in step; both return the lanes they answered, bit for bit as CollideOne.
  template <class Lanes>
  uint32_t CollideShortLanes(const Float3* previous, Float3* positions, Float3* velocities,
                             uint8_t* flags, const ResponseParams& params,
                             uint32_t* long_motions) const;
  template <class Lanes>
  uint32_t CollideWalkLanes(const uint32_t* index, uint32_t lanes, const Float3* previous,
                            Float3* positions, Float3* velocities, uint8_t* flags,
                            const ResponseParams& params) const;
  template <class Lanes>
  struct GapLanes;
  template <class Lanes>
  void GatherGapLanes(typename Lanes::I texel, uint32_t with_gaps, GapLanes<Lanes>* out) const;
  template <class Lanes>
  typename Lanes::I NormalCodes(const size_t* texel, typename Lanes::F use_back) const;
  template <class Lanes>
  typename Lanes::I GapSurfaceCodes(const size_t* texel, typename Lanes::I slot,
                                    typename Lanes::I code) const;
  // A lane still walking after this many texels goes one by one (through air, where the
  // one-by-one walk skips 8x8 blocks).
  static constexpr int kMaxLaneWalkTexels = 32;
  // CollideRange's lanes for one instruction set.
  struct LaneKernels {
    uint32_t width;  // particles per call
    uint32_t (BodyMapCollider::*short_motions)(const Float3*, Float3*, Float3*, uint8_t*,
                                               const ResponseParams&, uint32_t*) const;
    uint32_t (BodyMapCollider::*walks)(const uint32_t*, uint32_t, const Float3*, Float3*, Float3*,
                                       uint8_t*, const ResponseParams&) const;
  };
  static const LaneKernels& ScalarLaneKernels();  // lanes/lanes_baseline.cpp
  static const LaneKernels& Sse2LaneKernels();    // lanes/lanes_baseline.cpp
  static const LaneKernels& Avx2LaneKernels();    // lanes/lanes_avx2.cpp

  // Bilinear depth: top/bottom at texel coordinates (u, v) in half-texel cell (ci, cj).
  void SampleSlab(int ci, int cj, float u, float v, float* top, float* bottom) const;
  bool BilinearBlock(int i0, int j0) const;  // block with texel (i0, j0) as its lower corner
  Float3 SampleNormal(int ci, int cj, float u, float v, bool back) const;
  // Recomputes bounds, the clip box, the valid count, bilinear eligibility, the min/max blocks
  // and the gap flags from slabs_ (Build and sequence blending). row_spans (optional, 2 per row:
  // the renderer's): every texel of row j outside [row_spans[2j], row_spans[2j + 1]) is
  // background, so the passes skip it.
  void Finish(std::span<const uint32_t> row_spans = {});
  void FinishBounds(std::span<const uint32_t> row_spans);
  void FinishBilinearBlocks();
  void FinishMinMaxBlocks(std::span<const uint32_t> row_spans);
  void FinishAirReach(std::span<const uint32_t> row_spans);
  void CountGapsBeforeWords();  // gap_word_first_ from gap_texel_bits_
  void Clear();

  uint32_t width_ = 0, height_ = 0;
  float width_f_ = 0.f, height_f_ = 0.f;
  float origin_x_ = 0.f, origin_y_ = 0.f;
  float texel_size_ = 0.f, inv_texel_size_ = 0.f;  // metres, 1/metres
  DepthSampling sampling_ = DepthSampling::kNearest;
  BodyMapViewAxis view_axis_ = BodyMapViewAxis::kZ;
  InstructionSet instruction_set_limit_ = InstructionSet::kAvx2;  // kept by Clear
  int32_t clip_ = -1;
  float time_ = 0.f;
  Float3 bounds_min_{1.f, 1.f, 1.f}, bounds_max_{-1.f, -1.f, -1.f};
  double clip_lo_[3] = {0.0, 0.0, 0.0}, clip_hi_[3] = {-1.0, -1.0, -1.0};  // Liang-Barsky box
  float clip_lo_float_[2] = {0.f, 0.f}, clip_hi_float_[2] = {-1.f, -1.f};  // its x, y in float
  uint32_t blocks_w_ = 0, blocks_h_ = 0;
  BodyMapStats stats_;
  std::vector<Slab> slabs_;                // width*height, row-major
  std::vector<TexelNormals> normals_;      // width*height
  std::vector<uint8_t> bilinear_ok_;       // width*height (kBilinear only)
  std::vector<BlockBounds> blocks_;        // blocks_w_ * blocks_h_
  std::vector<uint8_t> air_reach_;         // width*height: texels to air (background or gaps), <= 2
  uint32_t gap_layers_ = 0;                // BodyMapPose::layers - 1
  std::vector<uint32_t> gap_texel_bits_;   // one bit per texel: has gaps
  std::vector<uint32_t> gap_word_first_;   // per word of it, the gap texels before it
  std::vector<Slab> gaps_;                 // gap_layers_ per gap texel
  std::vector<TexelNormals> gap_normals_;  // same index: front = upper, back = lower boundary
};

}  // namespace drape

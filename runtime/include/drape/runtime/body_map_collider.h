#pragma once
// Paper A's image-space body collider at run time: the front/back depth and normal maps of one
// posed body (drape/formats/body_map_data.h), turned into a per-texel "slab" of asset-frame z
// values, with a discrete inside test, a continuous segment test (2D texel walk with a per-texel
// slab solve, notes/algorithms.md §5.1) and a batch call that applies paper A's response (eq. 5).
//
// Conventions (see body_map_data.h): the view axis is z; texel (i, j) covers
// x in [origin_x + i*s, +s) and y in [origin_y + j*s, +s) (s = texel size). In texel units a
// point has u = (x - origin_x) / s, v = (y - origin_y) / s and lies in texel (floor u, floor v).
// The point is inside at that texel iff both maps are valid there and
//   front_z - D_front >= z >= (front_z - depth_range) + D_back,
// i.e. bottom <= z <= top with top/bottom the asset-frame z of the front/back surfaces, and z is
// in none of the texel's air gaps (poses with layers > 1: lower < z < upper for a gap's lower and
// upper boundary; the boundaries themselves are inside). Points outside the stored rectangle are
// outside.

#include <array>
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
#include "drape/runtime/math.h"

namespace drape {

// ---------------------------------------------------------------------------------------------
// Octahedral normal encoding (Cigolle et al. 2014, "A Survey of Efficient Representations for
// Independent Unit Vectors"), 2 x uint16 per normal. This is the encoding of
// NormalEncoding::kOct16; the bake uses these two functions so both sides agree bit for bit.
// Mapping: n is projected onto the octahedron |x|+|y|+|z| = 1; the lower hemisphere (z < 0) is
// folded over the diagonals; the resulting (a, b) in [-1, 1]^2 is stored as
// round((a * 0.5 + 0.5) * 65535). Decoding uses a = q * (2 / 65535) - 1. Round-trip error is below
// 0.004 degrees (measured in the tests). A zero or non-finite input encodes +z.

// +1 for x >= 0 (also for -0), -1 otherwise: the octahedral fold needs a sign that is never 0.
inline float OctSignNotZero(float x) { return x >= 0.f ? 1.f : -1.f; }

inline std::array<uint16_t, 2> EncodeOct16(Float3 n) {
  const float l1 = std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z);
  if (!(l1 > 1e-30f) || !std::isfinite(l1)) return {32768, 32768};  // (0, 0) in [-1,1]^2: +z
  float a = n.x / l1;
  float b = n.y / l1;
  if (n.z < 0.f) {
    const float folded_a = (1.f - std::fabs(b)) * OctSignNotZero(a);
    const float folded_b = (1.f - std::fabs(a)) * OctSignNotZero(b);
    a = folded_a;
    b = folded_b;
  }
  const auto quantise = [](float c) {
    const float unit = std::fmin(std::fmax(c * 0.5f + 0.5f, 0.f), 1.f);
    return static_cast<uint16_t>(std::lround(unit * 65535.f));
  };
  return {quantise(a), quantise(b)};
}

inline Float3 DecodeOct16(uint16_t qa, uint16_t qb) {
  Float3 n;
  constexpr float kScale = 2.f / 65535.f;  // a multiply, not a divide: on the contact path
  n.x = static_cast<float>(qa) * kScale - 1.f;
  n.y = static_cast<float>(qb) * kScale - 1.f;
  n.z = 1.f - std::fabs(n.x) - std::fabs(n.y);
  if (n.z < 0.f) {
    const float unfolded_x = (1.f - std::fabs(n.y)) * OctSignNotZero(n.x);
    const float unfolded_y = (1.f - std::fabs(n.x)) * OctSignNotZero(n.y);
    n.x = unfolded_x;
    n.y = unfolded_y;
  }
  return NormalizeOr(n, Float3{0.f, 0.f, 1.f});
}

// Paper A's colour encoding (NormalEncoding::kRgb8): n = c / 255 * 2 - 1, normalised.
inline Float3 DecodeRgb8(uint8_t r, uint8_t g, uint8_t b) {
  const Float3 n{static_cast<float>(r) / 255.f * 2.f - 1.f,
                 static_cast<float>(g) / 255.f * 2.f - 1.f,
                 static_cast<float>(b) / 255.f * 2.f - 1.f};
  return NormalizeOr(n, Float3{0.f, 0.f, 1.f});
}

// ---------------------------------------------------------------------------------------------

// How the depth between texel centres is reconstructed.
//  kNearest: the slab is constant over each texel (paper A). The segment test is exact: z is
//    linear along the segment, so each texel is one linear solve.
//  kBilinear: inside every 2x2 block of texel centres that are all valid and whose front and back
//    depths each spread less than 3 texel sizes, top and bottom are bilinear in (u, v); elsewhere
//    nearest (notes/algorithms.md §5.1 step 4). Along a segment a bilinear surface is quadratic
//    in t, and the segment test solves it exactly (in double) on a half-texel grid, so every
//    visited cell is either one bilinear patch or one nearest texel. About 2x the cells of
//    kNearest; the continuous test near a surface costs about 3.5x (the quadratics run in
//    every half-texel the segment does not clearly clear), see body_map_query_bench.cpp.
//    Depth error on a sphere of 0.3 m at 1/128 m texels: over 10x smaller than nearest (tested).
enum class DepthSampling : uint8_t { kNearest = 0, kBilinear = 1 };

// What Build found in the maps (texel counts over the stored rectangle).
struct BodyMapStats {
  uint32_t valid_texels = 0;      // both maps valid and top >= bottom
  uint32_t one_sided_texels = 0;  // exactly one map valid (silhouette disagreement): background
  uint32_t inverted_texels = 0;   // both valid but front surface below back surface: background
  uint32_t bilinear_blocks = 0;   // 2x2 blocks eligible for bilinear depth (kBilinear only)
  uint32_t gap_texels = 0;        // valid texels with at least one air gap (layers > 1)
};

class BodyMapSequence;

// One pose's collider. Immutable after Build (or after BodyMapSequence fills it). Queries are
// const, allocation-free and thread-safe.
//
// Memory (per texel of the pose's rectangle, whichever layout the file stored): 8 bytes of slab
// (top, bottom z as float) + 8 bytes of normals (front and back, re-encoded as oct16 whatever the
// input encoding: float32 input loses < 0.004 degrees) + 1 byte of bilinear eligibility in
// kBilinear mode, plus 8 bytes per 8x8 block for the min/max (Hi-Z) level. 1024 x 1024: 16.1 MiB
// (17.1 MiB bilinear). A pose with gap layers adds two bits per texel (which texels have gaps,
// and a 32-bit count per 32 of them) and, per texel that has a gap, 16 bytes per gap layer (the
// gaps' upper and lower z, their normals). memory_bytes() reports the exact figure.
//
// Air gaps (BodyMapPose::layers > 1): a texel's inside set is its slab minus its gaps, i.e. up to
// `layers` disjoint z intervals. Every query honours them: an entry into the body below a gap is
// a front entry with the normal of the gap's lower boundary, one from below into the body above
// it a back entry with the normal of the gap's upper boundary; depth and the started-inside
// push-out use the interval that holds the point. Texels with gaps are answered by the general
// walk (no single-texel quick path) and take no part in bilinear blocks (nearest there).
class BodyMapCollider {
 public:
  // Validates the pose and decodes it into the internal layout (allocates). A row-span pose is
  // first expanded into its dense rectangle (background outside the spans), so both layouts of
  // one bake give identical answers. On error the collider is left empty (every point outside).
  // Rejected: zero/huge width or height, texel size or depth range not finite and > 0,
  // non-finite origin or front_z, an unknown encoding or layout, a span table that
  // CheckBodyMapLayout refuses, an array of the chosen encoding whose length is not the stored
  // texel count (x3 / x2 for normals), a filled array of an encoding that was not chosen, a NaN
  // or negative depth, a non-finite float normal.
  Status Build(const BodyMapPose& pose, DepthSampling sampling = DepthSampling::kNearest);

  // Discrete test at one point (no allocation; about 3 ns per particle in cloth order, see
  // tests/bench/body_map_query_bench.cpp).
  bool IsInside(Float3 p) const {
    if (sampling_ != DepthSampling::kNearest) return IsInsideBilinear(p);
    const float u = (p.x - origin_x_) * inv_texel_size_;
    const float v = (p.y - origin_y_) * inv_texel_size_;
    if (!(u >= 0.f && v >= 0.f && u < width_f_ && v < height_f_)) return false;  // also NaN
    const uint32_t i = static_cast<uint32_t>(u), j = static_cast<uint32_t>(v);
    const Slab& s = slabs_[static_cast<size_t>(j) * width_ + i];
    const bool in_slab = (p.z <= s.top) & (p.z >= s.bottom);  // no branch: near a surface it is
                                                              // a coin toss
    return gap_layers_ == 0 ? in_slab : in_slab && !InGap(GapBase(i, j), p.z);
  }

  // Continuous test of the motion p0 -> p1 (a point query is p0 == p1).
  //  - The segment is clipped (Liang-Barsky, in double) to the box of the valid texels, then the
  //    texels it crosses are walked in order (Amanatides-Woo in 2D; the cell sequence runs from
  //    the texel of the clipped start to the texel of the clipped end, so the last texel is
  //    exactly the one IsInside(p1) reads). Long walks skip 8x8 blocks that the segment passes
  //    entirely in front of, behind, or that are empty (min/max level).
  //  - The first entry wins: through the front surface (normal from the front map), the back
  //    surface (back map), or a texel side wall (kCollisionSideWall; the entered texel's normal
  //    from the map whose surface is nearer in z). t is the entry parameter in [0, 1]; point is
  //    on the sampled surface (front/back) or on the texel wall.
  //  - Started inside (p0 inside): entries after the segment has left the body still count. If
  //    the segment never leaves and p1 is inside, p1 is pushed out along +z or -z to the nearer
  //    surface with that map's normal: t = 0, kCollisionStartedInside, point = that surface
  //    point above/below p1. If it leaves and does not re-enter: no contact.
  //  - depth = penetration of p1 along z (min of its distances to the two surfaces), 0 outside.
  //  - Non-finite input: contact = false, flags = kCollisionInvalidInput.
  ContactQuery Query(Float3 p0, Float3 p1) const;

  // Batch collision of particles moving previous[i] -> positions[i]: on contact applies
  // ApplyResponse (paper A eq. 5; the velocity changes only when V.N < 0) in place to
  // positions[i], velocities[i]. flags[i] is always written (CollisionFlags). A particle with a
  // non-finite previous/current position or velocity gets kCollisionInvalidInput and is left
  // untouched. OpenMP over particles, no allocation, bitwise identical at any thread count and
  // to Query + ApplyResponse per particle (with kNearest, four particles at a time in SSE2
  // lanes, or eight in AVX2 where the CPU has it: motions within a texel or across one edge,
  // then the others walked texel by texel in step for up to 32 texels; the rest one by one).
  // All four spans must have the same size; params must be finite. contact_count (optional)
  // receives the number of particles with kCollisionContact.
  Status CollideBatch(std::span<const Float3> previous, std::span<Float3> positions,
                      std::span<Float3> velocities, std::span<uint8_t> flags,
                      const ResponseParams& params, uint32_t* contact_count = nullptr) const;

  // With kNearest, CollideBatch takes particles eight at a time in AVX2 when the CPU has it,
  // else four in SSE2: the same bits either way (21-35 % less time on the speed-vs-error mix at
  // N = 256 and 512 on the humans, run out-sve17 in docs/PERFORMANCE.md). AllowAvx2(false) keeps
  // it to SSE2 (tests, measurement); the choice survives Build and sequence blending.
  void AllowAvx2(bool allow) { allow_avx2_ = allow; }
  bool uses_avx2() const;  // allowed, and the CPU (and OS) support it
  // Where the CPU also has AVX-512 (F, VL, DQ and BW), the eight lanes are the same code compiled
  // for it: still 256-bit vectors, no 512-bit ones, but 32 vector registers instead of 16, where
  // the walking lanes' loop spilled: a median 8 % less time on the speed-vs-error mix (runs
  // out-sve40 to 44 in docs/PERFORMANCE.md). The same bits again.
  // AllowAvx512(false) keeps the eight lanes to AVX2; AllowAvx2(false) keeps all to SSE2.
  void AllowAvx512(bool allow) { allow_avx512_ = allow; }
  bool uses_avx512() const;  // uses_avx2(), allowed, and the CPU (and OS) support AVX-512

  // Discrete batch: inside[i] = IsInside(points[i]) ? 1 : 0. Sizes must match.
  Status InsideBatch(std::span<const Float3> points, std::span<uint8_t> inside) const;

  bool empty() const { return width_ == 0; }
  uint32_t width() const { return width_; }         // texels
  uint32_t height() const { return height_; }       // texels
  float texel_size() const { return texel_size_; }  // metres
  float origin_x() const { return origin_x_; }
  float origin_y() const { return origin_y_; }
  DepthSampling sampling() const { return sampling_; }
  uint32_t layers() const { return gap_layers_ + 1; }  // the slab and its gap layers
  int32_t clip() const { return clip_; }
  float time() const { return time_; }
  // Asset-frame box of the valid texels (x, y: texel edges; z: lowest back / highest front
  // surface). Every inside point lies in it. Empty map: min > max.
  Float3 bounds_min() const { return bounds_min_; }
  Float3 bounds_max() const { return bounds_max_; }
  const BodyMapStats& stats() const { return stats_; }
  size_t memory_bytes() const;

  // Per-texel access (tests, tools): false for background; top/bottom are asset-frame z. With
  // gap layers a top can be one ulp above the maps' value (its lowest bit flags the texels with
  // gaps for the batch; see Finish).
  bool TexelSlab(uint32_t i, uint32_t j, float* top, float* bottom) const;
  Float3 TexelNormal(uint32_t i, uint32_t j, bool back) const;
  // The air gaps of texel (i, j), from the front: writes upper[g], lower[g] (asset-frame z) for
  // each and returns their number (0 for background and gap-free texels; arrays of layers() - 1).
  uint32_t TexelGaps(uint32_t i, uint32_t j, float* upper, float* lower) const;

 private:
  friend class BodyMapSequence;
  friend struct BodyMapWalk;
  friend struct BodyMapColliderTestAccess;  // tests: QueryWalk against Query's quick paths

  struct Slab {
    float top;     // z of the front surface; -inf on background (see Finish)
    float bottom;  // z of the back surface; +inf on background
  };
  struct TexelNormals {
    uint16_t front[2];  // oct16
    uint16_t back[2];
  };
  struct BlockBounds {  // one 8x8 block of texels, widened by one texel on every side
    float max_top;      // padded up; -inf when no valid texel
    float min_bottom;   // padded down; +inf when no valid texel
  };
  // The z interval of a texel's inside set that holds a point, with the surfaces bounding it:
  // slot 0/1 = the slab's front/back surface, 2 + 2g / 3 + 2g = gap g's upper/lower boundary.
  struct Interval {
    float top, bottom;
    int top_slot, bottom_slot;
  };
  static constexpr int kFrontSlot = 0, kBackSlot = 1;
  // Gaps are stored compactly (on a character a few percent of the texels have one): one bit per
  // texel in row-major order (bit k % 32 of gap_texel_bits_[k / 32]) and, per 32-bit word, the
  // number of gap texels in the words before it; the n-th gap texel in row-major order holds gap
  // g at gaps_[n * gap_layers_ + g] (upper in `top`, lower in `bottom`; an absent gap holds
  // top = -inf, bottom = +inf, which no z lies strictly between). GapBaseAt: the index of
  // row-major texel k's first gap, or -1 for none (shifts and a popcount: the lanes call it per
  // step on texels with gaps, where a division by the width cost more than the rest).
  int64_t GapBaseAt(uint32_t texel) const {
    const uint32_t word = gap_texel_bits_[texel >> 5];
    const uint32_t bit = 1u << (texel & 31u);
    if (!(word & bit)) return -1;
    return (static_cast<int64_t>(gap_word_first_[texel >> 5]) + std::popcount(word & (bit - 1u))) *
           gap_layers_;
  }
  int64_t GapBase(uint32_t i, uint32_t j) const { return GapBaseAt(j * width_ + i); }
  bool InGap(int64_t base, float z) const {
    if (base < 0) return false;
    const Slab* g = gaps_.data() + base;
    bool in = false;
    for (uint32_t k = 0; k < gap_layers_; ++k) in |= (z < g[k].top) & (z > g[k].bottom);
    return in;
  }
  // Up to kMaxBodyMapLayers intervals of texel (i, j), from the top; returns their number (0 for
  // background).
  int TexelIntervals(uint32_t i, uint32_t j, Interval* intervals) const;
  // The interval holding z at texel (i, j); the slab itself when no interval does. Without gap
  // layers it is the slab, read inline (the walk's contact path asks for every contact).
  Interval IntervalAt(uint32_t i, uint32_t j, float z) const {
    if (gap_layers_ == 0) {
      const Slab& s = slabs_[static_cast<size_t>(j) * width_ + i];
      return {s.top, s.bottom, kFrontSlot, kBackSlot};
    }
    return IntervalAmongGaps(i, j, z);
  }
  Interval IntervalAmongGaps(uint32_t i, uint32_t j, float z) const;
  Float3 SlotNormal(uint32_t i, uint32_t j, int slot) const;
  // The oct16 code (two values) of the surface in `slot` of row-major texel `texel` (SlotNormal's).
  const uint16_t* SlotCode(uint32_t texel, int slot) const;
  // One texel's gaps while Build decodes them (absent gaps: top = -inf, bottom = +inf).
  struct GapTexel {
    uint32_t i, j;
    Slab gaps[kMaxBodyMapLayers - 1];
    TexelNormals normals[kMaxBodyMapLayers - 1];
  };
  // Stores the texels' gaps compactly, in row-major order (sorts *texels). Needs width_, height_
  // and gap_layers_; sets blocks_w_ and blocks_h_ as Finish does.
  void PackGaps(std::vector<GapTexel>* texels);

  static constexpr uint32_t kBlockShift = 3;  // 8x8 texels per min/max block
  static constexpr uint32_t kBlockTexels = 1u << kBlockShift;

  // A motion's ends in texel units, computed once for the quick paths (the same expressions the
  // walk and IsInside use).
  struct TexelCoords {
    float u0, v0, u1, v1;
  };
  TexelCoords ToTexels(Float3 p0, Float3 p1) const {
    return {(p0.x - origin_x_) * inv_texel_size_, (p0.y - origin_y_) * inv_texel_size_,
            (p1.x - origin_x_) * inv_texel_size_, (p1.y - origin_y_) * inv_texel_size_};
  }
  // The quick answer for motions through air: true when every texel (or min/max block) the
  // walk from p0 to p1 could visit holds no z of the segment, so Query has no contact and p1 is
  // outside. Conservative: false whenever unsure (ends off the grid, long motions).
  bool ClearlyFree(Float3 p0, Float3 p1, const TexelCoords& t) const;
  // A motion clipped to the clip box (Liang-Barsky in double): the walked segment q0 -> q1 and
  // its parameters on p0 -> p1. An unclipped end is the input end itself.
  struct ClippedMotion {
    Float3 q0, q1;
    double t_start, t_end;
    bool start_on_z_face;  // entered through the box's top or bottom face (t_start > 0)
  };
  // False when the motion misses the box (then it has no contact and ends outside).
  bool ClipMotion(Float3 p0, Float3 p1, ClippedMotion* out) const;
  // Query without its quick paths: clip, walk, answer. Query gives the same bits.
  ContactQuery QueryWalk(Float3 p0, Float3 p1) const;
  // QueryWalk's clip, walk and answer into *out, which holds the defaults of a miss (finite
  // input, a non-empty map).
  void WalkInto(Float3 p0, Float3 p1, ContactQuery* out) const;
  // Query for a motion that stays in one texel of the grid (kNearest): fills *result and
  // returns true, bit for bit what the general path gives; false when the general path must
  // answer (ends in different texels, off the grid, or outside the clip box in z).
  bool QuerySingleTexel(Float3 p0, Float3 p1, const TexelCoords& t, ContactQuery* result) const;
  static constexpr int kFreeTestMaxTexels = 9;  // texels (or blocks) ClearlyFree reads at most
  bool IsInsideBilinear(Float3 p) const;
  void InsideRange(const Float3* points, uint8_t* inside, size_t count) const;  // kNearest
  // CollideBatch for one particle: the flags it writes; position and velocity respond in place.
  uint8_t CollideOne(Float3 from, Float3* position, Float3* velocity,
                     const ResponseParams& params) const;
  // CollideBatch over count particles on one thread; returns the number of contacts.
  uint32_t CollideRange(const Float3* previous, Float3* positions, Float3* velocities,
                        uint8_t* flags, size_t count, const ResponseParams& params) const;
  // CollideBatch for four particles at once (SSE2, kNearest, a non-empty map), for the lanes
  // whose motion stays in one texel or crosses one texel edge, with both ends in the clip box
  // (texels with gaps included), and for those whose motion keeps one coordinate outside the
  // clip box (no contact): writes their flags, positions and velocities bit for bit as
  // CollideOne would and returns their lane mask (bit l = particle l). The other lanes keep
  // their positions and velocities (written back, the same bits) and get flags the caller must
  // replace. *long_motions receives the lanes with finite input and both ends in the clip box
  // that cross more than one texel edge.
  uint32_t CollideFourShortMotions(const Float3* previous, Float3* positions, Float3* velocities,
                                   uint8_t* flags, const ResponseParams& params,
                                   uint32_t* long_motions) const;
  // CollideFourShortMotions for eight particles in AVX2 (body_map_collider_avx2.cpp), and in AVX2
  // with AVX-512 (body_map_collider_avx512.cpp): the same answers, bit for bit. Call only when
  // lane_kernel() is kAvx2, or kAvx512.
  uint32_t CollideEightShortMotionsAvx2(const Float3* previous, Float3* positions,
                                        Float3* velocities, uint8_t* flags,
                                        const ResponseParams& params, uint32_t* long_motions) const;
  uint32_t CollideEightShortMotionsAvx512(const Float3* previous, Float3* positions,
                                          Float3* velocities, uint8_t* flags,
                                          const ResponseParams& params,
                                          uint32_t* long_motions) const;
  // Both, written once over a lane pack (runtime/src/body_map_lane_walk.inl).
  template <class Lanes>
  uint32_t CollideShortLanes(const Float3* previous, Float3* positions, Float3* velocities,
                             uint8_t* flags, const ResponseParams& params,
                             uint32_t* long_motions) const;
  // CollideBatch for particles index[l] of the arrays, l in the mask `lanes` (SSE2, kNearest, a
  // non-empty map; index holds four entries, unused lanes any valid index): each lane walks its
  // motion, clipped to the clip box (ClipMotion), texel by texel, all four in step, texels with
  // gaps included. Answers the lanes with finite input that miss the box, or whose clipped ends
  // lie on the grid and whose walk ends (an entry, or the last texel) within kMaxLaneWalkTexels
  // texels: writes their flags, positions and velocities bit for bit as CollideOne would and
  // returns their mask; the other lanes are untouched.
  uint32_t CollideFourWalks(const uint32_t* index, uint32_t lanes, const Float3* previous,
                            Float3* positions, Float3* velocities, uint8_t* flags,
                            const ResponseParams& params) const;
  // CollideFourWalks for eight lanes (index holds eight entries), in AVX2 and in AVX2 with
  // AVX-512, as the short motions: the same answers, bit for bit.
  uint32_t CollideEightWalksAvx2(const uint32_t* index, uint32_t lanes, const Float3* previous,
                                 Float3* positions, Float3* velocities, uint8_t* flags,
                                 const ResponseParams& params) const;
  uint32_t CollideEightWalksAvx512(const uint32_t* index, uint32_t lanes, const Float3* previous,
                                   Float3* positions, Float3* velocities, uint8_t* flags,
                                   const ResponseParams& params) const;
  // The lanes CollideRange takes with kNearest: four SSE2, or eight (AVX2, AVX2 with AVX-512).
  enum class LaneKernel : uint8_t { kSse2, kAvx2, kAvx512 };
  LaneKernel lane_kernel() const;
  // Both, written once over a lane pack (runtime/src/body_map_lane_walk.inl).
  template <class Lanes>
  uint32_t CollideWalkLanes(const uint32_t* index, uint32_t lanes, const Float3* previous,
                            Float3* positions, Float3* velocities, uint8_t* flags,
                            const ResponseParams& params) const;
  // The gaps of one texel per lane and what both lane paths ask of them
  // (body_map_lane_walk.inl).
  template <class Lanes>
  struct GapLanes;
  // The gaps of the lanes' row-major texels into *out: of the lanes in `with_gaps`, whose
  // texels have gaps (LanesWithGaps in body_map_lane_walk.inl); absent ones (-inf, +inf) for
  // the others. out->layers stops after the last gap layer any of them has (0 for none).
  template <class Lanes>
  void GatherGapLanes(typename Lanes::I texel, uint32_t with_gaps, GapLanes<Lanes>* out) const;
  // The lanes' oct16 codes (two values per word, the first in the low half) of the front or,
  // where use_back, the back normal at texel[lane]; then the gaps' surfaces (slot >= 2,
  // SlotCode) put in (body_map_lane_walk.inl).
  template <class Lanes>
  typename Lanes::I NormalCodes(const size_t* texel, typename Lanes::F use_back) const;
  template <class Lanes>
  typename Lanes::I GapSurfaceCodes(const size_t* texel, typename Lanes::I slot,
                                    typename Lanes::I code) const;
  // A lane still walking after this many texels is answered one by one: a walk that long goes
  // through air, which the one-by-one walk skips 8x8 blocks at a time, and lanes in step
  // wait for the longest. Tuned on the speed-vs-error query sets (docs/PERFORMANCE.md).
  static constexpr int kMaxLaneWalkTexels = 32;
  // top/bottom at texel coordinates (u, v) >= 0 inside the grid, in half-texel cell (ci, cj) =
  // (floor 2u, floor 2v): bilinear in an eligible block, else the nearest texel.
  void SampleSlab(int ci, int cj, float u, float v, float* top, float* bottom) const;
  bool BilinearBlock(int i0, int j0) const;  // block with texel (i0, j0) as its lower corner
  Float3 SampleNormal(int ci, int cj, float u, float v, bool back) const;
  // Recomputes bounds, stats.valid_texels, bilinear eligibility and the min/max blocks from
  // slabs_ (used by Build and by sequence blending). First, with gap layers, it marks the texels
  // with gaps in their slabs: the lowest mantissa bit of each valid slab's top is set exactly on
  // the texels with gaps (gap_texel_bits_), so that the lanes read it from the slab they load
  // anyway instead of a second lookup per step (GatherGapLanes). A top moves up by at most one
  // ulp to carry it: about 3e-8 m at z = 0.5 m, out of the body.
  void Finish();
  void CountGapsBeforeWords();  // gap_word_first_ from gap_texel_bits_
  void Clear();

  uint32_t width_ = 0, height_ = 0;
  float width_f_ = 0.f, height_f_ = 0.f;
  float origin_x_ = 0.f, origin_y_ = 0.f;
  float texel_size_ = 0.f, inv_texel_size_ = 0.f;  // metres, 1/metres
  DepthSampling sampling_ = DepthSampling::kNearest;
  bool allow_avx2_ = true;    // AllowAvx2; Clear keeps it
  bool allow_avx512_ = true;  // AllowAvx512; Clear keeps it
  int32_t clip_ = -1;
  float time_ = 0.f;
  Float3 bounds_min_{1.f, 1.f, 1.f}, bounds_max_{-1.f, -1.f, -1.f};
  double clip_lo_[3] = {0.0, 0.0, 0.0}, clip_hi_[3] = {-1.0, -1.0, -1.0};  // Liang-Barsky box
  float clip_lo_float_[2] = {0.f, 0.f}, clip_hi_float_[2] = {-1.f, -1.f};  // its x, y in float
  uint32_t blocks_w_ = 0, blocks_h_ = 0;
  BodyMapStats stats_;
  std::vector<Slab> slabs_;            // width*height, row-major
  std::vector<TexelNormals> normals_;  // width*height
  std::vector<uint8_t> bilinear_ok_;   // width*height (kBilinear only): block (i, j)..(i+1, j+1)
  std::vector<BlockBounds> blocks_;    // blocks_w_ * blocks_h_
  uint32_t gap_layers_ = 0;            // BodyMapPose::layers - 1
  // The gap texels, one bit per texel in row-major order (see GapBaseAt), and per word of it the
  // gap texels before that word; empty without gaps.
  std::vector<uint32_t> gap_texel_bits_;
  std::vector<uint32_t> gap_word_first_;
  std::vector<Slab> gaps_;                 // gap_layers_ per gap texel (see GapBaseAt)
  std::vector<TexelNormals> gap_normals_;  // same index: front = upper, back = lower boundary
};

// How a sequence answers times between its baked poses.
//  kNearest: the baked pose nearest in time (ties: the earlier one).
//  kBracket: the two poses bracketing the time, blended per texel into a caller-owned scratch
//    collider when they share the same grid (width, height, origin, texel size): top and bottom
//    z are interpolated linearly where both poses are valid; a texel valid in one pose only keeps
//    that pose's slab while that pose is the nearer one in time (the silhouette switches halfway);
//    normals come from the nearer pose. Air gaps are blended where both poses have them and
//    taken from the nearer pose with its slab; a texel's gaps end at the first one a blended
//    pose lacks. Different grids or layer counts, a time on or outside the baked keys, or no
//    scratch: nearest.
enum class PoseBlend : uint8_t { kNearest = 0, kBracket = 1 };

// The baked poses of one clip (or the bind pose alone).
class BodyMapSequence {
 public:
  // poses: one clip's poses, sorted by non-decreasing finite time, all with the same clip index;
  // at least one. Every pose is built with `sampling`; the first failure is returned with the
  // pose index in its message and leaves the sequence empty.
  Status Build(std::span<const BodyMapPose> poses, DepthSampling sampling = DepthSampling::kNearest,
               PoseBlend blend = PoseBlend::kNearest);

  // The collider for `time` (seconds, clamped to the baked range). With kBracket and a non-null
  // scratch the answer may be *scratch, refilled by this call: the first fill allocates, later
  // fills of the same grid size do not. O(texels) per blended call. An empty sequence returns an
  // empty collider. Not thread-safe on the same scratch.
  const BodyMapCollider& At(float time, BodyMapCollider* scratch = nullptr) const;

  size_t size() const { return poses_.size(); }
  const BodyMapCollider& pose(size_t index) const { return poses_[index]; }
  PoseBlend blend() const { return blend_; }
  size_t memory_bytes() const;
  // BodyMapCollider::AllowAvx2 on every pose (a caller's scratch keeps its own).
  void AllowAvx2(bool allow) {
    for (BodyMapCollider& pose : poses_) pose.AllowAvx2(allow);
  }
  // BodyMapCollider::AllowAvx512 on every pose, likewise.
  void AllowAvx512(bool allow) {
    for (BodyMapCollider& pose : poses_) pose.AllowAvx512(allow);
  }

 private:
  // The gaps of the blend of a and b at weight w (of b) into *out, whose slabs are already
  // blended: see PoseBlend.
  static void BlendGaps(const BodyMapCollider& a, const BodyMapCollider& b, float w,
                        BodyMapCollider* out);

  std::vector<BodyMapCollider> poses_;
  PoseBlend blend_ = PoseBlend::kNearest;
  BodyMapCollider empty_;
};

}  // namespace drape

#pragma once
// Test-only entry points of BodyMapCollider: per-texel reads, and the general walk beside the
// quick paths it must agree with.

#include <cstdint>

#include "drape/runtime/body_map_collider.h"

namespace drape {

struct BodyMapColliderAccess {
  // false for background; top and bottom are view-frame z'. With gap layers a top can be one ulp
  // above the maps' value: its lowest bit flags the texels with gaps for the lanes.
  static bool TexelSlab(const BodyMapCollider& c, uint32_t i, uint32_t j, float* top,
                        float* bottom) {
    if (i >= c.width_ || j >= c.height_) return false;
    const BodyMapCollider::Slab& s = c.slabs_[static_cast<size_t>(j) * c.width_ + i];
    if (!(s.top >= s.bottom)) return false;
    *top = s.top;
    *bottom = s.bottom;
    return true;
  }
  static Float3 TexelNormal(const BodyMapCollider& c, uint32_t i, uint32_t j, bool back) {
    return c.TexelNormal(i, j, back);
  }
  // The air gaps of texel (i, j) from the front: upper[g], lower[g] (view-frame z', arrays of
  // layers() - 1); returns their number (0 for background and gap-free texels).
  static uint32_t TexelGaps(const BodyMapCollider& c, uint32_t i, uint32_t j, float* upper,
                            float* lower) {
    if (i >= c.width_ || j >= c.height_ || c.gap_layers_ == 0) return 0;
    const int64_t base = c.GapBase(i, j);
    if (base < 0) return 0;
    const BodyMapCollider::Slab* gaps = c.gaps_.data() + base;
    uint32_t count = 0;
    for (; count < c.gap_layers_ && gaps[count].top > gaps[count].bottom; ++count) {
      upper[count] = gaps[count].top;
      lower[count] = gaps[count].bottom;
    }
    return count;
  }
  // Texels from (i, j) to the nearest texel with air: background (beyond the grid counts) or
  // gaps in its slab (Chebyshev), capped at kSideExitTexels + 1.
  static uint32_t AirReach(const BodyMapCollider& c, uint32_t i, uint32_t j) {
    return c.air_reach_[static_cast<size_t>(j) * c.width_ + i];
  }
  static constexpr int kSideExitTexels = BodyMapCollider::kSideExitTexels;
  // Query without its quick paths: clip, walk, answer. Query gives the same bits.
  static ContactQuery QueryWalk(const BodyMapCollider& c, Float3 p0, Float3 p1) {
    return c.QueryWalk(p0, p1);
  }
  // Whether each quick path answers this motion.
  static bool SingleTexelAnswers(const BodyMapCollider& c, Float3 p0, Float3 p1) {
    ContactQuery unused;
    return c.sampling() == DepthSampling::kNearest &&
           c.QuerySingleTexel(p0, p1, c.ToTexels(p0, p1), &unused);
  }
  static bool ClearlyFree(const BodyMapCollider& c, Float3 p0, Float3 p1) {
    return c.ClearlyFree(p0, p1, c.ToTexels(p0, p1));
  }

  // CollideBatch's lanes in `set`'s pack, which the CPU must run: their width, the short-motion
  // lanes alone (which lanes they answer is not visible through the batch), and the walking
  // lanes alone, on particles index[l] for l in the mask `lanes`.
  static uint32_t LaneWidth(InstructionSet set) { return Kernels(set).width; }
  static uint32_t CollideShort(const BodyMapCollider& c, InstructionSet set, const Float3* previous,
                               Float3* positions, Float3* velocities, uint8_t* flags,
                               const ResponseParams& params, uint32_t* long_motions) {
    return (c.*Kernels(set).short_motions)(previous, positions, velocities, flags, params,
                                           long_motions);
  }
  static uint32_t CollideWalks(const BodyMapCollider& c, InstructionSet set, const uint32_t* index,
                               uint32_t lanes, const Float3* previous, Float3* positions,
                               Float3* velocities, uint8_t* flags, const ResponseParams& params) {
    return (c.*Kernels(set).walks)(index, lanes, previous, positions, velocities, flags, params);
  }

 private:
  static const BodyMapCollider::LaneKernels& Kernels(InstructionSet set) {
    return set == InstructionSet::kAvx2   ? BodyMapCollider::Avx2LaneKernels()
           : set == InstructionSet::kSse2 ? BodyMapCollider::Sse2LaneKernels()
                                          : BodyMapCollider::ScalarLaneKernels();
  }
};

}  // namespace drape

#include "drape/runtime/body_map_collider.h"

#include <algorithm>
#include <bit>
#include <cfloat>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>
#include <string>
#include <type_traits>

#include "common/cpu_features.h"
#include "body_map/lanes/sse2_lanes.h"

namespace drape {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

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
constexpr uint32_t kMaxMapSide = 1u << 16;  // texels per side accepted by Build
// The set bits among the low eight of a lane mask, in a few operations: std::popcount is a
// library call where the baseline x86-64 lacks popcnt, and CollideRange counts once per group.
constexpr uint32_t CountLaneBits(uint32_t lanes) {
  lanes = lanes - ((lanes >> 1) & 0x55u);
  lanes = (lanes & 0x33u) + ((lanes >> 2) & 0x33u);
  return (lanes + (lanes >> 4)) & 0x0fu;
}
static_assert(CountLaneBits(0xffu) == 8 && CountLaneBits(0xa5u) == 4 && CountLaneBits(0) == 0);
// Bilinear depth only where the four corner depths spread less than this many texel sizes
// (notes/algorithms.md §5.1 step 4): larger spreads are silhouettes or steps, where bilinear
// would invent a slope through air.
constexpr float kBilinearSpreadTexels = 3.f;
// A walk longer than this many cells uses the 8x8 min/max level to skip blocks; shorter walks go
// cell by cell (the block bookkeeping costs more than it saves there).
constexpr int kCoarseWalkMinCells = 12;

enum EntrySide : uint8_t { kEntryFront = 0, kEntryBack = 1, kEntrySideWall = 2 };

std::string DescribePose(const BodyMapPose& pose) {
  return "body map pose (clip " + std::to_string(pose.clip) + ", t=" + std::to_string(pose.time) +
         ", " + std::to_string(pose.width) + "x" + std::to_string(pose.height) + ")";
}

// Roots of c2 s^2 + c1 s + c0 strictly inside (0, length), in double (numerically stable form).
int QuadraticRootsInside(double c2, double c1, double c0, double length, double roots[2]) {
  int count = 0;
  const auto keep = [&](double r) {
    if (r > 0.0 && r < length) roots[count++] = r;
  };
  if (c2 == 0.0) {
    if (c1 != 0.0) keep(-c0 / c1);
    return count;
  }
  const double disc = c1 * c1 - 4.0 * c2 * c0;
  if (disc < 0.0) return 0;
  const double sq = std::sqrt(disc);
  const double q = -0.5 * (c1 + (c1 >= 0.0 ? sq : -sq));
  const double r1 = q / c2;
  keep(r1);
  if (q != 0.0) {
    const double r2 = c0 / q;
    if (r2 != r1) keep(r2);
  }
  return count;
}

// A line in grid-cell units (cell (c) covers [c * size, (c + 1) * size) for the walk's size).
struct GridLine {
  float g0x, g0y, g1x, g1y;
  float inv_dx, inv_dy;  // 1 / (g1 - g0), finite (see SafeInverse)
};

// 1 / d, limited to +-1e30 so that crossing parameters (|offset| < 2^18 cells) stay finite
// (d = +0 gives 1e30, never used: an axis without steps never reads its inverse).
inline float SafeInverse(float d) { return std::min(std::max(1.f / d, -1e30f), 1e30f); }

// c ? a : b without a branch. The walk's selects depend on the data (which axis steps next,
// which half of the segment), so branches there are mispredicted about half the time; the
// compiler does not if-convert float selects on baseline x86-64.
inline float Select(bool c, float a, float b) {
  const uint32_t mask = 0u - static_cast<uint32_t>(c);
  return std::bit_cast<float>((std::bit_cast<uint32_t>(a) & mask) |
                              (std::bit_cast<uint32_t>(b) & ~mask));
}

// floor for |x| < 2^31 (texel coordinates of clipped points): truncate, then step down for
// negative non-integers. Cheaper than std::floor without SSE4.1.
inline int FloorToInt(float x) {
  const int truncated = static_cast<int>(x);
  return truncated - (static_cast<float>(truncated) > x ? 1 : 0);
}

// Amanatides-Woo walk over the cells of size 2^cell_shift (in grid units) from cell (ci, cj) to
// (ci_end, cj_end), over s in [s_begin, s_end]. The cell sequence is fixed by the two end cells
// (|di| + |dj| steps, both at once on an exact corner), the crossing parameters only order the
// steps, so the walk always ends in (ci_end, cj_end). visit(ci, cj, s_enter, s_exit) returns true
// to stop. Returns true when stopped.
template <class Visit>
[[gnu::always_inline]] inline bool WalkCells(const GridLine& line, int cell_shift, int ci, int cj,
                                             int ci_end, int cj_end, float s_begin, float s_end,
                                             Visit&& visit) {
  const int step_i = (ci_end > ci) - (ci_end < ci);
  const int step_j = (cj_end > cj) - (cj_end < cj);
  int left_i = std::abs(ci_end - ci);
  int left_j = std::abs(cj_end - cj);
  const float cell = static_cast<float>(1 << cell_shift);
  const int edge_i = step_i > 0, edge_j = step_j > 0;  // which edge of the cell is crossed
  // Crossing parameters are finite (|inverse| <= 1e30); +inf marks an axis with no step left.
  const auto cross_x = [&](int c, int left) {
    return Select(left > 0, (static_cast<float>(c + edge_i) * cell - line.g0x) * line.inv_dx, kInf);
  };
  const auto cross_y = [&](int c, int left) {
    return Select(left > 0, (static_cast<float>(c + edge_j) * cell - line.g0y) * line.inv_dy, kInf);
  };
  float next_x = cross_x(ci, left_i);
  float next_y = cross_y(cj, left_j);
  float s_enter = s_begin;
  for (;;) {
    const float next = std::min(next_x, next_y);
    const float s_exit = std::min(std::max(next, s_enter), s_end);  // s_end when next = inf
    if (visit(ci, cj, s_enter, s_exit)) return true;
    if (next == kInf) return false;
    // Both at once on an exact corner: the segment does not enter either side neighbour.
    const bool step_x = next_x == next, step_y = next_y == next;
    ci += step_i * static_cast<int>(step_x);
    left_i -= step_x;
    cj += step_j * static_cast<int>(step_y);
    left_j -= step_y;
    next_x = Select(step_x, cross_x(ci, left_i), next_x);
    next_y = Select(step_y, cross_y(cj, left_j), next_y);
    s_enter = s_exit;
  }
}

}  // namespace

// The continuous test of one clipped segment: walks the cells, solves each, records the first
// entry. Cells are texels (kNearest) or half-texels (kBilinear: every half-texel lies in exactly
// one texel and one 2x2 bilinear block).
struct BodyMapWalk {
  // Member by member (an aggregate initialiser here compiled to a slow `rep stos`).
  BodyMapWalk(const BodyMapCollider& collider, float u_begin, float v_begin, float u_end,
              float v_end, float z_begin, float z_end, bool starts_on_z_face, bool starts_inside)
      : c(collider),
        u0(u_begin),
        v0(v_begin),
        u1(u_end),
        v1(v_end),
        z0(z_begin),
        z1(z_end),
        start_on_z_face(starts_on_z_face),
        inside_prev(starts_inside) {}

  const BodyMapCollider& c;
  // The clipped segment in texel units (u, v) and asset-frame z; s in [0, 1] runs along it.
  float u0, v0, u1, v1, z0, z1;
  bool start_on_z_face;  // the clipped start lies on the box's top/bottom face (entered along z)
  bool inside_prev;      // the segment is inside at the current cell's entry point
  // First entry.
  bool hit = false;
  EntrySide hit_side = kEntrySideWall;
  float hit_s = 0.f;
  int hit_ci = 0, hit_cj = 0;  // cell of the entry (texel, or half-texel in kBilinear)
  float hit_z = 0.f;           // the surface z (front/back) or the segment's z (side wall)
  int hit_slot = 0;            // the entered surface (BodyMapCollider::Interval slots)

  // Interpolation that is exact at s = 0 and s = 1 and constant when both ends are equal (a
  // segment lying on a texel edge or on a surface stays on it); monotone up to one rounding
  // where the two halves meet.
  static float Along(float a, float b, float s) {
    const float from_a = a + (b - a) * s;
    const float from_b = b - (b - a) * (1.f - s);
    return Select(s < 0.5f, from_a, from_b);
  }
  float U(float s) const { return Along(u0, u1, s); }
  float V(float s) const { return Along(v0, v1, s); }
  float Z(float s) const { return Along(z0, z1, s); }

  bool Hit(float s, EntrySide side, int ci, int cj, float z) {
    hit = true;
    hit_s = s;
    hit_side = side;
    hit_ci = ci;
    hit_cj = cj;
    hit_z = z;
    hit_slot = side == kEntryBack ? BodyMapCollider::kBackSlot : BodyMapCollider::kFrontSlot;
    return true;
  }
  bool HitSurface(float s, EntrySide side, int ci, int cj, float z, int slot) {
    Hit(s, side, ci, cj, z);
    hit_slot = slot;
    return true;
  }

  // An entry at a cell's start point that the previous cell did not contain: a side wall, or the
  // top/bottom face of the clip box when this is the clipped start.
  // `top_slot` / `bottom_slot` name the surfaces bounding the entered interval (the slab's own by
  // default; a gap's boundary in a texel with gaps).
  bool HitAtStart(float s, int ci, int cj, float top, float bottom,
                  int top_slot = BodyMapCollider::kFrontSlot,
                  int bottom_slot = BodyMapCollider::kBackSlot) {
    if (s == 0.f && start_on_z_face) {
      return z1 < z0 ? HitSurface(s, kEntryFront, ci, cj, top, top_slot)
                     : HitSurface(s, kEntryBack, ci, cj, bottom, bottom_slot);
    }
    return Hit(s, kEntrySideWall, ci, cj, Z(s));
  }

  // The s in [s_enter, s_exit] where z, linear from z_enter to z_exit over the piece, reaches
  // `surface`; the caller has checked from the end values that it does (so no near-zero divide).
  static float CrossingS(float surface, float z_enter, float z_exit, float s_enter, float s_exit) {
    const float r = (surface - z_enter) / (z_exit - z_enter);
    return std::min(std::max(s_enter + r * (s_exit - s_enter), s_enter), s_exit);
  }

  // Nearest depth: texel (i, j), constant slab, z linear in s -> one linear solve. (ci, cj) is
  // the walk cell that is recorded on a hit.
  [[gnu::always_inline]] bool VisitTexel(int i, int j, int ci, int cj, float s_enter,
                                         float s_exit) {
    if (i < 0 || j < 0 || i >= static_cast<int>(c.width_) || j >= static_cast<int>(c.height_)) {
      inside_prev = false;
      return false;
    }
    const size_t texel = static_cast<size_t>(j) * c.width_ + i;
    if (c.gap_layers_ != 0 && c.GapBase(static_cast<uint32_t>(i), static_cast<uint32_t>(j)) >= 0) {
      return VisitTexelWithGaps(static_cast<uint32_t>(i), static_cast<uint32_t>(j), ci, cj, s_enter,
                                s_exit);
    }
    const BodyMapCollider::Slab slab = c.slabs_[texel];
    const float z_enter = Z(s_enter);
    const float z_exit = Z(s_exit);
    if (z_enter <= slab.top && z_enter >= slab.bottom) {
      if (!inside_prev) return HitAtStart(s_enter, ci, cj, slab.top, slab.bottom);
      inside_prev = z_exit <= slab.top && z_exit >= slab.bottom;  // the slab is convex
      return false;
    }
    // Outside at entry: solve only when the end values say the surface is crossed (grazing
    // segments never divide by a near-zero difference), and clamp to the texel's interval.
    if (z_enter > slab.top) {  // also every background texel (top = -inf)
      if (z_exit <= slab.top) {
        return Hit(CrossingS(slab.top, z_enter, z_exit, s_enter, s_exit), kEntryFront, ci, cj,
                   slab.top);
      }
    } else if (z_exit >= slab.bottom) {  // below the back surface at entry
      return Hit(CrossingS(slab.bottom, z_enter, z_exit, s_enter, s_exit), kEntryBack, ci, cj,
                 slab.bottom);
    }
    inside_prev = false;
    return false;
  }

  // A texel with air gaps: its inside set is up to kMaxBodyMapLayers disjoint z intervals, sorted
  // from the top, and z is linear (monotone) along the piece, so the first entry is into the
  // next interval in the direction of motion, if the piece reaches it.
  bool VisitTexelWithGaps(uint32_t i, uint32_t j, int ci, int cj, float s_enter, float s_exit) {
    BodyMapCollider::Interval in[kMaxBodyMapLayers];
    const int count = c.TexelIntervals(i, j, in);
    const float z_enter = Z(s_enter);
    const float z_exit = Z(s_exit);
    int at = -1;  // the interval holding z_enter
    for (int k = 0; k < count; ++k) {
      if (z_enter <= in[k].top && z_enter >= in[k].bottom) at = k;
    }
    if (at >= 0 && !inside_prev) {
      return HitAtStart(s_enter, ci, cj, in[at].top, in[at].bottom, in[at].top_slot,
                        in[at].bottom_slot);
    }
    if (at >= 0 && z_exit <= in[at].top && z_exit >= in[at].bottom) return false;  // stays in
    // The next interval below (moving down) or above (moving up) the entry point.
    const auto solve = [&](float surface) {
      return CrossingS(surface, z_enter, z_exit, s_enter, s_exit);
    };
    if (z_exit < z_enter) {
      int next = 0;
      while (next < count && !(in[next].top < z_enter)) ++next;
      if (next < count && z_exit <= in[next].top) {
        return HitSurface(solve(in[next].top), kEntryFront, ci, cj, in[next].top,
                          in[next].top_slot);
      }
    } else if (z_exit > z_enter) {
      int next = count - 1;
      while (next >= 0 && !(in[next].bottom > z_enter)) --next;
      if (next >= 0 && z_exit >= in[next].bottom) {
        return HitSurface(solve(in[next].bottom), kEntryBack, ci, cj, in[next].bottom,
                          in[next].bottom_slot);
      }
    }
    inside_prev = false;
    return false;
  }

  // Bilinear depth: half-texel cell (ci, cj). In an eligible 2x2 block top and bottom are
  // bilinear, so along the segment z - top and z - bottom are quadratics in s: their roots split
  // the cell into intervals of constant inside/outside, classified at the midpoints (double).
  // The cell's end points are classified with SampleSlab in float, exactly as IsInside does, so
  // the walk agrees with IsInside(p1) at s = 1.
  bool VisitHalfTexel(int ci, int cj, float s_enter, float s_exit) {
    const int i = ci >> 1, j = cj >> 1;  // arithmetic shift: floor division for negatives too
    const int i0 = (ci - 1) >> 1, j0 = (cj - 1) >> 1;
    if (i < 0 || j < 0 || i >= static_cast<int>(c.width_) || j >= static_cast<int>(c.height_) ||
        !c.BilinearBlock(i0, j0)) {
      return VisitTexel(i, j, ci, cj, s_enter, s_exit);
    }
    const float u_enter = U(s_enter), v_enter = V(s_enter), z_enter = Z(s_enter);
    const float u_exit = U(s_exit), v_exit = V(s_exit), z_exit = Z(s_exit);
    float top_enter, bottom_enter, top_exit, bottom_exit;
    c.SampleSlab(ci, cj, u_enter, v_enter, &top_enter, &bottom_enter);
    c.SampleSlab(ci, cj, u_exit, v_exit, &top_exit, &bottom_exit);
    const bool in_enter = z_enter <= top_enter && z_enter >= bottom_enter;
    const bool in_exit = z_exit <= top_exit && z_exit >= bottom_exit;
    if (in_enter && !inside_prev) return HitAtStart(s_enter, ci, cj, top_enter, bottom_enter);

    // Bilinear coefficients of both surfaces: value = a + b fx + c fy + d fx fy.
    const size_t w = c.width_;
    const size_t k00 = static_cast<size_t>(j0) * w + i0;
    const BodyMapCollider::Slab s00 = c.slabs_[k00], s10 = c.slabs_[k00 + 1];
    const BodyMapCollider::Slab s01 = c.slabs_[k00 + w], s11 = c.slabs_[k00 + w + 1];
    // Quick answers without the quadratics: a bilinear patch lies between its corner values and
    // z is linear along the cell, so a piece entirely above the highest top (or below the lowest
    // bottom) is outside throughout, and one between the highest bottom and the lowest top is
    // inside throughout. The end classifications must agree (they are what IsInside says).
    const float z_lo = std::min(z_enter, z_exit), z_hi = std::max(z_enter, z_exit);
    const float top_max = std::max(std::max(s00.top, s10.top), std::max(s01.top, s11.top));
    const float bottom_min =
        std::min(std::min(s00.bottom, s10.bottom), std::min(s01.bottom, s11.bottom));
    if (!in_enter && !in_exit && (z_lo > top_max || z_hi < bottom_min)) {
      inside_prev = false;
      return false;
    }
    if (in_enter && in_exit) {  // inside_prev is true here (else HitAtStart returned)
      const float top_min = std::min(std::min(s00.top, s10.top), std::min(s01.top, s11.top));
      const float bottom_max =
          std::max(std::max(s00.bottom, s10.bottom), std::max(s01.bottom, s11.bottom));
      if (z_lo >= bottom_max && z_hi <= top_min) return false;
    }
    const double fx = static_cast<double>(u_enter) - (i0 + 0.5);
    const double fy = static_cast<double>(v_enter) - (j0 + 0.5);
    const double du = static_cast<double>(u1) - u0;  // per unit s
    const double dv = static_cast<double>(v1) - v0;
    const double dz = static_cast<double>(z1) - z0;
    const double length = static_cast<double>(s_exit) - s_enter;
    const auto quadratic = [&](double v00, double v10, double v01, double v11, double coef[3]) {
      const double b = v10 - v00, cc = v01 - v00, d = v11 - v10 - v01 + v00;
      const double value = v00 + b * fx + cc * fy + d * fx * fy;
      coef[0] = static_cast<double>(z_enter) - value;
      coef[1] = dz - (b * du + cc * dv + d * (fx * dv + fy * du));
      coef[2] = -d * du * dv;
    };
    double f_top[3], f_bottom[3];
    quadratic(s00.top, s10.top, s01.top, s11.top, f_top);
    quadratic(s00.bottom, s10.bottom, s01.bottom, s11.bottom, f_bottom);
    const auto eval = [](const double f[3], double s) { return f[0] + s * (f[1] + s * f[2]); };
    const auto inside_at = [&](double s) {
      return eval(f_top, s) <= 0.0 && eval(f_bottom, s) >= 0.0;
    };
    const auto nearer_side = [&](double s) {
      return std::fabs(eval(f_top, s)) <= std::fabs(eval(f_bottom, s)) ? kEntryFront : kEntryBack;
    };

    // Split points: 0, the roots (tagged with their surface), length.
    double points[6];
    EntrySide tags[6];
    int count = 0;
    points[count] = 0.0;
    tags[count++] = kEntrySideWall;
    if (length > 0.0) {
      double roots[2];
      const int n_top = QuadraticRootsInside(f_top[2], f_top[1], f_top[0], length, roots);
      for (int k = 0; k < n_top; ++k) {
        points[count] = roots[k];
        tags[count++] = kEntryFront;
      }
      const int n_bottom =
          QuadraticRootsInside(f_bottom[2], f_bottom[1], f_bottom[0], length, roots);
      for (int k = 0; k < n_bottom; ++k) {
        points[count] = roots[k];
        tags[count++] = kEntryBack;
      }
      for (int a = 2; a < count; ++a) {  // insertion sort of at most 4 roots
        for (int b = a; b > 1 && points[b] < points[b - 1]; --b) {
          std::swap(points[b], points[b - 1]);
          std::swap(tags[b], tags[b - 1]);
        }
      }
      points[count] = length;
      tags[count++] = kEntrySideWall;
    }
    bool status = in_enter;
    for (int k = 0; k + 1 < count; ++k) {
      const double from = points[k], to = points[k + 1];
      if (!(to > from)) continue;
      const bool inside_here = inside_at(0.5 * (from + to));
      if (inside_here && !status) {
        const EntrySide side = k == 0 ? nearer_side(from) : tags[k];
        return HitOnSurface(static_cast<float>(s_enter + from), side, ci, cj, s_enter, s_exit);
      }
      status = inside_here;
    }
    if (in_exit && !status) {
      return HitOnSurface(s_exit, nearer_side(length), ci, cj, s_enter, s_exit);
    }
    inside_prev = in_exit;
    return false;
  }

  // A bilinear front/back entry at s: the point is put on the sampled surface.
  bool HitOnSurface(float s, EntrySide side, int ci, int cj, float s_enter, float s_exit) {
    s = std::min(std::max(s, s_enter), s_exit);
    float top, bottom;
    c.SampleSlab(ci, cj, U(s), V(s), &top, &bottom);
    return Hit(s, side, ci, cj, side == kEntryFront ? top : bottom);
  }

  [[gnu::always_inline]] bool VisitCell(int sub, int ci, int cj, float s_enter, float s_exit) {
    return sub == 1 ? VisitTexel(ci, cj, ci, cj, s_enter, s_exit)
                    : VisitHalfTexel(ci, cj, s_enter, s_exit);
  }

  // Walks the whole clipped segment. sub = walk cells per texel (1 nearest, 2 bilinear).
  template <int kSub>
  void Run() {
    GridLine line;
    line.g0x = u0 * kSub;
    line.g0y = v0 * kSub;
    line.g1x = u1 * kSub;
    line.g1y = v1 * kSub;
    const int ci0 = FloorToInt(line.g0x), cj0 = FloorToInt(line.g0y);
    const int ci1 = FloorToInt(line.g1x), cj1 = FloorToInt(line.g1y);
    line.inv_dx = SafeInverse(line.g1x - line.g0x);
    line.inv_dy = SafeInverse(line.g1y - line.g0y);
    const auto visit = [this](int ci, int cj, float s_enter, float s_exit) {
      return VisitCell(kSub, ci, cj, s_enter, s_exit);
    };
    if (ci0 == ci1 && cj0 == cj1) {  // one cell: sub-texel motion, pure z motion, a point
      VisitCell(kSub, ci0, cj0, 0.f, 1.f);
      return;
    }
    if (std::abs(ci1 - ci0) <= 1 && std::abs(cj1 - cj0) <= 1) {
      // At most one crossing per axis (the common cloth step): the cells and their intervals
      // are those WalkCells would produce, without its loop.
      const auto crossing = [](int a, int b, float g0, float inv) {
        return std::min(std::max((static_cast<float>(std::max(a, b)) - g0) * inv, 0.f), 1.f);
      };
      if (cj0 == cj1) {
        const float s = crossing(ci0, ci1, line.g0x, line.inv_dx);
        if (!VisitCell(kSub, ci0, cj0, 0.f, s)) VisitCell(kSub, ci1, cj0, s, 1.f);
        return;
      }
      if (ci0 == ci1) {
        const float s = crossing(cj0, cj1, line.g0y, line.inv_dy);
        if (!VisitCell(kSub, ci0, cj0, 0.f, s)) VisitCell(kSub, ci0, cj1, s, 1.f);
        return;
      }
      const float sx = crossing(ci0, ci1, line.g0x, line.inv_dx);
      const float sy = crossing(cj0, cj1, line.g0y, line.inv_dy);
      const float first = std::min(sx, sy), second = std::max(sx, sy);
      if (VisitCell(kSub, ci0, cj0, 0.f, first)) return;
      // Through the side neighbour the segment reaches first; none on an exact corner.
      if (sx < sy && VisitCell(kSub, ci1, cj0, sx, sy)) return;
      if (sy < sx && VisitCell(kSub, ci0, cj1, sy, sx)) return;
      VisitCell(kSub, ci1, cj1, second, 1.f);
      return;
    }
    if (std::abs(ci1 - ci0) + std::abs(cj1 - cj0) < kCoarseWalkMinCells) {
      WalkCells(line, 0, ci0, cj0, ci1, cj1, 0.f, 1.f, visit);
      return;
    }
    // Two levels: walk the 8x8-texel blocks, skip those the segment passes entirely above the
    // highest front surface or below the lowest back surface (bounds over the block widened by
    // one texel, which also covers bilinear patches straddling it, padded for float rounding of
    // Z(s)), walk the cells of the others. A block's cell is floor(g / 2^shift) = floor(cell /
    // 2^shift) exactly, so the two levels agree on which block holds which cell.
    constexpr int kShift = static_cast<int>(BodyMapCollider::kBlockShift) + (kSub == 2 ? 1 : 0);
    constexpr int kBlockCells = 1 << kShift;
    const auto visit_block = [&](int bi, int bj, float s_enter, float s_exit) {
      if (bi < 0 || bj < 0 || bi >= static_cast<int>(c.blocks_w_) ||
          bj >= static_cast<int>(c.blocks_h_)) {
        inside_prev = false;
        return false;
      }
      const BodyMapCollider::BlockBounds& b = c.blocks_[static_cast<size_t>(bj) * c.blocks_w_ + bi];
      const float z_enter = Z(s_enter), z_exit = Z(s_exit);
      if (std::min(z_enter, z_exit) > b.max_top || std::max(z_enter, z_exit) < b.min_bottom) {
        inside_prev = false;
        return false;
      }
      const int lo_i = bi * kBlockCells, lo_j = bj * kBlockCells;
      const auto clamp_i = [&](int x) {
        return std::min(std::max(x, lo_i), lo_i + kBlockCells - 1);
      };
      const auto clamp_j = [&](int x) {
        return std::min(std::max(x, lo_j), lo_j + kBlockCells - 1);
      };
      // The block's first and last cells are the one-level walk's own: along each axis, the
      // cell after every edge whose crossing parameter (WalkCells' expression) is <= s_enter,
      // and before every edge whose crossing is >= s_exit. The position at s only estimates it:
      // near a block corner U(s) or V(s) can round to the other side of an edge, and the blocks
      // must visit exactly the cells of the one-level walk (the batch's lanes walk one level).
      const auto exact_cell = [](int estimate, int c0, int c1, float g0, float inverse, float s,
                                 bool strict) {
        const int step = (c1 > c0) - (c1 < c0);
        if (step == 0) return c0;
        const int edge = step > 0 ? 1 : 0;    // the edge a cell is left through
        const auto crossed = [&](int cell) {  // the edge leaving `cell` is crossed by s
          const float at = (static_cast<float>(cell + edge) - g0) * inverse;
          return strict ? at < s : at <= s;
        };
        int cell = std::min(std::max(estimate, std::min(c0, c1)), std::max(c0, c1));
        while (cell != c1 && crossed(cell)) cell += step;
        while (cell != c0 && !crossed(cell - step)) cell -= step;
        return cell;
      };
      const int first_i =
          clamp_i(s_enter == 0.f ? ci0
                                 : exact_cell(FloorToInt(U(s_enter) * kSub), ci0, ci1, line.g0x,
                                              line.inv_dx, s_enter, false));
      const int first_j =
          clamp_j(s_enter == 0.f ? cj0
                                 : exact_cell(FloorToInt(V(s_enter) * kSub), cj0, cj1, line.g0y,
                                              line.inv_dy, s_enter, false));
      const int last_i = clamp_i(s_exit == 1.f ? ci1
                                               : exact_cell(FloorToInt(U(s_exit) * kSub), ci0, ci1,
                                                            line.g0x, line.inv_dx, s_exit, true));
      const int last_j = clamp_j(s_exit == 1.f ? cj1
                                               : exact_cell(FloorToInt(V(s_exit) * kSub), cj0, cj1,
                                                            line.g0y, line.inv_dy, s_exit, true));
      return WalkCells(line, 0, first_i, first_j, last_i, last_j, s_enter, s_exit, visit);
    };
    WalkCells(line, kShift, ci0 >> kShift, cj0 >> kShift, ci1 >> kShift, cj1 >> kShift, 0.f, 1.f,
              visit_block);
  }
};

// ---------------------------------------------------------------------------------------------
// Build

void BodyMapCollider::Clear() {
  width_ = height_ = 0;
  width_f_ = height_f_ = 0.f;
  origin_x_ = origin_y_ = 0.f;
  texel_size_ = inv_texel_size_ = 0.f;
  clip_ = -1;
  time_ = 0.f;
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
}

Status BodyMapCollider::Build(const BodyMapPose& pose, DepthSampling sampling) {
  Clear();
  const auto fail = [&](const std::string& reason) {
    Clear();
    return Status(StatusCode::kInvalidArgument, DescribePose(pose) + ": " + reason);
  };
  if (pose.width == 0 || pose.height == 0 || pose.width > kMaxMapSide ||
      pose.height > kMaxMapSide) {
    return fail("width and height must be in [1, " + std::to_string(kMaxMapSide) + "]");
  }
  if (!(std::isfinite(pose.texel_size) && pose.texel_size > 0.f)) {
    return fail("texel_size must be finite and > 0");
  }
  if (!(std::isfinite(pose.depth_range) && pose.depth_range > 0.f)) {
    return fail("depth_range must be finite and > 0");
  }
  if (!std::isfinite(pose.origin_x) || !std::isfinite(pose.origin_y) ||
      !std::isfinite(pose.front_z)) {
    return fail("origin and front_z must be finite");
  }
  if (sampling != DepthSampling::kNearest && sampling != DepthSampling::kBilinear) {
    return fail("unknown depth sampling");
  }
  if (pose.layers < 1 || pose.layers > kMaxBodyMapLayers) {
    return fail("layers = " + std::to_string(pose.layers) + " is outside [1, " +
                std::to_string(kMaxBodyMapLayers) + "]");
  }
  if (const std::string problem = CheckBodyMapLayout(pose); !problem.empty()) return fail(problem);
  if (pose.layout != BodyMapLayout::kDense) {
    // Row spans: expand into the dense rectangle (background outside the spans) and build from
    // that, so both layouts of one bake give the same grid bit for bit. Setup-time memory only.
    try {
      BodyMapPose dense;
      if (Status expanded = ConvertBodyMapLayout(pose, BodyMapLayout::kDense, &dense);
          !expanded.ok()) {
        return fail(expanded.message());
      }
      return Build(dense, sampling);
    } catch (const std::bad_alloc&) {
      return fail("the expanded rectangle does not fit in memory");
    }
  }
  const size_t n = static_cast<size_t>(pose.width) * pose.height;
  const size_t layers = pose.layers;
  const std::vector<uint32_t>& gap_list = pose.gap_texels;  // dense texel indices here
  // Per array: layer 0 of every texel, then the gap layers of the listed texels.
  const size_t values = n + (layers - 1) * gap_list.size();
  const char* view_name[2] = {"front", "back"};

  // Exactly the arrays of the chosen encodings are filled (body_map_data.h).
  for (int view = 0; view < 2; ++view) {
    const std::string name = view_name[view];
    size_t depth_f32 = 0, depth_u16 = 0;
    switch (pose.depth_encoding) {
      case DepthEncoding::kFloat32:
        depth_f32 = values;
        break;
      case DepthEncoding::kUnorm16:
        depth_u16 = values;
        break;
      default:
        return fail("unknown depth encoding");
    }
    if (pose.depth_f32[view].size() != depth_f32 || pose.depth_u16[view].size() != depth_u16) {
      return fail(name + " depth arrays hold " + std::to_string(pose.depth_f32[view].size()) +
                  " float32 / " + std::to_string(pose.depth_u16[view].size()) +
                  " unorm16 values, expected " + std::to_string(depth_f32) + " / " +
                  std::to_string(depth_u16) + " for width*height=" + std::to_string(n) + ", " +
                  std::to_string(layers) + " layer(s) and " + std::to_string(gap_list.size()) +
                  " gap texels");
    }
    size_t normal_f32 = 0, normal_oct16 = 0, normal_rgb8 = 0;
    switch (pose.normal_encoding) {
      case NormalEncoding::kFloat32:
        normal_f32 = 3 * values;
        break;
      case NormalEncoding::kOct16:
        normal_oct16 = 2 * values;
        break;
      case NormalEncoding::kRgb8:
        normal_rgb8 = 3 * values;
        break;
      default:
        return fail("unknown normal encoding");
    }
    if (pose.normal_f32[view].size() != normal_f32 ||
        pose.normal_oct16[view].size() != normal_oct16 ||
        pose.normal_rgb8[view].size() != normal_rgb8) {
      return fail(name + " normal arrays hold " + std::to_string(pose.normal_f32[view].size()) +
                  " float32 / " + std::to_string(pose.normal_oct16[view].size()) + " oct16 / " +
                  std::to_string(pose.normal_rgb8[view].size()) + " rgb8 values, expected " +
                  std::to_string(normal_f32) + " / " + std::to_string(normal_oct16) + " / " +
                  std::to_string(normal_rgb8));
    }
  }

  slabs_.resize(n);
  normals_.resize(n);
  const float depth_range = pose.depth_range;
  const float back_plane_z = pose.front_z - pose.depth_range;
  // Array entry `index` of one view: false (and a failure message) for a corrupt value.
  std::string problem;
  const auto where = [&](int view, size_t index) {
    if (index < n) return std::string(view_name[view]) + " at texel " + std::to_string(index);
    const size_t layer = (index - n) / gap_list.size() + 1, t = (index - n) % gap_list.size();
    return std::string(view_name[view]) + " gap layer " + std::to_string(layer) + " at texel " +
           std::to_string(gap_list[t]);
  };
  const auto read_depth = [&](int view, size_t index, float* depth, bool* valid) {
    if (pose.depth_encoding == DepthEncoding::kFloat32) {
      const float d = pose.depth_f32[view][index];
      if (std::isnan(d) || d < 0.f) {
        problem = where(view, index) + ": depth is NaN or negative";
        return false;
      }
      *valid = d < depth_range;  // +inf and >= depth_range are background
      *depth = d;
    } else {
      const uint16_t q = pose.depth_u16[view][index];
      *valid = q != 65535;
      *depth = static_cast<float>(q) / 65535.f * depth_range;
    }
    return true;
  };
  // Normals are kept as oct16 whatever the input encoding.
  const auto read_normal = [&](int view, size_t index, uint16_t oct[2]) {
    const Float3 view_fallback{0.f, 0.f, view == 0 ? 1.f : -1.f};
    if (pose.normal_encoding == NormalEncoding::kOct16) {
      oct[0] = pose.normal_oct16[view][2 * index];
      oct[1] = pose.normal_oct16[view][2 * index + 1];
      return true;
    }
    Float3 normal;
    if (pose.normal_encoding == NormalEncoding::kFloat32) {
      const float* f = &pose.normal_f32[view][3 * index];
      normal = {f[0], f[1], f[2]};
      if (!IsFinite(normal)) {
        problem = where(view, index) + ": normal is not finite";
        return false;
      }
      normal = NormalizeOr(normal, view_fallback);
    } else {
      const uint8_t* c = &pose.normal_rgb8[view][3 * index];
      const Float3 raw{static_cast<float>(c[0]) / 255.f * 2.f - 1.f,
                       static_cast<float>(c[1]) / 255.f * 2.f - 1.f,
                       static_cast<float>(c[2]) / 255.f * 2.f - 1.f};
      normal = NormalizeOr(raw, view_fallback);
    }
    const std::array<uint16_t, 2> q = EncodeOct16(normal);
    oct[0] = q[0];
    oct[1] = q[1];
    return true;
  };
  for (size_t k = 0; k < n; ++k) {
    float depth[2];
    bool valid[2];
    for (int view = 0; view < 2; ++view) {
      if (!read_depth(view, k, &depth[view], &valid[view])) return fail(problem);
    }
    Slab slab{-kInf, kInf};
    if (valid[0] && valid[1]) {
      const float top = pose.front_z - depth[0];
      const float bottom = back_plane_z + depth[1];
      if (top >= bottom) {
        slab = {top, bottom};
      } else {
        ++stats_.inverted_texels;
      }
    } else if (valid[0] != valid[1]) {
      ++stats_.one_sided_texels;  // notes/algorithms.md §5.1 step 5b: treated as background
    }
    slabs_[k] = slab;
    if (!read_normal(0, k, normals_[k].front) || !read_normal(1, k, normals_[k].back)) {
      return fail(problem);
    }
  }

  // Gap layers: each gap must sit strictly inside the interval above it, so that the texel's
  // inside set is a sorted list of disjoint intervals (the walk relies on it). Decoded per listed
  // texel, stored compactly by PackGaps below.
  gap_layers_ = static_cast<uint32_t>(layers - 1);
  if (gap_layers_ == 0 && !gap_list.empty()) {
    return fail("gap_texels lists " + std::to_string(gap_list.size()) +
                " texels but layers = 1 (no gap layers)");
  }
  std::vector<GapTexel> gap_texels;
  gap_texels.reserve(gap_list.size());
  for (size_t t = 0; t < gap_list.size(); ++t) {
    const size_t k = gap_list[t];
    if (k >= n || (t > 0 && k <= gap_list[t - 1])) {
      return fail("gap_texels[" + std::to_string(t) + "] = " + std::to_string(k) +
                  (k >= n ? " is not a texel of the rectangle" : " does not increase"));
    }
    GapTexel& texel = gap_texels.emplace_back();
    texel.i = static_cast<uint32_t>(k % pose.width);
    texel.j = static_cast<uint32_t>(k / pose.width);
    for (size_t g = 0; g < gap_layers_; ++g) {
      texel.gaps[g] = Slab{-kInf, kInf};
      texel.normals[g] = TexelNormals{};
    }
    float floor_z = slabs_[k].top;  // the gap must lie below this (the previous interval's top)
    bool absent_before = false;
    for (size_t g = 0; g < gap_layers_; ++g) {
      const size_t index = n + g * gap_list.size() + t;
      float depth[2];
      bool valid[2];
      for (int view = 0; view < 2; ++view) {
        if (!read_depth(view, index, &depth[view], &valid[view])) return fail(problem);
      }
      if (!valid[0] && !valid[1]) {
        if (g == 0) return fail(where(0, index) + ": a listed texel has no gap 1");
        absent_before = true;
        continue;
      }
      const float upper = pose.front_z - depth[0];
      const float lower = back_plane_z + depth[1];
      const Slab& slab = slabs_[k];
      const char* reason = nullptr;
      if (valid[0] != valid[1]) {
        reason = "has only one of its two boundaries";
      } else if (!(slab.top >= slab.bottom)) {
        reason = "lies on a background texel";
      } else if (absent_before) {
        reason = "follows an absent gap (gaps are filled in order)";
      } else if (!(floor_z > upper && upper > lower && lower > slab.bottom)) {
        reason = "is not strictly inside the slab below the previous gap";
      }
      if (reason != nullptr) return fail(where(0, index) + ": the gap " + reason);
      texel.gaps[g] = {upper, lower};
      floor_z = lower;
      TexelNormals& normals = texel.normals[g];
      if (!read_normal(0, index, normals.front) || !read_normal(1, index, normals.back)) {
        return fail(problem);
      }
    }
  }

  width_ = pose.width;
  height_ = pose.height;
  width_f_ = static_cast<float>(width_);
  height_f_ = static_cast<float>(height_);
  origin_x_ = pose.origin_x;
  origin_y_ = pose.origin_y;
  texel_size_ = pose.texel_size;
  inv_texel_size_ = 1.f / pose.texel_size;
  sampling_ = sampling;
  clip_ = pose.clip;
  time_ = pose.time;
  PackGaps(&gap_texels);
  Finish();
  return Status::Ok();
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

void BodyMapCollider::Finish() {
  const size_t w = width_, h = height_;
  uint32_t valid = 0;
  size_t i_lo = w, i_hi = 0, j_lo = h, j_hi = 0;  // valid texel range, [lo, hi)
  float z_lo = kInf, z_hi = -kInf;
  for (size_t j = 0; j < h; ++j) {
    for (size_t i = 0; i < w; ++i) {
      Slab& s = slabs_[j * w + i];
      if (!(s.top >= s.bottom)) continue;  // background: top -inf, no gaps, its low bit clear
      if (gap_layers_ != 0) {
        const size_t k = j * w + i;
        s.top = WithGapFlag(s.top, (gap_texel_bits_[k >> 5] >> (k & 31u)) & 1u);
      }
      ++valid;
      i_lo = std::min(i_lo, i);
      i_hi = std::max(i_hi, i + 1);
      j_lo = std::min(j_lo, j);
      j_hi = std::max(j_hi, j + 1);
      z_lo = std::min(z_lo, s.bottom);
      z_hi = std::max(z_hi, s.top);
    }
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

  // Bilinear eligibility per 2x2 block (lower corner texel (i, j)).
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

  // Min/max level: 8x8 texel blocks, bounds over the block widened by one texel on each side,
  // padded by 10 um per metre of |z| (+ 10 um) against the float rounding of the walk's Z(s).
  blocks_w_ = static_cast<uint32_t>((w + kBlockTexels - 1) >> kBlockShift);
  blocks_h_ = static_cast<uint32_t>((h + kBlockTexels - 1) >> kBlockShift);
  blocks_.resize(static_cast<size_t>(blocks_w_) * blocks_h_);
  for (size_t bj = 0; bj < blocks_h_; ++bj) {
    for (size_t bi = 0; bi < blocks_w_; ++bi) {
      const size_t i_begin = bi * kBlockTexels > 0 ? bi * kBlockTexels - 1 : 0;
      const size_t j_begin = bj * kBlockTexels > 0 ? bj * kBlockTexels - 1 : 0;
      const size_t i_end = std::min(w, (bi + 1) * kBlockTexels + 1);
      const size_t j_end = std::min(h, (bj + 1) * kBlockTexels + 1);
      float max_top = -kInf, min_bottom = kInf;
      for (size_t j = j_begin; j < j_end; ++j) {
        for (size_t i = i_begin; i < i_end; ++i) {
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
  }
}

bool BodyMapCollider::uses_avx2() const { return allow_avx2_ && detail::CpuHasAvx2(); }

bool BodyMapCollider::uses_avx512() const {
  return allow_avx512_ && uses_avx2() && detail::CpuHasAvx512();
}

BodyMapCollider::LaneKernel BodyMapCollider::lane_kernel() const {
  return uses_avx512() ? LaneKernel::kAvx512 : uses_avx2() ? LaneKernel::kAvx2 : LaneKernel::kSse2;
}

size_t BodyMapCollider::memory_bytes() const {
  return sizeof(*this) + (slabs_.capacity() + gaps_.capacity()) * sizeof(Slab) +
         (normals_.capacity() + gap_normals_.capacity()) * sizeof(TexelNormals) +
         (gap_texel_bits_.capacity() + gap_word_first_.capacity()) * sizeof(uint32_t) +
         bilinear_ok_.capacity() + blocks_.capacity() * sizeof(BlockBounds);
}

bool BodyMapCollider::TexelSlab(uint32_t i, uint32_t j, float* top, float* bottom) const {
  if (i >= width_ || j >= height_) return false;
  const Slab& s = slabs_[static_cast<size_t>(j) * width_ + i];
  if (!(s.top >= s.bottom)) return false;
  *top = s.top;
  *bottom = s.bottom;
  return true;
}

Float3 BodyMapCollider::TexelNormal(uint32_t i, uint32_t j, bool back) const {
  if (i >= width_ || j >= height_) return Float3{0.f, 0.f, back ? -1.f : 1.f};
  const TexelNormals& n = normals_[static_cast<size_t>(j) * width_ + i];
  const uint16_t* q = back ? n.back : n.front;
  return DecodeOct16(q[0], q[1]);
}

uint32_t BodyMapCollider::TexelGaps(uint32_t i, uint32_t j, float* upper, float* lower) const {
  if (i >= width_ || j >= height_ || gap_layers_ == 0) return 0;
  const int64_t base = GapBase(i, j);
  if (base < 0) return 0;
  const Slab* gaps = gaps_.data() + base;
  uint32_t count = 0;
  for (; count < gap_layers_ && gaps[count].top > gaps[count].bottom; ++count) {
    upper[count] = gaps[count].top;
    lower[count] = gaps[count].bottom;
  }
  return count;
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

// ---------------------------------------------------------------------------------------------
// Sampling

bool BodyMapCollider::BilinearBlock(int i0, int j0) const {
  if (i0 < 0 || j0 < 0 || i0 + 1 >= static_cast<int>(width_) ||
      j0 + 1 >= static_cast<int>(height_)) {
    return false;
  }
  return bilinear_ok_[static_cast<size_t>(j0) * width_ + i0] != 0;
}

void BodyMapCollider::SampleSlab(int ci, int cj, float u, float v, float* top,
                                 float* bottom) const {
  const int i0 = (ci - 1) >> 1, j0 = (cj - 1) >> 1;
  if (sampling_ == DepthSampling::kBilinear && BilinearBlock(i0, j0)) {
    const float fx = u - (static_cast<float>(i0) + 0.5f);
    const float fy = v - (static_cast<float>(j0) + 0.5f);
    const size_t k = static_cast<size_t>(j0) * width_ + i0;
    const Slab& a = slabs_[k];
    const Slab& b = slabs_[k + 1];
    const Slab& c = slabs_[k + width_];
    const Slab& d = slabs_[k + width_ + 1];
    *top = (a.top * (1.f - fx) + b.top * fx) * (1.f - fy) + (c.top * (1.f - fx) + d.top * fx) * fy;
    *bottom = (a.bottom * (1.f - fx) + b.bottom * fx) * (1.f - fy) +
              (c.bottom * (1.f - fx) + d.bottom * fx) * fy;
    return;
  }
  const Slab& s = slabs_[static_cast<size_t>(cj >> 1) * width_ + static_cast<size_t>(ci >> 1)];
  *top = s.top;
  *bottom = s.bottom;
}

Float3 BodyMapCollider::SampleNormal(int ci, int cj, float u, float v, bool back) const {
  const int i0 = (ci - 1) >> 1, j0 = (cj - 1) >> 1;
  if (sampling_ == DepthSampling::kBilinear && BilinearBlock(i0, j0)) {
    const float fx = std::min(std::max(u - (static_cast<float>(i0) + 0.5f), 0.f), 1.f);
    const float fy = std::min(std::max(v - (static_cast<float>(j0) + 0.5f), 0.f), 1.f);
    const Float3 n00 = TexelNormal(static_cast<uint32_t>(i0), static_cast<uint32_t>(j0), back);
    const Float3 n10 = TexelNormal(static_cast<uint32_t>(i0 + 1), static_cast<uint32_t>(j0), back);
    const Float3 n01 = TexelNormal(static_cast<uint32_t>(i0), static_cast<uint32_t>(j0 + 1), back);
    const Float3 n11 =
        TexelNormal(static_cast<uint32_t>(i0 + 1), static_cast<uint32_t>(j0 + 1), back);
    const Float3 n =
        (n00 * (1.f - fx) + n10 * fx) * (1.f - fy) + (n01 * (1.f - fx) + n11 * fx) * fy;
    return NormalizeOr(n, n00);
  }
  return TexelNormal(static_cast<uint32_t>(ci >> 1), static_cast<uint32_t>(cj >> 1), back);
}

bool BodyMapCollider::IsInsideBilinear(Float3 p) const {
  const float u = (p.x - origin_x_) * inv_texel_size_;
  const float v = (p.y - origin_y_) * inv_texel_size_;
  if (!(u >= 0.f && v >= 0.f && u < width_f_ && v < height_f_)) return false;
  // The half-texel cell, computed as the walk computes it: floor(2u) (u >= 0 here).
  const int ci = static_cast<int>(u * 2.f), cj = static_cast<int>(v * 2.f);
  float top, bottom;
  SampleSlab(ci, cj, u, v, &top, &bottom);
  // A texel with gaps is never part of a bilinear block: its nearest slab minus its gaps.
  return p.z <= top && p.z >= bottom &&
         !(gap_layers_ != 0 &&
           InGap(GapBase(static_cast<uint32_t>(ci >> 1), static_cast<uint32_t>(cj >> 1)), p.z));
}

// ---------------------------------------------------------------------------------------------
// Queries

bool BodyMapCollider::QuerySingleTexel(Float3 p0, Float3 p1, const TexelCoords& t,
                                       ContactQuery* result) const {
  const float u0 = t.u0, v0 = t.v0, u1 = t.u1, v1 = t.v1;
  if (!(u0 >= 0.f && v0 >= 0.f && u0 < width_f_ && v0 < height_f_)) return false;
  const int i = static_cast<int>(u0), j = static_cast<int>(v0);
  // On the grid before the conversion (a float beyond int's range does not convert).
  if (!(u1 >= 0.f && v1 >= 0.f && u1 < width_f_ && v1 < height_f_) || static_cast<int>(u1) != i ||
      static_cast<int>(v1) != j) {
    return false;
  }
  const size_t texel = static_cast<size_t>(j) * width_ + static_cast<size_t>(i);
  // A contact reads this texel's normals from their own array: start that load now.
  __builtin_prefetch(&normals_[texel]);
  const Slab slab = slabs_[texel];
  const float z0 = p0.z, z1 = p1.z;
  // A background texel holds nothing (the general path clips or walks it to the same answer).
  // On a valid texel x and y lie in the clip box; the general path clips nothing only when z
  // does too, and then its walk is one visit of this texel over s in [0, 1], which is below.
  if (!(slab.top >= slab.bottom)) return true;
  if (gap_layers_ != 0 && GapBase(static_cast<uint32_t>(i), static_cast<uint32_t>(j)) >= 0) {
    return false;  // the walk solves the intervals
  }
  if (!(z0 >= clip_lo_[2] && z0 <= clip_hi_[2] && z1 >= clip_lo_[2] && z1 <= clip_hi_[2])) {
    return false;
  }
  const bool inside_start = z0 <= slab.top && z0 >= slab.bottom;
  const bool inside_end = z1 <= slab.top && z1 >= slab.bottom;
  result->inside_end = inside_end;
  if (inside_end) result->depth = std::min(slab.top - z1, z1 - slab.bottom);
  if (inside_start) {
    if (!inside_end) return true;                        // left through a surface, no entry
    const bool back = z1 - slab.bottom < slab.top - z1;  // never left: pushed out along z
    result->contact = true;
    result->t = 0.f;
    result->flags = kCollisionStartedInside;
    result->point = Float3{p1.x, p1.y, back ? slab.bottom : slab.top};
    result->normal = TexelNormal(static_cast<uint32_t>(i), static_cast<uint32_t>(j), back);
    return true;
  }
  // Outside at the start: an entry only where the end values say a surface is crossed.
  const bool from_front = z0 > slab.top;
  const float surface = from_front ? slab.top : slab.bottom;
  if (from_front ? !(z1 <= slab.top) : !(z1 >= slab.bottom)) return true;
  const float s = std::min(std::max((surface - z0) / (z1 - z0), 0.f), 1.f);
  result->contact = true;
  result->t = s;
  result->point =
      Float3{BodyMapWalk::Along(p0.x, p1.x, s), BodyMapWalk::Along(p0.y, p1.y, s), surface};
  result->normal = TexelNormal(static_cast<uint32_t>(i), static_cast<uint32_t>(j), !from_front);
  return true;
}

bool BodyMapCollider::ClearlyFree(Float3 p0, Float3 p1, const TexelCoords& t) const {
  const float u_lo = std::min(t.u0, t.u1), u_hi = std::max(t.u0, t.u1);
  const float v_lo = std::min(t.v0, t.v1), v_hi = std::max(t.v0, t.v1);
  if (!(u_lo >= 0.f && v_lo >= 0.f && u_hi < width_f_ && v_hi < height_f_)) return false;
  // The walk's cells lie between the texels of its clipped ends, and the clipped ends lie
  // between p0 and p1 (float rounding is monotone): the texel box of p0 and p1 holds every
  // cell. Bilinear cells also read the texels one step down and left (their 2x2 block).
  const int reach = sampling_ == DepthSampling::kBilinear ? 1 : 0;
  const int i_lo = std::max(static_cast<int>(u_lo) - reach, 0);
  const int j_lo = std::max(static_cast<int>(v_lo) - reach, 0);
  const int i_hi = std::min(static_cast<int>(u_hi) + reach, static_cast<int>(width_) - 1);
  const int j_hi = std::min(static_cast<int>(v_hi) + reach, static_cast<int>(height_) - 1);
  // The walk's z values are interpolated in float and may step an ulp or two beyond the end
  // values: pad by a millionth.
  const float z_lo = std::min(p0.z, p1.z), z_hi = std::max(p0.z, p1.z);
  const float pad = 1e-6f * (1.f + std::max(std::fabs(z_lo), std::fabs(z_hi)));
  const float below = z_lo - pad, above = z_hi + pad;
  bool free = true;
  if ((i_hi - i_lo + 1) * (j_hi - j_lo + 1) <= kFreeTestMaxTexels) {
    for (int j = j_lo; j <= j_hi; ++j) {
      const Slab* row = slabs_.data() + static_cast<size_t>(j) * width_;
      for (int i = i_lo; i <= i_hi; ++i) free &= (below > row[i].top) | (above < row[i].bottom);
    }
    return free;
  }
  // Longer motions: the 8x8 min/max blocks (each already widened by one texel and padded).
  const int bi_lo = i_lo >> kBlockShift, bi_hi = i_hi >> kBlockShift;
  const int bj_lo = j_lo >> kBlockShift, bj_hi = j_hi >> kBlockShift;
  if ((bi_hi - bi_lo + 1) * (bj_hi - bj_lo + 1) > kFreeTestMaxTexels) return false;
  for (int bj = bj_lo; bj <= bj_hi; ++bj) {
    const BlockBounds* row = blocks_.data() + static_cast<size_t>(bj) * blocks_w_;
    for (int bi = bi_lo; bi <= bi_hi; ++bi) {
      free &= (below > row[bi].max_top) | (above < row[bi].min_bottom);
    }
  }
  return free;
}

namespace {

// The answer of a motion without contact (flagged when the input is not finite): what every
// path of the continuous test starts from.
ContactQuery NoContact(Float3 p0, Float3 p1) {
  ContactQuery result;
  result.point = p1;
  result.normal = Float3{0.f, 0.f, 1.f};
  if (!IsFinite(p0) || !IsFinite(p1)) result.flags = kCollisionInvalidInput;
  return result;
}

}  // namespace

ContactQuery BodyMapCollider::Query(Float3 p0, Float3 p1) const {
  ContactQuery result = NoContact(p0, p1);
  if (result.flags == kCollisionInvalidInput || stats_.valid_texels == 0) return result;
  const TexelCoords texels = ToTexels(p0, p1);
  if (sampling_ == DepthSampling::kNearest && QuerySingleTexel(p0, p1, texels, &result)) {
    return result;
  }
  if (ClearlyFree(p0, p1, texels)) return result;
  WalkInto(p0, p1, &result);
  return result;  // one named result on every path: built in place, never copied
}

ContactQuery BodyMapCollider::QueryWalk(Float3 p0, Float3 p1) const {
  ContactQuery result = NoContact(p0, p1);
  if (result.flags != kCollisionInvalidInput && stats_.valid_texels != 0) {
    WalkInto(p0, p1, &result);
  }
  return result;
}

bool BodyMapCollider::ClipMotion(Float3 p0, Float3 p1, ClippedMotion* out) const {
  // Liang-Barsky in double (no overflow for any finite float input).
  const double a[3] = {p0.x, p0.y, p0.z};
  const double d[3] = {static_cast<double>(p1.x) - p0.x, static_cast<double>(p1.y) - p0.y,
                       static_cast<double>(p1.z) - p0.z};
  double t_start = 0.0, t_end = 1.0;
  int start_axis = -1, end_axis = -1;
  const double b[3] = {p1.x, p1.y, p1.z};
  bool p0_in_box = true, p1_in_box = true;
  for (int k = 0; k < 3; ++k) {  // (& not &&: six comparisons cost less than their branches)
    p0_in_box &= (a[k] >= clip_lo_[k]) & (a[k] <= clip_hi_[k]);
    p1_in_box &= (b[k] >= clip_lo_[k]) & (b[k] <= clip_hi_[k]);
  }
  // Both ends in the box is the common case near the body: nothing to clip, no divisions.
  for (int k = 0; k < 3 && !(p0_in_box && p1_in_box); ++k) {
    if (d[k] == 0.0) {
      if (a[k] < clip_lo_[k] || a[k] > clip_hi_[k]) return false;
      continue;
    }
    // The planes' parameters in order along the motion (min and max, not a branch on the
    // direction, which is data).
    const double t_low_plane = (clip_lo_[k] - a[k]) / d[k];
    const double t_high_plane = (clip_hi_[k] - a[k]) / d[k];
    const double t_lo = std::min(t_low_plane, t_high_plane);
    const double t_hi = std::max(t_low_plane, t_high_plane);
    const bool later_start = t_lo > t_start, earlier_end = t_hi < t_end;
    start_axis = later_start ? k : start_axis;
    t_start = later_start ? t_lo : t_start;
    end_axis = earlier_end ? k : end_axis;
    t_end = earlier_end ? t_hi : t_end;
  }
  if (t_start > t_end) return false;
  // A clipped end: on the clipping plane exactly in its axis, and clamped into the box in the
  // others (for |p1 - p0| beyond ~1e9 m the double product loses metres; the clamp keeps the walk
  // bounded by the box whatever the input).
  const auto clipped = [&](double t, int axis, bool is_start) {
    float q[3];
    for (int k = 0; k < 3; ++k) {
      const double x = std::min(std::max(a[k] + d[k] * t, clip_lo_[k]), clip_hi_[k]);
      q[k] = static_cast<float>(x);
    }
    if (axis >= 0) {
      // Moving up an axis, the segment enters at the low plane and leaves at the high one.
      const bool low_plane = (d[axis] > 0.0) == is_start;
      q[axis] = static_cast<float>(low_plane ? clip_lo_[axis] : clip_hi_[axis]);
    }
    return Float3{q[0], q[1], q[2]};
  };
  // Unclipped ends are used as they are, so the walk reads exactly the texels IsInside reads.
  // (t_end can round to 1 for an end far outside the box: such an end is still clamped.)
  out->q0 = t_start == 0.0 && p0_in_box ? p0 : clipped(t_start, start_axis, true);
  out->q1 = t_end == 1.0 && p1_in_box ? p1 : clipped(t_end, end_axis, false);
  out->t_start = t_start;
  out->t_end = t_end;
  out->start_on_z_face = t_start > 0.0 && start_axis == 2;
  return true;
}

void BodyMapCollider::WalkInto(Float3 p0, Float3 p1, ContactQuery* out) const {
  ContactQuery& result = *out;
  result.inside_end = IsInside(p1);
  ClippedMotion clip;
  if (!ClipMotion(p0, p1, &clip)) return;
  const Float3 q0 = clip.q0, q1 = clip.q1;
  const double t_start = clip.t_start, t_end = clip.t_end;
  const bool start_inside = t_start == 0.0 && IsInside(p0);

  BodyMapWalk walk(*this, (q0.x - origin_x_) * inv_texel_size_,
                   (q0.y - origin_y_) * inv_texel_size_, (q1.x - origin_x_) * inv_texel_size_,
                   (q1.y - origin_y_) * inv_texel_size_, q0.z, q1.z,
                   /*starts_on_z_face=*/clip.start_on_z_face,
                   /*starts_inside=*/start_inside);
  if (sampling_ == DepthSampling::kNearest) {
    walk.Run<1>();
  } else {
    walk.Run<2>();
  }

  // The z interval of the inside set around z in walk cell (ci, cj), with its surfaces: the
  // bilinear patch in an eligible block, else the texel's interval (gaps split the slab).
  const auto interval_at = [&](int ci, int cj, float u, float v, float z) {
    if (sampling_ == DepthSampling::kNearest) {
      return IntervalAt(static_cast<uint32_t>(ci), static_cast<uint32_t>(cj), z);
    }
    if (!BilinearBlock((ci - 1) >> 1, (cj - 1) >> 1)) {
      return IntervalAt(static_cast<uint32_t>(ci >> 1), static_cast<uint32_t>(cj >> 1), z);
    }
    Interval patch{0.f, 0.f, kFrontSlot, kBackSlot};
    SampleSlab(ci, cj, u, v, &patch.top, &patch.bottom);
    return patch;
  };
  const auto normal_at = [&](int ci, int cj, float u, float v, int slot) {
    if (sampling_ == DepthSampling::kNearest) {
      return SlotNormal(static_cast<uint32_t>(ci), static_cast<uint32_t>(cj), slot);
    }
    if (slot >= 2) {  // a gap's boundary: its texel has no bilinear block
      return SlotNormal(static_cast<uint32_t>(ci >> 1), static_cast<uint32_t>(cj >> 1), slot);
    }
    return SampleNormal(ci, cj, u, v, slot == kBackSlot);
  };

  // Penetration of p1 along z (the start-inside push-out uses the same numbers).
  Interval p1_interval{0.f, 0.f, kFrontSlot, kBackSlot};
  int p1_ci = 0, p1_cj = 0;
  const float p1_u = (p1.x - origin_x_) * inv_texel_size_;
  const float p1_v = (p1.y - origin_y_) * inv_texel_size_;
  if (result.inside_end) {
    const float cells = sampling_ == DepthSampling::kNearest ? 1.f : 2.f;
    p1_ci = static_cast<int>(p1_u * cells);
    p1_cj = static_cast<int>(p1_v * cells);
    p1_interval = interval_at(p1_ci, p1_cj, p1_u, p1_v, p1.z);
    result.depth = std::min(p1_interval.top - p1.z, p1.z - p1_interval.bottom);
  }

  if (walk.hit) {
    const float s = walk.hit_s;
    result.contact = true;
    result.t = static_cast<float>(
        std::min(std::max(t_start + static_cast<double>(s) * (t_end - t_start), 0.0), 1.0));
    result.point =
        Float3{BodyMapWalk::Along(q0.x, q1.x, s), BodyMapWalk::Along(q0.y, q1.y, s), walk.hit_z};
    const float u = walk.U(s), v = walk.V(s);
    int slot = walk.hit_slot;
    if (walk.hit_side == kEntrySideWall) {
      result.flags = kCollisionSideWall;
      // The wall's own normal would be horizontal; the texel's surface normal from the map
      // whose surface is nearer in z describes the body better (notes/algorithms.md §5.1 step 3).
      const Interval wall = interval_at(walk.hit_ci, walk.hit_cj, u, v, walk.hit_z);
      slot = walk.hit_z - wall.bottom < wall.top - walk.hit_z ? wall.bottom_slot : wall.top_slot;
      // The wall point belongs to the entered texel, whose slab contains it: a particle put there
      // (plus separation along the mostly-z map normal) would still test inside. Step back across
      // the wall by a thousandth of a texel, into the texel the segment came from.
      const float dx = q1.x - q0.x, dy = q1.y - q0.y;
      const float length = std::sqrt(dx * dx + dy * dy);
      if (length > 0.f) {
        const float back_off = 1e-3f * texel_size_ / length;
        result.point.x -= dx * back_off;
        result.point.y -= dy * back_off;
      }
    }
    result.normal = normal_at(walk.hit_ci, walk.hit_cj, u, v, slot);
    return;
  }
  if (result.inside_end) {
    // Started inside and never left (or, defensively, any inside end the walk did not explain):
    // push p1 out along z to the nearer surface of its interval.
    const bool back = p1.z - p1_interval.bottom < p1_interval.top - p1.z;
    result.contact = true;
    result.t = 0.f;
    result.flags = start_inside ? kCollisionStartedInside : kCollisionNone;
    result.point = Float3{p1.x, p1.y, back ? p1_interval.bottom : p1_interval.top};
    result.normal =
        normal_at(p1_ci, p1_cj, p1_u, p1_v, back ? p1_interval.bottom_slot : p1_interval.top_slot);
  }
}

uint8_t BodyMapCollider::CollideOne(Float3 from, Float3* position, Float3* velocity,
                                    const ResponseParams& params) const {
  if (!IsFinite(from) || !IsFinite(*position) || !IsFinite(*velocity)) {
    return kCollisionInvalidInput;
  }
  const ContactQuery q = Query(from, *position);
  if (!q.contact) return kCollisionNone;
  ApplyResponse(q, params, position, velocity);
  return static_cast<uint8_t>(kCollisionContact | q.flags);
}

uint32_t BodyMapCollider::CollideRange(const Float3* previous, Float3* positions,
                                       Float3* velocities, uint8_t* flags, size_t count,
                                       const ResponseParams& params) const {
  size_t k = 0;
#if defined(__SSE2__)
  if (sampling_ == DepthSampling::kNearest && stats_.valid_texels != 0) {
    // Groups of consecutive particles go through the short-motion lanes first; the particles
    // they do not answer queue for the walking lanes, and what those do not answer goes one by
    // one. Eight lanes in AVX2 (or AVX2 with AVX-512) when the CPU has it, else four: the same
    // bits. Where particles move a texel or more per step the short lanes answer few and their work
    // is wasted: after a group with half or more of its motions across more than one texel edge,
    // the next kScalarParticles particles queue directly. Every path gives the same bits.
    constexpr uint32_t kScalarParticles = 16;
    const LaneKernel kernel = lane_kernel();
    const uint32_t width = kernel == LaneKernel::kSse2 ? 4u : 8u;
    const auto short_lanes =
        kernel == LaneKernel::kAvx512 ? &BodyMapCollider::CollideEightShortMotionsAvx512
        : kernel == LaneKernel::kAvx2 ? &BodyMapCollider::CollideEightShortMotionsAvx2
                                      : &BodyMapCollider::CollideFourShortMotions;
    const auto walk_lanes = kernel == LaneKernel::kAvx512
                                ? &BodyMapCollider::CollideEightWalksAvx512
                            : kernel == LaneKernel::kAvx2 ? &BodyMapCollider::CollideEightWalksAvx2
                                                          : &BodyMapCollider::CollideFourWalks;
    uint32_t skip_short = 0;  // groups
    // The particles waiting for the walking lanes: fewer than `width` between groups, so a group
    // adds at most `width` more.
    uint32_t queued[16] = {};
    uint32_t queued_count = 0;
    // Walks the first `width` queued particles (all of them, padded, for the last group).
    const auto walk_queued = [&] {
      const uint32_t walked = std::min(queued_count, width);
      for (uint32_t lane = walked; lane < width; ++lane) queued[lane] = queued[0];
      const uint32_t lanes = (1u << walked) - 1u;
      const uint32_t answered =
          (this->*walk_lanes)(queued, lanes, previous, positions, velocities, flags, params);
      for (uint32_t left = lanes & ~answered; left != 0; left &= left - 1u) {
        const uint32_t q = queued[std::countr_zero(left)];
        flags[q] = CollideOne(previous[q], &positions[q], &velocities[q], params);
      }
      // The rest (fewer than `width`) to the front: a fixed copy, not a loop of data-dependent
      // length (walked + 8 <= 16; entries past queued_count are never read).
      for (uint32_t i = 0; i < 8; ++i) queued[i] = queued[walked + i];  // forward: dest <= src
      queued_count -= walked;
    };
    for (; k + width <= count; k += width) {
      uint32_t answered = 0, long_motions = 0;
      if (skip_short > 0) {
        --skip_short;
      } else {
        answered = (this->*short_lanes)(previous + k, positions + k, velocities + k, flags + k,
                                        params, &long_motions);
        if (2 * CountLaneBits(long_motions) >= width) {
          skip_short = kScalarParticles / width;
        }
      }
      // The unanswered lanes join the queue without a branch each: which lanes a group answers
      // is data, and mispredicted branches here cost more than the stores.
      for (uint32_t lane = 0; lane < width; ++lane) {
        queued[queued_count] = static_cast<uint32_t>(k + lane);
        queued_count += ((answered >> lane) & 1u) ^ 1u;
      }
      if (queued_count >= width) walk_queued();
    }
    while (queued_count != 0) walk_queued();
  }
#endif
  for (; k < count; ++k) {
    flags[k] = CollideOne(previous[k], &positions[k], &velocities[k], params);
  }
  uint32_t contacts = 0;
  for (size_t i = 0; i < count; ++i) contacts += flags[i] & kCollisionContact;
  return contacts;
}

#if defined(__SSE2__)
}  // namespace drape

#include "body_map/lanes/lane_walk.inl"

namespace drape {
namespace {

using Lanes4 = detail::Sse2Lanes;

}  // namespace

uint32_t BodyMapCollider::CollideFourShortMotions(const Float3* previous, Float3* positions,
                                                  Float3* velocities, uint8_t* flags,
                                                  const ResponseParams& params,
                                                  uint32_t* long_motions) const {
  return CollideShortLanes<Lanes4>(previous, positions, velocities, flags, params, long_motions);
}

uint32_t BodyMapCollider::CollideFourWalks(const uint32_t* index, uint32_t lanes,
                                           const Float3* previous, Float3* positions,
                                           Float3* velocities, uint8_t* flags,
                                           const ResponseParams& params) const {
  return CollideWalkLanes<Lanes4>(index, lanes, previous, positions, velocities, flags, params);
}
#endif

Status BodyMapCollider::CollideBatch(std::span<const Float3> previous, std::span<Float3> positions,
                                     std::span<Float3> velocities, std::span<uint8_t> flags,
                                     const ResponseParams& params, uint32_t* contact_count) const {
  if (contact_count != nullptr) *contact_count = 0;
  const size_t n = positions.size();
  if (previous.size() != n || velocities.size() != n || flags.size() != n) {
    return Status(StatusCode::kInvalidArgument,
                  "BodyMapCollider::CollideBatch: span sizes differ (previous " +
                      std::to_string(previous.size()) + ", positions " + std::to_string(n) +
                      ", velocities " + std::to_string(velocities.size()) + ", flags " +
                      std::to_string(flags.size()) + ")");
  }
  if (!std::isfinite(params.friction) || !std::isfinite(params.restitution) ||
      !std::isfinite(params.separation)) {
    return Status(StatusCode::kInvalidArgument,
                  "BodyMapCollider::CollideBatch: response parameters must be finite");
  }
  if (empty()) {
    return Status(StatusCode::kInvalidState, "BodyMapCollider::CollideBatch: collider not built");
  }
  // Chunks through CollideRange, for the reason InsideBatch gives, taken by the threads as
  // they finish: a particle's cost runs from a few nanoseconds (free, resting) to hundreds (long
  // walks), and cloth groups them, so equal shares in order leave a thread idle. Each particle's
  // answer depends on that particle alone, so the schedule does not change a bit.
  const int64_t count = static_cast<int64_t>(n);
  constexpr int64_t kChunk = 1024;
  const int64_t chunks = (count + kChunk - 1) / kChunk;
  uint32_t contacts = 0;  // an integer sum: the same at any thread count
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : contacts) if (chunks > 1)
  for (int64_t chunk = 0; chunk < chunks; ++chunk) {
    const size_t begin = static_cast<size_t>(chunk * kChunk);
    const size_t end = std::min(static_cast<size_t>(count), begin + static_cast<size_t>(kChunk));
    contacts += CollideRange(previous.data() + begin, positions.data() + begin,
                             velocities.data() + begin, flags.data() + begin, end - begin, params);
  }
  if (contact_count != nullptr) *contact_count = contacts;
  return Status::Ok();
}

void BodyMapCollider::InsideRange(const Float3* points, uint8_t* inside, size_t count) const {
  const float origin_x = origin_x_, origin_y = origin_y_, inv_texel = inv_texel_size_;
  const float width_f = width_f_, height_f = height_f_;
  const size_t width = width_;
  const Slab* const slabs = slabs_.data();
  for (size_t k = 0; k < count; ++k) {
    const Float3 p = points[k];
    const float u = (p.x - origin_x) * inv_texel;
    const float v = (p.y - origin_y) * inv_texel;
    uint8_t result = 0;
    if (u >= 0.f && v >= 0.f && u < width_f && v < height_f) {
      const Slab& slab = slabs[static_cast<size_t>(v) * width + static_cast<size_t>(u)];
      result = static_cast<uint8_t>((p.z <= slab.top) & (p.z >= slab.bottom));
    }
    inside[k] = result;
  }
}

Status BodyMapCollider::InsideBatch(std::span<const Float3> points,
                                    std::span<uint8_t> inside) const {
  if (points.size() != inside.size()) {
    return Status(StatusCode::kInvalidArgument,
                  "BodyMapCollider::InsideBatch: " + std::to_string(points.size()) +
                      " points but " + std::to_string(inside.size()) + " result slots");
  }
  const int64_t count = static_cast<int64_t>(points.size());
  if (sampling_ != DepthSampling::kNearest || gap_layers_ != 0) {
#pragma omp parallel for schedule(static) if (count > 16384)
    for (int64_t k = 0; k < count; ++k) inside[k] = IsInside(points[k]) ? 1 : 0;
    return Status::Ok();
  }
  // Chunks of 4096 points, each through InsideRange: inside an OpenMP region every shared
  // variable is read through a pointer and the uint8_t stores may alias it, so a plain loop
  // reloads the map's fields for every point (measured 2x slower).
  constexpr int64_t kChunk = 4096;
  const int64_t chunks = (count + kChunk - 1) / kChunk;
#pragma omp parallel for schedule(static) if (chunks > 4)
  for (int64_t chunk = 0; chunk < chunks; ++chunk) {
    const int64_t begin = chunk * kChunk;
    const int64_t end = std::min(count, begin + kChunk);
    InsideRange(points.data() + begin, inside.data() + begin, static_cast<size_t>(end - begin));
  }
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// Sequence

namespace {

bool SameGrid(const BodyMapCollider& a, const BodyMapCollider& b) {
  return a.width() == b.width() && a.height() == b.height() && a.origin_x() == b.origin_x() &&
         a.origin_y() == b.origin_y() && a.texel_size() == b.texel_size() &&
         a.sampling() == b.sampling() && a.layers() == b.layers();
}

}  // namespace

Status BodyMapSequence::Build(std::span<const BodyMapPose> poses, DepthSampling sampling,
                              PoseBlend blend) {
  poses_.clear();
  blend_ = blend;
  if (poses.empty()) {
    return Status(StatusCode::kInvalidArgument, "BodyMapSequence::Build: no poses");
  }
  if (blend != PoseBlend::kNearest && blend != PoseBlend::kBracket) {
    return Status(StatusCode::kInvalidArgument, "BodyMapSequence::Build: unknown pose blend");
  }
  for (size_t k = 0; k < poses.size(); ++k) {
    const std::string where = "BodyMapSequence::Build: pose " + std::to_string(k);
    if (!std::isfinite(poses[k].time)) {
      return Status(StatusCode::kInvalidArgument, where + " has a non-finite time");
    }
    if (poses[k].clip != poses[0].clip) {
      return Status(StatusCode::kInvalidArgument,
                    where + " belongs to clip " + std::to_string(poses[k].clip) + ", pose 0 to " +
                        std::to_string(poses[0].clip));
    }
    if (k > 0 && poses[k].time < poses[k - 1].time) {
      return Status(
          StatusCode::kInvalidArgument,
          where + " is earlier than pose " + std::to_string(k - 1) + " (not sorted by time)");
    }
  }
  poses_.resize(poses.size());
  for (size_t k = 0; k < poses.size(); ++k) {
    Status status = poses_[k].Build(poses[k], sampling);
    if (!status.ok()) {
      poses_.clear();
      return Status(status.code(),
                    "BodyMapSequence::Build: pose " + std::to_string(k) + ": " + status.message());
    }
  }
  return Status::Ok();
}

const BodyMapCollider& BodyMapSequence::At(float time, BodyMapCollider* scratch) const {
  if (poses_.empty()) return empty_;
  if (!(time > poses_.front().time())) return poses_.front();  // also NaN
  if (!(time < poses_.back().time())) return poses_.back();
  // First pose later than `time`; its predecessor is at or before it.
  const auto later = std::upper_bound(
      poses_.begin(), poses_.end(), time,
      [](float value, const BodyMapCollider& pose) { return value < pose.time(); });
  const BodyMapCollider& b = *later;
  const BodyMapCollider& a = *(later - 1);
  const float w = (time - a.time()) / (b.time() - a.time());  // in (0, 1) up to rounding
  const bool a_nearer = w <= 0.5f;
  if (blend_ != PoseBlend::kBracket || scratch == nullptr || !(w > 0.f && w < 1.f) ||
      !SameGrid(a, b)) {
    return a_nearer ? a : b;
  }
  BodyMapCollider& out = *scratch;
  const BodyMapCollider& nearer = a_nearer ? a : b;
  const size_t n = a.slabs_.size();
  out.width_ = a.width_;
  out.height_ = a.height_;
  out.width_f_ = a.width_f_;
  out.height_f_ = a.height_f_;
  out.origin_x_ = a.origin_x_;
  out.origin_y_ = a.origin_y_;
  out.texel_size_ = a.texel_size_;
  out.inv_texel_size_ = a.inv_texel_size_;
  out.sampling_ = a.sampling_;
  out.clip_ = a.clip_;
  out.time_ = time;
  out.stats_ = nearer.stats_;
  out.slabs_.resize(n);  // allocates only when the scratch has never held this grid size
  out.normals_.resize(n);
  const int64_t count = static_cast<int64_t>(n);
#pragma omp parallel for schedule(static) if (count > 65536)
  for (int64_t k = 0; k < count; ++k) {
    const BodyMapCollider::Slab sa = a.slabs_[k], sb = b.slabs_[k];
    const bool valid_a = sa.top >= sa.bottom, valid_b = sb.top >= sb.bottom;
    BodyMapCollider::Slab slab{-kInf, kInf};
    if (valid_a && valid_b) {
      slab = {(1.f - w) * sa.top + w * sb.top, (1.f - w) * sa.bottom + w * sb.bottom};
    } else if (valid_a && a_nearer) {
      slab = sa;
    } else if (valid_b && !a_nearer) {
      slab = sb;
    }
    out.slabs_[k] = slab;
    out.normals_[k] = nearer.normals_[k];
  }
  BlendGaps(a, b, w, &out);
  out.Finish();
  return out;
}

void BodyMapSequence::BlendGaps(const BodyMapCollider& a, const BodyMapCollider& b, float w,
                                BodyMapCollider* out) {
  using Slab = BodyMapCollider::Slab;
  const uint32_t layers = a.gap_layers_;
  out->gap_layers_ = layers;
  out->blocks_w_ = a.blocks_w_;
  out->blocks_h_ = a.blocks_h_;
  out->gaps_.clear();
  out->gap_normals_.clear();
  if (layers == 0) {
    out->gap_texel_bits_.clear();
    out->gap_word_first_.clear();
    return;
  }
  const size_t words = a.gap_texel_bits_.size();
  out->gap_texel_bits_.assign(words, 0u);  // no allocation once the scratch held this grid
  // Room for both poses' gaps: a blend never keeps more gap texels than the two have together.
  out->gaps_.reserve(a.gaps_.size() + b.gaps_.size());
  out->gap_normals_.reserve(a.gap_normals_.size() + b.gap_normals_.size());
  const BodyMapCollider& nearer = w <= 0.5f ? a : b;
  for (size_t word = 0; word < words; ++word) {
    uint32_t candidates = a.gap_texel_bits_[word] | b.gap_texel_bits_[word];
    while (candidates != 0) {
      const int bit = std::countr_zero(candidates);
      candidates &= candidates - 1;
      const size_t k = word * 32 + static_cast<size_t>(bit);
      const Slab slab = out->slabs_[k];
      if (!(slab.top >= slab.bottom)) continue;  // background has no gaps
      const bool both =
          a.slabs_[k].top >= a.slabs_[k].bottom && b.slabs_[k].top >= b.slabs_[k].bottom;
      const uint32_t texel = static_cast<uint32_t>(k);
      const int64_t base_a = a.GapBaseAt(texel), base_b = b.GapBaseAt(texel);
      const int64_t base_nearer = nearer.GapBaseAt(texel);
      Slab gaps[kMaxBodyMapLayers];
      bool more = true;
      for (uint32_t g = 0; g < layers; ++g) {
        Slab gap{-kInf, kInf};
        if (both) {
          // A convex combination keeps the strict order top > upper > lower > ... > bottom.
          if (base_a >= 0 && base_b >= 0) {
            const Slab ga = a.gaps_[base_a + g], gb = b.gaps_[base_b + g];
            if (ga.top > ga.bottom && gb.top > gb.bottom) {
              gap = {(1.f - w) * ga.top + w * gb.top, (1.f - w) * ga.bottom + w * gb.bottom};
            }
          }
        } else if (base_nearer >= 0) {  // the slab is the nearer pose's: so are its gaps
          gap = nearer.gaps_[base_nearer + g];
        }
        more = more && gap.top > gap.bottom;  // the first gap one pose lacks ends the list
        gaps[g] = more ? gap : Slab{-kInf, kInf};
      }
      if (!(gaps[0].top > gaps[0].bottom)) continue;
      // Kept gaps exist in the nearer pose (blended ones in both), so its normals are there.
      out->gap_texel_bits_[word] |= 1u << bit;
      out->gaps_.insert(out->gaps_.end(), gaps, gaps + layers);
      out->gap_normals_.insert(out->gap_normals_.end(), nearer.gap_normals_.begin() + base_nearer,
                               nearer.gap_normals_.begin() + base_nearer + layers);
    }
  }
  out->CountGapsBeforeWords();
}

size_t BodyMapSequence::memory_bytes() const {
  size_t bytes = sizeof(*this);
  for (const BodyMapCollider& pose : poses_) bytes += pose.memory_bytes();
  return bytes;
}

}  // namespace drape

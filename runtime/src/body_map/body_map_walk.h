#pragma once
// Private to the runtime: the continuous test's walk over the texels (or, with bilinear depth,
// the half-texels) a clipped segment crosses, with the per-cell slab solve (docs/ALGORITHMS.md
// §7.2). Included by body_map_query.cpp alone: the walk is inlined there.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>

#include "drape/runtime/body_map_collider.h"

namespace drape::detail {

inline constexpr float kWalkInf = std::numeric_limits<float>::infinity();

// A walk longer than this many cells uses the 8x8 min/max level to skip blocks; shorter walks go
// cell by cell (the block bookkeeping costs more than it saves there).
constexpr int kCoarseWalkMinCells = 12;

enum EntrySide : uint8_t { kEntryFront = 0, kEntryBack = 1, kEntrySideWall = 2 };

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
    return Select(left > 0, (static_cast<float>(c + edge_i) * cell - line.g0x) * line.inv_dx,
                  kWalkInf);
  };
  const auto cross_y = [&](int c, int left) {
    return Select(left > 0, (static_cast<float>(c + edge_j) * cell - line.g0y) * line.inv_dy,
                  kWalkInf);
  };
  float next_x = cross_x(ci, left_i);
  float next_y = cross_y(cj, left_j);
  float s_enter = s_begin;
  for (;;) {
    const float next = std::min(next_x, next_y);
    const float s_exit = std::min(std::max(next, s_enter), s_end);  // s_end when next = inf
    if (visit(ci, cj, s_enter, s_exit)) return true;
    if (next == kWalkInf) return false;
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

}  // namespace drape::detail

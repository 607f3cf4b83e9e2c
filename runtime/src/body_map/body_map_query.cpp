// BodyMapCollider::Query: the quick paths (a motion within one texel, a motion through air),
// the clip of the motion to the maps' box, the walk and the answer (docs/ALGORITHMS.md §7.2,
// §7.5); and the bilinear depth the walk samples (§7.3).
#include <algorithm>
#include <cmath>

#include "body_map/body_map_walk.h"
#include "drape/runtime/body_map_collider.h"
#include "drape/runtime/normal_encoding.h"

namespace drape {
namespace {

using detail::BodyMapWalk;
using detail::FloorToInt;
using detail::kEntryBack;
using detail::kEntryFront;
using detail::kEntrySideWall;

}  // namespace

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

// A point inside at its texel's interval, *depth metres from the nearer surface along z: when
// that is more than a texel and the texel touches air (a background texel: a silhouette; or a
// texel with gaps: air between two parts that closes here), the nearest point (stepped 1e-3
// texel into it) of a neighbouring texel whose column holds p.z outside, if nearer. Beside a
// silhouette or a closing gap, a point just inside the shell is millimetres from the side and up
// to the body's thickness from either surface along z; a push along z moves it that far across
// the body. The candidate is tested with IsInsideView itself, so the exit tests outside whatever
// the sampling and the gaps.
bool BodyMapCollider::NearerSideExit(Float3 p, float* depth, Float3* exit) const {
  if (!(*depth > texel_size_)) return false;
  const float u = (p.x - origin_x_) * inv_texel_size_, v = (p.y - origin_y_) * inv_texel_size_;
  const int i = static_cast<int>(u), j = static_cast<int>(v);  // p is inside: on the grid
  // Away from all air (most of a body's texels): no side to leave through.
  if (air_reach_[static_cast<size_t>(j) * width_ + static_cast<size_t>(i)] > kSideExitTexels) {
    return false;
  }
  constexpr float kInset = 1e-3f;  // texels: the exit belongs to the outside texel
  bool found = false;
  for (int dj = -kSideExitTexels; dj <= kSideExitTexels; ++dj) {
    for (int di = -kSideExitTexels; di <= kSideExitTexels; ++di) {
      if (di == 0 && dj == 0) continue;
      const float ci = static_cast<float>(i + di), cj = static_cast<float>(j + dj);
      const float eu = std::clamp(u, ci + kInset, ci + 1.f - kInset);
      const float ev = std::clamp(v, cj + kInset, cj + 1.f - kInset);
      const float du = (eu - u) * texel_size_, dv = (ev - v) * texel_size_;
      const float distance = std::sqrt(du * du + dv * dv);
      if (!(distance < *depth)) continue;
      const Float3 candidate{origin_x_ + eu * texel_size_, origin_y_ + ev * texel_size_, p.z};
      if (IsInsideView(candidate)) continue;
      *depth = distance;
      *exit = candidate;
      found = true;
    }
  }
  return found;
}

// The push-out through a texel's side: to the exit NearerSideExit found, with the horizontal
// direction of the push as the normal (the wall's; a silhouette's surface faces about that way).
void BodyMapCollider::PlaceOnSideExit(Float3 p, Float3 exit, ContactQuery* result) const {
  const float dx = exit.x - p.x, dy = exit.y - p.y;
  const float length = std::sqrt(dx * dx + dy * dy);
  result->point = exit;
  result->normal = length > 0.f ? Float3{dx / length, dy / length, 0.f} : result->normal;
  result->flags = static_cast<uint8_t>(result->flags | kCollisionSideWall);
}

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
  Float3 side_exit{};
  bool through_side = false;
  if (inside_end) {
    result->depth = std::min(slab.top - z1, z1 - slab.bottom);
    through_side = NearerSideExit(p1, &result->depth, &side_exit);
  }
  if (inside_start) {
    if (!inside_end) return false;  // left: whether it crossed the body is the walk's (§7.4)
    // Never left: pushed out to the nearest exit, along z or through a texel's side.
    const bool back = z1 - slab.bottom < slab.top - z1;
    result->contact = true;
    result->t = 0.f;
    result->flags = kCollisionStartedInside;
    result->point = Float3{p1.x, p1.y, back ? slab.bottom : slab.top};
    result->normal = TexelNormal(static_cast<uint32_t>(i), static_cast<uint32_t>(j), back);
    if (through_side) PlaceOnSideExit(p1, side_exit, result);
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
  if (view_axis_ == BodyMapViewAxis::kZ) return QueryView(p0, p1);
  ContactQuery result = QueryView(ToBodyMapView(view_axis_, p0), ToBodyMapView(view_axis_, p1));
  result.point = FromBodyMapView(view_axis_, result.point);
  result.normal = FromBodyMapView(view_axis_, result.normal);
  return result;
}

ContactQuery BodyMapCollider::QueryView(Float3 p0, Float3 p1) const {
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
  result.inside_end = IsInsideView(p1);
  ClippedMotion clip;
  if (!ClipMotion(p0, p1, &clip)) return;
  const Float3 q0 = clip.q0, q1 = clip.q1;
  const double t_start = clip.t_start, t_end = clip.t_end;
  const bool start_inside = t_start == 0.0 && IsInsideView(p0);

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

  // Penetration of p1: to the nearer surface along z, or through a texel's side when that is
  // nearer (the start-inside push-out uses the same numbers).
  Interval p1_interval{0.f, 0.f, kFrontSlot, kBackSlot};
  int p1_ci = 0, p1_cj = 0;
  const float p1_u = (p1.x - origin_x_) * inv_texel_size_;
  const float p1_v = (p1.y - origin_y_) * inv_texel_size_;
  Float3 side_exit{};
  bool through_side = false;
  if (result.inside_end) {
    const float cells = sampling_ == DepthSampling::kNearest ? 1.f : 2.f;
    p1_ci = static_cast<int>(p1_u * cells);
    p1_cj = static_cast<int>(p1_v * cells);
    p1_interval = interval_at(p1_ci, p1_cj, p1_u, p1_v, p1.z);
    result.depth = std::min(p1_interval.top - p1.z, p1.z - p1_interval.bottom);
    through_side = NearerSideExit(p1, &result.depth, &side_exit);
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
      // whose surface is nearer in z describes the body better (docs/ALGORITHMS.md §7.2).
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
    // push p1 out to its nearest exit, along z to the nearer surface of its interval or through
    // a texel's side.
    const bool back = p1.z - p1_interval.bottom < p1_interval.top - p1.z;
    result.contact = true;
    result.t = 0.f;
    result.flags = start_inside ? kCollisionStartedInside : kCollisionNone;
    result.point = Float3{p1.x, p1.y, back ? p1_interval.bottom : p1_interval.top};
    result.normal =
        normal_at(p1_ci, p1_cj, p1_u, p1_v, back ? p1_interval.bottom_slot : p1_interval.top_slot);
    if (through_side) PlaceOnSideExit(p1, side_exit, &result);
  } else if (start_inside) {
    // Started inside and left with no entry. Leaving the body, it left through the surface it
    // started nearer to, or was inside for about the depth it started at; crossing it from inside
    // the shell (a particle the solver left within epsilon of a limb, pushed through it) it left
    // elsewhere after more than half the body's thickness there: then it goes back out along z
    // to the nearer surface of its start (docs §7.4). The reversed segment's first entry is where
    // this one left (it never re-entered).
    ContactQuery reverse;
    WalkInto(p1, p0, &reverse);
    const float cells = sampling_ == DepthSampling::kNearest ? 1.f : 2.f;
    const float p0_u = (p0.x - origin_x_) * inv_texel_size_;
    const float p0_v = (p0.y - origin_y_) * inv_texel_size_;
    const int p0_ci = static_cast<int>(p0_u * cells), p0_cj = static_cast<int>(p0_v * cells);
    const Interval start = interval_at(p0_ci, p0_cj, p0_u, p0_v, p0.z);
    const double dx = double{p1.x} - p0.x, dy = double{p1.y} - p0.y, dz = double{p1.z} - p0.z;
    const double inside = (1.0 - reverse.t) * std::sqrt(dx * dx + dy * dy + dz * dz);
    const bool back = p0.z - start.bottom < start.top - p0.z;
    const bool through_near = back ? reverse.point.z <= start.bottom : reverse.point.z >= start.top;
    if (reverse.contact && !through_near && inside > 0.5 * (double{start.top} - start.bottom)) {
      result.contact = true;
      result.t = 0.f;
      result.flags = kCollisionStartedInside;
      result.point = Float3{p0.x, p0.y, back ? start.bottom : start.top};
      result.normal =
          normal_at(p0_ci, p0_cj, p0_u, p0_v, back ? start.bottom_slot : start.top_slot);
    }
  }
}

}  // namespace drape

// Paper B's response ray: from the map table's source through the particle, against the hull
// triangles listed in its cell (docs/ALGORITHMS.md §5.3).
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "common/branchless.h"
#include "drape/runtime/hull_collider_set.h"
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace drape {
namespace {

using detail::SelectIf;

constexpr float kPi = 3.14159265358979323846f;

// ---- Watertight ray/triangle test (Woop, Benthin, Wald 2013) for a ray S + t d, t > 0. The
// axes are permuted so that d's largest component is kz (indexing small arrays, no branches).
struct WatertightRay {
  int kx = 0, ky = 1, kz = 2;
  float sx = 0.f, sy = 0.f, sz = 1.f;
  float origin[3] = {0.f, 0.f, 0.f};
};
WatertightRay MakeRay(Float3 origin, Float3 d) {
  WatertightRay r;
  r.origin[0] = origin.x;
  r.origin[1] = origin.y;
  r.origin[2] = origin.z;
  const float dir[3] = {d.x, d.y, d.z};
  const float ax = std::fabs(d.x), ay = std::fabs(d.y), az = std::fabs(d.z);
  // Integer selects (conditional moves): the axis choice is data dependent and unpredictable.
  const int k_xy = ay > az ? 1 : 2, k_xz = ax > az ? 0 : 2;
  r.kz = ax > ay ? k_xz : k_xy;
  const int next = r.kz == 2 ? 0 : r.kz + 1;
  const int after = next == 2 ? 0 : next + 1;
  const bool flip = dir[r.kz] < 0.f;  // keep the winding
  r.kx = flip ? after : next;
  r.ky = flip ? next : after;
  r.sx = dir[r.kx] / dir[r.kz];
  r.sy = dir[r.ky] / dir[r.kz];
  r.sz = 1.f / dir[r.kz];
  return r;
}
// For a block of `lanes` (1 to 4) listed triangles: all-ones in the used lanes, and the list
// entry each lane loads (unused lanes repeat the last used one).
alignas(16) constexpr int32_t kLaneMasks[5][4] = {
    {0, 0, 0, 0}, {-1, 0, 0, 0}, {-1, -1, 0, 0}, {-1, -1, -1, 0}, {-1, -1, -1, -1}};
constexpr uint32_t kLaneSource[5][4] = {
    {0, 0, 0, 0}, {0, 0, 0, 0}, {0, 1, 1, 1}, {0, 1, 2, 2}, {0, 1, 2, 3}};
// Returns true and the ray parameter t > 0 on a hit (either side of the triangle).
bool IntersectWatertight(const WatertightRay& r, const float* tri, float* t_hit) {
  const float a[3] = {tri[0] - r.origin[0], tri[1] - r.origin[1], tri[2] - r.origin[2]};
  const float b[3] = {tri[3] - r.origin[0], tri[4] - r.origin[1], tri[5] - r.origin[2]};
  const float c[3] = {tri[6] - r.origin[0], tri[7] - r.origin[1], tri[8] - r.origin[2]};
  const float az = a[r.kz], bz = b[r.kz], cz = c[r.kz];
  const float ax = a[r.kx] - r.sx * az, ay = a[r.ky] - r.sy * az;
  const float bx = b[r.kx] - r.sx * bz, by = b[r.ky] - r.sy * bz;
  const float cx = c[r.kx] - r.sx * cz, cy = c[r.ky] - r.sy * cz;
  float u = cx * by - cy * bx;
  float v = ax * cy - ay * cx;
  float w = bx * ay - by * ax;
  if (u == 0.f || v == 0.f || w == 0.f) {
    u = static_cast<float>(double(cx) * by - double(cy) * bx);
    v = static_cast<float>(double(ax) * cy - double(ay) * cx);
    w = static_cast<float>(double(bx) * ay - double(by) * ax);
  }
  if ((u < 0.f || v < 0.f || w < 0.f) && (u > 0.f || v > 0.f || w > 0.f)) return false;
  const float det = u + v + w;
  if (det == 0.f) return false;
  const float t_scaled = u * (r.sz * az) + v * (r.sz * bz) + w * (r.sz * cz);
  if (det > 0.f ? !(t_scaled > 0.f) : !(t_scaled < 0.f)) return false;
  *t_hit = t_scaled / det;
  return true;
}

// atan2 by a minimax polynomial on [0, 1] after octant reduction: max error about 1e-5 rad,
// far inside the map table builder's cell margin (>= 1e-4 rad). Result in [-pi, pi].
float FastAtan2(float y, float x) {
  const float ax = std::fabs(x), ay = std::fabs(y);
  const float hi = std::max(ax, ay), lo = std::min(ax, ay);
  if (!(hi > 0.f)) return 0.f;
  const float a = lo / hi;
  const float s = a * a;
  float r = ((-0.0464964749f * s + 0.15931422f) * s - 0.327622764f) * s * a + a;
  // The octant corrections as selects, not branches (the signs are unpredictable).
  r = SelectIf(ay > ax, 1.57079637f - r, r);
  r = SelectIf(x < 0.f, 3.14159274f - r, r);
  return SelectIf(y < 0.f, -r, r);
}

}  // namespace

bool HullColliderSet::MapRay(const HullRecord& h, Float3 p, Float3* point, uint32_t* plane) const {
  Float3 source = h.map_origin;
  uint32_t row = 0;
  if (h.map_kind == MapTableKind::kCylinder) {
    const float z = Dot(p - h.map_origin, h.map_axis);
    const float clamped = std::min(std::max(z, 0.f), h.map_length);
    source = h.map_origin + h.map_axis * clamped;
    if (h.map_length > 0.f)
      row = std::min(h.map_rows - 1, static_cast<uint32_t>(clamped / h.map_length *
                                                           static_cast<float>(h.map_rows)));
  }
  const Float3 d = p - source;
  const float length = Length(d);
  if (!(length > 1e-12f)) return false;
  const float along_reference = Dot(d, h.map_reference), along_binormal = Dot(d, h.map_binormal);
  if (h.map_kind == MapTableKind::kSphere) {
    const float radial =
        std::sqrt(along_reference * along_reference + along_binormal * along_binormal);
    const float theta = FastAtan2(radial, Dot(d, h.map_axis));  // in [0, pi]
    row = std::min(h.map_rows - 1, static_cast<uint32_t>(theta * h.map_row_scale));
  }
  float phi = FastAtan2(along_binormal, along_reference);
  phi = SelectIf(phi < 0.f, phi + 2.f * kPi, phi);
  const uint32_t col = std::min(h.map_cols - 1, static_cast<uint32_t>(phi * h.map_col_scale));
  const uint32_t cell = h.map_cell_begin + row * h.map_cols + col;
  const WatertightRay ray = MakeRay(source, d);
  float best = std::numeric_limits<float>::infinity();
  uint32_t best_triangle = 0;
  const float* triangles = &ray_triangles_[9 * size_t(h.triangle_begin)];
  const uint32_t list_begin = map_cell_offsets_[cell], list_end = map_cell_offsets_[cell + 1];
#if defined(__SSE2__)
  // Four listed triangles per iteration, each lane the scalar test's arithmetic in the same order
  // (so the same bits); a lane with an edge function of exactly 0 is redone by the scalar test
  // (its double fallback). The nearest hit wins, the first in list order on ties, as in the loop.
  const __m128 origin[3] = {_mm_set1_ps(ray.origin[0]), _mm_set1_ps(ray.origin[1]),
                            _mm_set1_ps(ray.origin[2])};
  const __m128 shear_x = _mm_set1_ps(ray.sx), shear_y = _mm_set1_ps(ray.sy);
  const __m128 scale_z = _mm_set1_ps(ray.sz), zero = _mm_setzero_ps();
  for (uint32_t e = list_begin; e < list_end; e += 4) {
    const uint32_t lanes = std::min(4u, list_end - e);
    uint32_t index[4];
    for (uint32_t l = 0; l < 4; ++l) index[l] = map_triangles_[e + kLaneSource[lanes][l]];
    // vertex[k][axis]: vertex k of the four triangles minus the origin (the loads read 4 floats;
    // ray_triangles_ is padded so the last triangle's third vertex stays in bounds).
    __m128 vertex[3][3];
    for (int k = 0; k < 3; ++k) {
      __m128 r0 = _mm_loadu_ps(triangles + 9 * size_t(index[0]) + 3 * k);
      __m128 r1 = _mm_loadu_ps(triangles + 9 * size_t(index[1]) + 3 * k);
      __m128 r2 = _mm_loadu_ps(triangles + 9 * size_t(index[2]) + 3 * k);
      __m128 r3 = _mm_loadu_ps(triangles + 9 * size_t(index[3]) + 3 * k);
      _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
      vertex[k][0] = _mm_sub_ps(r0, origin[0]);
      vertex[k][1] = _mm_sub_ps(r1, origin[1]);
      vertex[k][2] = _mm_sub_ps(r2, origin[2]);
    }
    const __m128 az = vertex[0][ray.kz], bz = vertex[1][ray.kz], cz = vertex[2][ray.kz];
    const __m128 ax = _mm_sub_ps(vertex[0][ray.kx], _mm_mul_ps(shear_x, az));
    const __m128 ay = _mm_sub_ps(vertex[0][ray.ky], _mm_mul_ps(shear_y, az));
    const __m128 bx = _mm_sub_ps(vertex[1][ray.kx], _mm_mul_ps(shear_x, bz));
    const __m128 by = _mm_sub_ps(vertex[1][ray.ky], _mm_mul_ps(shear_y, bz));
    const __m128 cx = _mm_sub_ps(vertex[2][ray.kx], _mm_mul_ps(shear_x, cz));
    const __m128 cy = _mm_sub_ps(vertex[2][ray.ky], _mm_mul_ps(shear_y, cz));
    const __m128 u = _mm_sub_ps(_mm_mul_ps(cx, by), _mm_mul_ps(cy, bx));
    const __m128 v = _mm_sub_ps(_mm_mul_ps(ax, cy), _mm_mul_ps(ay, cx));
    const __m128 w = _mm_sub_ps(_mm_mul_ps(bx, ay), _mm_mul_ps(by, ax));
    const int valid = (1 << lanes) - 1;
    int redo = _mm_movemask_ps(_mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(u, zero), _mm_cmpeq_ps(v, zero)),
                                         _mm_cmpeq_ps(w, zero))) &
               valid;
    const __m128 negative =
        _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(u, zero), _mm_cmplt_ps(v, zero)), _mm_cmplt_ps(w, zero));
    const __m128 positive =
        _mm_or_ps(_mm_or_ps(_mm_cmpgt_ps(u, zero), _mm_cmpgt_ps(v, zero)), _mm_cmpgt_ps(w, zero));
    const __m128 det = _mm_add_ps(_mm_add_ps(u, v), w);
    const __m128 t_scaled = _mm_add_ps(
        _mm_add_ps(_mm_mul_ps(u, _mm_mul_ps(scale_z, az)), _mm_mul_ps(v, _mm_mul_ps(scale_z, bz))),
        _mm_mul_ps(w, _mm_mul_ps(scale_z, cz)));
    const __m128 det_positive = _mm_cmpgt_ps(det, zero);
    const __m128 forward = _mm_or_ps(_mm_and_ps(det_positive, _mm_cmpgt_ps(t_scaled, zero)),
                                     _mm_andnot_ps(det_positive, _mm_cmplt_ps(t_scaled, zero)));
    const __m128 accepted = _mm_andnot_ps(_mm_and_ps(negative, positive),
                                          _mm_and_ps(_mm_cmpneq_ps(det, zero), forward));
    const __m128 t_lanes = _mm_div_ps(t_scaled, det);
    // A NaN t (only with overflowing coordinates) goes to the scalar loop too: the vector minimum
    // below would not skip it the way "hit < best" does.
    redo |= _mm_movemask_ps(_mm_and_ps(accepted, _mm_cmpunord_ps(t_lanes, t_lanes))) & valid;
    const int hits = _mm_movemask_ps(accepted) & valid & ~redo;
    if (redo == 0) {
      // The smallest t of the accepted lanes (+inf for the others) and its first lane: what the
      // sequential strict "hit < best" keeps.
      const __m128 lane_valid = _mm_load_ps(reinterpret_cast<const float*>(kLaneMasks[lanes]));
      const __m128 kept = _mm_and_ps(accepted, lane_valid);
      const __m128 t_kept =
          _mm_or_ps(_mm_and_ps(kept, t_lanes), _mm_andnot_ps(kept, _mm_set1_ps(best)));
      __m128 t_min = _mm_min_ps(t_kept, _mm_shuffle_ps(t_kept, t_kept, _MM_SHUFFLE(2, 3, 0, 1)));
      t_min = _mm_min_ps(t_min, _mm_shuffle_ps(t_min, t_min, _MM_SHUFFLE(1, 0, 3, 2)));
      const float lane_best = _mm_cvtss_f32(t_min);
      const int at = _mm_movemask_ps(_mm_and_ps(kept, _mm_cmpeq_ps(t_kept, t_min)));
      const uint32_t first = static_cast<uint32_t>(__builtin_ctz(static_cast<unsigned>(at | 16)));
      const bool better = lane_best < best;
      best_triangle = better ? index[first & 3] : best_triangle;
      best = better ? lane_best : best;
      continue;
    }
    alignas(16) float t[4];
    _mm_store_ps(t, t_lanes);
    for (uint32_t l = 0; l < lanes; ++l) {
      float hit = t[l];
      const bool is_hit = (redo >> l) & 1
                              ? IntersectWatertight(ray, triangles + 9 * size_t(index[l]), &hit)
                              : ((hits >> l) & 1) != 0;
      if (is_hit && hit < best) {
        best = hit;
        best_triangle = index[l];
      }
    }
  }
#else
  for (uint32_t e = list_begin; e < list_end; ++e) {
    const uint32_t t = map_triangles_[e];
    float hit;
    if (IntersectWatertight(ray, triangles + 9 * size_t(t), &hit) && hit < best) {
      best = hit;
      best_triangle = t;
    }
  }
#endif
  if (!(best < std::numeric_limits<float>::infinity())) return false;
  *point = source + d * best;
  *plane = ray_triangle_planes_[h.triangle_begin + best_triangle];
  return true;
}

}  // namespace drape

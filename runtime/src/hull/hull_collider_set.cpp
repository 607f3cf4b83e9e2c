#include "drape/runtime/hull_collider_set.h"

#include "drape/runtime/exact_orientation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <new>
#include <string>
#include <utility>

#include "common/cpu_features.h"
#include "body_map/lanes/sse2_lanes.h"
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#endif

namespace drape {
namespace {

constexpr float kPi = 3.14159265358979323846f;
constexpr uint32_t kMaxPlanes = 4096;
constexpr uint32_t kPlanePad = 8;        // planes per hull padded to a multiple of this
constexpr float kPadOffset = 3.0e38f;    // padded planes: 0.p - 3e38, never the max
constexpr float kPadCenter = 3.0e38f;    // padded broad-phase spheres: never reached
constexpr double kScrewMinAngle = 1e-4;  // radians; below: pivot about the OBB centre
constexpr float kUnitTolerance = 1e-3f;

using detail::CpuHasAvx2;

bool Finite(Float3 a) { return IsFinite(a); }
bool Finite(const Mat34& m) {
  for (float v : m.m)
    if (!std::isfinite(v)) return false;
  return true;
}
std::string At(const char* kind, size_t index, const std::string& field) {
  return std::string(kind) + "[" + std::to_string(index) + "]." + field;
}
Status Invalid(const std::string& where, const std::string& why) {
  return Status(StatusCode::kInvalidArgument, "HullColliderSet: " + where + " " + why);
}

// ---- Rigid transforms in double.
struct QuatD {
  double x = 0, y = 0, z = 0, w = 1;
};
QuatD Mul(const QuatD& a, const QuatD& b) {
  return {
      a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
      a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}
QuatD Conjugate(const QuatD& q) { return {-q.x, -q.y, -q.z, q.w}; }
QuatD NormalizeQ(const QuatD& q) {
  const double len = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (!(len > 1e-300)) return QuatD{};
  return {q.x / len, q.y / len, q.z / len, q.w / len};
}
// The rotation nearest to the 3x3 part of m (Shepperd's method on the possibly non-orthonormal
// matrix, then normalised): scale and shear are dropped.
QuatD RotationOf(const Mat34& m) {
  const double m00 = m.m[0], m01 = m.m[1], m02 = m.m[2];
  const double m10 = m.m[4], m11 = m.m[5], m12 = m.m[6];
  const double m20 = m.m[8], m21 = m.m[9], m22 = m.m[10];
  // Normalise the columns first so a uniform scale does not bias the trace test.
  const double c0 = std::sqrt(m00 * m00 + m10 * m10 + m20 * m20);
  const double c1 = std::sqrt(m01 * m01 + m11 * m11 + m21 * m21);
  const double c2 = std::sqrt(m02 * m02 + m12 * m12 + m22 * m22);
  const double s0 = c0 > 1e-30 ? 1.0 / c0 : 1.0, s1 = c1 > 1e-30 ? 1.0 / c1 : 1.0,
               s2 = c2 > 1e-30 ? 1.0 / c2 : 1.0;
  const double a00 = m00 * s0, a01 = m01 * s1, a02 = m02 * s2;
  const double a10 = m10 * s0, a11 = m11 * s1, a12 = m12 * s2;
  const double a20 = m20 * s0, a21 = m21 * s1, a22 = m22 * s2;
  const double trace = a00 + a11 + a22;
  QuatD q;
  if (trace > 0.0) {
    const double s = std::sqrt(trace + 1.0) * 2.0;
    q = {(a21 - a12) / s, (a02 - a20) / s, (a10 - a01) / s, 0.25 * s};
  } else if (a00 > a11 && a00 > a22) {
    const double s = std::sqrt(1.0 + a00 - a11 - a22) * 2.0;
    q = {0.25 * s, (a01 + a10) / s, (a02 + a20) / s, (a21 - a12) / s};
  } else if (a11 > a22) {
    const double s = std::sqrt(1.0 + a11 - a00 - a22) * 2.0;
    q = {(a01 + a10) / s, 0.25 * s, (a12 + a21) / s, (a02 - a20) / s};
  } else {
    const double s = std::sqrt(1.0 + a22 - a00 - a11) * 2.0;
    q = {(a02 + a20) / s, (a12 + a21) / s, 0.25 * s, (a10 - a01) / s};
  }
  return NormalizeQ(q);
}
struct Vec3D {
  double x = 0, y = 0, z = 0;
};
Vec3D ToD(Float3 a) { return {a.x, a.y, a.z}; }
Float3 ToF(const Vec3D& a) {
  return {static_cast<float>(a.x), static_cast<float>(a.y), static_cast<float>(a.z)};
}
Vec3D operator+(const Vec3D& a, const Vec3D& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec3D operator-(const Vec3D& a, const Vec3D& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3D operator*(const Vec3D& a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double DotD(const Vec3D& a, const Vec3D& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3D CrossD(const Vec3D& a, const Vec3D& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double LengthD(const Vec3D& a) { return std::sqrt(DotD(a, a)); }
Vec3D Rotate(const QuatD& q, const Vec3D& v) {
  const Vec3D u{q.x, q.y, q.z};
  const Vec3D t = CrossD(u, v) * 2.0;
  return v + t * q.w + CrossD(u, t);
}
struct RigidD {
  QuatD rotation;
  Vec3D translation;
};
Vec3D Apply(const RigidD& r, const Vec3D& p) { return Rotate(r.rotation, p) + r.translation; }
Mat34 ToMat34(const RigidD& r) {
  const QuatD& q = r.rotation;
  const double xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
  const double xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
  const double wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
  const double e[12] = {1.0 - 2.0 * (yy + zz), 2.0 * (xy - wz),       2.0 * (xz + wy),
                        r.translation.x,       2.0 * (xy + wz),       1.0 - 2.0 * (xx + zz),
                        2.0 * (yz - wx),       r.translation.y,       2.0 * (xz - wy),
                        2.0 * (yz + wx),       1.0 - 2.0 * (xx + yy), r.translation.z};
  Mat34 m;
  for (int i = 0; i < 12; ++i) m.m[i] = static_cast<float>(e[i]);
  return m;
}
// world -> frame for a rigid frame -> world, in double, then rounded.
Mat34 InverseToMat34(const RigidD& r) {
  RigidD inv;
  inv.rotation = Conjugate(r.rotation);
  inv.translation = Rotate(inv.rotation, r.translation) * -1.0;
  return ToMat34(inv);
}
// world -> OBB frame: p_obb[k] = axes[k] . (to_collider(p) - center).
Mat34 ObbFromWorld(const RigidD& collider_to_world, Float3 center, const Float3 axes[3]) {
  RigidD inv;
  inv.rotation = Conjugate(collider_to_world.rotation);
  inv.translation = Rotate(inv.rotation, collider_to_world.translation) * -1.0;
  Mat34 m;
  const Vec3D c = ToD(center);
  // Columns of the world->collider rotation applied to the basis vectors.
  const Vec3D ex = Rotate(inv.rotation, {1, 0, 0}), ey = Rotate(inv.rotation, {0, 1, 0}),
              ez = Rotate(inv.rotation, {0, 0, 1});
  for (int k = 0; k < 3; ++k) {
    const Vec3D a = ToD(axes[k]);
    m.m[4 * k + 0] = static_cast<float>(DotD(a, ex));
    m.m[4 * k + 1] = static_cast<float>(DotD(a, ey));
    m.m[4 * k + 2] = static_cast<float>(DotD(a, ez));
    m.m[4 * k + 3] = static_cast<float>(DotD(a, inv.translation - c));
  }
  return m;
}

// condition ? if_true : if_false without a branch (bit masks on SSE2; a plain select elsewhere).
inline float SelectIf(bool condition, float if_true, float if_false) {
#if defined(__SSE2__)
  const __m128 mask = _mm_castsi128_ps(_mm_set1_epi32(-static_cast<int>(condition)));
  return _mm_cvtss_f32(
      _mm_or_ps(_mm_and_ps(mask, _mm_set_ss(if_true)), _mm_andnot_ps(mask, _mm_set_ss(if_false))));
#else
  return condition ? if_true : if_false;
#endif
}

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

// Moves p along the unit normal n until signed(p) >= 0 in float (a handful of steps at most).
template <typename SignedDistance>
Float3 NudgeOut(Float3 p, Float3 n, float scale, SignedDistance signed_distance) {
  float f = signed_distance(p);
  float step = 1e-7f * scale;
  // The first step is taken unconditionally and kept by selects: a point projected onto a plane
  // lands on either side of it by rounding, so a branch here is mispredicted half of the time.
  // Same steps and values as the plain loop.
  const Float3 moved = p + n * std::max(-f, step);
  const float f_moved = signed_distance(moved);
  const bool needed = f < 0.f;
  p = {SelectIf(needed, moved.x, p.x), SelectIf(needed, moved.y, p.y),
       SelectIf(needed, moved.z, p.z)};
  f = SelectIf(needed, f_moved, f);
  step = SelectIf(needed, step * 2.f, step);
  for (int k = 1; f < 0.f && k < 24; ++k) {
    p = p + n * std::max(-f, step);
    f = signed_distance(p);
    step *= 2.f;
  }
  return p;
}

}  // namespace

// =================================================================================================
// Build and validation
// =================================================================================================

void HullColliderSet::Clear() { *this = HullColliderSet(); }

Status HullColliderSet::ValidateOptions(const HullColliderOptions& options) const {
  if (options.gauss_seidel_passes < 1 || options.gauss_seidel_passes > 16)
    return Invalid("options.gauss_seidel_passes", "is not in [1, 16]");
  if (static_cast<uint8_t>(options.inside_test) > 1)
    return Invalid("options.inside_test", "is unknown");
  if (static_cast<uint8_t>(options.response) > 1) return Invalid("options.response", "is unknown");
  if (static_cast<uint8_t>(options.entry_response) > 1)
    return Invalid("options.entry_response", "is unknown");
  for (size_t i = 0; i < hulls_.size(); ++i) {
    if (options.inside_test == InsideTest::kKirkpatrick && !hulls_[i].has_hierarchy)
      return Invalid(At("hulls", i, "upper/lower"),
                     "are empty but the Kirkpatrick inside test was chosen");
    if (options.response == HullResponse::kMapTableRay && !hulls_[i].has_map)
      return Invalid(At("hulls", i, "map"), "is empty but the map-table response was chosen");
  }
  return Status::Ok();
}

Status HullColliderSet::SetOptions(const HullColliderOptions& options) {
  Status status = ValidateOptions(options);
  if (status.ok()) {
    options_ = options;
    simd_level_ = options.allow_avx2 && CpuHasAvx2() ? 2 : 1;
  }
  return status;
}

namespace {

Status ValidateHierarchy(const KirkpatrickHierarchy& k, size_t plane_count, const std::string& at) {
  const size_t vertices = k.vertices_uv.size() / 2;
  const size_t nodes = k.node_triangles.size() / 3;
  if (k.vertices_uv.size() % 2 != 0) return Invalid(at + ".vertices_uv", "size is odd");
  if (k.node_triangles.size() % 3 != 0 || nodes == 0)
    return Invalid(at + ".node_triangles", "size is 0 or not a multiple of 3");
  if (nodes > (1u << 24)) return Invalid(at + ".node_triangles", "has more than 2^24 nodes");
  if (k.child_offsets.size() != nodes + 1 || k.child_offsets[0] != 0 ||
      k.child_offsets[nodes] != k.children.size())
    return Invalid(at + ".child_offsets",
                   "do not have node_count + 1 entries from 0 to the child count");
  if (k.leaf_planes.size() != nodes) return Invalid(at + ".leaf_planes", "size is not node_count");
  if (!(k.root_begin < k.root_end && k.root_end <= nodes))
    return Invalid(at + ".root_begin/root_end", "range is empty or out of range");
  for (size_t i = 0; i < k.vertices_uv.size(); ++i)
    if (!std::isfinite(k.vertices_uv[i]))
      return Invalid(at + ".vertices_uv[" + std::to_string(i) + "]", "is not finite");
  for (size_t i = 0; i < k.node_triangles.size(); ++i)
    if (k.node_triangles[i] >= vertices)
      return Invalid(at + ".node_triangles[" + std::to_string(i) + "]", "is out of range");
  bool has_face = false;
  for (size_t n = 0; n < nodes; ++n) {
    if (k.child_offsets[n] > k.child_offsets[n + 1])
      return Invalid(at + ".child_offsets[" + std::to_string(n) + "]", "decreases");
    for (uint32_t e = k.child_offsets[n]; e < k.child_offsets[n + 1]; ++e)
      if (k.children[e] >= n)
        return Invalid(at + ".children[" + std::to_string(e) + "]", "is not below its parent node");
    if (k.leaf_planes[n] < -1 || k.leaf_planes[n] >= static_cast<int64_t>(plane_count))
      return Invalid(at + ".leaf_planes[" + std::to_string(n) + "]", "is not -1 or a plane index");
    if (k.leaf_planes[n] >= 0 && k.child_offsets[n] == k.child_offsets[n + 1]) has_face = true;
    const uint32_t* t = &k.node_triangles[3 * n];
    const float* uv = k.vertices_uv.data();
    if (Orient2dExact(uv[2 * t[0]], uv[2 * t[0] + 1], uv[2 * t[1]], uv[2 * t[1] + 1], uv[2 * t[2]],
                      uv[2 * t[2] + 1]) <= 0)
      return Invalid(at + ".node_triangles[" + std::to_string(n) + "]",
                     "is not strictly counter-clockwise");
  }
  if (!has_face) return Invalid(at, "has no leaf on a hull plane");
  return Status::Ok();
}

Status ValidateHull(const HullColliderData& h, size_t index, uint32_t joint_count) {
  if (h.joint < 0 || static_cast<uint32_t>(h.joint) >= joint_count)
    return Invalid(At("hulls", index, "joint"), "is out of range");
  if (!Finite(h.bind_frame)) return Invalid(At("hulls", index, "bind_frame"), "is not finite");
  if (h.planes.empty() || h.planes.size() > kMaxPlanes)
    return Invalid(At("hulls", index, "planes"), "count is not in [1, 4096]");
  for (size_t i = 0; i < h.planes.size(); ++i) {
    const Plane& p = h.planes[i];
    if (!Finite(p.normal) || !std::isfinite(p.offset))
      return Invalid(At("hulls", index, "planes[" + std::to_string(i) + "]"), "is not finite");
    if (std::fabs(Length(p.normal) - 1.f) > kUnitTolerance)
      return Invalid(At("hulls", index, "planes[" + std::to_string(i) + "].normal"),
                     "is not unit length");
  }
  for (size_t i = 0; i < h.vertices.size(); ++i)
    if (!Finite(h.vertices[i]))
      return Invalid(At("hulls", index, "vertices[" + std::to_string(i) + "]"), "is not finite");
  if (h.triangles.size() % 3 != 0)
    return Invalid(At("hulls", index, "triangles"), "size is not a multiple of 3");
  for (size_t i = 0; i < h.triangles.size(); ++i)
    if (h.triangles[i] >= h.vertices.size())
      return Invalid(At("hulls", index, "triangles[" + std::to_string(i) + "]"), "is out of range");
  if (h.triangle_planes.size() != h.triangles.size() / 3)
    return Invalid(At("hulls", index, "triangle_planes"), "size is not the triangle count");
  for (size_t i = 0; i < h.triangle_planes.size(); ++i)
    if (h.triangle_planes[i] >= h.planes.size())
      return Invalid(At("hulls", index, "triangle_planes[" + std::to_string(i) + "]"),
                     "is out of range");
  const Obb& o = h.obb;
  if (!Finite(o.center) || !Finite(o.half_extents) || !Finite(o.axes[0]) || !Finite(o.axes[1]) ||
      !Finite(o.axes[2]))
    return Invalid(At("hulls", index, "obb"), "is not finite");
  if (o.half_extents.x < 0.f || o.half_extents.y < 0.f || o.half_extents.z < 0.f)
    return Invalid(At("hulls", index, "obb.half_extents"), "are negative");
  for (int a = 0; a < 3; ++a) {
    if (std::fabs(Length(o.axes[a]) - 1.f) > kUnitTolerance)
      return Invalid(At("hulls", index, "obb.axes"), "are not unit length");
    for (int b = a + 1; b < 3; ++b)
      if (std::fabs(Dot(o.axes[a], o.axes[b])) > kUnitTolerance)
        return Invalid(At("hulls", index, "obb.axes"), "are not orthogonal");
  }
  const bool upper = !h.upper.node_triangles.empty(), lower = !h.lower.node_triangles.empty();
  if (upper != lower)
    return Invalid(At("hulls", index, "upper/lower"), "only one hierarchy is present");
  if (upper) {
    if (!Finite(h.projection_axis) || !Finite(h.projection_u) || !Finite(h.projection_v))
      return Invalid(At("hulls", index, "projection axes"), "are not finite");
    Status s = ValidateHierarchy(h.upper, h.planes.size(), At("hulls", index, "upper"));
    if (!s.ok()) return s;
    s = ValidateHierarchy(h.lower, h.planes.size(), At("hulls", index, "lower"));
    if (!s.ok()) return s;
    // Every hierarchy vertex but the enclosing triangle's corners (the root's vertices) is the
    // projection of a hull vertex, bit for bit: the exact ties and the fill leaves' guard planes
    // rely on it, and a hull whose OBB or axes changed after the bake fails here.
    std::vector<uint64_t> projected;
    for (const Float3& v : h.vertices) {
      const HullUv q = ProjectHullUv(v, h.obb.center, h.projection_u, h.projection_v);
      uint32_t bits[2];
      std::memcpy(&bits[0], &q.u, sizeof(float));
      std::memcpy(&bits[1], &q.v, sizeof(float));
      projected.push_back((uint64_t(bits[0]) << 32) | bits[1]);
    }
    std::sort(projected.begin(), projected.end());
    for (const KirkpatrickHierarchy* k : {&h.upper, &h.lower}) {
      const uint32_t* root = &k->node_triangles[3 * k->root_begin];
      for (uint32_t v : k->node_triangles) {
        if (v == root[0] || v == root[1] || v == root[2]) continue;
        uint32_t bits[2];
        std::memcpy(bits, &k->vertices_uv[2 * v], sizeof(bits));
        if (!std::binary_search(projected.begin(), projected.end(),
                                (uint64_t(bits[0]) << 32) | bits[1]))
          return Invalid(At("hulls", index, k == &h.upper ? "upper" : "lower"),
                         "has a vertex that is not the projection of a hull vertex (stale bake?)");
      }
    }
  }
  const MapTableData& t = h.map;
  const bool has_map = !(t.rows == 0 && t.cols == 0 && t.cell_offsets.empty());
  if (has_map) {
    const std::string at = At("hulls", index, "map");
    if (static_cast<uint8_t>(t.kind) > 1) return Invalid(at + ".kind", "is unknown");
    if (t.rows < 1 || t.cols < 1 || static_cast<uint64_t>(t.rows) * t.cols > (1u << 20))
      return Invalid(at, "rows x cols is not in [1, 2^20]");
    const size_t cells = static_cast<size_t>(t.rows) * t.cols;
    if (t.cell_offsets.size() != cells + 1 || t.cell_offsets[0] != 0 ||
        t.cell_offsets[cells] != t.cell_triangles.size())
      return Invalid(at + ".cell_offsets",
                     "do not have rows*cols + 1 entries from 0 to the list size");
    for (size_t c = 0; c < cells; ++c)
      if (t.cell_offsets[c] > t.cell_offsets[c + 1])
        return Invalid(at + ".cell_offsets[" + std::to_string(c) + "]", "decreases");
    for (size_t i = 0; i < t.cell_triangles.size(); ++i)
      if (t.cell_triangles[i] >= h.triangles.size() / 3)
        return Invalid(at + ".cell_triangles[" + std::to_string(i) + "]", "is out of range");
    if (!Finite(t.origin) || !Finite(t.axis) || !Finite(t.reference) || !std::isfinite(t.length))
      return Invalid(at, "origin, axis, reference or length is not finite");
    if (std::fabs(Length(t.axis) - 1.f) > kUnitTolerance ||
        std::fabs(Length(t.reference) - 1.f) > kUnitTolerance ||
        std::fabs(Dot(t.axis, t.reference)) > kUnitTolerance)
      return Invalid(at, "axis and reference are not orthonormal");
    if (t.length < 0.f) return Invalid(at + ".length", "is negative");
  }
  return Status::Ok();
}

}  // namespace

Status HullColliderSet::Build(std::span<const HullColliderData> hulls,
                              std::span<const JointSphereData> spheres, uint32_t joint_count,
                              const HullColliderOptions& options) {
  Clear();
  for (size_t i = 0; i < hulls.size(); ++i) {
    Status s = ValidateHull(hulls[i], i, joint_count);
    if (!s.ok()) return s;
  }
  for (size_t i = 0; i < spheres.size(); ++i) {
    const JointSphereData& s = spheres[i];
    if (s.joint < 0 || static_cast<uint32_t>(s.joint) >= joint_count)
      return Invalid(At("spheres", i, "joint"), "is out of range");
    if (!Finite(s.center)) return Invalid(At("spheres", i, "center"), "is not finite");
    if (!(std::isfinite(s.radius) && s.radius > 0.f))
      return Invalid(At("spheres", i, "radius"), "is not finite and > 0");
  }
  joint_count_ = joint_count;

  for (size_t i = 0; i < hulls.size(); ++i) {
    const HullColliderData& h = hulls[i];
    HullRecord r;
    r.joint = h.joint;
    r.bind_frame = h.bind_frame;
    // Planes, padded.
    r.plane_begin = static_cast<uint32_t>(plane_nx_.size());
    r.plane_count = static_cast<uint32_t>(h.planes.size());
    r.plane_padded = (r.plane_count + kPlanePad - 1) / kPlanePad * kPlanePad;
    for (uint32_t p = 0; p < r.plane_padded; ++p) {
      const bool real = p < r.plane_count;
      const Plane plane = real ? h.planes[p] : Plane{Float3{}, kPadOffset};
      plane_nx_.push_back(plane.normal.x);
      plane_ny_.push_back(plane.normal.y);
      plane_nz_.push_back(plane.normal.z);
      plane_d_.push_back(plane.offset);
      planes_.push_back(plane);
    }
    // OBB, grown so that float rounding of the transforms and of the planes never rejects a point
    // the plane test accepts: the half extents cover every vertex too, plus 1e-5 relative and
    // 1e-6 m absolute.
    r.obb_center = h.obb.center;
    for (int a = 0; a < 3; ++a) r.obb_axes[a] = h.obb.axes[a];
    float half[3] = {h.obb.half_extents.x, h.obb.half_extents.y, h.obb.half_extents.z};
    float scale = Length(h.obb.center);
    for (const Float3& v : h.vertices) {
      scale = std::max(scale, Length(v));
      for (int a = 0; a < 3; ++a)
        half[a] = std::max(half[a], std::fabs(Dot(v - h.obb.center, h.obb.axes[a])));
    }
    const float grow = 1e-6f + 2e-6f * scale;
    for (float& x : half) x = x * (1.f + 1e-5f) + grow;
    r.obb_half = {half[0], half[1], half[2]};
    r.bound_radius = Length(r.obb_half) * (1.f + 1e-5f) + grow;
    // Triangles for the ray test.
    r.triangle_begin = static_cast<uint32_t>(ray_triangle_planes_.size());
    r.triangle_count = static_cast<uint32_t>(h.triangles.size() / 3);
    for (uint32_t t = 0; t < r.triangle_count; ++t) {
      for (int c = 0; c < 3; ++c) {
        const Float3 v = h.vertices[h.triangles[3 * t + c]];
        ray_triangles_.push_back(v.x);
        ray_triangles_.push_back(v.y);
        ray_triangles_.push_back(v.z);
      }
      ray_triangle_planes_.push_back(h.triangle_planes[t]);
    }
    // Kirkpatrick hierarchies.
    r.has_hierarchy = !h.upper.node_triangles.empty();
    r.uv_origin = h.obb.center;
    r.uv_u = h.projection_u;
    r.uv_v = h.projection_v;
    if (r.has_hierarchy) {
      if (node_child_begin_.empty()) node_child_begin_.push_back(0);
      if (node_guard_begin_.empty()) node_guard_begin_.push_back(0);
      // Hull vertices by their projection (float bits, as the bake stored them), and the planes
      // of the faces around each vertex (CSR), for the fill leaves' guard planes.
      std::vector<std::array<uint32_t, 3>> uv_keys;
      for (uint32_t v = 0; v < h.vertices.size(); ++v) {
        const HullUv q = ProjectHullUv(h.vertices[v], r.uv_origin, r.uv_u, r.uv_v);
        uint32_t bits[2];
        std::memcpy(&bits[0], &q.u, sizeof(float));
        std::memcpy(&bits[1], &q.v, sizeof(float));
        uv_keys.push_back({bits[0], bits[1], v});
      }
      std::sort(uv_keys.begin(), uv_keys.end());
      std::vector<std::pair<uint32_t, uint32_t>> vertex_plane;
      for (size_t t = 0; t < h.triangles.size() / 3; ++t)
        for (int c = 0; c < 3; ++c)
          vertex_plane.push_back({h.triangles[3 * t + c], h.triangle_planes[t]});
      std::sort(vertex_plane.begin(), vertex_plane.end());
      vertex_plane.erase(std::unique(vertex_plane.begin(), vertex_plane.end()), vertex_plane.end());
      std::vector<uint32_t> incident_begin(h.vertices.size() + 1, 0), incident_planes;
      for (const auto& [v, plane] : vertex_plane) {
        ++incident_begin[v + 1];
        incident_planes.push_back(plane);
      }
      for (size_t v = 0; v < h.vertices.size(); ++v) incident_begin[v + 1] += incident_begin[v];
      for (int side = 0; side < 2; ++side) {
        const KirkpatrickHierarchy& k = side == 0 ? h.upper : h.lower;
        Hierarchy& out = side == 0 ? r.upper : r.lower;
        const uint32_t base = static_cast<uint32_t>(node_leaf_plane_.size());
        out.node_begin = base;
        out.node_count = k.node_count();
        out.root_begin = base + k.root_begin;
        out.root_end = base + k.root_end;
        double sum_u = 0.0, sum_v = 0.0;
        uint32_t faces = 0;
        for (uint32_t n = 0; n < out.node_count; ++n) {
          const uint32_t* tri = &k.node_triangles[3 * n];
          for (int e = 0; e < 3; ++e) {
            const uint32_t from = tri[e], to = tri[(e + 1) % 3];
            const uint32_t a = std::min(from, to), b = std::max(from, to);
            EdgeFunction f;
            f.au = k.vertices_uv[2 * a];
            f.av = k.vertices_uv[2 * a + 1];
            f.du = double(k.vertices_uv[2 * b]) - f.au;
            f.dv = double(k.vertices_uv[2 * b + 1]) - f.av;
            if (from != a) {  // the node uses the edge as B -> A: the interior is on the other side
              f.du = -f.du;
              f.dv = -f.dv;
            }
            node_edges_.push_back(f);
          }
          node_leaf_plane_.push_back(k.leaf_planes[n]);
          for (uint32_t e = k.child_offsets[n]; e < k.child_offsets[n + 1]; ++e)
            node_children_.push_back(base + k.children[e]);
          node_child_begin_.push_back(static_cast<uint32_t>(node_children_.size()));
          // Guard planes of a fill leaf: every plane of a hull face incident to a hull vertex that
          // projects onto one of the leaf's vertices other than the enclosing triangle's corners
          // (the root's vertices). Each fill triangle lies beyond one silhouette edge or vertex;
          // a point projecting there is inside the hull only if it is inside the faces meeting at
          // that rim (see the header), which is what the guards test.
          if (k.leaf_planes[n] < 0 && k.child_offsets[n] == k.child_offsets[n + 1] &&
              k.root_end - k.root_begin == 1) {
            const uint32_t* root = &k.node_triangles[3 * k.root_begin];
            const size_t first = node_guard_planes_.size();
            for (int c = 0; c < 3; ++c) {
              const uint32_t v = tri[c];
              if (v == root[0] || v == root[1] || v == root[2]) continue;
              uint32_t bits[2];
              std::memcpy(bits, &k.vertices_uv[2 * v], sizeof(bits));
              auto it = std::lower_bound(uv_keys.begin(), uv_keys.end(),
                                         std::array<uint32_t, 3>{bits[0], bits[1], 0});
              for (; it != uv_keys.end() && (*it)[0] == bits[0] && (*it)[1] == bits[1]; ++it)
                for (uint32_t e = incident_begin[(*it)[2]]; e < incident_begin[(*it)[2] + 1]; ++e)
                  node_guard_planes_.push_back(incident_planes[e]);
            }
            std::sort(node_guard_planes_.begin() + static_cast<std::ptrdiff_t>(first),
                      node_guard_planes_.end());
            node_guard_planes_.erase(
                std::unique(node_guard_planes_.begin() + static_cast<std::ptrdiff_t>(first),
                            node_guard_planes_.end()),
                node_guard_planes_.end());
          }
          node_guard_begin_.push_back(static_cast<uint32_t>(node_guard_planes_.size()));
          if (k.leaf_planes[n] >= 0 && k.child_offsets[n] == k.child_offsets[n + 1]) {
            for (int c = 0; c < 3; ++c) {
              sum_u += k.vertices_uv[2 * tri[c]];
              sum_v += k.vertices_uv[2 * tri[c] + 1];
            }
            ++faces;
          }
        }
        // The mean of the face leaves' vertices: a convex combination of points of the (convex)
        // projected hull with positive weights, so strictly inside it.
        out.interior_u = sum_u / (3.0 * faces);
        out.interior_v = sum_v / (3.0 * faces);
      }
    }
    // Map table.
    const MapTableData& t = h.map;
    r.has_map = !(t.rows == 0 && t.cols == 0 && t.cell_offsets.empty());
    if (r.has_map) {
      r.map_kind = t.kind;
      r.map_rows = t.rows;
      r.map_cols = t.cols;
      r.map_row_scale = static_cast<float>(t.rows) / kPi;
      r.map_col_scale = static_cast<float>(t.cols) / (2.f * kPi);
      r.map_origin = t.origin;
      r.map_axis = t.axis;
      r.map_reference = t.reference;
      r.map_binormal = Cross(t.axis, t.reference);
      r.map_length = t.kind == MapTableKind::kCylinder ? t.length : 0.f;
      r.map_cell_begin = static_cast<uint32_t>(map_cell_offsets_.size());
      const uint32_t list_base = static_cast<uint32_t>(map_triangles_.size());
      for (uint32_t offset : t.cell_offsets) map_cell_offsets_.push_back(list_base + offset);
      map_triangles_.insert(map_triangles_.end(), t.cell_triangles.begin(), t.cell_triangles.end());
    }
    hulls_.push_back(r);
  }
  // The map-table ray loads each vertex as 4 floats: the last triangle's third vertex reads 3
  // floats past it.
  ray_triangles_.insert(ray_triangles_.end(), 3, 0.f);
  for (const JointSphereData& s : spheres) spheres_.push_back({s.joint, s.center, s.radius});

  Status status = ValidateOptions(options);
  if (!status.ok()) {
    Clear();
    return status;
  }
  options_ = options;
  simd_level_ = options.allow_avx2 && CpuHasAvx2() ? 2 : 1;

  const size_t colliders = hulls_.size() + spheres_.size();
  collider_count_ = static_cast<uint32_t>(colliders);
  motions_.assign(colliders, Motion{});
  active_.assign(colliders, ActiveFrames{});
  const size_t padded = (colliders + 7) / 8 * 8;
  for (auto* v : {&sweep_x_, &sweep_y_, &sweep_z_, &full_x_, &full_y_, &full_z_})
    v->assign(padded, kPadCenter);
  sweep_r_.assign(padded, 0.f);
  full_r_.assign(padded, 0.f);
  // Bind pose: identity skinning.
  std::vector<Mat34> identity(joint_count_ > 0 ? joint_count_ : 1);
  return SetPose(identity, identity);
}

size_t HullColliderSet::memory_bytes() const {
  return sizeof(*this) + hulls_.size() * sizeof(HullRecord) +
         spheres_.size() * sizeof(SphereRecord) + (plane_nx_.size() * 4) * sizeof(float) +
         planes_.size() * sizeof(Plane) + ray_triangles_.size() * sizeof(float) +
         ray_triangle_planes_.size() * sizeof(uint32_t) +
         node_edges_.size() * sizeof(EdgeFunction) + node_leaf_plane_.size() * sizeof(int32_t) +
         (node_guard_begin_.size() + node_guard_planes_.size()) * sizeof(uint32_t) +
         (node_child_begin_.size() + node_children_.size() + map_cell_offsets_.size() +
          map_triangles_.size()) *
             sizeof(uint32_t) +
         motions_.size() * sizeof(Motion) + active_.size() * sizeof(ActiveFrames) +
         (sweep_x_.size() * 8) * sizeof(float);
}

// =================================================================================================
// Pose
// =================================================================================================

Status HullColliderSet::SetPose(std::span<const Mat34> skinning_start,
                                std::span<const Mat34> skinning_end) {
  if (skinning_start.size() < joint_count_ || skinning_end.size() < joint_count_)
    return Status(StatusCode::kInvalidArgument,
                  "HullColliderSet::SetPose: fewer skinning matrices than the " +
                      std::to_string(joint_count_) + " joints");
  for (uint32_t j = 0; j < joint_count_; ++j)
    if (!Finite(skinning_start[j]) || !Finite(skinning_end[j]))
      return Status(StatusCode::kInvalidArgument,
                    "HullColliderSet::SetPose: skinning matrix of joint " + std::to_string(j) +
                        " is not finite");
  const uint32_t hull_total = static_cast<uint32_t>(hulls_.size());
  for (uint32_t k = 0; k < motions_.size(); ++k) {
    Motion& m = motions_[k];
    RigidD w0, w1;
    Vec3D local_center;  // the bounding-sphere centre in the collider's frame
    if (k < hull_total) {
      const HullRecord& h = hulls_[k];
      const Mat34 m0 = Multiply(skinning_start[h.joint], h.bind_frame);
      const Mat34 m1 = Multiply(skinning_end[h.joint], h.bind_frame);
      w0 = {RotationOf(m0), {m0.m[3], m0.m[7], m0.m[11]}};
      w1 = {RotationOf(m1), {m1.m[3], m1.m[7], m1.m[11]}};
      local_center = ToD(h.obb_center);
    } else {
      const SphereRecord& s = spheres_[k - hull_total];
      w0.translation = ToD(TransformPoint(skinning_start[s.joint], s.center));
      w1.translation = ToD(TransformPoint(skinning_end[s.joint], s.center));
    }
    // Keep the quaternions in one hemisphere so the relative rotation is the short one.
    if (w0.rotation.x * w1.rotation.x + w0.rotation.y * w1.rotation.y +
            w0.rotation.z * w1.rotation.z + w0.rotation.w * w1.rotation.w <
        0.0)
      w1.rotation = {-w1.rotation.x, -w1.rotation.y, -w1.rotation.z, -w1.rotation.w};
    m.rotation0 = {static_cast<float>(w0.rotation.x), static_cast<float>(w0.rotation.y),
                   static_cast<float>(w0.rotation.z), static_cast<float>(w0.rotation.w)};
    m.translation0 = ToF(w0.translation);
    const Vec3D c0 = Apply(w0, local_center), c1 = Apply(w1, local_center);
    m.center0 = ToF(c0);
    m.center1 = ToF(c1);
    // Relative motion D = W1 W0^-1 = (Rd, td).
    QuatD rel = NormalizeQ(Mul(w1.rotation, Conjugate(w0.rotation)));
    if (rel.w < 0.0) rel = {-rel.x, -rel.y, -rel.z, -rel.w};
    const Vec3D td = w1.translation - Rotate(rel, w0.translation);
    const double sin_half = std::sqrt(rel.x * rel.x + rel.y * rel.y + rel.z * rel.z);
    const double angle = 2.0 * std::atan2(sin_half, rel.w);
    Vec3D pivot = c0, shift = c1 - c0;
    if (angle > kScrewMinAngle) {
      const Vec3D axis = Vec3D{rel.x, rel.y, rel.z} * (1.0 / sin_half);
      const Vec3D t_perp = td - axis * DotD(td, axis);
      const double cot_half = rel.w / sin_half;
      const Vec3D q = (t_perp + CrossD(axis, t_perp) * cot_half) * 0.5;
      pivot = q + axis * DotD(c0 - q, axis);  // the screw-axis point nearest the centre
      shift = Rotate(rel, pivot) + td - pivot;
    }
    m.relative = {static_cast<float>(rel.x), static_cast<float>(rel.y), static_cast<float>(rel.z),
                  static_cast<float>(rel.w)};
    m.pivot = ToF(pivot);
    m.shift = ToF(shift);
    Float3 center;
    float radius;
    ComputeSweep(k, 0.f, 1.f, &center, &radius);
    full_x_[k] = center.x;
    full_y_[k] = center.y;
    full_z_[k] = center.z;
    full_r_[k] = radius;
  }
  return SelectSubstep(0.f, 1.f);
}

// Collider frame -> world at fraction s, in double (see the header: screw interpolation).
Mat34 HullColliderSet::ColliderWorldAt(uint32_t collider, float s) const {
  const Motion& m = motions_[collider];
  const QuatD q0{m.rotation0.x, m.rotation0.y, m.rotation0.z, m.rotation0.w};
  const QuatD rel{m.relative.x, m.relative.y, m.relative.z, m.relative.w};
  const double sd = s;
  const QuatD rs = NormalizeQ({sd * rel.x, sd * rel.y, sd * rel.z, (1.0 - sd) + sd * rel.w});
  RigidD w;
  w.rotation = NormalizeQ(Mul(rs, q0));
  const Vec3D pivot = ToD(m.pivot);
  w.translation = Rotate(rs, ToD(m.translation0) - pivot) + pivot + ToD(m.shift) * sd;
  return ToMat34(w);
}

void HullColliderSet::ComputeFrames(uint32_t collider, float s0, float s1, ActiveFrames* f) const {
  const Motion& m = motions_[collider];
  const uint32_t hull_total = static_cast<uint32_t>(hulls_.size());
  const QuatD q0{m.rotation0.x, m.rotation0.y, m.rotation0.z, m.rotation0.w};
  const QuatD rel{m.relative.x, m.relative.y, m.relative.z, m.relative.w};
  auto rigid_at = [&](double s) {
    const QuatD rs = NormalizeQ({s * rel.x, s * rel.y, s * rel.z, (1.0 - s) + s * rel.w});
    RigidD w;
    w.rotation = NormalizeQ(Mul(rs, q0));
    const Vec3D pivot = ToD(m.pivot);
    w.translation = Rotate(rs, ToD(m.translation0) - pivot) + pivot + ToD(m.shift) * s;
    return w;
  };
  if (collider < hull_total) {
    const HullRecord& h = hulls_[collider];
    const RigidD w0 = rigid_at(s0), w1 = rigid_at(s1);
    f->to_local_start = InverseToMat34(w0);
    f->to_local_end = InverseToMat34(w1);
    f->to_obb_start = ObbFromWorld(w0, h.obb_center, h.obb_axes);
    f->to_obb_end = ObbFromWorld(w1, h.obb_center, h.obb_axes);
    f->to_world_end = ToMat34(w1);
  } else {
    const Float3 c0 = Lerp(m.center0, m.center1, s0), c1 = Lerp(m.center0, m.center1, s1);
    f->to_local_start = TranslationMatrix(-c0);
    f->to_local_end = TranslationMatrix(-c1);
    f->to_obb_start = f->to_local_start;
    f->to_obb_end = f->to_local_end;
    f->to_world_end = TranslationMatrix(c1);
  }
}

void HullColliderSet::ComputeSweep(uint32_t collider, float s0, float s1, Float3* center,
                                   float* radius) const {
  const Motion& m = motions_[collider];
  const uint32_t hull_total = static_cast<uint32_t>(hulls_.size());
  Vec3D c0, c1;
  double base;
  if (collider < hull_total) {
    const HullRecord& h = hulls_[collider];
    const Mat34 w0 = ColliderWorldAt(collider, s0), w1 = ColliderWorldAt(collider, s1);
    c0 = ToD(TransformPoint(w0, h.obb_center));
    c1 = ToD(TransformPoint(w1, h.obb_center));
    base = h.bound_radius;
  } else {
    c0 = ToD(Lerp(m.center0, m.center1, s0));
    c1 = ToD(Lerp(m.center0, m.center1, s1));
    base = spheres_[collider - hull_total].radius;
  }
  // The centre moves on an arc about the screw axis (angle <= pi) plus a shift along it: the
  // arc stays within the ball on its chord, the shift within half its length of the middle.
  const Vec3D chord = c1 - c0;
  const double sin_half =
      std::sqrt(double(m.relative.x) * m.relative.x + double(m.relative.y) * m.relative.y +
                double(m.relative.z) * m.relative.z);
  double sweep = 0.5 * LengthD(chord);
  if (collider < hull_total && sin_half > 0.0) {
    const Vec3D axis = Vec3D{m.relative.x, m.relative.y, m.relative.z} * (1.0 / sin_half);
    const double along = DotD(chord, axis);
    sweep = 0.5 * LengthD(chord - axis * along) + 0.5 * std::fabs(along);
  }
  const Vec3D mid = (c0 + c1) * 0.5;
  const double magnitude = LengthD(mid) + base + sweep;
  *center = ToF(mid);
  *radius = static_cast<float>((base + sweep) * (1.0 + 1e-5) + 1e-6 + 4e-7 * magnitude);
}

Status HullColliderSet::SelectSubstep(float s0, float s1) {
  if (!(s0 >= 0.f && s0 <= s1 && s1 <= 1.f))
    return Status(StatusCode::kInvalidArgument,
                  "HullColliderSet::SelectSubstep: fractions are not 0 <= s0 <= s1 <= 1");
  active_s0_ = s0;
  active_s1_ = s1;
  for (uint32_t k = 0; k < motions_.size(); ++k) {
    ComputeFrames(k, s0, s1, &active_[k]);
    Float3 center;
    float radius;
    ComputeSweep(k, s0, s1, &center, &radius);
    sweep_x_[k] = center.x;
    sweep_y_[k] = center.y;
    sweep_z_[k] = center.z;
    sweep_r_[k] = radius;
  }
  // The union sphere, in double: centre the middle of the spheres' box, radius the farthest
  // sphere surface, grown by 1e-4 relative and 1e-4 of the magnitude (far above the ~1e-6
  // relative rounding of the float tests).
  if (collider_count_ > 0) {
    Vec3D lo{kPadCenter, kPadCenter, kPadCenter}, hi{-kPadCenter, -kPadCenter, -kPadCenter};
    for (uint32_t k = 0; k < collider_count_; ++k) {
      lo = {std::min(lo.x, double(sweep_x_[k]) - sweep_r_[k]),
            std::min(lo.y, double(sweep_y_[k]) - sweep_r_[k]),
            std::min(lo.z, double(sweep_z_[k]) - sweep_r_[k])};
      hi = {std::max(hi.x, double(sweep_x_[k]) + sweep_r_[k]),
            std::max(hi.y, double(sweep_y_[k]) + sweep_r_[k]),
            std::max(hi.z, double(sweep_z_[k]) + sweep_r_[k])};
    }
    const Vec3D center = (lo + hi) * 0.5;
    double radius = 0.0;
    for (uint32_t k = 0; k < collider_count_; ++k)
      radius = std::max(
          radius, LengthD(Vec3D{sweep_x_[k], sweep_y_[k], sweep_z_[k]} - center) + sweep_r_[k]);
    sweep_union_center_ = ToF(center);
    sweep_union_radius_ =
        static_cast<float>(radius * (1.0 + 1e-4) + 1e-4 * (LengthD(center) + radius) + 1e-6);
  }
  return Status::Ok();
}

Mat34 HullColliderSet::HullWorldTransform(uint32_t hull, float s) const {
  return ColliderWorldAt(hull, s);
}

Float3 HullColliderSet::SphereCenter(uint32_t sphere, float s) const {
  const Motion& m = motions_[hulls_.size() + sphere];
  return Lerp(m.center0, m.center1, s);
}

// =================================================================================================
// Narrow phase kernels (collider frame)
// =================================================================================================

namespace {

// ---- Plane kernels. Each hull's planes are SoA float arrays padded to a multiple of 8 with
// planes (0, 0, 0, 3e38) that never win a max, never separate and never clip. Every plane value is
// ((nx px + ny py) + nz pz) - d in float, the same expression as PlaneSignedDistance, whatever the
// vector width: SSE (4 lanes), AVX2 (8 lanes, chosen at Build when the CPU has it) and the
// portable scalar loops give bitwise identical results (max/min and OR reductions do not depend on
// the order).
struct PlaneSoa {
  const float* nx;
  const float* ny;
  const float* nz;
  const float* d;
  uint32_t padded;  // multiple of 8
};
struct DualResult {
  float max_a, max_b;  // valid only when !separated
  bool separated;      // one plane has both ends strictly outside: the segment misses the hull
};
struct ClipResult {
  float t_in, t_out;  // max entering t (-1: none), min leaving t (1: none)
};

float ScalarValue(const PlaneSoa& s, uint32_t i, Float3 p) {
  return s.nx[i] * p.x + s.ny[i] * p.y + s.nz[i] * p.z - s.d[i];
}

float MaxScalar(const PlaneSoa& s, Float3 p) {
  float m = -kPadOffset;
  for (uint32_t i = 0; i < s.padded; ++i) {
    const float v = ScalarValue(s, i, p);
    m = v > m ? v : m;
  }
  return m;
}
uint32_t FirstEqualScalar(const PlaneSoa& s, Float3 p, float value) {
  for (uint32_t i = 0; i < s.padded; ++i)
    if (ScalarValue(s, i, p) == value) return i;
  return 0;
}
DualResult DualScalar(const PlaneSoa& s, Float3 a, Float3 b) {
  DualResult r{-kPadOffset, -kPadOffset, false};
  for (uint32_t i = 0; i < s.padded; ++i) {
    const float fa = ScalarValue(s, i, a), fb = ScalarValue(s, i, b);
    if (fa > 0.f && fb > 0.f) return {0.f, 0.f, true};
    r.max_a = fa > r.max_a ? fa : r.max_a;
    r.max_b = fb > r.max_b ? fb : r.max_b;
  }
  return r;
}
// DualScalar(s, a, a) with half the work: the same per-plane values and reductions.
DualResult DualSameScalar(const PlaneSoa& s, Float3 a) {
  DualResult r{-kPadOffset, -kPadOffset, false};
  for (uint32_t i = 0; i < s.padded; ++i) {
    const float fa = ScalarValue(s, i, a);
    if (fa > 0.f) return {0.f, 0.f, true};
    r.max_a = fa > r.max_a ? fa : r.max_a;
  }
  r.max_b = r.max_a;
  return r;
}
ClipResult ClipScalar(const PlaneSoa& s, Float3 a, Float3 b) {
  ClipResult r{-1.f, 1.f};
  for (uint32_t i = 0; i < s.padded; ++i) {
    const float fa = ScalarValue(s, i, a), fb = ScalarValue(s, i, b);
    const float t = fa / (fa - fb);
    if (fa > 0.f) r.t_in = t > r.t_in ? t : r.t_in;
    if (!(fa > 0.f) && fb > 0.f) r.t_out = t < r.t_out ? t : r.t_out;
  }
  return r;
}
// First plane entering at exactly t_in.
uint32_t EntryScalar(const PlaneSoa& s, Float3 a, Float3 b, float t_in) {
  for (uint32_t i = 0; i < s.padded; ++i) {
    const float fa = ScalarValue(s, i, a), fb = ScalarValue(s, i, b);
    if (fa > 0.f && fa / (fa - fb) == t_in) return i;
  }
  return 0;
}

#if defined(__SSE2__)
inline __m128 ValueSse(const PlaneSoa& s, uint32_t i, __m128 px, __m128 py, __m128 pz) {
  __m128 v = _mm_mul_ps(_mm_loadu_ps(s.nx + i), px);
  v = _mm_add_ps(v, _mm_mul_ps(_mm_loadu_ps(s.ny + i), py));
  v = _mm_add_ps(v, _mm_mul_ps(_mm_loadu_ps(s.nz + i), pz));
  return _mm_sub_ps(v, _mm_loadu_ps(s.d + i));
}
inline float HorizontalMax(__m128 v) {
  alignas(16) float l[4];
  _mm_store_ps(l, v);
  return std::max(std::max(l[0], l[1]), std::max(l[2], l[3]));
}
inline float HorizontalMin(__m128 v) {
  alignas(16) float l[4];
  _mm_store_ps(l, v);
  return std::min(std::min(l[0], l[1]), std::min(l[2], l[3]));
}
float MaxSse(const PlaneSoa& s, Float3 p) {
  const __m128 px = _mm_set1_ps(p.x), py = _mm_set1_ps(p.y), pz = _mm_set1_ps(p.z);
  __m128 m0 = _mm_set1_ps(-kPadOffset), m1 = m0;
  for (uint32_t i = 0; i < s.padded; i += 8) {
    m0 = _mm_max_ps(ValueSse(s, i, px, py, pz), m0);
    m1 = _mm_max_ps(ValueSse(s, i + 4, px, py, pz), m1);
  }
  return HorizontalMax(_mm_max_ps(m0, m1));
}
uint32_t FirstEqualSse(const PlaneSoa& s, Float3 p, float value) {
  const __m128 px = _mm_set1_ps(p.x), py = _mm_set1_ps(p.y), pz = _mm_set1_ps(p.z);
  const __m128 target = _mm_set1_ps(value);
  for (uint32_t i = 0; i < s.padded; i += 4) {
    const int mask = _mm_movemask_ps(_mm_cmpeq_ps(ValueSse(s, i, px, py, pz), target));
    if (mask != 0) return i + static_cast<uint32_t>(__builtin_ctz(static_cast<unsigned>(mask)));
  }
  return 0;
}
DualResult DualSse(const PlaneSoa& s, Float3 a, Float3 b) {
  const __m128 ax = _mm_set1_ps(a.x), ay = _mm_set1_ps(a.y), az = _mm_set1_ps(a.z);
  const __m128 bx = _mm_set1_ps(b.x), by = _mm_set1_ps(b.y), bz = _mm_set1_ps(b.z);
  const __m128 zero = _mm_setzero_ps();
  __m128 ma = _mm_set1_ps(-kPadOffset), mb = ma;
  for (uint32_t i = 0; i < s.padded; i += 8) {
    const __m128 fa0 = ValueSse(s, i, ax, ay, az), fb0 = ValueSse(s, i, bx, by, bz);
    const __m128 fa1 = ValueSse(s, i + 4, ax, ay, az), fb1 = ValueSse(s, i + 4, bx, by, bz);
    const __m128 sep = _mm_or_ps(_mm_and_ps(_mm_cmpgt_ps(fa0, zero), _mm_cmpgt_ps(fb0, zero)),
                                 _mm_and_ps(_mm_cmpgt_ps(fa1, zero), _mm_cmpgt_ps(fb1, zero)));
    if (_mm_movemask_ps(sep) != 0) return {0.f, 0.f, true};
    ma = _mm_max_ps(_mm_max_ps(fa0, fa1), ma);
    mb = _mm_max_ps(_mm_max_ps(fb0, fb1), mb);
  }
  return {HorizontalMax(ma), HorizontalMax(mb), false};
}
// DualSse(s, a, a) with half the work: the same per-plane values and the same reduction order.
DualResult DualSameSse(const PlaneSoa& s, Float3 a) {
  const __m128 ax = _mm_set1_ps(a.x), ay = _mm_set1_ps(a.y), az = _mm_set1_ps(a.z);
  const __m128 zero = _mm_setzero_ps();
  __m128 ma = _mm_set1_ps(-kPadOffset);
  for (uint32_t i = 0; i < s.padded; i += 8) {
    const __m128 fa0 = ValueSse(s, i, ax, ay, az), fa1 = ValueSse(s, i + 4, ax, ay, az);
    const __m128 sep = _mm_or_ps(_mm_cmpgt_ps(fa0, zero), _mm_cmpgt_ps(fa1, zero));
    if (_mm_movemask_ps(sep) != 0) return {0.f, 0.f, true};
    ma = _mm_max_ps(_mm_max_ps(fa0, fa1), ma);
  }
  const float m = HorizontalMax(ma);
  return {m, m, false};
}
ClipResult ClipSse(const PlaneSoa& s, Float3 a, Float3 b) {
  const __m128 ax = _mm_set1_ps(a.x), ay = _mm_set1_ps(a.y), az = _mm_set1_ps(a.z);
  const __m128 bx = _mm_set1_ps(b.x), by = _mm_set1_ps(b.y), bz = _mm_set1_ps(b.z);
  const __m128 zero = _mm_setzero_ps();
  __m128 t_in = _mm_set1_ps(-1.f), t_out = _mm_set1_ps(1.f);
  for (uint32_t i = 0; i < s.padded; i += 4) {
    const __m128 fa = ValueSse(s, i, ax, ay, az), fb = ValueSse(s, i, bx, by, bz);
    const __m128 t = _mm_div_ps(fa, _mm_sub_ps(fa, fb));
    const __m128 entering = _mm_cmpgt_ps(fa, zero);
    const __m128 leaving = _mm_andnot_ps(entering, _mm_cmpgt_ps(fb, zero));
    t_in = _mm_max_ps(detail::SelectLanes(entering, t, t_in), t_in);
    t_out = _mm_min_ps(detail::SelectLanes(leaving, t, t_out), t_out);
  }
  return {HorizontalMax(t_in), HorizontalMin(t_out)};
}
uint32_t EntrySse(const PlaneSoa& s, Float3 a, Float3 b, float t_in) {
  const __m128 ax = _mm_set1_ps(a.x), ay = _mm_set1_ps(a.y), az = _mm_set1_ps(a.z);
  const __m128 bx = _mm_set1_ps(b.x), by = _mm_set1_ps(b.y), bz = _mm_set1_ps(b.z);
  const __m128 zero = _mm_setzero_ps(), target = _mm_set1_ps(t_in);
  for (uint32_t i = 0; i < s.padded; i += 4) {
    const __m128 fa = ValueSse(s, i, ax, ay, az), fb = ValueSse(s, i, bx, by, bz);
    const __m128 t = _mm_div_ps(fa, _mm_sub_ps(fa, fb));
    const int mask = _mm_movemask_ps(_mm_and_ps(_mm_cmpgt_ps(fa, zero), _mm_cmpeq_ps(t, target)));
    if (mask != 0) return i + static_cast<uint32_t>(__builtin_ctz(static_cast<unsigned>(mask)));
  }
  return 0;
}
#endif

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#define DRAPE_HULL_AVX2 1
#define DRAPE_AVX2 __attribute__((target("avx2")))
DRAPE_AVX2 inline __m256 ValueAvx(const PlaneSoa& s, uint32_t i, __m256 px, __m256 py, __m256 pz) {
  __m256 v = _mm256_mul_ps(_mm256_loadu_ps(s.nx + i), px);
  v = _mm256_add_ps(v, _mm256_mul_ps(_mm256_loadu_ps(s.ny + i), py));
  v = _mm256_add_ps(v, _mm256_mul_ps(_mm256_loadu_ps(s.nz + i), pz));
  return _mm256_sub_ps(v, _mm256_loadu_ps(s.d + i));
}
DRAPE_AVX2 inline float HorizontalMaxAvx(__m256 v) {
  alignas(32) float l[8];
  _mm256_store_ps(l, v);
  return std::max(std::max(std::max(l[0], l[1]), std::max(l[2], l[3])),
                  std::max(std::max(l[4], l[5]), std::max(l[6], l[7])));
}
DRAPE_AVX2 inline float HorizontalMinAvx(__m256 v) {
  alignas(32) float l[8];
  _mm256_store_ps(l, v);
  return std::min(std::min(std::min(l[0], l[1]), std::min(l[2], l[3])),
                  std::min(std::min(l[4], l[5]), std::min(l[6], l[7])));
}
DRAPE_AVX2 float MaxAvx(const PlaneSoa& s, Float3 p) {
  const __m256 px = _mm256_set1_ps(p.x), py = _mm256_set1_ps(p.y), pz = _mm256_set1_ps(p.z);
  __m256 m = _mm256_set1_ps(-kPadOffset);
  for (uint32_t i = 0; i < s.padded; i += 8) m = _mm256_max_ps(ValueAvx(s, i, px, py, pz), m);
  return HorizontalMaxAvx(m);
}
DRAPE_AVX2 uint32_t FirstEqualAvx(const PlaneSoa& s, Float3 p, float value) {
  const __m256 px = _mm256_set1_ps(p.x), py = _mm256_set1_ps(p.y), pz = _mm256_set1_ps(p.z);
  const __m256 target = _mm256_set1_ps(value);
  for (uint32_t i = 0; i < s.padded; i += 8) {
    const int mask =
        _mm256_movemask_ps(_mm256_cmp_ps(ValueAvx(s, i, px, py, pz), target, _CMP_EQ_OQ));
    if (mask != 0) return i + static_cast<uint32_t>(__builtin_ctz(static_cast<unsigned>(mask)));
  }
  return 0;
}
DRAPE_AVX2 DualResult DualAvx(const PlaneSoa& s, Float3 a, Float3 b) {
  const __m256 ax = _mm256_set1_ps(a.x), ay = _mm256_set1_ps(a.y), az = _mm256_set1_ps(a.z);
  const __m256 bx = _mm256_set1_ps(b.x), by = _mm256_set1_ps(b.y), bz = _mm256_set1_ps(b.z);
  const __m256 zero = _mm256_setzero_ps();
  __m256 ma = _mm256_set1_ps(-kPadOffset), mb = ma;
  for (uint32_t i = 0; i < s.padded; i += 8) {
    const __m256 fa = ValueAvx(s, i, ax, ay, az), fb = ValueAvx(s, i, bx, by, bz);
    const __m256 sep =
        _mm256_and_ps(_mm256_cmp_ps(fa, zero, _CMP_GT_OQ), _mm256_cmp_ps(fb, zero, _CMP_GT_OQ));
    if (_mm256_movemask_ps(sep) != 0) return {0.f, 0.f, true};
    ma = _mm256_max_ps(fa, ma);
    mb = _mm256_max_ps(fb, mb);
  }
  return {HorizontalMaxAvx(ma), HorizontalMaxAvx(mb), false};
}
// DualAvx(s, a, a) with half the work: the same per-plane values and the same reduction order.
DRAPE_AVX2 DualResult DualSameAvx(const PlaneSoa& s, Float3 a) {
  const __m256 ax = _mm256_set1_ps(a.x), ay = _mm256_set1_ps(a.y), az = _mm256_set1_ps(a.z);
  const __m256 zero = _mm256_setzero_ps();
  __m256 ma = _mm256_set1_ps(-kPadOffset);
  for (uint32_t i = 0; i < s.padded; i += 8) {
    const __m256 fa = ValueAvx(s, i, ax, ay, az);
    if (_mm256_movemask_ps(_mm256_cmp_ps(fa, zero, _CMP_GT_OQ)) != 0) return {0.f, 0.f, true};
    ma = _mm256_max_ps(fa, ma);
  }
  const float m = HorizontalMaxAvx(ma);
  return {m, m, false};
}
DRAPE_AVX2 ClipResult ClipAvx(const PlaneSoa& s, Float3 a, Float3 b) {
  const __m256 ax = _mm256_set1_ps(a.x), ay = _mm256_set1_ps(a.y), az = _mm256_set1_ps(a.z);
  const __m256 bx = _mm256_set1_ps(b.x), by = _mm256_set1_ps(b.y), bz = _mm256_set1_ps(b.z);
  const __m256 zero = _mm256_setzero_ps();
  __m256 t_in = _mm256_set1_ps(-1.f), t_out = _mm256_set1_ps(1.f);
  for (uint32_t i = 0; i < s.padded; i += 8) {
    const __m256 fa = ValueAvx(s, i, ax, ay, az), fb = ValueAvx(s, i, bx, by, bz);
    const __m256 t = _mm256_div_ps(fa, _mm256_sub_ps(fa, fb));
    const __m256 entering = _mm256_cmp_ps(fa, zero, _CMP_GT_OQ);
    const __m256 leaving = _mm256_andnot_ps(entering, _mm256_cmp_ps(fb, zero, _CMP_GT_OQ));
    t_in = _mm256_max_ps(_mm256_blendv_ps(t_in, t, entering), t_in);
    t_out = _mm256_min_ps(_mm256_blendv_ps(t_out, t, leaving), t_out);
  }
  return {HorizontalMaxAvx(t_in), HorizontalMinAvx(t_out)};
}
DRAPE_AVX2 uint32_t EntryAvx(const PlaneSoa& s, Float3 a, Float3 b, float t_in) {
  const __m256 ax = _mm256_set1_ps(a.x), ay = _mm256_set1_ps(a.y), az = _mm256_set1_ps(a.z);
  const __m256 bx = _mm256_set1_ps(b.x), by = _mm256_set1_ps(b.y), bz = _mm256_set1_ps(b.z);
  const __m256 zero = _mm256_setzero_ps(), target = _mm256_set1_ps(t_in);
  for (uint32_t i = 0; i < s.padded; i += 8) {
    const __m256 fa = ValueAvx(s, i, ax, ay, az), fb = ValueAvx(s, i, bx, by, bz);
    const __m256 t = _mm256_div_ps(fa, _mm256_sub_ps(fa, fb));
    const int mask = _mm256_movemask_ps(
        _mm256_and_ps(_mm256_cmp_ps(fa, zero, _CMP_GT_OQ), _mm256_cmp_ps(t, target, _CMP_EQ_OQ)));
    if (mask != 0) return i + static_cast<uint32_t>(__builtin_ctz(static_cast<unsigned>(mask)));
  }
  return 0;
}
#endif

// Broad phase: indices k < total with |mid - c_k|^2 <= (r_k + half)^2 (SoA padded to a multiple of
// 8 with spheres that never pass), at most `capacity`, in index order. Same arithmetic at any
// width.
uint32_t SphereFilterScalar(const float* xs, const float* ys, const float* zs, const float* rs,
                            uint32_t total, Float3 mid, float half, uint32_t* out,
                            uint32_t capacity) {
  uint32_t count = 0;
  for (uint32_t k = 0; k < total && count < capacity; ++k) {
    const float dx = mid.x - xs[k], dy = mid.y - ys[k], dz = mid.z - zs[k];
    const float rr = rs[k] + half;
    if (dx * dx + dy * dy + dz * dz <= rr * rr) out[count++] = k;
  }
  return count;
}
#if defined(__SSE2__)
uint32_t SphereFilterSse(const float* xs, const float* ys, const float* zs, const float* rs,
                         uint32_t total, Float3 mid, float half, uint32_t* out, uint32_t capacity) {
  const __m128 mx = _mm_set1_ps(mid.x), my = _mm_set1_ps(mid.y), mz = _mm_set1_ps(mid.z);
  const __m128 hv = _mm_set1_ps(half);
  uint32_t count = 0;
  for (uint32_t k = 0; k < total; k += 4) {
    const __m128 dx = _mm_sub_ps(mx, _mm_loadu_ps(xs + k));
    const __m128 dy = _mm_sub_ps(my, _mm_loadu_ps(ys + k));
    const __m128 dz = _mm_sub_ps(mz, _mm_loadu_ps(zs + k));
    const __m128 d2 =
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
    const __m128 rr = _mm_add_ps(_mm_loadu_ps(rs + k), hv);
    unsigned mask = static_cast<unsigned>(_mm_movemask_ps(_mm_cmple_ps(d2, _mm_mul_ps(rr, rr))));
    while (mask != 0 && count < capacity) {
      const uint32_t index = k + static_cast<uint32_t>(__builtin_ctz(mask));
      mask &= mask - 1;
      if (index < total) out[count++] = index;  // padding fails unless the segment is ~1e38 long
    }
  }
  return count;
}
#endif
#if defined(DRAPE_HULL_AVX2)
DRAPE_AVX2 uint32_t SphereFilterAvx(const float* xs, const float* ys, const float* zs,
                                    const float* rs, uint32_t total, Float3 mid, float half,
                                    uint32_t* out, uint32_t capacity) {
  const __m256 mx = _mm256_set1_ps(mid.x), my = _mm256_set1_ps(mid.y), mz = _mm256_set1_ps(mid.z);
  const __m256 hv = _mm256_set1_ps(half);
  uint32_t count = 0;
  for (uint32_t k = 0; k < total; k += 8) {
    const __m256 dx = _mm256_sub_ps(mx, _mm256_loadu_ps(xs + k));
    const __m256 dy = _mm256_sub_ps(my, _mm256_loadu_ps(ys + k));
    const __m256 dz = _mm256_sub_ps(mz, _mm256_loadu_ps(zs + k));
    const __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                                    _mm256_mul_ps(dz, dz));
    const __m256 rr = _mm256_add_ps(_mm256_loadu_ps(rs + k), hv);
    unsigned mask = static_cast<unsigned>(
        _mm256_movemask_ps(_mm256_cmp_ps(d2, _mm256_mul_ps(rr, rr), _CMP_LE_OQ)));
    while (mask != 0 && count < capacity) {
      const uint32_t index = k + static_cast<uint32_t>(__builtin_ctz(mask));
      mask &= mask - 1;
      if (index < total) out[count++] = index;
    }
  }
  return count;
}
#endif

#if defined(DRAPE_HULL_AVX2)
// The SphereFilter test of eight midpoints and half lengths against one sphere.
DRAPE_AVX2 inline __m256 SphereTestAvx(__m256 mx, __m256 my, __m256 mz, __m256 half, float cx,
                                       float cy, float cz, float r) {
  const __m256 dx = _mm256_sub_ps(mx, _mm256_set1_ps(cx));
  const __m256 dy = _mm256_sub_ps(my, _mm256_set1_ps(cy));
  const __m256 dz = _mm256_sub_ps(mz, _mm256_set1_ps(cz));
  const __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                                  _mm256_mul_ps(dz, dz));
  const __m256 rr = _mm256_add_ps(_mm256_set1_ps(r), half);
  return _mm256_cmp_ps(d2, _mm256_mul_ps(rr, rr), _CMP_LE_OQ);
}
// The broad phase of eight particles at once (lanes beyond `lanes` repeat the first): per
// particle, the bit mask of the colliders k < total (<= 32) that BroadPhase keeps, by the same
// arithmetic (mid = (p0 + p1) * 0.5, half = |p1 - p0| * 0.50001, the SphereFilter test). A group
// wholly outside the union sphere (centre, radius) gets empty masks without the per-collider
// tests. Returns the lanes whose previous and current positions and velocity are all finite (bit
// l for lane l; IsFinite's answer, as x - x == 0).
DRAPE_AVX2 uint32_t SphereMasksAvx(const Float3* p0, const Float3* p1, const Float3* velocity,
                                   uint32_t lanes, const float* xs, const float* ys,
                                   const float* zs, const float* rs, uint32_t total,
                                   Float3 union_center, float union_radius, uint32_t* masks) {
  alignas(32) float coordinates[9][8];
  if (lanes == 8) {
    // Eight Float3 are 24 contiguous floats: three per-axis vectors by two 128-bit loads per
    // 256-bit register and five shuffles.
    const Float3* sources[3] = {p0, p1, velocity};
    for (int array = 0; array < 3; ++array) {
      const float* f = &sources[array]->x;
      const __m256 m03 =
          _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(f)), _mm_loadu_ps(f + 12), 1);
      const __m256 m14 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(f + 4)),
                                              _mm_loadu_ps(f + 16), 1);
      const __m256 m25 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(f + 8)),
                                              _mm_loadu_ps(f + 20), 1);
      const __m256 xy = _mm256_shuffle_ps(m14, m25, _MM_SHUFFLE(2, 1, 3, 2));
      const __m256 yz = _mm256_shuffle_ps(m03, m14, _MM_SHUFFLE(1, 0, 2, 1));
      _mm256_store_ps(coordinates[3 * array + 0],
                      _mm256_shuffle_ps(m03, xy, _MM_SHUFFLE(2, 0, 3, 0)));
      _mm256_store_ps(coordinates[3 * array + 1],
                      _mm256_shuffle_ps(yz, xy, _MM_SHUFFLE(3, 1, 2, 0)));
      _mm256_store_ps(coordinates[3 * array + 2],
                      _mm256_shuffle_ps(yz, m25, _MM_SHUFFLE(3, 0, 3, 1)));
    }
  } else {
    for (uint32_t l = 0; l < 8; ++l) {
      const uint32_t from = l < lanes ? l : 0;
      coordinates[0][l] = p0[from].x;
      coordinates[1][l] = p0[from].y;
      coordinates[2][l] = p0[from].z;
      coordinates[3][l] = p1[from].x;
      coordinates[4][l] = p1[from].y;
      coordinates[5][l] = p1[from].z;
      coordinates[6][l] = velocity[from].x;
      coordinates[7][l] = velocity[from].y;
      coordinates[8][l] = velocity[from].z;
    }
  }
  const __m256 zero = _mm256_setzero_ps();
  __m256 finite = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
  for (int c = 0; c < 9; ++c) {
    const __m256 x = _mm256_load_ps(coordinates[c]);
    finite = _mm256_and_ps(finite, _mm256_cmp_ps(_mm256_sub_ps(x, x), zero, _CMP_EQ_OQ));
  }
  const __m256 ax = _mm256_load_ps(coordinates[0]), ay = _mm256_load_ps(coordinates[1]),
               az = _mm256_load_ps(coordinates[2]), bx = _mm256_load_ps(coordinates[3]),
               by = _mm256_load_ps(coordinates[4]), bz = _mm256_load_ps(coordinates[5]);
  const __m256 one_half = _mm256_set1_ps(0.5f);
  const __m256 mx = _mm256_mul_ps(_mm256_add_ps(ax, bx), one_half);
  const __m256 my = _mm256_mul_ps(_mm256_add_ps(ay, by), one_half);
  const __m256 mz = _mm256_mul_ps(_mm256_add_ps(az, bz), one_half);
  const __m256 sx = _mm256_sub_ps(bx, ax), sy = _mm256_sub_ps(by, ay), sz = _mm256_sub_ps(bz, az);
  const __m256 length2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(sx, sx), _mm256_mul_ps(sy, sy)),
                                       _mm256_mul_ps(sz, sz));
  const __m256 half = _mm256_mul_ps(_mm256_sqrt_ps(length2), _mm256_set1_ps(0.50001f));
  const uint32_t finite_lanes = static_cast<uint32_t>(_mm256_movemask_ps(finite));
  // Invalid lanes fail every test; the skip needs the valid ones outside the union sphere.
  // The union test's sum is grown by 1e-5 relative (the float tests round by ~1e-7 relative), so
  // a lane that passes any collider's test passes it whatever its half length.
  const __m256 ux = _mm256_sub_ps(mx, _mm256_set1_ps(union_center.x));
  const __m256 uy = _mm256_sub_ps(my, _mm256_set1_ps(union_center.y));
  const __m256 uz = _mm256_sub_ps(mz, _mm256_set1_ps(union_center.z));
  const __m256 ud2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(ux, ux), _mm256_mul_ps(uy, uy)),
                                   _mm256_mul_ps(uz, uz));
  const __m256 urr =
      _mm256_mul_ps(_mm256_add_ps(_mm256_set1_ps(union_radius), half), _mm256_set1_ps(1.00001f));
  const __m256 near = _mm256_cmp_ps(ud2, _mm256_mul_ps(urr, urr), _CMP_LE_OQ);
  __m256i acc = _mm256_setzero_si256();
  if (_mm256_movemask_ps(_mm256_and_ps(near, finite)) != 0) {
    for (uint32_t k = 0; k < total; ++k) {
      const __m256 inside = SphereTestAvx(mx, my, mz, half, xs[k], ys[k], zs[k], rs[k]);
      acc = _mm256_or_si256(acc, _mm256_and_si256(_mm256_castps_si256(inside),
                                                  _mm256_set1_epi32(static_cast<int>(1u << k))));
    }
  }
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(masks), acc);
  return finite_lanes;
}
#endif

struct PlaneKernels {
  float (*max)(const PlaneSoa&, Float3);
  uint32_t (*first_equal)(const PlaneSoa&, Float3, float);
  DualResult (*dual)(const PlaneSoa&, Float3, Float3);
  DualResult (*dual_same)(const PlaneSoa&, Float3);  // dual(s, a, a)
  ClipResult (*clip)(const PlaneSoa&, Float3, Float3);
  uint32_t (*entry)(const PlaneSoa&, Float3, Float3, float);
  uint32_t (*spheres)(const float*, const float*, const float*, const float*, uint32_t, Float3,
                      float, uint32_t*, uint32_t);
};
// level: 0 portable scalar, 1 SSE, 2 AVX2.
const PlaneKernels& Kernels(uint8_t level) {
  static const PlaneKernels scalar{MaxScalar,  FirstEqualScalar, DualScalar,        DualSameScalar,
                                   ClipScalar, EntryScalar,      SphereFilterScalar};
#if defined(__SSE2__)
  static const PlaneKernels sse{MaxSse,  FirstEqualSse, DualSse,        DualSameSse,
                                ClipSse, EntrySse,      SphereFilterSse};
#else
  static const PlaneKernels& sse = scalar;
#endif
#if defined(DRAPE_HULL_AVX2)
  static const PlaneKernels avx{MaxAvx,  FirstEqualAvx, DualAvx,        DualSameAvx,
                                ClipAvx, EntryAvx,      SphereFilterAvx};
#else
  static const PlaneKernels& avx = sse;
#endif
  return level >= 2 ? avx : (level == 1 ? sse : scalar);
}

}  // namespace

float HullColliderSet::PlaneMax(const HullRecord& h, Float3 p, uint32_t* arg) const {
  const uint32_t b = h.plane_begin;
  const PlaneSoa soa{&plane_nx_[b], &plane_ny_[b], &plane_nz_[b], &plane_d_[b], h.plane_padded};
  const PlaneKernels& k = Kernels(simd_level_);
  const float m = k.max(soa, p);
  if (arg != nullptr) *arg = k.first_equal(soa, p, m);
  return m;
}

uint32_t HullColliderSet::Locate(const Hierarchy& k, HullUv q, uint32_t* steps) const {
  const double qu = q.u, qv = q.v;
  const double wu = k.interior_u - qu, wv = k.interior_v - qv;  // tie-break direction
  uint32_t tests = 0;
  // Accepts q (perturbed by simulation of simplicity towards the interior point, then along +u,
  // then +v) when all three canonical edge functions are positive.
  auto accept = [&](uint32_t node, double* min_edge) {
    ++tests;
    const EdgeFunction* e = &node_edges_[3 * size_t(node)];
    double lowest = std::numeric_limits<double>::infinity();
    bool inside = true;
    for (int i = 0; i < 3; ++i) {
      const double value = e[i].du * (qv - e[i].av) - e[i].dv * (qu - e[i].au);
      lowest = std::min(lowest, value);
      if (value > 0.0) continue;
      if (value < 0.0) {
        inside = false;
        continue;
      }
      double tie = e[i].du * wv - e[i].dv * wu;
      if (tie == 0.0) tie = -e[i].dv;
      if (tie == 0.0) tie = e[i].du;
      if (tie < 0.0) inside = false;
    }
    if (min_edge != nullptr) *min_edge = lowest;
    return inside;
  };
  // Picks the accepting node of [list], or (rounding, never in exact arithmetic) the one whose
  // smallest edge value is largest.
  auto pick = [&](const uint32_t* list, uint32_t count) {
    uint32_t best = list[0];
    double best_value = -std::numeric_limits<double>::infinity();
    for (uint32_t i = 0; i < count; ++i) {
      double lowest;
      if (accept(list[i], &lowest)) return list[i];
      if (lowest > best_value) {
        best_value = lowest;
        best = list[i];
      }
    }
    return best;
  };
  uint32_t node = k.root_begin;
  double best_root = -std::numeric_limits<double>::infinity();
  for (uint32_t r = k.root_begin; r < k.root_end; ++r) {
    double lowest;
    if (accept(r, &lowest)) {
      node = r;
      break;
    }
    if (lowest > best_root) {
      best_root = lowest;
      node = r;
    }
  }
  while (node_child_begin_[node + 1] > node_child_begin_[node]) {
    const uint32_t begin = node_child_begin_[node];
    node = pick(&node_children_[begin], node_child_begin_[node + 1] - begin);
  }
  if (steps != nullptr) *steps = tests;
  return node;
}

bool HullColliderSet::InsideKirkpatrick(const HullRecord& h, Float3 p) const {
  const HullUv q = ProjectHullUv(p, h.uv_origin, h.uv_u, h.uv_v);
  auto side_holds = [&](uint32_t leaf) {
    const int32_t plane = node_leaf_plane_[leaf];
    if (plane >= 0) return PlaneSignedDistance(planes_[h.plane_begin + plane], p) <= 0.f;
    const uint32_t begin = node_guard_begin_[leaf], end = node_guard_begin_[leaf + 1];
    if (begin == end) return false;  // outside the projected hull
    for (uint32_t i = begin; i < end; ++i)
      if (PlaneSignedDistance(planes_[h.plane_begin + node_guard_planes_[i]], p) > 0.f)
        return false;
    return true;
  };
  return side_holds(Locate(h.upper, q, nullptr)) && side_holds(Locate(h.lower, q, nullptr));
}

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

void HullColliderSet::PushOut(const HullRecord& h, Float3 p, float max_value,
                              ContactQuery* c) const {
  const uint32_t b = h.plane_begin;
  const PlaneSoa soa{&plane_nx_[b], &plane_ny_[b], &plane_nz_[b], &plane_d_[b], h.plane_padded};
  const uint32_t j = Kernels(simd_level_).first_equal(soa, p, max_value);
  const Plane& plane = planes_[b + j];
  const Float3 projected = p - plane.normal * max_value;
  c->point = NudgeOut(projected, plane.normal, 1.f + std::fabs(plane.offset),
                      [&](Float3 x) { return PlaneSignedDistance(plane, x); });
  c->normal = plane.normal;
}

ContactQuery HullColliderSet::HullNarrow(const HullRecord& h, Float3 a, Float3 b) const {
  ContactQuery c;
  const bool kirkpatrick = options_.inside_test == InsideTest::kKirkpatrick;
  const uint32_t base = h.plane_begin;
  const PlaneSoa soa{&plane_nx_[base], &plane_ny_[base], &plane_nz_[base], &plane_d_[base],
                     h.plane_padded};
  const PlaneKernels& kernels = Kernels(simd_level_);
  float max_a = 1.f, max_b;
  if (options_.continuous) {
    // A particle at rest (or a point query) tests one point: the same answer for half the work.
    const DualResult dual = std::memcmp(&a, &b, sizeof(Float3)) == 0 ? kernels.dual_same(soa, a)
                                                                     : kernels.dual(soa, a, b);
    if (dual.separated) return c;  // one plane has both ends outside: no contact
    max_a = dual.max_a;
    max_b = dual.max_b;
  } else {
    max_b = kernels.max(soa, b);
  }
  const bool inside_b = kirkpatrick ? InsideKirkpatrick(h, b) : max_b <= 0.f;
  c.inside_end = inside_b;
  c.depth = inside_b ? std::max(0.f, -max_b) : 0.f;
  auto discrete = [&](float t, uint8_t flags) {
    c.contact = true;
    c.t = t;
    c.flags = flags;
    if (options_.response == HullResponse::kMapTableRay) {
      uint32_t plane;
      Float3 hit;
      if (MapRay(h, b, &hit, &plane)) {
        const Plane& pl = planes_[base + plane];
        c.point = NudgeOut(hit, pl.normal, 1.f + std::fabs(pl.offset),
                           [&](Float3 x) { return PlaneSignedDistance(pl, x); });
        c.normal = pl.normal;
        return;
      }
      c.flags |= kCollisionFallback;
    }
    PushOut(h, b, max_b, &c);
  };
  if (!options_.continuous) {
    if (inside_b) discrete(1.f, kCollisionNone);
    return c;
  }
  const bool inside_a = kirkpatrick ? InsideKirkpatrick(h, a) : max_a <= 0.f;
  if (inside_a) {
    if (inside_b) discrete(0.f, kCollisionStartedInside);
    return c;
  }
  // Cyrus-Beck clip of a -> b by the half-spaces (no plane has both ends outside here, so every
  // entering plane has fb <= 0 and fa - fb > 0).
  const ClipResult clip = kernels.clip(soa, a, b);
  if (clip.t_in >= 0.f && clip.t_in <= clip.t_out) {
    const Plane& pl = planes_[base + kernels.entry(soa, a, b, clip.t_in)];
    const Float3 target = options_.entry_response == EntryResponse::kProjectEnd
                              ? b - pl.normal * PlaneSignedDistance(pl, b)
                              : a + (b - a) * clip.t_in;
    c.contact = true;
    c.t = clip.t_in;
    c.point = NudgeOut(target, pl.normal, 1.f + std::fabs(pl.offset),
                       [&](Float3 x) { return PlaneSignedDistance(pl, x); });
    c.normal = pl.normal;
    return c;
  }
  if (inside_b) discrete(1.f, kCollisionNone);  // rounding: inside without a found entry
  return c;
}

ContactQuery HullColliderSet::SphereNarrow(float radius, Float3 a, Float3 b) const {
  ContactQuery c;
  const float r2 = radius * radius;
  const float lb2 = Dot(b, b);
  const bool inside_b = lb2 <= r2;
  c.inside_end = inside_b;
  c.depth = inside_b ? std::max(0.f, radius - std::sqrt(lb2)) : 0.f;
  auto outside_sphere = [&](Float3 x) { return Dot(x, x) - r2; };
  auto radial = [&](float t, uint8_t flags) {
    const Float3 n = NormalizeOr(b, NormalizeOr(a - b, NormalizeOr(a, Float3{0.f, 1.f, 0.f})));
    c.contact = true;
    c.t = t;
    c.flags = flags;
    c.normal = n;
    c.point = NudgeOut(n * radius, n, radius, outside_sphere);
  };
  if (!options_.continuous) {
    if (inside_b) radial(1.f, kCollisionNone);
    return c;
  }
  if (Dot(a, a) <= r2) {
    if (inside_b) radial(0.f, kCollisionStartedInside);
    return c;
  }
  // |a + t (b - a)|^2 = r^2, first root, in double.
  const Vec3D ad = ToD(a), dd = ToD(b - a);
  const double qa = DotD(dd, dd), qb = DotD(ad, dd), qc = DotD(ad, ad) - double(radius) * radius;
  const double disc = qb * qb - qa * qc;
  if (qa > 0.0 && qb < 0.0 && disc >= 0.0) {
    const double t = (-qb - std::sqrt(disc)) / qa;
    if (t <= 1.0) {
      const Float3 entry_point = ToF(ad + dd * t);
      const Float3 n = NormalizeOr(entry_point, NormalizeOr(a, Float3{0.f, 1.f, 0.f}));
      c.contact = true;
      c.t = static_cast<float>(std::max(0.0, t));
      c.normal = n;
      auto outside_plane = [&](Float3 x) { return Dot(n, x) - radius; };
      if (options_.entry_response == EntryResponse::kProjectEnd) {
        // Onto the tangent plane at the entry point: on or outside the sphere.
        const Float3 target = b - n * (Dot(n, b) - radius);
        c.point = NudgeOut(target, n, radius, outside_plane);
      } else {
        c.point = NudgeOut(n * radius, n, radius, outside_sphere);
      }
      return c;
    }
  }
  if (inside_b) radial(1.f, kCollisionNone);
  return c;
}

// =================================================================================================
// World-space queries
// =================================================================================================

ContactQuery HullColliderSet::ColliderContact(uint32_t collider, const ActiveFrames& f, Float3 p0,
                                              Float3 p1) const {
  ContactQuery c;
  const uint32_t hull_total = static_cast<uint32_t>(hulls_.size());
  if (collider < hull_total) {
    const HullRecord& h = hulls_[collider];
    // OBB rejection in the OBB frame: the end point, then (continuous) the segment.
    // Both ends are transformed and all compares evaluated without short circuits: one branch
    // on the whole test (whether the end is inside is a coin toss near the hull, and a
    // mispredicted branch costs more than the arithmetic).
    const Float3 bo = TransformPoint(f.to_obb_end, p1);
    const Float3 ao = TransformPoint(f.to_obb_start, p0);
    const Float3 half = h.obb_half;
    const bool end_in =
        (std::fabs(bo.x) <= half.x) & (std::fabs(bo.y) <= half.y) & (std::fabs(bo.z) <= half.z);
    const bool beyond_one_face =
        ((ao.x > half.x) & (bo.x > half.x)) | ((ao.x < -half.x) & (bo.x < -half.x)) |
        ((ao.y > half.y) & (bo.y > half.y)) | ((ao.y < -half.y) & (bo.y < -half.y)) |
        ((ao.z > half.z) & (bo.z > half.z)) | ((ao.z < -half.z) & (bo.z < -half.z));
    const bool reject = !end_in && (!options_.continuous || beyond_one_face);
    if (reject) return c;
    const Float3 a = TransformPoint(f.to_local_start, p0);
    const Float3 b = TransformPoint(f.to_local_end, p1);
    c = HullNarrow(h, a, b);
  } else {
    const Float3 a = TransformPoint(f.to_local_start, p0);
    const Float3 b = TransformPoint(f.to_local_end, p1);
    c = SphereNarrow(spheres_[collider - hull_total].radius, a, b);
  }
  if (c.contact) {
    c.point = TransformPoint(f.to_world_end, c.point);
    c.normal = TransformVector(f.to_world_end, c.normal);
  }
  return c;
}

uint32_t HullColliderSet::BroadPhase(Float3 p0, Float3 p1, float s0, float s1, bool active,
                                     uint32_t* out) const {
  // Sphere around the particle's segment against the colliders' swept spheres. The whole-step
  // spheres filter first when the fractions are not the selected ones; the candidates are then
  // tested against their swept sphere over [s0, s1] computed here, with the same arithmetic as
  // SelectSubstep's, so both paths keep exactly the same candidates.
  const float* xs = active ? sweep_x_.data() : full_x_.data();
  const float* ys = active ? sweep_y_.data() : full_y_.data();
  const float* zs = active ? sweep_z_.data() : full_z_.data();
  const float* rs = active ? sweep_r_.data() : full_r_.data();
  const Float3 mid = (p0 + p1) * 0.5f;
  const float half = Length(p1 - p0) * 0.50001f;
  uint32_t count =
      Kernels(simd_level_).spheres(xs, ys, zs, rs, collider_count_, mid, half, out, kMaxCandidates);
  if (active) return count;
  uint32_t kept = 0;
  for (uint32_t i = 0; i < count; ++i) {
    Float3 center;
    float radius;
    ComputeSweep(out[i], s0, s1, &center, &radius);
    const float dx = mid.x - center.x, dy = mid.y - center.y, dz = mid.z - center.z;
    const float rr = radius + half;
    if (dx * dx + dy * dy + dz * dz <= rr * rr) out[kept++] = out[i];
  }
  return kept;
}

namespace {

// The contact planes one particle has been pushed out through in one ResolveParticle call, as
// half-spaces n . x >= d (d = n . contact point + separation). Each is a supporting plane of its
// collider (a hull face plane, or a sphere's tangent plane), so a point on the outer side of all
// of them is outside every collider that produced one. Re-imposing them after each response is
// what stops a particle pinched between overlapping colliders (armpit, crotch, a skirt between
// the thighs at a large step) from being pushed out of one collider into the other and back.
class ContactPlanes {
 public:
  void Add(Float3 normal, float offset) {
    if (count_ == kMax) {  // keep the newest: shift the oldest out
      for (uint32_t i = 1; i < kMax; ++i) planes_[i - 1] = planes_[i];
      --count_;
    }
    planes_[count_++] = {normal, offset};
  }
  uint32_t count() const { return count_; }

  // Moves *x to the nearest point on the outer side of every plane, by an active-set solve in
  // double over at most three planes (the nearest point of a polyhedral region in 3D lies on at
  // most three of its faces). Leaves *x unchanged and returns false when the violated planes have
  // no common solution (they face each other: the particle is pinched with no room).
  bool Enforce(Float3* x) const {
    const double x0[3] = {x->x, x->y, x->z};
    double p[3] = {x0[0], x0[1], x0[2]};
    // The largest violation at the start: the projection may not move the particle much farther
    // than that. Planes that nearly face each other (a pinch between two colliders a few degrees
    // off parallel) meet in a line far away; following it would throw the particle across the
    // body. Refusing keeps the last response (the Gauss-Seidel passes go on from there).
    double start_violation = 0.0;
    for (uint32_t i = 0; i < count_; ++i) {
      start_violation = std::max(start_violation, Offset(i) - Dot3(i, x0));
    }
    uint32_t active[3];
    uint32_t active_count = 0;
    bool skipped[kMax] = {false, false, false, false};  // redundant with the active planes
    const auto build_and_solve = [&](double lambda[3]) {
      double g[3][3], r[3];
      for (uint32_t a = 0; a < active_count; ++a) {
        for (uint32_t b = 0; b < active_count; ++b) g[a][b] = DotNormals(active[a], active[b]);
        r[a] = Offset(active[a]) - Dot3(active[a], x0);
      }
      return Solve(g, r, active_count, lambda);
    };
    for (uint32_t round = 0; round < 2 * kMax; ++round) {
      // The most violated plane not yet active (violations below kTolerance are rounding).
      uint32_t worst = kMax;
      double worst_violation = kTolerance;
      for (uint32_t i = 0; i < count_; ++i) {
        bool is_active = skipped[i];
        for (uint32_t k = 0; k < active_count; ++k) is_active |= active[k] == i;
        const double v = Offset(i) - Dot3(i, p);
        if (!is_active && v > worst_violation) {
          worst = i;
          worst_violation = v;
        }
      }
      if (worst == kMax) break;
      if (active_count == 3) return false;
      active[active_count++] = worst;
      // p = x0 + sum_j lambda_j n_j with n_k . p = d_k for the active planes: G lambda = r.
      double lambda[3] = {0.0, 0.0, 0.0};
      if (!build_and_solve(lambda)) {
        // Dependent on the active planes (the same face met twice, coplanar neighbours): skip
        // it; the final check says whether it holds anyway.
        --active_count;
        skipped[worst] = true;
        if (!build_and_solve(lambda)) return false;
      }
      // A negative multiplier: that plane holds without being pushed on; drop it and re-solve.
      for (uint32_t a = 0; a < active_count;) {
        if (lambda[a] < 0.0) {
          for (uint32_t b = a + 1; b < active_count; ++b) active[b - 1] = active[b];
          --active_count;
          if (!build_and_solve(lambda)) return false;
          a = 0;
          continue;
        }
        ++a;
      }
      for (int k = 0; k < 3; ++k) {
        p[k] = x0[k];
        for (uint32_t a = 0; a < active_count; ++a) p[k] += lambda[a] * Component(active[a], k);
      }
    }
    for (uint32_t i = 0; i < count_; ++i) {
      if (Offset(i) - Dot3(i, p) > kTolerance) return false;  // infeasible: a pinch
    }
    const double moved =
        std::sqrt((p[0] - x0[0]) * (p[0] - x0[0]) + (p[1] - x0[1]) * (p[1] - x0[1]) +
                  (p[2] - x0[2]) * (p[2] - x0[2]));
    if (moved > kMaxStretch * start_violation + kTolerance) return false;
    *x = Float3{static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2])};
    // Rounding to float can leave a plane a few ulps short: nudge out along it.
    for (uint32_t i = 0; i < count_; ++i) {
      const Float3 n = planes_[i].normal;
      for (int tries = 0; tries < 4 && Dot(n, *x) < planes_[i].offset; ++tries) {
        const float push = std::max(planes_[i].offset - Dot(n, *x), 1e-7f);
        *x = *x + n * push;
      }
    }
    return true;
  }

 private:
  static constexpr uint32_t kMax = 4;
  static constexpr double kTolerance = 1e-6;  // metres: violations below this are rounding
  // The projection may move the particle at most this many times its largest violation: the
  // planes then meet at 11.4 degrees or more (cot(5.7 deg) = 10); narrower wedges are refused.
  static constexpr double kMaxStretch = 10.0;
  struct HalfSpace {
    Float3 normal;
    float offset;
  };
  double Offset(uint32_t i) const { return planes_[i].offset; }
  double Component(uint32_t i, int k) const {
    const Float3 n = planes_[i].normal;
    return k == 0 ? n.x : (k == 1 ? n.y : n.z);
  }
  double Dot3(uint32_t i, const double q[3]) const {
    return Component(i, 0) * q[0] + Component(i, 1) * q[1] + Component(i, 2) * q[2];
  }
  double DotNormals(uint32_t i, uint32_t j) const {
    return Component(i, 0) * Component(j, 0) + Component(i, 1) * Component(j, 1) +
           Component(i, 2) * Component(j, 2);
  }
  // Gaussian elimination with partial pivoting on an n x n system, n <= 3. False when singular
  // (parallel or dependent planes).
  static bool Solve(double g[3][3], double r[3], uint32_t n, double out[3]) {
    double a[3][4];
    for (uint32_t i = 0; i < n; ++i) {
      for (uint32_t j = 0; j < n; ++j) a[i][j] = g[i][j];
      a[i][3] = r[i];
    }
    for (uint32_t col = 0; col < n; ++col) {
      uint32_t pivot = col;
      for (uint32_t row = col + 1; row < n; ++row) {
        if (std::fabs(a[row][col]) > std::fabs(a[pivot][col])) pivot = row;
      }
      if (std::fabs(a[pivot][col]) < 1e-9) return false;
      if (pivot != col) {
        for (uint32_t j = 0; j < 4; ++j) std::swap(a[pivot][j], a[col][j]);
      }
      for (uint32_t row = 0; row < n; ++row) {
        if (row == col) continue;
        const double f = a[row][col] / a[col][col];
        for (uint32_t j = col; j < 4; ++j) a[row][j] -= f * a[col][j];
      }
    }
    for (uint32_t i = 0; i < n; ++i) out[i] = a[i][3] / a[i][i];
    return true;
  }

  HalfSpace planes_[kMax];
  uint32_t count_ = 0;
};

}  // namespace

template <bool kActive>
void HullColliderSet::ResolveParticle(Float3 p0, Float3* p1, Float3* velocity, uint8_t* flags,
                                      const ResponseParams& params, float s0, float s1,
                                      const uint32_t* first_candidates) const {
  uint8_t result = kCollisionNone;
  Float3 position = *p1, vel = *velocity;
  uint32_t last_single = UINT32_MAX;  // the one collider resolved in the previous pass, if so
  ContactPlanes planes;
  for (uint32_t pass = 0; pass < options_.gauss_seidel_passes; ++pass) {
    // Candidates for the current segment: a response may have moved the particle towards a
    // collider the original segment did not reach.
    uint32_t candidates[kMaxCandidates];
    uint32_t count = 0;
    if (pass == 0 && first_candidates != nullptr) {
      for (uint32_t mask = *first_candidates; mask != 0; mask &= mask - 1)
        candidates[count++] = static_cast<uint32_t>(__builtin_ctz(mask));
    } else {
      count = BroadPhase(p0, position, s0, s1, kActive, candidates);
    }
    if (count == 0) break;
    // Only the collider just resolved: its response left the particle on or outside it.
    if (pass > 0 && count == 1 && candidates[0] == last_single) break;
    // Transforms: the cached ones, or (other fractions) computed into raw stack storage so the
    // common path does not pay for constructing them.
    const ActiveFrames* frames[kMaxCandidates];
    alignas(
        ActiveFrames) unsigned char storage[kActive ? 1 : kMaxCandidates * sizeof(ActiveFrames)];
    for (uint32_t i = 0; i < count; ++i) {
      if constexpr (kActive) {
        frames[i] = &active_[candidates[i]];
      } else {
        ActiveFrames* f = new (storage + i * sizeof(ActiveFrames)) ActiveFrames;
        ComputeFrames(candidates[i], s0, s1, f);
        frames[i] = f;
      }
    }
    // Raw storage again: only the first `count` are constructed.
    alignas(ContactQuery) unsigned char contact_storage[kMaxCandidates * sizeof(ContactQuery)];
    ContactQuery* contacts = reinterpret_cast<ContactQuery*>(contact_storage);
    uint32_t order[kMaxCandidates];
    uint32_t hits = 0;
    for (uint32_t i = 0; i < count; ++i) {
      // The collider resolved alone in the previous pass left the particle on or outside it.
      if (candidates[i] == last_single) {
        new (&contacts[i]) ContactQuery();
        continue;
      }
      new (&contacts[i]) ContactQuery(ColliderContact(candidates[i], *frames[i], p0, position));
      if (contacts[i].contact) order[hits++] = i;
    }
    if (hits == 0) break;
    // Deepest first; ties keep collider order (insertion sort is stable).
    for (uint32_t i = 1; i < hits; ++i) {
      const uint32_t key = order[i];
      uint32_t j = i;
      while (j > 0 && contacts[order[j - 1]].depth < contacts[key].depth) {
        order[j] = order[j - 1];
        --j;
      }
      order[j] = key;
    }
    for (uint32_t rank = 0; rank < hits; ++rank) {
      const uint32_t i = order[rank];
      const ContactQuery c =
          rank == 0 ? contacts[i] : ColliderContact(candidates[i], *frames[i], p0, position);
      if (!c.contact) continue;
      ApplyResponse(c, params, &position, &vel);
      result |= static_cast<uint8_t>(kCollisionContact | c.flags);
      planes.Add(c.normal, Dot(c.normal, c.point) + params.separation);
      if (planes.count() > 1) planes.Enforce(&position);
    }
    last_single = hits == 1 ? candidates[order[0]] : UINT32_MAX;
  }
  *p1 = position;
  *velocity = vel;
  *flags = result;
}

Status HullColliderSet::CollideBatch(std::span<const Float3> previous, std::span<Float3> positions,
                                     std::span<Float3> velocities, std::span<uint8_t> flags,
                                     const ResponseParams& params, float substep_start,
                                     float substep_end, uint32_t* contact_count) const {
  if (contact_count != nullptr) *contact_count = 0;
  const size_t n = positions.size();
  if (previous.size() != n || velocities.size() != n || flags.size() != n)
    return Status(
        StatusCode::kInvalidArgument,
        "HullColliderSet::CollideBatch: previous, positions, velocities and flags differ in size");
  if (!(std::isfinite(params.friction) && params.friction >= 0.f && params.friction <= 1.f &&
        std::isfinite(params.restitution) && params.restitution >= 0.f &&
        params.restitution <= 1.f && std::isfinite(params.separation) && params.separation >= 0.f))
    return Status(
        StatusCode::kInvalidArgument,
        "HullColliderSet::CollideBatch: friction/restitution not in [0, 1] or separation < 0");
  if (!(substep_start >= 0.f && substep_start <= substep_end && substep_end <= 1.f))
    return Status(StatusCode::kInvalidArgument,
                  "HullColliderSet::CollideBatch: substep fractions are not 0 <= s0 <= s1 <= 1");
  const bool active = substep_start == active_s0_ && substep_end == active_s1_;
  const int64_t count = static_cast<int64_t>(n);
  uint32_t contacts = 0;
#if defined(DRAPE_HULL_AVX2)
  if (active && simd_level_ >= 2 && collider_count_ <= 32) {
    // The first broad phase of eight particles at once (no branch per particle and collider); a
    // particle without candidates is done (ResolveParticle would leave it as it is).
    const int64_t groups = (count + 7) / 8;
#pragma omp parallel for schedule(dynamic, 32) reduction(+ : contacts) if (count > 4096)
    for (int64_t g = 0; g < groups; ++g) {
      const size_t first = static_cast<size_t>(g) * 8;
      const uint32_t lanes = static_cast<uint32_t>(std::min<size_t>(8, n - first));
      alignas(32) uint32_t masks[8];
      const uint32_t finite =
          SphereMasksAvx(&previous[first], &positions[first], &velocities[first], lanes,
                         sweep_x_.data(), sweep_y_.data(), sweep_z_.data(), sweep_r_.data(),
                         collider_count_, sweep_union_center_, sweep_union_radius_, masks);
      // Only the invalid lanes and those with candidates need more; the others are done.
      uint32_t work = ~finite;
      for (uint32_t l = 0; l < 8; ++l) work |= masks[l] != 0 ? 1u << l : 0u;
      work &= (1u << lanes) - 1;
      std::memset(&flags[first], kCollisionNone, lanes);
      for (; work != 0; work &= work - 1) {
        const uint32_t l = static_cast<uint32_t>(__builtin_ctz(work));
        const size_t k = first + l;
        if (!((finite >> l) & 1u)) {
          flags[k] = kCollisionInvalidInput;
          continue;
        }
        ResolveParticle<true>(previous[k], &positions[k], &velocities[k], &flags[k], params,
                              substep_start, substep_end, &masks[l]);
        if (flags[k] & kCollisionContact) ++contacts;
      }
    }
    if (contact_count != nullptr) *contact_count = contacts;
    return Status::Ok();
  }
#endif
  // Small batches stay on the calling thread: waking a team costs more than it saves, and on a
  // loaded machine far more (measured: a 961-particle sheet 25x slower with 2 threads).
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : contacts) if (count > 4096)
  for (int64_t i = 0; i < count; ++i) {
    const size_t k = static_cast<size_t>(i);
    if (!IsFinite(previous[k]) || !IsFinite(positions[k]) || !IsFinite(velocities[k])) {
      flags[k] = kCollisionInvalidInput;
      continue;
    }
    if (active) {
      ResolveParticle<true>(previous[k], &positions[k], &velocities[k], &flags[k], params,
                            substep_start, substep_end);
    } else {
      ResolveParticle<false>(previous[k], &positions[k], &velocities[k], &flags[k], params,
                             substep_start, substep_end);
    }
    if (flags[k] & kCollisionContact) ++contacts;
  }
  if (contact_count != nullptr) *contact_count = contacts;
  return Status::Ok();
}

ContactQuery HullColliderSet::Query(Float3 p0, Float3 p1, uint8_t kinds) const {
  ContactQuery best;
  if (!IsFinite(p0) || !IsFinite(p1)) {
    best.flags = kCollisionInvalidInput;
    return best;
  }
  bool inside = false;
  float depth = 0.f;
  const uint32_t hull_total = static_cast<uint32_t>(hulls_.size());
  for (uint32_t k = 0; k < motions_.size(); ++k) {
    const bool is_hull = k < hull_total;
    if (!(kinds & (is_hull ? kColliderHulls : kColliderSpheres))) continue;
    const ContactQuery c = ColliderContact(k, active_[k], p0, p1);
    inside = inside || c.inside_end;
    depth = std::max(depth, c.depth);
    if (!c.contact) continue;
    const bool better =
        !best.contact || c.depth > best.depth || (c.depth == best.depth && c.t < best.t);
    if (better) best = c;
  }
  best.inside_end = inside;
  best.depth = depth;
  return best;
}

// =================================================================================================
// Per-collider access
// =================================================================================================

bool HullColliderSet::InsideLocal(uint32_t hull, Float3 p, InsideTest test) const {
  const HullRecord& h = hulls_[hull];
  if (test == InsideTest::kKirkpatrick) return h.has_hierarchy && InsideKirkpatrick(h, p);
  return PlaneMax(h, p, nullptr) <= 0.f;
}

float HullColliderSet::MaxPlaneDistanceLocal(uint32_t hull, Float3 p, uint32_t* plane) const {
  return PlaneMax(hulls_[hull], p, plane);
}

int32_t HullColliderSet::LocateLocal(uint32_t hull, Float3 p, bool upper, uint32_t* steps) const {
  const HullRecord& h = hulls_[hull];
  if (steps != nullptr) *steps = 0;
  if (!h.has_hierarchy) return -1;
  return node_leaf_plane_[Locate(upper ? h.upper : h.lower,
                                 ProjectHullUv(p, h.uv_origin, h.uv_u, h.uv_v), steps)];
}

ContactQuery HullColliderSet::QueryHullLocal(uint32_t hull, Float3 a, Float3 b) const {
  if (!IsFinite(a) || !IsFinite(b)) {
    ContactQuery c;
    c.flags = kCollisionInvalidInput;
    return c;
  }
  return HullNarrow(hulls_[hull], a, b);
}

bool HullColliderSet::MapTableRayLocal(uint32_t hull, Float3 p, Float3* point,
                                       Float3* normal) const {
  const HullRecord& h = hulls_[hull];
  if (!h.has_map) return false;
  uint32_t plane;
  if (!MapRay(h, p, point, &plane)) return false;
  *normal = planes_[h.plane_begin + plane].normal;
  return true;
}

}  // namespace drape

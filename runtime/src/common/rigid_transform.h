#pragma once
// Private to the runtime: rigid transforms in double (a unit quaternion and a translation), for
// posing colliders and interpolating their motion within a step without the rounding of float
// compositions; results are rounded to float matrices once.

#include <cmath>

#include "drape/formats/types.h"

namespace drape::detail {

struct QuatD {
  double x = 0, y = 0, z = 0, w = 1;
};
inline QuatD Mul(const QuatD& a, const QuatD& b) {
  return {
      a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
      a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}
inline QuatD Conjugate(const QuatD& q) { return {-q.x, -q.y, -q.z, q.w}; }
inline QuatD NormalizeQ(const QuatD& q) {
  const double len = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (!(len > 1e-300)) return QuatD{};
  return {q.x / len, q.y / len, q.z / len, q.w / len};
}
// The rotation nearest to the 3x3 part of m (Shepperd's method on the possibly non-orthonormal
// matrix, then normalised): scale and shear are dropped.
inline QuatD RotationOf(const Mat34& m) {
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
inline Vec3D ToD(Float3 a) { return {a.x, a.y, a.z}; }
inline Float3 ToF(const Vec3D& a) {
  return {static_cast<float>(a.x), static_cast<float>(a.y), static_cast<float>(a.z)};
}
inline Vec3D operator+(const Vec3D& a, const Vec3D& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3D operator-(const Vec3D& a, const Vec3D& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3D operator*(const Vec3D& a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline double DotD(const Vec3D& a, const Vec3D& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3D CrossD(const Vec3D& a, const Vec3D& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double LengthD(const Vec3D& a) { return std::sqrt(DotD(a, a)); }
inline Vec3D Rotate(const QuatD& q, const Vec3D& v) {
  const Vec3D u{q.x, q.y, q.z};
  const Vec3D t = CrossD(u, v) * 2.0;
  return v + t * q.w + CrossD(u, t);
}
struct RigidD {
  QuatD rotation;
  Vec3D translation;
};
inline Vec3D Apply(const RigidD& r, const Vec3D& p) {
  return Rotate(r.rotation, p) + r.translation;
}
inline Mat34 ToMat34(const RigidD& r) {
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
inline Mat34 InverseToMat34(const RigidD& r) {
  RigidD inv;
  inv.rotation = Conjugate(r.rotation);
  inv.translation = Rotate(inv.rotation, r.translation) * -1.0;
  return ToMat34(inv);
}

}  // namespace drape::detail

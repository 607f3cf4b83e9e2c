#pragma once
// Inline vector, quaternion and 3x4 matrix arithmetic on the plain types of drape/formats/types.h.
// Float throughout: this is the arithmetic the runtime's containment guarantees are stated in.

#include <cmath>

#include "drape/formats/types.h"

namespace drape {

inline Float3 operator+(Float3 a, Float3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Float3 operator-(Float3 a, Float3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Float3 operator-(Float3 a) { return {-a.x, -a.y, -a.z}; }
inline Float3 operator*(Float3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline Float3 operator*(float s, Float3 a) { return {a.x * s, a.y * s, a.z * s}; }
inline Float3& operator+=(Float3& a, Float3 b) { return a = a + b; }
inline Float3& operator-=(Float3& a, Float3 b) { return a = a - b; }
inline Float3& operator*=(Float3& a, float s) { return a = a * s; }
inline float Dot(Float3 a, Float3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Float3 Cross(Float3 a, Float3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float Length(Float3 a) { return std::sqrt(Dot(a, a)); }
inline Float3 Lerp(Float3 a, Float3 b, float t) { return a + (b - a) * t; }
// Unit vector along a, or `fallback` when a is (near) zero.
inline Float3 NormalizeOr(Float3 a, Float3 fallback) {
  const float len = Length(a);
  return len > 1e-20f ? a * (1.f / len) : fallback;
}
inline bool IsFinite(Float3 a) {
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
}
inline bool IsFinite(const Mat34& m) {
  for (float v : m.m)
    if (!std::isfinite(v)) return false;
  return true;
}

// Quaternions (x, y, z, w).
inline Quat Multiply(Quat a, Quat b) {
  return {
      a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
      a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}
inline Quat Normalize(Quat q) {
  const float len = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (!(len > 1e-20f)) return Quat{};
  const float inv = 1.f / len;
  return {q.x * inv, q.y * inv, q.z * inv, q.w * inv};
}
// Normalised linear interpolation on the shorter arc (hemisphere check). For keys sampled at
// 30 Hz or more the angle between neighbours is small and nlerp differs from slerp by < 1e-4 rad.
inline Quat Nlerp(Quat a, Quat b, float t) {
  const float dot = a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w;
  const float s = dot < 0.f ? -1.f : 1.f;
  return Normalize({a.x + (s * b.x - a.x) * t, a.y + (s * b.y - a.y) * t, a.z + (s * b.z - a.z) * t,
                    a.w + (s * b.w - a.w) * t});
}

// 3x4 matrices (row-major, column vectors).
inline Float3 TransformPoint(const Mat34& m, Float3 p) {
  return {m.m[0] * p.x + m.m[1] * p.y + m.m[2] * p.z + m.m[3],
          m.m[4] * p.x + m.m[5] * p.y + m.m[6] * p.z + m.m[7],
          m.m[8] * p.x + m.m[9] * p.y + m.m[10] * p.z + m.m[11]};
}
inline Float3 TransformVector(const Mat34& m, Float3 v) {
  return {m.m[0] * v.x + m.m[1] * v.y + m.m[2] * v.z, m.m[4] * v.x + m.m[5] * v.y + m.m[6] * v.z,
          m.m[8] * v.x + m.m[9] * v.y + m.m[10] * v.z};
}
// Applies the transpose of the 3x3 part: the inverse rotation when m is rigid.
inline Float3 TransformVectorTransposed(const Mat34& m, Float3 v) {
  return {m.m[0] * v.x + m.m[4] * v.y + m.m[8] * v.z, m.m[1] * v.x + m.m[5] * v.y + m.m[9] * v.z,
          m.m[2] * v.x + m.m[6] * v.y + m.m[10] * v.z};
}
// The cube root of the linear part's |determinant|: 1 for a rigid motion, 100 for a rig bound
// in centimetres and posed in metres.
inline float UniformScale(const Mat34& m) {
  const double det = double(m.m[0]) * (double(m.m[5]) * m.m[10] - double(m.m[6]) * m.m[9]) -
                     double(m.m[1]) * (double(m.m[4]) * m.m[10] - double(m.m[6]) * m.m[8]) +
                     double(m.m[2]) * (double(m.m[4]) * m.m[9] - double(m.m[5]) * m.m[8]);
  return static_cast<float>(std::cbrt(std::fabs(det)));
}
inline Mat34 Multiply(const Mat34& a, const Mat34& b) {
  Mat34 r;
  for (int row = 0; row < 3; ++row) {
    const float* ar = &a.m[4 * row];
    for (int col = 0; col < 4; ++col) {
      float v = ar[0] * b.m[col] + ar[1] * b.m[4 + col] + ar[2] * b.m[8 + col];
      if (col == 3) v += ar[3];
      r.m[4 * row + col] = v;
    }
  }
  return r;
}
// The pure translation by t.
inline Mat34 TranslationMatrix(Float3 t) {
  Mat34 m;
  m.m[3] = t.x;
  m.m[7] = t.y;
  m.m[11] = t.z;
  return m;
}
// Inverse of a rigid transform (rotation + translation).
inline Mat34 InverseRigid(const Mat34& m) {
  Mat34 r;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) r.m[4 * row + col] = m.m[4 * col + row];
  const Float3 t{m.m[3], m.m[7], m.m[11]};
  const Float3 rt = TransformVectorTransposed(m, t);
  r.m[3] = -rt.x;
  r.m[7] = -rt.y;
  r.m[11] = -rt.z;
  return r;
}
// General affine inverse (3x3 by cofactors). Returns false when the 3x3 part is singular.
bool InverseAffine(const Mat34& m, Mat34* inverse);

// Scale, then rotate, then translate.
Mat34 ToMatrix(const Transform& t);
// Linear interpolation of translation and scale, nlerp of rotation.
Transform Interpolate(const Transform& a, const Transform& b, float t);

}  // namespace drape

#include "drape/runtime/math.h"

namespace drape {

bool InverseAffine(const Mat34& m, Mat34* inverse) {
  const float a = m.m[0], b = m.m[1], c = m.m[2];
  const float d = m.m[4], e = m.m[5], f = m.m[6];
  const float g = m.m[8], h = m.m[9], i = m.m[10];
  const float co00 = e * i - f * h, co01 = f * g - d * i, co02 = d * h - e * g;
  const float det = a * co00 + b * co01 + c * co02;
  if (!(std::fabs(det) > 1e-30f) || !std::isfinite(det)) return false;
  const float inv = 1.f / det;
  Mat34 r;
  r.m[0] = co00 * inv;
  r.m[1] = (c * h - b * i) * inv;
  r.m[2] = (b * f - c * e) * inv;
  r.m[4] = co01 * inv;
  r.m[5] = (a * i - c * g) * inv;
  r.m[6] = (c * d - a * f) * inv;
  r.m[8] = co02 * inv;
  r.m[9] = (b * g - a * h) * inv;
  r.m[10] = (a * e - b * d) * inv;
  const Float3 t{m.m[3], m.m[7], m.m[11]};
  r.m[3] = -(r.m[0] * t.x + r.m[1] * t.y + r.m[2] * t.z);
  r.m[7] = -(r.m[4] * t.x + r.m[5] * t.y + r.m[6] * t.z);
  r.m[11] = -(r.m[8] * t.x + r.m[9] * t.y + r.m[10] * t.z);
  *inverse = r;
  return true;
}

Mat34 ToMatrix(const Transform& t) {
  const Quat q = t.rotation;
  const float xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
  const float xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
  const float wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
  const Float3 s = t.scale;
  Mat34 m;
  m.m[0] = (1.f - 2.f * (yy + zz)) * s.x;
  m.m[1] = 2.f * (xy - wz) * s.y;
  m.m[2] = 2.f * (xz + wy) * s.z;
  m.m[3] = t.translation.x;
  m.m[4] = 2.f * (xy + wz) * s.x;
  m.m[5] = (1.f - 2.f * (xx + zz)) * s.y;
  m.m[6] = 2.f * (yz - wx) * s.z;
  m.m[7] = t.translation.y;
  m.m[8] = 2.f * (xz - wy) * s.x;
  m.m[9] = 2.f * (yz + wx) * s.y;
  m.m[10] = (1.f - 2.f * (xx + yy)) * s.z;
  m.m[11] = t.translation.z;
  return m;
}

Transform Interpolate(const Transform& a, const Transform& b, float t) {
  return {Lerp(a.translation, b.translation, t), Nlerp(a.rotation, b.rotation, t),
          Lerp(a.scale, b.scale, t)};
}

}  // namespace drape

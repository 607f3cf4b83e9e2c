#pragma once
// Rigid transforms the shape tests and benchmark build their shapes' poses with.

#include <cmath>

#include "drape/formats/types.h"

namespace drape::test {

// Rotation by `degrees` about `axis` (normalised here), then the translation.
inline Mat34 Pose(Float3 translation, Float3 axis = {0.f, 0.f, 1.f}, double degrees = 0.0) {
  const double a = degrees * 3.14159265358979323846 / 180.0, c = std::cos(a), s = std::sin(a);
  const double length =
      std::sqrt(double(axis.x) * axis.x + double(axis.y) * axis.y + double(axis.z) * axis.z);
  const double x = axis.x / length, y = axis.y / length, z = axis.z / length, t = 1.0 - c;
  const double r[9] = {t * x * x + c,     t * x * y - s * z, t * x * z + s * y,
                       t * x * y + s * z, t * y * y + c,     t * y * z - s * x,
                       t * x * z - s * y, t * y * z + s * x, t * z * z + c};
  Mat34 m;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) m.m[4 * row + col] = static_cast<float>(r[3 * row + col]);
  m.m[3] = translation.x;
  m.m[7] = translation.y;
  m.m[11] = translation.z;
  return m;
}

}  // namespace drape::test

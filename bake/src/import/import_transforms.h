#pragma once
// Matrices in the import: assimp's row-major 4x4 to Eigen's, Eigen's to the asset's 3x4, and the
// decomposition into the translation, rotation and scale the skeleton stores.

#include <assimp/matrix4x4.h>

#include <Eigen/Dense>

#include "drape/formats/types.h"

namespace drape::bake::detail {

using Mat4 = Eigen::Matrix4d;

inline Mat4 ToEigen(const aiMatrix4x4& m) {
  Mat4 r;
  r << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3,
      m.d4;
  return r;
}

// The asset's 3x4 (rows), with (0, 0, 0, 1) below.
inline Mat4 ToEigen(const Mat34& m) {
  Mat4 r = Mat4::Identity();
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) r(row, col) = m.m[4 * row + col];
  return r;
}

// The top three rows, rounded to float.
inline Mat34 ToMat34(const Mat4& m) {
  Mat34 r;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) r.m[4 * row + col] = static_cast<float>(m(row, col));
  return r;
}

inline Eigen::Vector3d TransformPoint(const Mat4& m, const Eigen::Vector3d& p) {
  return (m * p.homogeneous()).head<3>();
}

inline bool AllFinite(const Mat4& m) { return m.allFinite(); }

// Polar decomposition of an affine matrix into translation, rotation and per-axis scale.
// A reflection is carried by a negative scale on z. Returns the relative size of the shear that
// a TRS transform cannot represent (0 for a clean TRS matrix).
double Decompose(const Mat4& m, Transform* t);

}  // namespace drape::bake::detail

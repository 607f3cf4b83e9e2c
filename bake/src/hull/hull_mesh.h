#pragma once
// The hull stage's own geometry: a small double vector algebra (the stored data is float), the
// rounding to the stored float precision, and an indexed triangle mesh.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "drape/formats/types.h"

namespace drape::bake::detail {

struct Vec3 {
  double x = 0.0, y = 0.0, z = 0.0;
};
inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator*(Vec3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline double Dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 Cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double Norm(Vec3 a) { return std::sqrt(Dot(a, a)); }
inline double MaxAbs(Vec3 a) { return std::max({std::fabs(a.x), std::fabs(a.y), std::fabs(a.z)}); }
inline Vec3 ToVec3(Float3 f) { return {f.x, f.y, f.z}; }
// Round to float through a volatile: GCC 12.2 at -O2/-O3 folds an SLP-vectorised pair of
// (double)(float)x round trips back to x (measured on this toolchain; -O1 is correct), which
// would silently keep double coordinates where the stored float ones are meant.
inline float ToFloat(double v) {
  volatile float f = static_cast<float>(v);
  return f;
}
inline Float3 ToFloat3(Vec3 v) { return {ToFloat(v.x), ToFloat(v.y), ToFloat(v.z)}; }
// Rounds each coordinate to the nearest float: the stored precision.
inline Vec3 RoundToFloat(Vec3 v) { return ToVec3(ToFloat3(v)); }
inline double AbsDot(Vec3 a, Vec3 b) {
  return std::fabs(a.x) * std::fabs(b.x) + std::fabs(a.y) * std::fabs(b.y) +
         std::fabs(a.z) * std::fabs(b.z);
}

// Worst-case relative error of a float dot product of 3 terms in any order (gamma_3 for unit
// roundoff u = 2^-24) plus the rounding of the double evaluation that replaces it here.
constexpr double kFloatDot3Error =
    3.0 * 5.9604644775390625e-08 / (1.0 - 3.0 * 5.9604644775390625e-08) + 1e-15;

// Smallest float >= value (value finite).
inline float RoundUpToFloat(double value) {
  float f = ToFloat(value);
  if (static_cast<double>(f) < value) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

inline uint64_t EdgeKey(uint32_t a, uint32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<uint64_t>(a) << 32) | b;
}

// An indexed triangle mesh whose coordinates are exactly representable in float.
struct Mesh {
  std::vector<Vec3> points;
  std::vector<std::array<uint32_t, 3>> triangles;  // counter-clockwise seen from outside
};

// Sorts the points lexicographically and removes exact duplicates (a deterministic input order
// for the hull, whatever order the points were made in).
void SortUnique(std::vector<Vec3>* points);

}  // namespace drape::bake::detail

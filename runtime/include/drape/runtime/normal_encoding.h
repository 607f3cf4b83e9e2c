#pragma once
// The normal encodings of the body maps (NormalEncoding in drape/formats/body_map_data.h), shared
// by the bake and the runtime so both sides agree bit for bit.

#include <array>
#include <cmath>
#include <cstdint>

#include "drape/formats/types.h"
#include "drape/runtime/math.h"

namespace drape {

// Octahedral normal encoding (Cigolle et al. 2014, "A Survey of Efficient Representations for
// Independent Unit Vectors"), 2 x uint16 per normal. This is the encoding of
// NormalEncoding::kOct16; the bake uses these two functions so both sides agree bit for bit.
// Mapping: n is projected onto the octahedron |x|+|y|+|z| = 1; the lower hemisphere (z < 0) is
// folded over the diagonals; the resulting (a, b) in [-1, 1]^2 is stored as
// round((a * 0.5 + 0.5) * 65535). Decoding uses a = q * (2 / 65535) - 1. Round-trip error is below
// 0.004 degrees (measured in the tests). A zero or non-finite input encodes +z.

// +1 for x >= 0 (also for -0), -1 otherwise: the octahedral fold needs a sign that is never 0.
inline float OctSignNotZero(float x) { return x >= 0.f ? 1.f : -1.f; }

inline std::array<uint16_t, 2> EncodeOct16(Float3 n) {
  const float l1 = std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z);
  if (!(l1 > 1e-30f) || !std::isfinite(l1)) return {32768, 32768};  // (0, 0) in [-1,1]^2: +z
  float a = n.x / l1;
  float b = n.y / l1;
  if (n.z < 0.f) {
    const float folded_a = (1.f - std::fabs(b)) * OctSignNotZero(a);
    const float folded_b = (1.f - std::fabs(a)) * OctSignNotZero(b);
    a = folded_a;
    b = folded_b;
  }
  // c is finite here. Compares and a truncation instead of fmin/fmax/lround (library calls
  // without -ffast-math; the body-map renderer encodes two normals per texel every frame), with
  // the same results: in double, x + 0.5 is exact for 0 <= x <= 65535 and its truncation is
  // lround(x).
  const auto quantise = [](float c) {
    float unit = c * 0.5f + 0.5f;
    unit = unit < 0.f ? 0.f : unit;
    unit = unit > 1.f ? 1.f : unit;
    return static_cast<uint16_t>(static_cast<double>(unit * 65535.f) + 0.5);
  };
  return {quantise(a), quantise(b)};
}

inline Float3 DecodeOct16(uint16_t qa, uint16_t qb) {
  Float3 n;
  constexpr float kScale = 2.f / 65535.f;  // a multiply, not a divide: on the contact path
  n.x = static_cast<float>(qa) * kScale - 1.f;
  n.y = static_cast<float>(qb) * kScale - 1.f;
  n.z = 1.f - std::fabs(n.x) - std::fabs(n.y);
  if (n.z < 0.f) {
    const float unfolded_x = (1.f - std::fabs(n.y)) * OctSignNotZero(n.x);
    const float unfolded_y = (1.f - std::fabs(n.x)) * OctSignNotZero(n.y);
    n.x = unfolded_x;
    n.y = unfolded_y;
  }
  return NormalizeOr(n, Float3{0.f, 0.f, 1.f});
}

// Paper A's colour encoding (NormalEncoding::kRgb8): n = c / 255 * 2 - 1, normalised.
inline Float3 DecodeRgb8(uint8_t r, uint8_t g, uint8_t b) {
  const Float3 n{static_cast<float>(r) / 255.f * 2.f - 1.f,
                 static_cast<float>(g) / 255.f * 2.f - 1.f,
                 static_cast<float>(b) / 255.f * 2.f - 1.f};
  return NormalizeOr(n, Float3{0.f, 0.f, 1.f});
}

}  // namespace drape

#pragma once
// Small POD types shared by the file schema and the runtime API. Plain data, so an engine can hand
// its own buffers: Float3 is three packed floats, Mat34 twelve.

#include <cstdint>

namespace drape {

struct Float3 {
  float x = 0.f, y = 0.f, z = 0.f;
};

struct Quat {  // unit quaternion, (x, y, z) vector part, w scalar part
  float x = 0.f, y = 0.f, z = 0.f, w = 1.f;
};

// A rigid or affine 3x4 transform, row-major: row r is (m[4r], m[4r+1], m[4r+2] | m[4r+3]).
// Applied to column vectors: p' = R p + t with t = (m[3], m[7], m[11]).
struct Mat34 {
  float m[12] = {1.f, 0.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 0.f, 1.f, 0.f};
};

// Local joint transform: scale, then rotate, then translate.
struct Transform {
  Float3 translation;
  Quat rotation;
  Float3 scale{1.f, 1.f, 1.f};
};

static_assert(sizeof(Float3) == 12 && sizeof(Quat) == 16 && sizeof(Mat34) == 48);

}  // namespace drape

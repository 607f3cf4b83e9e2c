#pragma once
// Paper A's image-space body collider: front and back orthographic depth and normal maps of the
// posed body, offset by epsilon. The view axis is the asset frame's z (the body faces +z).

#include <cstdint>
#include <vector>

namespace drape {

enum class DepthEncoding : uint8_t {
  kFloat32 = 0,  // metres from the camera plane; background is exactly depth_range (test >=)
  kUnorm16 = 1,  // min(round(depth / depth_range * 65535), 65534); 65535 is background
};

enum class NormalEncoding : uint8_t {
  kFloat32 = 0,  // 3 floats per texel, unit length (0,0,0 on background)
  kOct16 = 1,    // octahedral, 2 x uint16 per texel (about 0.004 degrees); the exact
                 // encode/decode is documented in bake/include/drape/bake/body_map_baker.h
  kRgb8 = 2,     // paper A's colour encoding, 3 x uint8 per texel (about 0.4 degrees)
};

// One pose's maps. Texel (i, j) covers asset-frame x in [origin_x + i*texel_size, +texel_size)
// and y in [origin_y + j*texel_size, +texel_size); row-major, j * width + i. Only the rectangle
// around the covered texels is stored; everything outside it is background.
struct BodyMapPose {
  int32_t clip = -1;   // clip index, or -1 for the rest pose as authored (see docs/FORMAT.md)
  float time = 0.f;    // seconds into the clip
  uint32_t width = 0;  // texels
  uint32_t height = 0;
  float origin_x = 0.f, origin_y = 0.f;  // metres, asset frame
  float texel_size = 0.f;                // metres, > 0
  float front_z = 0.f;                   // asset-frame z of the front camera plane
  float depth_range = 0.f;  // metres between the front and back planes (paper's W'), > 0
  DepthEncoding depth_encoding = DepthEncoding::kFloat32;
  NormalEncoding normal_encoding = NormalEncoding::kFloat32;
  // Index 0 is the front view (looking along -z), 1 the back view (looking along +z). The back
  // map is not mirrored: the same texel covers the same (x, y) in both. Depth is measured from
  // each view's own camera plane. Exactly the arrays of the chosen encodings are filled.
  std::vector<float> depth_f32[2];
  std::vector<uint16_t> depth_u16[2];
  std::vector<float> normal_f32[2];       // 3 per texel
  std::vector<uint16_t> normal_oct16[2];  // 2 per texel
  std::vector<uint8_t> normal_rgb8[2];    // 3 per texel
};

struct BodyMapSet {
  float epsilon = 0.f;      // metres the surface was offset along its normals before rendering
  uint32_t resolution = 0;  // N of the N x N window the maps were rendered in
  bool fitted_window =
      false;  // true: the window was fitted to the body's L x H (not the paper's square)
  std::vector<BodyMapPose> poses;
};

}  // namespace drape

#pragma once
// Private to the body map baker: writing one entry of a pose's per-texel arrays in the pose's
// depth and normal encodings (docs/FORMAT.md, body-map encodings). Layer 0 (step 7) and the gap
// layers (step 8, gap_layers.h) write through these.

#include <cstddef>
#include <cstdint>

#include "drape/bake/body_map_baker.h"

namespace drape::bake {

inline constexpr uint16_t kUnorm16Background = 65535;

// Writes a valid depth (metres from the view's plane, in [0, depth_range)) at array entry
// `entry` of `view` in the pose's depth encoding.
inline void WriteDepth(BodyMapPose* pose, int view, size_t entry, float depth) {
  if (pose->depth_encoding == DepthEncoding::kFloat32) {
    pose->depth_f32[view][entry] = depth;
  } else {
    pose->depth_u16[view][entry] = EncodeDepthUnorm16(depth, pose->depth_range);
  }
}

inline void WriteBackgroundDepth(BodyMapPose* pose, int view, size_t entry) {
  if (pose->depth_encoding == DepthEncoding::kFloat32) {
    pose->depth_f32[view][entry] = pose->depth_range;
  } else {
    pose->depth_u16[view][entry] = kUnorm16Background;
  }
}

// Writes a unit normal at array entry `entry` of `view` in the pose's normal encoding.
inline void WriteNormal(BodyMapPose* pose, int view, size_t entry, Float3 normal) {
  switch (pose->normal_encoding) {
    case NormalEncoding::kFloat32:
      pose->normal_f32[view][3 * entry] = normal.x;
      pose->normal_f32[view][3 * entry + 1] = normal.y;
      pose->normal_f32[view][3 * entry + 2] = normal.z;
      break;
    case NormalEncoding::kOct16: {
      const OctNormal16 code = EncodeNormalOct16(normal);
      pose->normal_oct16[view][2 * entry] = code.u;
      pose->normal_oct16[view][2 * entry + 1] = code.v;
      break;
    }
    case NormalEncoding::kRgb8:
      EncodeNormalRgb8(normal, &pose->normal_rgb8[view][3 * entry]);
      break;
  }
}

}  // namespace drape::bake

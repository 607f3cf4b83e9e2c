#pragma once
// Assets and body-map poses the format tests build, encode and damage: a small complete asset,
// the same with a row-span pose, and a hand-made pose with depth layers. Header-only (formats
// headers, GoogleTest and the standard library).

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "drape/formats/asset_file.h"

namespace drape::test {

// A small but complete asset: 3 joints, a clip, a skinned mesh, a body-map pose, a hull with a
// Kirkpatrick hierarchy and a map table, a joint sphere.
inline CharacterAsset SmallAsset() {
  CharacterAsset a;
  a.info.source_name = "small.gltf";
  a.info.tool_version = "test";
  a.skeleton.joint_names = {"root", "spine", "head"};
  a.skeleton.parents = {-1, 0, 1};
  a.skeleton.rest_local.resize(3);
  a.skeleton.rest_local[1].translation = {0.f, 0.5f, 0.f};
  a.skeleton.rest_local[2].translation = {0.f, 0.4f, 0.f};
  a.skeleton.inverse_bind.resize(3);
  a.skeleton.inverse_bind[1].m[7] = -0.5f;
  a.skeleton.inverse_bind[2].m[7] = -0.9f;
  ClipData clip;
  clip.name = "nod";
  clip.duration = 0.1f;
  clip.sample_rate = 30.f;
  clip.frame_count = 4;
  clip.keys.assign(12, Transform{});
  a.clips.push_back(clip);
  a.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  a.mesh.triangles = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  a.mesh.influence_offsets = {0, 1, 2, 4, 5};
  a.mesh.influence_joints = {0, 1, 1, 2, 2};
  a.mesh.influence_weights = {1.f, 1.f, 0.5f, 0.5f, 1.f};
  a.body_maps.epsilon = 0.005f;
  a.body_maps.resolution = 4;
  BodyMapPose pose;
  pose.width = 2;
  pose.height = 2;
  pose.texel_size = 0.5f;
  pose.depth_range = 1.f;
  pose.depth_encoding = DepthEncoding::kUnorm16;
  pose.normal_encoding = NormalEncoding::kOct16;
  for (int v = 0; v < 2; ++v) {
    pose.depth_u16[v] = {100, 200, 65535, 300};
    pose.normal_oct16[v] = {1, 2, 3, 4, 5, 6, 7, 8};
  }
  a.body_maps.poses.push_back(pose);
  HullColliderData hull;
  hull.joint = 1;
  hull.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  hull.triangles = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  hull.triangle_planes = {0, 1, 2, 3};
  hull.obb.axes[0] = {1, 0, 0};
  hull.obb.axes[1] = {0, 1, 0};
  hull.obb.axes[2] = {0, 0, 1};
  hull.planes = {
      {{0, 0, -1}, 0}, {{0, -1, 0}, 0}, {{-1, 0, 0}, 0}, {{0.577f, 0.577f, 0.577f}, 0.578f}};
  hull.plane_internal = {0, 1, 0, 0};  // one face a cut between convex pieces
  hull.upper.vertices_uv = {0, 0, 1, 0, 0, 1};
  hull.upper.node_triangles = {0, 1, 2, 0, 1, 2};
  hull.upper.child_offsets = {0, 0, 1};
  hull.upper.children = {0};
  hull.upper.leaf_planes = {3, -1};
  hull.upper.root_begin = 1;
  hull.upper.root_end = 2;
  hull.map.rows = 1;
  hull.map.cols = 2;
  hull.map.axis = {0, 1, 0};
  hull.map.reference = {1, 0, 0};
  hull.map.cell_offsets = {0, 2, 4};
  hull.map.cell_triangles = {0, 1, 2, 3};
  a.hulls.push_back(hull);
  a.joint_spheres.push_back({2, 1, {0.f, 0.9f, 0.f}, 0.05f});
  return a;
}

inline std::vector<uint8_t> Encode(const CharacterAsset& a) {
  std::vector<uint8_t> bytes;
  const Status s = EncodeAsset(a, &bytes);
  EXPECT_TRUE(s.ok()) << s.message();
  return bytes;
}

// Rewrites the payload and header checksums after a deliberate edit, so the decoder's later
// checks (versions, counts, indices) are the ones under test.
inline void FixChecksums(std::vector<uint8_t>& bytes) {
  auto put = [&](size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) bytes[at + i] = static_cast<uint8_t>(v >> (8 * i));
  };
  put(24, Crc32({bytes.data() + kAssetHeaderSize, bytes.size() - kAssetHeaderSize}));
  put(28, Crc32({bytes.data(), 28}));
}

inline std::vector<uint8_t> ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// ---- Row spans ---------------------------------------------------------------------------------

// SmallAsset plus a second pose in the row-span layout: 6 x 3 texels, float32 depth and rgb8
// normals, two spans in row 0, one in row 1, none in row 2.
inline CharacterAsset SpansAsset() {
  CharacterAsset a = SmallAsset();
  BodyMapPose dense;
  dense.clip = 0;
  dense.time = 0.1f;
  dense.width = 6;
  dense.height = 3;
  dense.origin_x = -0.25f;
  dense.origin_y = 0.5f;
  dense.texel_size = 0.125f;
  dense.front_z = 0.5f;
  dense.depth_range = 1.f;
  dense.depth_encoding = DepthEncoding::kFloat32;
  dense.normal_encoding = NormalEncoding::kRgb8;
  const char* covered =
      "XX.XX."
      ".XXXX."
      "......";  // row 0 first
  for (int v = 0; v < 2; ++v) {
    dense.depth_f32[v].assign(18, dense.depth_range);
    dense.normal_rgb8[v].assign(54, 0);
    for (size_t k = 0; k < 18; ++k) {
      if (covered[k] != 'X') continue;
      dense.depth_f32[v][k] = 0.25f + 0.01f * static_cast<float>(k);
      dense.normal_rgb8[v][3 * k + 2] = v == 0 ? 255 : 0;
      dense.normal_rgb8[v][3 * k] = static_cast<uint8_t>(100 + k);
    }
  }
  BodyMapPose spans;
  EXPECT_TRUE(ConvertBodyMapLayout(dense, BodyMapLayout::kRowSpans, &spans).ok());
  a.body_maps.poses.push_back(spans);
  return a;
}

// ---- Depth layers ------------------------------------------------------------------------------

// The slab and the gaps of LayeredDensePose, a 5 x 3 rectangle (row 0 first): 'X' slab only,
// '1' slab and gap 1, '2' slab and gaps 1 and 2, '.' background in every layer.
inline constexpr const char* kLayeredTexels =
    "X21.X"
    ".X12."
    "2X...";

// Depth of `view` in layer k at dense texel n, in metres from that view's camera: boundaries in
// the order top > upper_1 > lower_1 > upper_2 > lower_2 > bottom (depth_range 1, so the back
// depth d is at z = front_z - 1 + d). Distinct per texel, so a misplaced value shows.
inline float LayerDepth(int view, size_t k, size_t n) {
  static const float kFront[3] = {0.10f, 0.30f, 0.50f};
  static const float kBack[3] = {0.10f, 0.60f, 0.40f};
  return (view == 0 ? kFront[k] : kBack[k]) + 0.001f * static_cast<float>(n);
}

// Layer k holds a surface at dense texel n.
inline bool HasLayer(size_t k, size_t n) {
  const char c = kLayeredTexels[n];
  return k == 0 ? c != '.' : (c == '2' || (c == '1' && k == 1));
}

// A dense pose with `layers` layers (1 to 3) of the texels above, in the given encodings, stored
// as the format stores them: layer 0 of every texel, then the gap layers of the texels with a
// gap ('1' and '2': gap_texels = {1, 2, 7, 8, 10}); background values everywhere a layer has
// no surface (as the bake writes).
inline BodyMapPose LayeredDensePose(DepthEncoding depth, NormalEncoding normal, uint8_t layers) {
  BodyMapPose p;
  p.clip = 0;
  p.time = 0.05f;
  p.width = 5;
  p.height = 3;
  p.origin_x = -0.3f;
  p.origin_y = 0.25f;
  p.texel_size = 0.125f;
  p.front_z = 0.5f;
  p.depth_range = 1.f;
  p.depth_encoding = depth;
  p.normal_encoding = normal;
  p.layers = layers;
  const size_t texels = 15;
  for (size_t n = 0; n < texels && layers > 1; ++n)
    if (HasLayer(1, n)) p.gap_texels.push_back(static_cast<uint32_t>(n));
  const size_t gaps = p.gap_texels.size();
  const size_t entries = texels + (layers - 1u) * gaps;
  for (int v = 0; v < 2; ++v) {
    if (depth == DepthEncoding::kFloat32) {
      p.depth_f32[v].assign(entries, p.depth_range);
    } else {
      p.depth_u16[v].assign(entries, 65535);
    }
    p.normal_f32[v].assign(normal == NormalEncoding::kFloat32 ? 3 * entries : 0, 0.f);
    p.normal_oct16[v].assign(normal == NormalEncoding::kOct16 ? 2 * entries : 0, 0);
    p.normal_rgb8[v].assign(normal == NormalEncoding::kRgb8 ? 3 * entries : 0, 0);
    for (size_t k = 0; k < layers; ++k) {
      for (size_t t = 0; t < (k == 0 ? texels : gaps); ++t) {
        const size_t n = k == 0 ? t : p.gap_texels[t];
        if (!HasLayer(k, n)) continue;
        const size_t e = k == 0 ? n : texels + (k - 1) * gaps + t;
        const float d = LayerDepth(v, k, n);
        if (depth == DepthEncoding::kFloat32) {
          p.depth_f32[v][e] = d;
        } else {
          p.depth_u16[v][e] = static_cast<uint16_t>(std::lround(d * 65535.f));
        }
        const size_t code = 40 * k + 2 * n + static_cast<size_t>(v);  // < 256, distinct
        for (size_t c = 0; c < 3; ++c) {
          if (normal == NormalEncoding::kFloat32)
            p.normal_f32[v][3 * e + c] = 0.001f * static_cast<float>(code + c);
          if (normal == NormalEncoding::kRgb8)
            p.normal_rgb8[v][3 * e + c] = static_cast<uint8_t>(code + c);
          if (normal == NormalEncoding::kOct16 && c < 2)
            p.normal_oct16[v][2 * e + c] = static_cast<uint16_t>(500 * code + c);
        }
      }
    }
  }
  return p;
}

// Every per-texel array and the span table of two poses are equal.
inline void ExpectSameMaps(const BodyMapPose& a, const BodyMapPose& b) {
  EXPECT_EQ(a.layout, b.layout);
  EXPECT_EQ(a.layers, b.layers);
  EXPECT_EQ(a.row_span_offsets, b.row_span_offsets);
  EXPECT_EQ(a.span_begin, b.span_begin);
  EXPECT_EQ(a.span_texel_offsets, b.span_texel_offsets);
  EXPECT_EQ(a.gap_texels, b.gap_texels);
  for (int v = 0; v < 2; ++v) {
    EXPECT_EQ(a.depth_f32[v], b.depth_f32[v]) << "view " << v;
    EXPECT_EQ(a.depth_u16[v], b.depth_u16[v]) << "view " << v;
    EXPECT_EQ(a.normal_f32[v], b.normal_f32[v]) << "view " << v;
    EXPECT_EQ(a.normal_oct16[v], b.normal_oct16[v]) << "view " << v;
    EXPECT_EQ(a.normal_rgb8[v], b.normal_rgb8[v]) << "view " << v;
  }
}

// SmallAsset plus a three-layer pose of the texels above, in row spans, float32 depth and oct16
// normals.
inline CharacterAsset LayeredAsset() {
  CharacterAsset a = SmallAsset();
  BodyMapPose spans;
  const Status s =
      ConvertBodyMapLayout(LayeredDensePose(DepthEncoding::kFloat32, NormalEncoding::kOct16, 3),
                           BodyMapLayout::kRowSpans, &spans);
  EXPECT_TRUE(s.ok()) << s.message();
  a.body_maps.poses.push_back(spans);
  return a;
}

}  // namespace drape::test

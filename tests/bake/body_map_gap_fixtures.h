#pragma once
// The scene of the body-map gap-layer tests (boxes with split faces and octahedron spheres, with
// air between them along z) and the check every gap-layer bake must pass: each texel's layers are
// strictly nested, read as the documented decoder and as a float reader would. Header-only.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include "body_map_fixtures.h"
#include "drape/bake/body_map_baker.h"
#include "octahedron_sphere.h"

namespace drape::bake::body_map_fixtures {

// Appends an axis-aligned closed box to `m` with separate vertices per face, counter-clockwise
// seen from outside, without the faces `skip` names (bit 2*axis + side: bit 4 is the z-low face),
// so an open box can be built too. Same geometry as AddSplitBox; kept separate because the hash
// constants of GapLayersLeaveTheSlabByteIdentical were recorded with exactly this vertex order.
inline void AddPortableBox(Mesh* m, double x0, double y0, double z0, double x1, double y1,
                           double z1, unsigned skip = 0) {
  const double lo[3] = {x0, y0, z0}, hi[3] = {x1, y1, z1};
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      if (skip & (1u << (2 * axis + side))) continue;
      const uint32_t base = static_cast<uint32_t>(m->positions.size());
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int corner = 0; corner < 4; ++corner) {
        double c[3];
        c[axis] = side ? hi[axis] : lo[axis];
        c[u] = (corner == 1 || corner == 2) ? hi[u] : lo[u];
        c[v] = (corner >= 2) ? hi[v] : lo[v];
        m->positions.push_back(
            {static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2])});
      }
      // Corners 0..3 go counter-clockwise around +axis: reversed on the low side.
      if (side) {
        m->triangles.insert(m->triangles.end(),
                            {base, base + 1, base + 2, base, base + 2, base + 3});
      } else {
        m->triangles.insert(m->triangles.end(),
                            {base, base + 2, base + 1, base, base + 3, base + 2});
      }
    }
  }
}

// A sphere from a 4^levels-subdivided octahedron on radius r (square roots only, so the same
// positions on every IEEE machine), counter-clockwise seen from outside, shared vertices.
inline void AddOctaSphere(Mesh* m, double cx, double cy, double cz, double r, int levels) {
  const test::UnitSphereMesh sphere = test::OctahedronSphere(levels);
  const uint32_t base = static_cast<uint32_t>(m->positions.size());
  for (const auto& q : sphere.positions) {
    m->positions.push_back({static_cast<float>(cx + r * q[0]), static_cast<float>(cy + r * q[1]),
                            static_cast<float>(cz + r * q[2])});
  }
  for (const auto& f : sphere.triangles) {
    m->triangles.insert(m->triangles.end(), {base + f[0], base + f[1], base + f[2]});
  }
}

// A block, a plate in front of it, a sphere further in front and one beside it: flat and curved
// surfaces, shared and split vertices, air between them along z.
inline Mesh GapScene() {
  Mesh m;
  AddPortableBox(&m, -0.20, -0.30, -0.10, 0.20, 0.30, 0.05);  // block
  AddPortableBox(&m, -0.10, -0.12, 0.12, 0.14, 0.08, 0.15);   // plate in front of it
  AddOctaSphere(&m, 0.05, 0.20, 0.30, 0.07, 4);               // sphere further in front
  AddOctaSphere(&m, -0.25, -0.05, -0.02, 0.09, 3);            // sphere overlapping the side
  return m;
}

// The array entry of `layer` at texel (i, j) (body_map_baker.h, encodings), or -1 where the
// texel is not stored (layer 0) or not in the gap list (layers >= 1).
inline int64_t LayerEntry(const BodyMapPose& pose, uint32_t i, uint32_t j, uint32_t layer) {
  const int64_t index = BodyMapTexelIndex(pose, i, j);
  if (index < 0 || layer == 0) return index;
  const auto& list = pose.gap_texels;
  const auto found = std::lower_bound(list.begin(), list.end(), static_cast<uint32_t>(index));
  if (found == list.end() || *found != index) return -1;
  return static_cast<int64_t>(BodyMapStoredTexels(pose) + (layer - 1) * list.size() +
                              static_cast<size_t>(found - list.begin()));
}

// The raw depth code of `layer` at texel (i, j) decoded as a float reader would (unorm16:
// code / 65535 * depth_range in float), or NaN on background.
inline float FloatReaderDepth(const BodyMapPose& pose, int view, uint32_t i, uint32_t j,
                              uint32_t layer) {
  const int64_t index = LayerEntry(pose, i, j, layer);
  if (index < 0) return std::numeric_limits<float>::quiet_NaN();
  const size_t entry = static_cast<size_t>(index);
  if (pose.depth_encoding == DepthEncoding::kFloat32) {
    const float d = pose.depth_f32[view][entry];
    return d < pose.depth_range ? d : std::numeric_limits<float>::quiet_NaN();
  }
  const uint16_t code = pose.depth_u16[view][entry];
  if (code == 65535) return std::numeric_limits<float>::quiet_NaN();
  return static_cast<float>(code) / 65535.f * pose.depth_range;
}

// Every texel's layers as body_map_data.h requires: a gap has both boundaries or neither, layers
// are filled in order, and top > upper_1 > lower_1 > upper_2 > ... > bottom in asset z, with the
// documented decoder in double and with a float reader's arithmetic. Returns the texels checked
// that hold at least one gap.
inline size_t ExpectStrictlyNested(const BodyMapPose& pose) {
  const double back_z = double(pose.front_z) - double(pose.depth_range);
  const float back_zf = pose.front_z - pose.depth_range;
  size_t with_gaps = 0, violations = 0;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      const BodyMapTexel top = ReadBodyMapTexel(pose, 0, i, j),
                         bottom = ReadBodyMapTexel(pose, 1, i, j);
      double ceiling = double(pose.front_z) - top.depth;
      float ceiling_f = pose.front_z - FloatReaderDepth(pose, 0, i, j, 0);
      const double floor = back_z + bottom.depth;
      const float floor_f = back_zf + FloatReaderDepth(pose, 1, i, j, 0);
      bool absent = !top.valid;
      for (uint32_t layer = 1; layer < pose.layers; ++layer) {
        const BodyMapTexel upper = ReadBodyMapTexel(pose, 0, i, j, layer);
        const BodyMapTexel lower = ReadBodyMapTexel(pose, 1, i, j, layer);
        if (!upper.valid && !lower.valid) {
          absent = true;
          continue;
        }
        with_gaps += layer == 1;
        const double upper_z = double(pose.front_z) - upper.depth;
        const double lower_z = back_z + lower.depth;
        const float upper_f = pose.front_z - FloatReaderDepth(pose, 0, i, j, layer);
        const float lower_f = back_zf + FloatReaderDepth(pose, 1, i, j, layer);
        const bool ok = !absent && upper.valid && lower.valid && ceiling > upper_z &&
                        upper_z > lower_z && lower_z > floor && ceiling_f > upper_f &&
                        upper_f > lower_f && lower_f > floor_f;
        if (!ok && violations++ < 5) {
          ADD_FAILURE() << "texel " << i << "," << j << " layer " << layer << ": ceiling "
                        << ceiling << " upper " << upper_z << " lower " << lower_z << " floor "
                        << floor;
        }
        ceiling = lower_z;
        ceiling_f = lower_f;
      }
    }
  }
  EXPECT_EQ(violations, 0u);
  // The gap list: strictly increasing, exactly the texels with a gap.
  EXPECT_EQ(with_gaps, pose.gap_texels.size());
  EXPECT_TRUE(std::adjacent_find(pose.gap_texels.begin(), pose.gap_texels.end(),
                                 std::greater_equal<uint32_t>()) == pose.gap_texels.end());
  if (pose.layers == 1) {
    EXPECT_TRUE(pose.gap_texels.empty());
  }
  return with_gaps;
}

}  // namespace drape::bake::body_map_fixtures

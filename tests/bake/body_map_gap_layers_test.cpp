// Body-map gap layers (body_map_baker.h step 8): the air between surfaces along the view, the
// thickest gaps kept in depth order, no gap from open or inconsistent surfaces or thinner than
// the minimum, layer 0 byte-identical to a bake without gaps, strict nesting after unorm16
// quantisation and on curved meshes, and the bake report's gap fields.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "body_map_fixtures.h"
#include "body_map_gap_fixtures.h"
#include "drape/bake/bake_config.h"
#include "drape/bake/bake_pipeline.h"
#include "drape/bake/body_map_baker.h"
#include "test_support.h"

namespace drape::bake {
namespace {

using namespace body_map_fixtures;

// A single quad at height z over [x0, x1] x [y0, y1], facing +z (up) or -z: an open surface.
void AddQuad(Mesh* m, double x0, double y0, double x1, double y1, double z, bool up) {
  const uint32_t base = static_cast<uint32_t>(m->positions.size());
  for (const auto& [x, y] : {std::pair{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}) {
    m->positions.push_back({static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
  }
  if (up) {
    m->triangles.insert(m->triangles.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  } else {
    m->triangles.insert(m->triangles.end(), {base, base + 2, base + 1, base, base + 3, base + 2});
  }
}

// A thin closed sheet over [x0, x1] x [y0, y1] whose bottom is z = z0 + slope * (x - x0) and whose
// top is `thickness` above it (vertical sides; separate vertices per face).
void AddSlantedSheet(Mesh* m, double x0, double y0, double x1, double y1, double z0, double slope,
                     double thickness) {
  const auto bottom = [&](double x) { return z0 + slope * (x - x0); };
  const Vec3d corner[8] = {{x0, y0, bottom(x0)},
                           {x1, y0, bottom(x1)},
                           {x1, y1, bottom(x1)},
                           {x0, y1, bottom(x0)},
                           {x0, y0, bottom(x0) + thickness},
                           {x1, y0, bottom(x1) + thickness},
                           {x1, y1, bottom(x1) + thickness},
                           {x0, y1, bottom(x0) + thickness}};
  const int faces[6][4] = {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 1, 5, 4},
                           {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  const Vec3d centre = Scale(Add(corner[0], corner[6]), 0.5);
  for (const auto& face : faces) {
    const uint32_t base = static_cast<uint32_t>(m->positions.size());
    Vec3d face_centre;
    for (int k : face) {
      m->positions.push_back({static_cast<float>(corner[k].x), static_cast<float>(corner[k].y),
                              static_cast<float>(corner[k].z)});
      face_centre = Add(face_centre, Scale(corner[k], 0.25));
    }
    const Vec3d outward = Sub(face_centre, centre);
    AddOutwardTriangle(m, base, base + 1, base + 2, outward);
    AddOutwardTriangle(m, base, base + 2, base + 3, outward);
  }
}

// FNV-1a 64 over the bytes of everything a bake writes (header floats, span table, arrays).
uint64_t Fnv(uint64_t h, const void* data, size_t bytes) {
  const unsigned char* b = static_cast<const unsigned char*>(data);
  for (size_t k = 0; k < bytes; ++k) {
    h ^= b[k];
    h *= 1099511628211ull;
  }
  return h;
}
template <class T>
uint64_t FnvVector(uint64_t h, const std::vector<T>& v) {
  const uint64_t n = v.size();
  h = Fnv(h, &n, sizeof(n));
  return Fnv(h, v.data(), v.size() * sizeof(T));
}
uint64_t PoseHash(const BodyMapPose& p) {
  uint64_t h = 14695981039346656037ull;
  for (const void* field :
       {static_cast<const void*>(&p.width), static_cast<const void*>(&p.height),
        static_cast<const void*>(&p.origin_x), static_cast<const void*>(&p.origin_y),
        static_cast<const void*>(&p.texel_size), static_cast<const void*>(&p.front_z),
        static_cast<const void*>(&p.depth_range)}) {
    h = Fnv(h, field, 4);
  }
  h = FnvVector(h, p.row_span_offsets);
  h = FnvVector(h, p.span_begin);
  h = FnvVector(h, p.span_texel_offsets);
  for (int view = 0; view < 2; ++view) {
    h = FnvVector(h, p.depth_f32[view]);
    h = FnvVector(h, p.depth_u16[view]);
    h = FnvVector(h, p.normal_f32[view]);
    h = FnvVector(h, p.normal_oct16[view]);
    h = FnvVector(h, p.normal_rgb8[view]);
  }
  return h;
}

// The gaps a texel centre should hold: (upper z, lower z) front to back.
using ExpectedGaps = std::vector<std::pair<double, double>>;

struct GapCheck {
  size_t texels_with_gaps = 0;  // texels checked that hold a gap
  size_t skipped = 0;           // texel centres within 1e-4 texel of an outline
};

// Compares every texel's gap layers with `expected` (positions within `tolerance` metres, the
// upper normal (0,0,-1) and the lower (0,0,+1) within `normal_tolerance`); texel centres within
// 1e-4 texel of one of the x = `outline_x` or y = `outline_y` lines are skipped.
template <class Expected>
GapCheck ExpectGaps(const BodyMapPose& pose, Expected expected,
                    const std::vector<double>& outline_x, const std::vector<double>& outline_y,
                    double tolerance, double normal_tolerance) {
  GapCheck check;
  const double t = pose.texel_size;
  const double back_z = double(pose.front_z) - double(pose.depth_range);
  size_t failures = 0;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      const Vec3d p = TexelCentre(pose, i, j);
      bool on_outline = false;
      for (double x : outline_x) on_outline |= std::fabs(p.x - x) < 1e-4 * t;
      for (double y : outline_y) on_outline |= std::fabs(p.y - y) < 1e-4 * t;
      if (on_outline) {
        ++check.skipped;
        continue;
      }
      const ExpectedGaps gaps = expected(p);
      for (uint32_t layer = 1; layer < pose.layers; ++layer) {
        const BodyMapTexel upper = ReadBodyMapTexel(pose, 0, i, j, layer);
        const BodyMapTexel lower = ReadBodyMapTexel(pose, 1, i, j, layer);
        const bool want = layer <= gaps.size();
        bool ok = upper.valid == want && lower.valid == want;
        if (ok && want) {
          const auto [upper_z, lower_z] = gaps[layer - 1];
          ok = std::fabs(double(pose.front_z) - upper.depth - upper_z) <= tolerance &&
               std::fabs(back_z + lower.depth - lower_z) <= tolerance &&
               std::fabs(upper.normal.z + 1.0) <= normal_tolerance &&
               std::fabs(lower.normal.z - 1.0) <= normal_tolerance;
        }
        if (!ok && failures++ < 5) {
          ADD_FAILURE() << "texel " << i << "," << j << " (" << p.x << ", " << p.y << ") layer "
                        << layer << ": expected " << (want ? "a gap" : "none") << ", read "
                        << (upper.valid ? "upper " + std::to_string(pose.front_z - upper.depth)
                                        : std::string("no upper"))
                        << " / "
                        << (lower.valid ? "lower " + std::to_string(back_z + lower.depth)
                                        : std::string("no lower"));
        }
      }
      check.texels_with_gaps += !gaps.empty();
    }
  }
  EXPECT_EQ(failures, 0u);
  return check;
}

bool Inside(Vec3d p, double x0, double y0, double x1, double y1) {
  return p.x > x0 && p.x < x1 && p.y > y0 && p.y < y1;
}

TEST(BodyMapBaker, GapLayerHoldsTheAirBetweenAPlateAndABlock) {
  Mesh mesh;
  const Vec3d block_lo{-0.20, -0.30, -0.10}, block_hi{0.20, 0.30, 0.05};
  const Vec3d plate_lo{-0.10, -0.12, 0.12}, plate_hi{0.14, 0.08, 0.15};
  AddSplitBox(&mesh, block_lo, block_hi);
  AddSplitBox(&mesh, plate_lo, plate_hi);
  for (const bool compact : {false, true}) {
    SCOPED_TRACE(compact ? "unorm16 + oct16" : "float32");
    BodyMapOptions o = DenseGapOptions(200, 3, compact);
    BodyMapPoseStats stats;
    const BodyMapPose pose = BakeOrDie(mesh, o, &stats);
    ASSERT_EQ(pose.layers, 3);
    // The split boxes' faces move by exactly epsilon along their normals: the gap is the plate's
    // back face lowered by epsilon down to the block's front face raised by epsilon, over the
    // plate's own x,y rectangle (its side faces are edge-on).
    const double eps = o.epsilon;
    const double tolerance = compact ? double(pose.depth_range) / 65535.0 + 1e-6 : 1e-6;
    const GapCheck check = ExpectGaps(
        pose,
        [&](Vec3d p) {
          return Inside(p, plate_lo.x, plate_lo.y, plate_hi.x, plate_hi.y)
                     ? ExpectedGaps{{plate_lo.z - eps, block_hi.z + eps}}
                     : ExpectedGaps{};
        },
        {plate_lo.x, plate_hi.x}, {plate_lo.y, plate_hi.y}, tolerance, compact ? 1e-3 : 1e-6);
    const double t = pose.texel_size;
    const double area = (plate_hi.x - plate_lo.x) * (plate_hi.y - plate_lo.y) / (t * t);
    EXPECT_NEAR(double(check.texels_with_gaps), area,
                2 * ((plate_hi.x - plate_lo.x) + (plate_hi.y - plate_lo.y)) / t + 4);
    EXPECT_GT(check.texels_with_gaps, 1000u);
    EXPECT_NEAR(double(stats.gap_texels), double(check.texels_with_gaps), double(check.skipped));
    EXPECT_EQ(stats.layers, 3);
    EXPECT_EQ(stats.dropped_gaps, 0u);
    EXPECT_GT(stats.gap_ms, 0.0);
    // Layer 0 for every texel of the rectangle, the two gap layers and the list for the texels
    // with a gap.
    const size_t per_texel = compact ? 2 * (2 + 4) : 2 * (4 + 12);
    const size_t listed = pose.gap_texels.size();
    EXPECT_EQ(listed, stats.gap_texels);
    EXPECT_EQ(stats.bytes,
              per_texel * (size_t(pose.width) * pose.height + 2 * listed) + 4 * listed);
    // Layer 0 is still the slab: the plate's front face to the block's back face.
    const uint32_t ci = pose.width / 2, cj = pose.height / 2;
    ASSERT_TRUE(Inside(TexelCentre(pose, ci, cj), plate_lo.x, plate_lo.y, plate_hi.x, plate_hi.y));
    EXPECT_NEAR(pose.front_z - ReadBodyMapTexel(pose, 0, ci, cj).depth, plate_hi.z + eps,
                tolerance);
    EXPECT_NEAR(pose.front_z - pose.depth_range + ReadBodyMapTexel(pose, 1, ci, cj).depth,
                block_lo.z - eps, tolerance);
    EXPECT_GT(ExpectStrictlyNested(pose), 1000u);
  }
}

TEST(BodyMapBaker, GapLayersKeepTheThickestGapsInDepthOrder) {
  // Plate B in front of plate A in front of a block; B covers x < 0.05, A covers x > -0.05.
  // Where both are: the gap B -> A (20 mm) and, deeper but thicker, A -> block (60 mm).
  Mesh mesh;
  const double eps = 0.005;
  AddSplitBox(&mesh, {-0.20, -0.20, -0.10}, {0.20, 0.20, 0.00});  // block
  AddSplitBox(&mesh, {-0.05, -0.10, 0.07}, {0.10, 0.10, 0.09});   // A
  AddSplitBox(&mesh, {-0.10, -0.10, 0.12}, {0.05, 0.10, 0.14});   // B
  const std::pair<double, double> b_to_a{0.12 - eps, 0.09 + eps}, a_to_block{0.07 - eps, eps},
      b_to_block{0.12 - eps, eps};
  const std::vector<double> outline_x = {-0.10, -0.05, 0.05, 0.10}, outline_y = {-0.10, 0.10};
  const auto in_y = [](Vec3d p) { return p.y > -0.10 && p.y < 0.10; };
  for (const int layers : {2, 3, 4}) {
    SCOPED_TRACE(testing::Message() << "layers " << int(layers));
    BodyMapOptions o = DenseGapOptions(160, static_cast<uint8_t>(layers));
    o.epsilon = static_cast<float>(eps);
    BodyMapPoseStats stats;
    const BodyMapPose pose = BakeOrDie(mesh, o, &stats);
    size_t both = 0;
    const GapCheck check = ExpectGaps(
        pose,
        [&](Vec3d p) {
          if (!in_y(p) || p.x <= -0.10 || p.x >= 0.10) return ExpectedGaps{};
          if (p.x < -0.05) return ExpectedGaps{b_to_block};
          if (p.x > 0.05) return ExpectedGaps{a_to_block};
          ++both;
          // layers = 2 keeps one: the thicker, although it is the deeper.
          return layers == 2 ? ExpectedGaps{a_to_block} : ExpectedGaps{b_to_a, a_to_block};
        },
        outline_x, outline_y, 1e-6, 1e-6);
    EXPECT_GT(both, 500u);
    EXPECT_GT(check.texels_with_gaps, both + 500);  // and texels under one plate only
    EXPECT_NEAR(double(stats.gap_texels), double(check.texels_with_gaps), double(check.skipped));
    EXPECT_NEAR(double(stats.dropped_gaps), layers == 2 ? double(both) : 0.0,
                double(check.skipped));
    ExpectStrictlyNested(pose);
  }
}

TEST(BodyMapBaker, OpenOrInconsistentSurfacesGiveNoGap) {
  // Six things in front of a block, each over its own cell (columns x in [-0.15, -0.02] and
  // [0.02, 0.15], rows y in [-0.18, -0.07], [-0.05, 0.05], [0.07, 0.18]); no epsilon, so that
  // the lone quads stay flat.
  Mesh mesh;
  AddPortableBox(&mesh, -0.20, -0.20, -0.10, 0.20, 0.20, 0.00);
  // Closed: a plate (a gap from 0.05 down to the block), and a plate over a flattened box of
  // zero thickness at z = 0.03, whose faces enter and leave at the same depth: entering sorts
  // first, so the count stays >= 0 and the texel keeps its thicker gap, plate -> sheet (the
  // sheet -> block one is beyond layers - 1 = 1).
  AddPortableBox(&mesh, 0.02, 0.07, 0.05, 0.15, 0.18, 0.08);
  AddPortableBox(&mesh, 0.02, -0.05, 0.12, 0.15, 0.05, 0.14);
  AddPortableBox(&mesh, 0.02, -0.05, 0.03, 0.15, 0.05, 0.03);
  // Open: a box without its back face under a closed plate (the count reaches 0 between them but
  // ends at 1), a lone quad facing +z (it ends at 1), a lone quad facing -z (it goes negative at
  // once), and a plate wound inside out (-1, +1, then the block's +1, -1: it ends at 0 but went
  // negative first).
  AddPortableBox(&mesh, -0.15, 0.07, 0.10, -0.02, 0.18, 0.12);
  AddPortableBox(&mesh, -0.15, 0.07, 0.05, -0.02, 0.18, 0.08, 1u << 4);
  AddQuad(&mesh, -0.15, -0.05, -0.02, 0.05, 0.06, /*up=*/true);
  AddQuad(&mesh, -0.15, -0.18, -0.02, -0.07, 0.06, /*up=*/false);
  AddPortableBox(&mesh, 0.02, -0.18, 0.05, 0.15, -0.07, 0.08);
  for (size_t t = mesh.triangles.size() - 36; t < mesh.triangles.size(); t += 3) {
    std::swap(mesh.triangles[t + 1], mesh.triangles[t + 2]);
  }
  BodyMapOptions o = DenseGapOptions(160, 2);
  o.epsilon = 0.f;
  BodyMapPoseStats stats;
  const BodyMapPose pose = BakeOrDie(mesh, o, &stats);
  size_t plate = 0, sheet = 0;
  const GapCheck check = ExpectGaps(
      pose,
      [&](Vec3d p) {
        if (Inside(p, 0.02, 0.07, 0.15, 0.18)) return ++plate, ExpectedGaps{{0.05, 0.0}};
        if (Inside(p, 0.02, -0.05, 0.15, 0.05)) return ++sheet, ExpectedGaps{{0.12, 0.03}};
        return ExpectedGaps{};
      },
      {-0.15, -0.02, 0.02, 0.15}, {-0.18, -0.07, -0.05, 0.05, 0.07, 0.18}, 1e-6, 1e-6);
  EXPECT_GT(plate, 1000u);
  EXPECT_GT(sheet, 1000u);
  EXPECT_EQ(check.texels_with_gaps, plate + sheet);
  EXPECT_NEAR(double(stats.dropped_gaps), double(sheet), double(check.skipped));
  EXPECT_NEAR(double(stats.gap_texels), double(check.texels_with_gaps), double(check.skipped));
  // The open surfaces are in layer 0 all the same: paper A's slab from them to the block's back.
  for (const auto& [x, y, top] : {std::tuple{-0.085, 0.125, 0.12},
                                  {-0.085, 0.0, 0.06},
                                  {-0.085, -0.125, 0.06},
                                  {0.085, -0.125, 0.08}}) {
    const uint32_t i = static_cast<uint32_t>((x - pose.origin_x) / pose.texel_size);
    const uint32_t j = static_cast<uint32_t>((y - pose.origin_y) / pose.texel_size);
    const BodyMapTexel front = ReadBodyMapTexel(pose, 0, i, j);
    ASSERT_TRUE(front.valid) << x << ", " << y;
    EXPECT_NEAR(pose.front_z - front.depth, top, 1e-6) << x << ", " << y;
    EXPECT_FALSE(ReadBodyMapTexel(pose, 0, i, j, 1).valid) << x << ", " << y;
  }
}

TEST(BodyMapBaker, GapsThinnerThanTheMinimumAreNotStored) {
  // Two plates above a block, no epsilon: 0.05 mm of air under the first (below kMinBodyMapGap,
  // 0.1 mm), 0.2 mm under the second.
  ASSERT_EQ(kMinBodyMapGap, 1e-4);
  Mesh mesh;
  AddPortableBox(&mesh, -0.20, -0.20, -0.10, 0.20, 0.20, 0.00);
  AddPortableBox(&mesh, -0.15, -0.15, 0.00005, -0.02, 0.15, 0.02);
  AddPortableBox(&mesh, 0.02, -0.15, 0.0002, 0.15, 0.15, 0.02);
  BodyMapOptions o = DenseGapOptions(160, 2);
  o.epsilon = 0.f;
  BodyMapPoseStats stats;
  const BodyMapPose pose = BakeOrDie(mesh, o, &stats);
  const GapCheck check = ExpectGaps(
      pose,
      [](Vec3d p) {
        return Inside(p, 0.02, -0.15, 0.15, 0.15) ? ExpectedGaps{{0.0002, 0.0}} : ExpectedGaps{};
      },
      {-0.15, -0.02, 0.02, 0.15}, {-0.15, 0.15}, 1e-6, 1e-6);
  EXPECT_GT(check.texels_with_gaps, 1000u);
  EXPECT_EQ(stats.dropped_gaps, 0u);
}

// A part of zero thickness (both sides of a square at one height, as the two sides of a part
// seen edge-on meet on its silhouette) above or below a block: no body, so layer 0 ends at the
// block and the air between them is no gap, as the run-time renderer draws it
// (BodyMapRenderer.APartSeenEdgeOnDoesNotFillTheAir).
TEST(BodyMapBaker, APartSeenEdgeOnDoesNotFillTheAir) {
  for (const double sliver_z : {-0.3, 0.3}) {
    SCOPED_TRACE(sliver_z);
    Mesh mesh;
    AddPortableBox(&mesh, -0.20, -0.20, -0.10, 0.20, 0.20, 0.00);
    AddQuad(&mesh, -0.1, -0.1, 0.1, 0.1, sliver_z, true);
    AddQuad(&mesh, -0.1, -0.1, 0.1, 0.1, sliver_z, false);
    BodyMapOptions o = DenseGapOptions(160, 3);
    o.epsilon = 0.f;
    BodyMapPoseStats stats;
    const BodyMapPose pose = BakeOrDie(mesh, o, &stats);
    const uint32_t ci = pose.width / 2, cj = pose.height / 2;
    ASSERT_TRUE(Inside(TexelCentre(pose, ci, cj), -0.1, -0.1, 0.1, 0.1));
    const BodyMapTexel front = ReadBodyMapTexel(pose, 0, ci, cj);
    const BodyMapTexel back = ReadBodyMapTexel(pose, 1, ci, cj);
    ASSERT_TRUE(front.valid && back.valid);
    EXPECT_NEAR(pose.front_z - front.depth, 0.0, 1e-6);
    EXPECT_NEAR(pose.front_z - pose.depth_range + back.depth, -0.1, 1e-6);
    EXPECT_NEAR(front.normal.z, 1.0, 1e-6);
    EXPECT_NEAR(back.normal.z, -1.0, 1e-6);
    EXPECT_FALSE(ReadBodyMapTexel(pose, 0, ci, cj, 1).valid);
    EXPECT_EQ(stats.gap_texels, 0u);
  }
}

TEST(BodyMapBaker, GapLayersLeaveTheSlabByteIdentical) {
  const Mesh scene = GapScene();
  // Hashes of layers = 1 bakes recorded before gap layers existed (the same meshes and options):
  // asking for no gap must not change a byte. FNV-1a over every field the bake writes.
  struct Case {
    DepthEncoding depth;
    NormalEncoding normal;
    BodyMapLayout layout;
    uint32_t resolution;
    uint64_t hash;
  };
  const Case cases[] = {{DepthEncoding::kFloat32, NormalEncoding::kFloat32, BodyMapLayout::kDense,
                         200, 0x25a4ba18ef37c2b9ull},
                        {DepthEncoding::kUnorm16, NormalEncoding::kOct16, BodyMapLayout::kRowSpans,
                         256, 0xd90cb6c4340bd0f2ull},
                        {DepthEncoding::kUnorm16, NormalEncoding::kRgb8, BodyMapLayout::kDense, 160,
                         0x8160848a5c820c99ull}};
  for (const Case& c : cases) {
    BodyMapOptions o;
    o.resolution = c.resolution;
    o.depth_encoding = c.depth;
    o.normal_encoding = c.normal;
    o.layout = c.layout;
    ASSERT_EQ(o.layers, 1) << "paper A's slab alone is the default";
    BodyMapPoseStats stats;
    const BodyMapPose one = BakeOrDie(scene, o, &stats);
    EXPECT_EQ(PoseHash(one), c.hash) << "resolution " << c.resolution;
    EXPECT_EQ(one.layers, 1);
    EXPECT_EQ(stats.gap_texels, 0u);
    EXPECT_EQ(stats.gap_ms, 0.0);
    // Layer 0 of a bake with gaps is the same bytes, followed by the gap layers.
    if (c.layout != BodyMapLayout::kDense) continue;
    o.layers = 3;
    const BodyMapPose three = BakeOrDie(scene, o, &stats);
    EXPECT_GT(stats.gap_texels, 1000u);
    const size_t texels = size_t(one.width) * one.height;
    const size_t gap_entries = 2 * three.gap_texels.size();
    EXPECT_EQ(three.gap_texels.size(), stats.gap_texels);
    EXPECT_TRUE(one.gap_texels.empty());
    for (int view = 0; view < 2; ++view) {
      const auto same_prefix = [&](const auto& a, const auto& b, size_t per_texel) {
        ASSERT_EQ(a.size(), per_texel * texels);
        ASSERT_EQ(b.size(), per_texel * (texels + gap_entries));
        if (!a.empty()) {
          EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])));
        }
      };
      same_prefix(one.depth_f32[view], three.depth_f32[view], c.depth == DepthEncoding::kFloat32);
      same_prefix(one.depth_u16[view], three.depth_u16[view], c.depth == DepthEncoding::kUnorm16);
      same_prefix(one.normal_f32[view], three.normal_f32[view],
                  c.normal == NormalEncoding::kFloat32 ? 3 : 0);
      same_prefix(one.normal_oct16[view], three.normal_oct16[view],
                  c.normal == NormalEncoding::kOct16 ? 2 : 0);
      same_prefix(one.normal_rgb8[view], three.normal_rgb8[view],
                  c.normal == NormalEncoding::kRgb8 ? 3 : 0);
    }
  }
}

TEST(BodyMapBaker, Unorm16GapsAreStrictlyNestedAfterQuantisation) {
  // A slanted sheet 1 um thick (less than a unorm16 step, ~2.9 um here) between a slanted slab
  // and a block, no epsilon: the lower boundary of the first gap (the sheet's top, from the
  // back) and the upper boundary of the second (the sheet's bottom, from the front) quantise on
  // different grids and often swap. Such a gap must be dropped, the texel keeping the first.
  Mesh mesh;
  AddPortableBox(&mesh, -0.20, -0.20, -0.10, 0.20, 0.20, 0.00);
  AddSlantedSheet(&mesh, -0.15, -0.15, 0.15, 0.15, 0.030, 0.01, 1e-6);
  AddSlantedSheet(&mesh, -0.15, -0.15, 0.15, 0.15, 0.060, 0.01, 0.01);
  BodyMapOptions o;
  o.resolution = 200;
  o.epsilon = 0.f;
  o.depth_encoding = DepthEncoding::kUnorm16;
  o.normal_encoding = NormalEncoding::kOct16;
  o.layout = BodyMapLayout::kDense;
  o.layers = 3;
  BodyMapPoseStats stats;
  const BodyMapPose pose = BakeOrDie(mesh, o, &stats);
  EXPECT_GT(ExpectStrictlyNested(pose), 10000u);
  size_t two = 0, one = 0;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      if (!Inside(TexelCentre(pose, i, j), -0.149, -0.149, 0.149, 0.149)) continue;
      const bool first = ReadBodyMapTexel(pose, 0, i, j, 1).valid;
      const bool second = ReadBodyMapTexel(pose, 0, i, j, 2).valid;
      two += first && second;
      one += first && !second;
    }
  }
  std::printf("[ unorm16 nesting ] %zu texels keep both gaps, %zu only the first; %zu dropped\n",
              two, one, stats.dropped_gaps);
  // Both outcomes occur, and every single-gap texel is a dropped one.
  EXPECT_GT(two, 1000u);
  EXPECT_GT(one, 1000u);
  EXPECT_GE(stats.dropped_gaps, one);
  // With float32 depth nothing needs dropping.
  o.depth_encoding = DepthEncoding::kFloat32;
  BodyMapPoseStats float_stats;
  const BodyMapPose exact = BakeOrDie(mesh, o, &float_stats);
  ExpectStrictlyNested(exact);
  EXPECT_EQ(float_stats.dropped_gaps, 0u);
  EXPECT_EQ(float_stats.gap_texels, stats.gap_texels);
}

TEST(BodyMapBaker, GapLayersOnCurvedClosedMeshesAreNested) {
  const Mesh scene = GapScene();
  for (const bool compact : {false, true}) {
    BodyMapOptions o = DenseGapOptions(256, 4, compact, NormalEncoding::kRgb8);
    BodyMapPoseStats stats;
    const BodyMapPose pose = BakeOrDie(scene, o, &stats);
    EXPECT_EQ(ExpectStrictlyNested(pose), stats.gap_texels);
    // Upper boundaries face into the gap (down), lower ones up: clearly so, except near a
    // sphere's silhouette, where the vertex normals of the equator ring have z = 0.
    size_t wrong_way = 0, clear = 0, gaps = 0;
    for (uint32_t j = 0; j < pose.height; ++j) {
      for (uint32_t i = 0; i < pose.width; ++i) {
        for (uint32_t layer = 1; layer < pose.layers; ++layer) {
          const BodyMapTexel upper = ReadBodyMapTexel(pose, 0, i, j, layer);
          if (!upper.valid) break;
          const BodyMapTexel lower = ReadBodyMapTexel(pose, 1, i, j, layer);
          ++gaps;
          wrong_way += upper.normal.z > 0.05f || lower.normal.z < -0.05f;
          clear += upper.normal.z < -0.5f && lower.normal.z > 0.5f;
        }
      }
    }
    EXPECT_GT(gaps, 5000u);
    EXPECT_EQ(wrong_way, 0u);
    EXPECT_GT(clear, gaps * 9 / 10);
  }
}

TEST(BodyMapBaker, BakeReportCarriesTheGapFields) {
  BakeConfig config;
  config.hulls_enabled = false;
  config.spheres_enabled = false;
  config.maps.resolution = 128;
  config.maps.layers = 2;
  BakeResult result;
  const Status status = BakeCharacter(test::MannequinPath(), config, &result);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(result.asset.body_maps.poses.size(), 1u);
  EXPECT_EQ(result.asset.body_maps.poses[0].layers, 2);
  const nlohmann::json& report = result.report["body_maps"]["poses"][0];
  EXPECT_EQ(report["layers"], 2);
  EXPECT_TRUE(report["gap_texels"].is_number_unsigned()) << report.dump();
  EXPECT_TRUE(report["dropped_gaps"].is_number_unsigned()) << report.dump();
  EXPECT_GT(report["gap_ms"].get<double>(), 0.0);
}

}  // namespace
}  // namespace drape::bake

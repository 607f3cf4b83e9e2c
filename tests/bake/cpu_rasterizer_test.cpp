// Tests of the body map bake's private CPU rasterizer (bake/src/body_map/cpu_rasterizer.h): the
// two-view pass is bit-identical to two single-view passes, and images reused from an earlier call
// (the same input again, or a bigger raster before a smaller one; the rasterizer keeps its working
// depths in them) give exactly what fresh images give, with no stale texel. The fragment pass
// of the gap layers: its nearest fragments are the rasterizer's texels bit for bit, and on a
// closed mesh every texel's facing signs sum to zero (even with texel centres on edges and
// vertices: the top-left rule is a consistent tie-break).

#include "body_map/cpu_rasterizer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include "octahedron_sphere.h"

namespace drape::bake {
namespace {

// A triangle soup in raster coordinates that exercises the rasterizer's rules: vertices on a
// half-texel lattice (texel centres exactly on edges and vertices: the top-left rule), shared
// vertices and edges, integer depths (equal depths: the lower triangle index wins), triangles
// partly outside the raster, slivers, zero-area triangles and zero vertex normals.
struct Soup {
  uint32_t width = 0, height = 0;
  std::vector<double> window_x, window_y, depth_front, depth_back, normals, positions;
  std::vector<uint32_t> triangles;

  MapRasterInput Input() const {
    MapRasterInput in;
    in.width = width;
    in.height = height;
    in.depth_range = 10.0;
    in.window_x = window_x;
    in.window_y = window_y;
    in.view_depth[0] = depth_front;
    in.view_depth[1] = depth_back;
    in.normals = normals;
    in.positions = positions;
    in.triangles = triangles;
    return in;
  }
};

Soup MakeSoup(uint64_t seed, uint32_t width, uint32_t height, int triangle_count,
              double triangle_size) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Soup s;
  s.width = width;
  s.height = height;
  const auto add_vertex = [&](double x, double y) {
    s.window_x.push_back(std::round(2.0 * x) / 2.0);  // texel units, on the half-texel lattice
    s.window_y.push_back(std::round(2.0 * y) / 2.0);
    s.depth_front.push_back(std::round(4.0 * unit(rng)));  // metres, ties on purpose
    s.depth_back.push_back(std::round(4.0 * unit(rng)));
    const bool zero_normal = s.window_x.size() % 7 == 0;  // the face-normal fallback
    for (int c = 0; c < 3; ++c) s.normals.push_back(zero_normal ? 0.0 : unit(rng) - 0.5);
    for (int c = 0; c < 3; ++c) s.positions.push_back(unit(rng));
    return static_cast<uint32_t>(s.window_x.size() - 1);
  };
  const int shared = triangle_count / 2 + 3;
  for (int v = 0; v < shared; ++v) {
    add_vertex(-5.0 + unit(rng) * (width + 10.0), -5.0 + unit(rng) * (height + 10.0));
  }
  std::uniform_int_distribution<uint32_t> pick(0, static_cast<uint32_t>(shared - 1));
  for (int t = 0; t < triangle_count; ++t) {
    const uint32_t a = pick(rng);
    uint32_t b = pick(rng), c = pick(rng);
    if (t % 4 != 0) {  // mostly small triangles near a shared vertex
      b = add_vertex(s.window_x[a] + (unit(rng) - 0.5) * triangle_size,
                     s.window_y[a] + (unit(rng) - 0.5) * triangle_size);
      if (t % 4 == 1) c = a;  // zero area
      if (t % 4 == 2) {       // collinear sliver
        c = add_vertex(2.0 * s.window_x[b] - s.window_x[a], 2.0 * s.window_y[b] - s.window_y[a]);
      }
    }
    s.triangles.insert(s.triangles.end(), {a, b, c});
  }
  return s;
}

void ExpectSameImage(const MapViewImage& a, const MapViewImage& b) {
  ASSERT_EQ(a.valid.size(), b.valid.size());
  ASSERT_EQ(a.depth.size(), b.depth.size());
  ASSERT_EQ(a.normal.size(), b.normal.size());
  EXPECT_EQ(a.valid, b.valid);
  EXPECT_EQ(0, std::memcmp(a.depth.data(), b.depth.data(), a.depth.size() * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(a.normal.data(), b.normal.data(), a.normal.size() * sizeof(float)));
}

size_t CountValid(const MapViewImage& image) {
  size_t count = 0;
  for (uint8_t v : image.valid) count += v;
  return count;
}

// Both views from fresh buffers, one view at a time.
void RasterizeFresh(const Soup& soup, MapViewImage images[2]) {
  const MapRasterInput in = soup.Input();
  for (int view = 0; view < 2; ++view) {
    images[view] = MapViewImage{};
    RasterizeViewCpu(in, view, &images[view]);
  }
}

TEST(CpuRasterizer, TwoViewPassMatchesSingleViewPasses) {
  for (uint64_t seed : {1u, 2u, 3u}) {
    const Soup soup = MakeSoup(seed, 120 + static_cast<uint32_t>(seed), 90, 4000, 12.0);
    MapViewImage single[2], both[2];
    RasterizeFresh(soup, single);
    RasterizeViewsCpu(soup.Input(), both);
    for (int view = 0; view < 2; ++view) {
      SCOPED_TRACE(testing::Message() << "seed " << seed << " view " << view);
      EXPECT_GT(CountValid(single[view]), 1000u) << "the soup must cover texels";
      ExpectSameImage(both[view], single[view]);
    }
  }
}

TEST(CpuRasterizer, ReusedBuffersMatchFreshOnesAndKeepNoStaleTexel) {
  // Big, the same big input again, then smaller rasters, through one pair of images: every call
  // must equal a call with fresh images.
  const Soup big = MakeSoup(11, 300, 200, 6000, 40.0);
  const Soup smaller = MakeSoup(12, 64, 48, 300, 6.0);
  const Soup narrower = MakeSoup(13, 40, 170, 500, 8.0);  // fewer texels, more rows
  MapViewImage reused[2];
  for (const Soup* soup : {&big, &big, &smaller, &narrower, &big}) {
    MapViewImage fresh[2];
    RasterizeFresh(*soup, fresh);
    RasterizeViewsCpu(soup->Input(), reused);
    for (int view = 0; view < 2; ++view) {
      SCOPED_TRACE(testing::Message() << soup->width << " x " << soup->height << " view " << view);
      ExpectSameImage(reused[view], fresh[view]);
    }
    // The single-view entry point through the same images, too.
    for (int view = 0; view < 2; ++view) {
      RasterizeViewCpu(soup->Input(), view, &reused[view]);
      ExpectSameImage(reused[view], fresh[view]);
    }
  }
}

// --- The fragment pass (CollectFragmentsCpu) ---

uint32_t Bits(float v) { return std::bit_cast<uint32_t>(v); }
uint64_t Bits(double v) { return std::bit_cast<uint64_t>(v); }

TEST(CpuRasterizer, NearestFragmentsAreTheRasterizedTexelsBitForBit) {
  for (uint64_t seed : {21u, 22u, 23u}) {
    const Soup soup = MakeSoup(seed, 110 + static_cast<uint32_t>(seed), 95, 4000, 14.0);
    const MapRasterInput in = soup.Input();
    MapViewImage images[2];
    std::vector<uint32_t> faces[2];
    for (int view = 0; view < 2; ++view) RasterizeViewCpu(in, view, &images[view], &faces[view]);
    MapFragments fragments;
    ASSERT_TRUE(CollectFragmentsCpu(in, 1, &fragments));
    const size_t texels = static_cast<size_t>(in.width) * in.height;
    ASSERT_EQ(fragments.offsets.size(), texels + 1);
    ASSERT_EQ(fragments.offsets.back(), fragments.depth.size());
    ASSERT_EQ(fragments.triangle.size(), fragments.depth.size());
    ASSERT_EQ(fragments.facing.size(), fragments.depth.size());
    size_t mismatches = 0, multi = 0;
    for (uint32_t j = 0; j < in.height; ++j) {
      for (uint32_t i = 0; i < in.width; ++i) {
        const size_t n = static_cast<size_t>(j) * in.width + i;
        const uint32_t begin = fragments.offsets[n], end = fragments.offsets[n + 1];
        ASSERT_LE(begin, end);
        mismatches += (begin < end) != (images[0].valid[n] != 0);
        if (begin == end) continue;
        multi += end - begin > 1;
        // The winners: minimum depth, ties to the lower triangle (the rasterizer's GL_LESS).
        for (int view = 0; view < 2; ++view) {
          double best = 0.0;
          uint32_t best_triangle = 0;
          for (uint32_t f = begin; f < end; ++f) {
            const uint32_t t = fragments.triangle[f];
            const double d = FragmentDepth(in, view, t, i, j);
            if (view == 0) mismatches += Bits(d) != Bits(fragments.depth[f]);
            if (f == begin || d < best) {
              best = d;
              best_triangle = t;
            }
          }
          mismatches += Bits(static_cast<float>(best)) != Bits(images[view].depth[n]);
          mismatches += best_triangle != faces[view][n];
          float normal[3];
          FragmentNormal(in, best_triangle, i, j, view == 0 ? 1.0 : -1.0, normal);
          for (int c = 0; c < 3; ++c) {
            mismatches += Bits(normal[c]) != Bits(images[view].normal[3 * n + c]);
          }
        }
        for (uint32_t f = begin; f < end; ++f) {
          // Ascending triangles; the facing is the sign of the window area.
          if (f > begin) mismatches += fragments.triangle[f] <= fragments.triangle[f - 1];
          const uint32_t t = fragments.triangle[f];
          const uint32_t a = soup.triangles[3 * t], b = soup.triangles[3 * t + 1],
                         c = soup.triangles[3 * t + 2];
          const double area2 =
              (soup.window_x[b] - soup.window_x[a]) * (soup.window_y[c] - soup.window_y[a]) -
              (soup.window_y[b] - soup.window_y[a]) * (soup.window_x[c] - soup.window_x[a]);
          mismatches += fragments.facing[f] != (area2 > 0.0 ? 1 : -1);
        }
      }
    }
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    EXPECT_EQ(mismatches, 0u);
    EXPECT_GT(multi, 1000u) << "the soup must overlap itself";
    // Reused storage gives the same fragments.
    MapFragments again = fragments;
    ASSERT_TRUE(CollectFragmentsCpu(MakeSoup(seed + 100, 40, 30, 200, 5.0).Input(), 1, &again));
    ASSERT_TRUE(CollectFragmentsCpu(in, 1, &again));
    EXPECT_EQ(again.offsets, fragments.offsets);
    EXPECT_EQ(again.triangle, fragments.triangle);
    EXPECT_EQ(again.facing, fragments.facing);
    EXPECT_EQ(0, std::memcmp(again.depth.data(), fragments.depth.data(),
                             fragments.depth.size() * sizeof(double)));
    // min_fragments = 3: the texels with 3 or more keep the same fragments, the others none.
    MapFragments three;
    ASSERT_TRUE(CollectFragmentsCpu(in, 3, &three));
    ASSERT_EQ(three.offsets.size(), fragments.offsets.size());
    size_t kept = 0, filter_mismatches = 0;
    for (size_t n = 0; n < texels; ++n) {
      const uint32_t begin = fragments.offsets[n], end = fragments.offsets[n + 1];
      const uint32_t count = three.offsets[n + 1] - three.offsets[n];
      if (end - begin < 3) {
        filter_mismatches += count != 0;
        continue;
      }
      ++kept;
      filter_mismatches += count != end - begin;
      for (uint32_t k = 0; k < count && count == end - begin; ++k) {
        filter_mismatches +=
            three.triangle[three.offsets[n] + k] != fragments.triangle[begin + k] ||
            Bits(three.depth[three.offsets[n] + k]) != Bits(fragments.depth[begin + k]) ||
            three.facing[three.offsets[n] + k] != fragments.facing[begin + k];
      }
    }
    EXPECT_GT(kept, 100u);
    EXPECT_EQ(filter_mismatches, 0u);
    EXPECT_LT(three.depth.size(), fragments.depth.size());
  }
}

// A closed sphere (a subdivided octahedron, counter-clockwise seen from outside) in raster
// coordinates, its vertices snapped to the half-texel lattice so that texel centres fall on
// edges and vertices and every edge test is exact.
Soup MakeSnappedSphere(double cx, double cy, double radius, int levels) {
  const test::UnitSphereMesh sphere = test::OctahedronSphere(levels);
  const std::vector<std::array<double, 3>>& p = sphere.positions;
  const std::vector<std::array<uint32_t, 3>>& t = sphere.triangles;
  Soup s;
  s.width = static_cast<uint32_t>(2 * cx);
  s.height = static_cast<uint32_t>(2 * cy);
  for (const auto& q : p) {
    s.window_x.push_back(std::round(2.0 * (cx + radius * q[0])) / 2.0);
    s.window_y.push_back(std::round(2.0 * (cy + radius * q[1])) / 2.0);
    s.depth_front.push_back(2.0 - q[2]);
    s.depth_back.push_back(2.0 + q[2]);
    for (int c = 0; c < 3; ++c) s.normals.push_back(q[c]);
    s.positions.insert(s.positions.end(), {s.window_x.back(), s.window_y.back(), q[2]});
  }
  for (const auto& f : t) s.triangles.insert(s.triangles.end(), {f[0], f[1], f[2]});
  return s;
}

TEST(CpuRasterizer, ClosedMeshFacingsSumToZeroAtEveryTexel) {
  const Soup sphere = MakeSnappedSphere(40.0, 35.0, 30.0, 4);  // 2048 triangles
  const MapRasterInput in = sphere.Input();
  MapFragments fragments;
  ASSERT_TRUE(CollectFragmentsCpu(in, 1, &fragments));
  size_t covered = 0, unbalanced = 0, entering_first = 0;
  for (size_t n = 0; n + 1 < fragments.offsets.size(); ++n) {
    const uint32_t begin = fragments.offsets[n], end = fragments.offsets[n + 1];
    if (begin == end) continue;
    ++covered;
    int sum = 0;
    for (uint32_t f = begin; f < end; ++f) sum += fragments.facing[f];
    unbalanced += sum != 0;
    // Among the nearest fragments (depths within rounding of the minimum: at the silhouette the
    // front and back triangles meet) one enters the body.
    double nearest = fragments.depth[begin];
    for (uint32_t f = begin; f < end; ++f) nearest = std::min(nearest, fragments.depth[f]);
    bool enters = false;
    for (uint32_t f = begin; f < end; ++f)
      enters = enters || (fragments.depth[f] <= nearest + 1e-9 && fragments.facing[f] == 1);
    entering_first += enters;
  }
  EXPECT_GT(covered, 2500u);  // about pi * 30^2
  EXPECT_EQ(unbalanced, 0u);
  EXPECT_EQ(entering_first, covered);
}

}  // namespace
}  // namespace drape::bake

// Tests of the body map bake's private CPU rasterizer (bake/src/cpu_rasterizer.h): the two-view
// pass is bit-identical to two single-view passes, and images reused from an earlier call (the
// same input again, or a bigger raster before a smaller one; the rasterizer keeps its working
// depths in them) give exactly what fresh images give, with no stale texel.

#include "../../bake/src/cpu_rasterizer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

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

}  // namespace
}  // namespace drape::bake

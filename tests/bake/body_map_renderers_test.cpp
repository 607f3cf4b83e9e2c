// The body-map renderers: the CPU rasterizer bakes the same bytes every time; the OSMesa path is
// deterministic too and agrees with the CPU reference (coverage, depth within the vertex-snapping
// bound, normals), in one tile and in several, and its slab gets the CPU's gap layers.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "body_map_fixtures.h"
#include "body_map_gap_fixtures.h"
#include "drape/bake/body_map_baker.h"

namespace drape::bake {
namespace {

using namespace body_map_fixtures;

// Compares two bakes of the same window texel by texel over the union of their rectangles.
struct MapDifference {
  size_t window_texels = 0, coverage_mismatch = 0, both_valid = 0;
  double max_depth_diff = 0.0, p999_depth_diff = 0.0, max_normal_deg = 0.0;
  size_t depth_over_1um = 0;
  // Largest depth difference relative to the surface slope: diff / (texel * tan(theta)), theta
  // the angle between the normal (of bake a) and the view axis. Vertex snapping moves a triangle
  // by a fraction of a texel; the depth then changes by that fraction times the slope.
  double max_diff_per_slope_texel = 0.0;
  double max_cos_over_1um = 0.0;  // max |n.z| over texels whose depth differs by > 1e-6 m
};
MapDifference Compare(const BodyMapPose& a, const BodyMapPose& b, size_t window_texels) {
  MapDifference d;
  d.window_texels = window_texels;
  const double t = a.texel_size;
  const long di = std::lround((double(b.origin_x) - a.origin_x) / t);
  const long dj = std::lround((double(b.origin_y) - a.origin_y) / t);
  const long i_lo = std::min(0L, di), j_lo = std::min(0L, dj);
  const long i_hi = std::max<long>(a.width, di + long(b.width));
  const long j_hi = std::max<long>(a.height, dj + long(b.height));
  std::vector<double> diffs;
  for (long j = j_lo; j < j_hi; ++j) {
    for (long i = i_lo; i < i_hi; ++i) {
      for (int view = 0; view < 2; ++view) {
        const bool in_a = i >= 0 && j >= 0 && i < long(a.width) && j < long(a.height);
        const bool in_b =
            i - di >= 0 && j - dj >= 0 && i - di < long(b.width) && j - dj < long(b.height);
        const BodyMapTexel ta =
            in_a ? ReadBodyMapTexel(a, view, uint32_t(i), uint32_t(j)) : BodyMapTexel{};
        const BodyMapTexel tb =
            in_b ? ReadBodyMapTexel(b, view, uint32_t(i - di), uint32_t(j - dj)) : BodyMapTexel{};
        if (ta.valid != tb.valid) {
          if (view == 0) ++d.coverage_mismatch;
          continue;
        }
        if (!ta.valid) continue;
        if (view == 0) ++d.both_valid;
        const double diff = std::fabs(double(ta.depth) - tb.depth);
        diffs.push_back(diff);
        d.max_depth_diff = std::max(d.max_depth_diff, diff);
        const double nz = std::min(1.0, std::fabs(double(ta.normal.z)));
        const double tan_theta = std::sqrt(std::max(0.0, 1.0 - nz * nz)) / std::max(nz, 1e-9);
        if (diff > 1e-6) {
          ++d.depth_over_1um;
          d.max_cos_over_1um = std::max(d.max_cos_over_1um, nz);
          d.max_diff_per_slope_texel =
              std::max(d.max_diff_per_slope_texel, (diff - 1e-6) / (t * tan_theta));
        }
        d.max_normal_deg = std::max(d.max_normal_deg, AngleDeg(ToD3(ta.normal), ToD3(tb.normal)));
      }
    }
  }
  if (!diffs.empty()) {
    std::sort(diffs.begin(), diffs.end());
    d.p999_depth_diff = diffs[std::min(diffs.size() - 1, size_t(0.999 * double(diffs.size())))];
  }
  return d;
}

void ExpectOsMesaMatchesCpu(const Mesh& mesh, uint32_t resolution, const char* label) {
  if (!OsMesaRendererAvailable()) GTEST_SKIP() << "OSMesa renderer not available in this build";
  BodyMapOptions cpu = FloatOptions(resolution), gl = FloatOptions(resolution);
  gl.renderer = MapRenderer::kOsMesa;
  BodyMapPoseStats cpu_stats, gl_stats;
  const BodyMapPose a = BakeOrDie(mesh, cpu, &cpu_stats);
  const BodyMapPose b = BakeOrDie(mesh, gl, &gl_stats);
  ASSERT_EQ(a.texel_size, b.texel_size);
  ASSERT_EQ(a.front_z, b.front_z);
  ASSERT_EQ(a.depth_range, b.depth_range);
  const MapDifference d = Compare(a, b, size_t(resolution) * resolution);
  const double mismatch_fraction = double(d.coverage_mismatch) / double(d.window_texels);
  const double over_fraction = double(d.depth_over_1um) / double(2 * d.both_valid);
  std::printf(
      "[ osmesa vs cpu ] %s N=%u: renderer '%s', coverage mismatch %zu texels (%.5f %%), "
      "silhouette conflicts %u, both valid %zu, depth |diff| max %.3g m, p99.9 %.3g m, "
      "> 1e-6 m on %zu texel-views (%.4f %%, all with |n.z| <= %.3f), max (diff - 1e-6) / "
      "(texel * tan theta) %.4f, normal max %.3f deg\n",
      label, resolution, gl_stats.renderer, d.coverage_mismatch, 100.0 * mismatch_fraction,
      gl_stats.silhouette_conflicts, d.both_valid, d.max_depth_diff, d.p999_depth_diff,
      d.depth_over_1um, 100.0 * over_fraction, d.max_cos_over_1um, d.max_diff_per_slope_texel,
      d.max_normal_deg);
  EXPECT_LE(mismatch_fraction, 1e-4);  // 0.01 % of the window's texels
  // Depth: within 1e-6 m on texels valid in both, except on steep texels next to the outline,
  // where llvmpipe's vertex snapping (8 sub-pixel bits: a vertex moves by <= 1/512 texel per
  // axis) shifts a triangle whose depth changes by tan(theta) per unit of x,y. There the bound
  // is 1e-6 m + texel * tan(theta) / 256. Measured (printed above): p99.9 under 1e-6 m, the
  // larger differences all at |n.z| < 0.14, and at most 0.0008 texel * tan(theta).
  EXPECT_LE(d.p999_depth_diff, 1e-6);
  EXPECT_LE(over_fraction, 1e-3);
  EXPECT_LE(d.max_diff_per_slope_texel, 1.0 / 256.0);
  EXPECT_LE(d.max_normal_deg, 0.1);
}

TEST(BodyMapBaker, OsMesaAgreesWithCpuOnSphere) {
  ExpectOsMesaMatchesCpu(MakeSphere({0.05, 1.0, -0.02}, 0.3, 50, 50), 1024, "sphere 4.9k");
}

TEST(BodyMapBaker, OsMesaAgreesWithCpuOn80kTriangles) {
  ExpectOsMesaMatchesCpu(MakeSphere({0.0, 0.0, 0.0}, 0.3, 200, 200), 1024, "sphere 79.6k");
}

TEST(BodyMapBaker, OsMesaIsUnavailableOrDeterministic) {
  const Mesh sphere = MakeSphere({0.0, 0.0, 0.0}, 0.3, 30, 30);
  BodyMapOptions o = FloatOptions(256);
  o.renderer = MapRenderer::kOsMesa;
  BodyMapPose a, b;
  const Status status = BakeBodyMapPose(sphere.positions, sphere.triangles, o, &a);
  if (!OsMesaRendererAvailable()) {
    EXPECT_EQ(status.code(), StatusCode::kInvalidState);
    EXPECT_NE(status.message().find("OSMesa renderer not available"), std::string::npos);
    return;
  }
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_TRUE(BakeBodyMapPose(sphere.positions, sphere.triangles, o, &b).ok());
  EXPECT_EQ(a.depth_f32[0], b.depth_f32[0]);
  EXPECT_EQ(a.depth_f32[1], b.depth_f32[1]);
  EXPECT_EQ(a.normal_f32[0], b.normal_f32[0]);
}

TEST(BodyMapBaker, OsMesaTilesAgreeWithCpuOnATallFittedWindow) {
  // 0.33 m x 1.53 m: at N = 2048 the fitted window is about 950 x 4400 texels, so the OSMesa
  // path renders it in several 2048-texel tiles; the seams must not show.
  const Mesh capsule = MakeCapsule({0.0, 0.9, 0.0}, 0.15, 0.6, 32, 64);
  if (!OsMesaRendererAvailable()) GTEST_SKIP() << "OSMesa renderer not available in this build";
  BodyMapOptions cpu = FloatOptions(2048), gl = FloatOptions(2048);
  cpu.fitted_window = gl.fitted_window = true;
  gl.renderer = MapRenderer::kOsMesa;
  BodyMapPoseStats stats;
  const BodyMapPose a = BakeOrDie(capsule, cpu, &stats);
  const BodyMapPose b = BakeOrDie(capsule, gl);
  ASSERT_GT(stats.window_height, 4096u);
  const MapDifference d = Compare(a, b, size_t(stats.window_width) * size_t(stats.window_height));
  std::printf(
      "[ osmesa vs cpu ] tall capsule, fitted %u x %u: coverage mismatch %zu, depth max "
      "%.3g m, p99.9 %.3g m, max (diff - 1e-6) / (texel * tan theta) %.4f\n",
      stats.window_width, stats.window_height, d.coverage_mismatch, d.max_depth_diff,
      d.p999_depth_diff, d.max_diff_per_slope_texel);
  EXPECT_LE(double(d.coverage_mismatch) / double(d.window_texels), 1e-4);
  EXPECT_LE(d.p999_depth_diff, 1e-6);
  EXPECT_LE(d.max_diff_per_slope_texel, 1.0 / 256.0);
}

TEST(BodyMapBaker, CpuBakesAreByteIdentical) {
  const Mesh sphere = MakeSphere({0.01, 0.02, 0.03}, 0.3, 50, 50);
  BodyMapOptions o;  // defaults: float depth, oct16 normals, N = 1024
  o.resolution = 512;
  const BodyMapPose a = BakeOrDie(sphere, o), b = BakeOrDie(sphere, o);
  for (int view = 0; view < 2; ++view) {
    ASSERT_EQ(a.depth_f32[view].size(), b.depth_f32[view].size());
    EXPECT_EQ(0, std::memcmp(a.depth_f32[view].data(), b.depth_f32[view].data(),
                             a.depth_f32[view].size() * sizeof(float)));
    EXPECT_EQ(a.normal_oct16[view], b.normal_oct16[view]);
  }
  EXPECT_EQ(a.row_span_offsets, b.row_span_offsets);
  EXPECT_EQ(a.span_begin, b.span_begin);
  EXPECT_EQ(a.span_texel_offsets, b.span_texel_offsets);
  EXPECT_EQ(0, std::memcmp(&a.origin_x, &b.origin_x, sizeof(float)));
  EXPECT_EQ(0, std::memcmp(&a.front_z, &b.front_z, sizeof(float)));
}

TEST(BodyMapBaker, OsMesaSlabGetsTheCpuGaps) {
  if (!OsMesaRendererAvailable()) GTEST_SKIP() << "OSMesa renderer not available in this build";
  const Mesh scene = GapScene();
  BodyMapOptions o = DenseGapOptions(256, 3);
  BodyMapPoseStats cpu_stats, gl_stats;
  const BodyMapPose cpu = BakeOrDie(scene, o, &cpu_stats);
  o.renderer = MapRenderer::kOsMesa;
  const BodyMapPose gl = BakeOrDie(scene, o, &gl_stats);
  ASSERT_EQ(gl.width, cpu.width);
  ASSERT_EQ(gl.height, cpu.height);
  EXPECT_EQ(ExpectStrictlyNested(gl), gl_stats.gap_texels);
  // The gaps come from the same CPU fragment pass: they differ only where OSMesa's slab does.
  size_t differ = 0;
  for (uint32_t j = 0; j < cpu.height; ++j) {
    for (uint32_t i = 0; i < cpu.width; ++i) {
      for (uint32_t layer = 1; layer < 3; ++layer) {
        const BodyMapTexel a = ReadBodyMapTexel(cpu, 0, i, j, layer);
        const BodyMapTexel b = ReadBodyMapTexel(gl, 0, i, j, layer);
        differ += a.valid != b.valid || (a.valid && Bits(a.depth) != Bits(b.depth));
      }
    }
  }
  std::printf("[ osmesa gaps ] %zu gap texels (cpu %zu), %zu texel-layers differ, %zu dropped\n",
              gl_stats.gap_texels, cpu_stats.gap_texels, differ, gl_stats.dropped_gaps);
  EXPECT_GT(cpu_stats.gap_texels, 1000u);
  EXPECT_LE(differ, cpu_stats.gap_texels / 100);
}

}  // namespace
}  // namespace drape::bake

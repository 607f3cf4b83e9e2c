// Body-map bakes of shapes with known surfaces: a UV sphere, a box with split faces and a capsule
// give the depth at every texel centre between the inner and the outer analytic surface, normals
// within the tessellation's bound, and the covered area the shape projects to.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "body_map_fixtures.h"
#include "drape/bake/body_map_baker.h"

namespace drape::bake {
namespace {

using namespace body_map_fixtures;

// Largest angle between a vertex normal and the analytic normal at that (offset) vertex,
// degrees. `axis_point` maps a point to the centre of its osculating sphere or cylinder.
template <typename AxisPoint>
double MaxVertexNormalDeviationDeg(const std::vector<Vec3d>& q, const std::vector<Vec3d>& normals,
                                   AxisPoint axis_point) {
  double deviation = 0.0;
  for (size_t v = 0; v < q.size(); ++v) {
    deviation = std::max(deviation, AngleDeg(normals[v], Sub(q[v], axis_point(q[v]))));
  }
  return deviation;
}

// Why the normal tolerance is what it is: when every vertex normal is radial, the interpolated
// normal sum(lambda_k n_k) is parallel to p_tri - centre, the radial direction of the rasterized
// point p_tri itself. The analytic normal is taken at the outer surface point above the same
// texel, which differs from p_tri only along z, by at most z_outer - z_inner: an angle of at most
// (z_outer - z_inner) / r_inner as seen from the centre. Non-radial vertex normals add at most
// their deviation. So: tolerance = deviation + (z_outer - z_inner) / r_inner + float rounding.
double NormalToleranceDeg(double vertex_deviation_deg, double z_outer, double z_inner,
                          double r_inner) {
  return vertex_deviation_deg + (z_outer - z_inner) / r_inner / kDegree + 0.01;
}

TEST(BodyMapBaker, SphereDepthCoverageAndNormalsMatchAnalytic) {
  const Vec3d c{0.05, 1.0, -0.02};
  const double r = 0.3;
  const Mesh sphere = MakeSphere(c, r, 50, 50);  // 4900 triangles
  ASSERT_EQ(sphere.triangles.size() / 3, 4900u);
  BodyMapOptions o = FloatOptions(512);
  BodyMapPoseStats stats;
  const BodyMapPose pose = BakeOrDie(sphere, o, &stats);
  ASSERT_GT(pose.width, 0u);

  std::vector<Vec3d> normals;
  const std::vector<Vec3d> q = OffsetVertices(sphere, o.epsilon, &normals);
  const double r_outer = r + o.epsilon;
  const double sag = SphereSag(sphere, q, c, r_outer);
  const double vertex_deviation_deg =
      MaxVertexNormalDeviationDeg(q, normals, [&](Vec3d) { return c; });
  ASSERT_GT(sag, 0.0);
  ASSERT_LT(sag, 2e-3);  // the tessellation is what we think it is
  const double r_inner = r_outer - sag;
  const double back_z = double(pose.front_z) - double(pose.depth_range);
  const double t = pose.texel_size;

  // The square window of paper A: side = 2 r' + 2 margin, N texels.
  EXPECT_NEAR(t, (2 * r_outer + 2 * o.margin) / o.resolution, 1e-4 * t);
  EXPECT_EQ(stats.window_width, o.resolution);
  EXPECT_EQ(stats.window_height, o.resolution);
  EXPECT_EQ(stats.silhouette_conflicts, 0u);  // one rasterizer, same texel centres: no conflict

  size_t checked_depth = 0, checked_normals = 0, valid = 0;
  double max_central_depth_error = 0.0, max_normal_error_deg = 0.0;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      const Vec3d p = TexelCentre(pose, i, j);
      const double rho = std::hypot(p.x - c.x, p.y - c.y);
      const BodyMapTexel front = ReadBodyMapTexel(pose, 0, i, j);
      const BodyMapTexel back = ReadBodyMapTexel(pose, 1, i, j);
      ASSERT_EQ(front.valid, back.valid) << i << "," << j;
      valid += front.valid ? 1 : 0;
      // Coverage: the inner ball always projects under the mesh, nothing lies beyond r'.
      if (rho < r_inner - 1e-6) {
        EXPECT_TRUE(front.valid) << i << "," << j << " rho " << rho;
      }
      if (rho > r_outer + 1e-6) {
        EXPECT_FALSE(front.valid) << i << "," << j << " rho " << rho;
      }
      if (!front.valid || rho >= r_inner - 1e-6) continue;
      // The visible surface lies between the inner and the outer sphere along z.
      const double z_outer = std::sqrt(r_outer * r_outer - rho * rho);
      const double z_inner = std::sqrt(r_inner * r_inner - rho * rho);
      const double front_lo = double(pose.front_z) - (c.z + z_outer);
      const double front_hi = double(pose.front_z) - (c.z + z_inner);
      const double back_lo = (c.z - z_outer) - back_z;
      const double back_hi = (c.z - z_inner) - back_z;
      constexpr double kRounding = 2e-6;  // float storage of metres-scale values and origins
      EXPECT_GE(front.depth, front_lo - kRounding) << i << "," << j;
      EXPECT_LE(front.depth, front_hi + kRounding) << i << "," << j;
      EXPECT_GE(back.depth, back_lo - kRounding) << i << "," << j;
      EXPECT_LE(back.depth, back_hi + kRounding) << i << "," << j;
      if (z_outer >= 0.9 * r_outer) {
        max_central_depth_error =
            std::max(max_central_depth_error, std::fabs(front.depth - front_lo));
      }
      ++checked_depth;
      // Normals: the analytic outward normal at the analytic surface point above the texel.
      const Vec3d n_front{p.x - c.x, p.y - c.y, z_outer};
      const Vec3d n_back{p.x - c.x, p.y - c.y, -z_outer};
      if (n_front.z / r_outer >= 0.3) {
        const double tolerance_deg =
            NormalToleranceDeg(vertex_deviation_deg, z_outer, z_inner, r_inner);
        const double front_error = AngleDeg(ToD3(front.normal), n_front);
        const double back_error = AngleDeg(ToD3(back.normal), n_back);
        EXPECT_LE(front_error, tolerance_deg) << i << "," << j;
        EXPECT_LE(back_error, tolerance_deg) << i << "," << j;
        max_normal_error_deg = std::max({max_normal_error_deg, front_error, back_error});
        EXPECT_NEAR(Len(ToD3(front.normal)), 1.0, 1e-6);
        ++checked_normals;
      }
    }
  }
  // The covered area is between the inner and the outer disc (plus a texel of outline).
  const double area_texels = double(valid) * t * t;
  EXPECT_GE(area_texels, kPi * r_inner * r_inner - 2 * kPi * r_inner * t);
  EXPECT_LE(area_texels, kPi * r_outer * r_outer + 2 * kPi * r_outer * t);
  EXPECT_NEAR(stats.coverage, double(valid) / (double(o.resolution) * o.resolution), 1e-6);
  EXPECT_EQ(stats.valid_texels, valid);
  EXPECT_GT(checked_depth, 0.8 * kPi * r * r / (t * t));
  EXPECT_GT(checked_normals, 0.5 * kPi * r * r / (t * t));
  // Near the view axis (n.z >= 0.9) the depth is within sag / 0.9 of the analytic sphere.
  EXPECT_LE(max_central_depth_error, sag / 0.9 + 2e-6);
  EXPECT_LT(max_normal_error_deg, 2.0);  // "within a few degrees" (measured about 0.6)
  std::printf(
      "[ sphere 4.9k N=512 ] sag %.3g m, vertex normal deviation %.3f deg, max normal "
      "error %.3f deg, max central depth error %.3g m\n",
      sag, vertex_deviation_deg, max_normal_error_deg, max_central_depth_error);
}

TEST(BodyMapBaker, SplitBoxGivesExactDepthNormalsAndCoverage) {
  Mesh box;
  const Vec3d lo{-0.2013, -0.3107, 0.1031}, hi{0.1517, 0.4291, 0.3543};
  AddSplitBox(&box, lo, hi);
  BodyMapOptions o = FloatOptions(300);
  BodyMapPoseStats stats;
  const BodyMapPose pose = BakeOrDie(box, o, &stats);
  const double eps = o.epsilon;
  double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9, z0 = 1e9, z1 = -1e9;
  for (Float3 p : box.positions) {
    x0 = std::min(x0, double(p.x));
    x1 = std::max(x1, double(p.x));
    y0 = std::min(y0, double(p.y));
    y1 = std::max(y1, double(p.y));
    z0 = std::min(z0, double(p.z));
    z1 = std::max(z1, double(p.z));
  }
  // Window: square, side max(L', H') with L' = L + 2 eps + 2 margin.
  const double side = std::max(x1 - x0, y1 - y0) + 2 * eps + 2 * o.margin;
  EXPECT_NEAR(pose.texel_size, side / o.resolution, 1e-6 * side / o.resolution);
  const double t = pose.texel_size;
  const double back_z = double(pose.front_z) - double(pose.depth_range);
  size_t valid = 0;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      const Vec3d p = TexelCentre(pose, i, j);
      const BodyMapTexel front = ReadBodyMapTexel(pose, 0, i, j);
      const BodyMapTexel back = ReadBodyMapTexel(pose, 1, i, j);
      // The side faces are edge-on: exactly the texel centres over the x,y rectangle are covered.
      const double inset = std::min({p.x - x0, x1 - p.x, p.y - y0, y1 - p.y});
      if (std::fabs(inset) < 1e-4 * t) continue;  // centre on the outline: either answer is fine
      ASSERT_EQ(front.valid, inset > 0) << i << "," << j;
      ASSERT_EQ(back.valid, inset > 0) << i << "," << j;
      if (!front.valid) continue;
      ++valid;
      EXPECT_NEAR(front.depth, double(pose.front_z) - (z1 + eps), 1e-6);
      EXPECT_NEAR(back.depth, (z0 - eps) - back_z, 1e-6);
      EXPECT_NEAR(front.normal.z, 1.0, 1e-6);
      EXPECT_NEAR(back.normal.z, -1.0, 1e-6);
    }
  }
  const double expected = (x1 - x0) * (y1 - y0) / (t * t);
  EXPECT_NEAR(double(valid), expected, 2 * ((x1 - x0) + (y1 - y0)) / t + 4);
  EXPECT_EQ(stats.valid_texels, valid);
  // Row spans (the default): exactly the valid texels are stored, plus the span table.
  ASSERT_EQ(pose.layout, BodyMapLayout::kRowSpans);
  EXPECT_EQ(stats.stored_texels, stats.valid_texels);
  EXPECT_EQ(stats.bytes, 2 * stats.stored_texels * (4 + 12) + SpanTableBytes(pose));
}

TEST(BodyMapBaker, CapsuleDepthAndNormalsMatchAnalytic) {
  const Vec3d c{0.0, 0.9, 0.05};
  const double r = 0.12, half = 0.35;
  const Mesh capsule = MakeCapsule(c, r, half, 32, 64);
  BodyMapOptions o = FloatOptions(512);
  o.fitted_window = true;
  BodyMapPoseStats stats;
  const BodyMapPose pose = BakeOrDie(capsule, o, &stats);
  std::vector<Vec3d> normals;
  const std::vector<Vec3d> q = OffsetVertices(capsule, o.epsilon, &normals);
  const double r_outer = r + o.epsilon;
  // Sag: r' minus the smallest distance of any offset triangle to the axis segment (sampled).
  double min_axis_distance = 1e9;
  for (size_t tri = 0; tri < capsule.triangles.size(); tri += 3) {
    const Vec3d a = q[capsule.triangles[tri]], b = q[capsule.triangles[tri + 1]],
                cc = q[capsule.triangles[tri + 2]];
    for (int u = 0; u <= 16; ++u) {
      for (int v = 0; u + v <= 16; ++v) {
        const Vec3d p = Add(a, Add(Scale(Sub(b, a), u / 16.0), Scale(Sub(cc, a), v / 16.0)));
        const Vec3d axis{c.x, std::clamp(p.y - c.y, -half, half) + c.y, c.z};
        min_axis_distance = std::min(min_axis_distance, Len(Sub(p, axis)));
      }
    }
  }
  const double sag = (r_outer - min_axis_distance) * 1.1 + 1e-6;  // sampling slack
  const double r_inner = r_outer - sag;
  const double vertex_deviation_deg = MaxVertexNormalDeviationDeg(q, normals, [&](Vec3d p) {
    return Vec3d{c.x, std::clamp(p.y - c.y, -half, half) + c.y, c.z};
  });
  double max_normal_error_deg = 0.0;
  const double back_z = double(pose.front_z) - double(pose.depth_range);

  // Fitted window: the same texel budget as N x N, smaller texels than the square window.
  const double box_l = 2 * r_outer + 2 * o.margin, box_h = 2 * (r_outer + half) + 2 * o.margin;
  EXPECT_NEAR(pose.texel_size, std::sqrt(box_l * box_h) / o.resolution, 1e-6);
  EXPECT_LT(pose.texel_size, std::max(box_l, box_h) / o.resolution);
  EXPECT_LE(double(stats.window_width) * stats.window_height,
            double(o.resolution) * o.resolution + stats.window_width + stats.window_height + 1);

  size_t checked = 0;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      const Vec3d p = TexelCentre(pose, i, j);
      const double axis_y = std::clamp(p.y - c.y, -half, half) + c.y;
      const double rho = std::hypot(p.x - c.x, p.y - axis_y);
      const BodyMapTexel front = ReadBodyMapTexel(pose, 0, i, j);
      const BodyMapTexel back = ReadBodyMapTexel(pose, 1, i, j);
      ASSERT_EQ(front.valid, back.valid);
      if (rho < r_inner - 1e-6) {
        EXPECT_TRUE(front.valid) << i << "," << j;
      }
      if (rho > r_outer + 1e-6) {
        EXPECT_FALSE(front.valid) << i << "," << j;
      }
      if (!front.valid || rho >= r_inner - 1e-6) continue;
      const double z_outer = std::sqrt(r_outer * r_outer - rho * rho);
      const double z_inner = std::sqrt(r_inner * r_inner - rho * rho);
      EXPECT_GE(front.depth, double(pose.front_z) - (c.z + z_outer) - 2e-6);
      EXPECT_LE(front.depth, double(pose.front_z) - (c.z + z_inner) + 2e-6);
      EXPECT_GE(back.depth, (c.z - z_outer) - back_z - 2e-6);
      EXPECT_LE(back.depth, (c.z - z_inner) - back_z + 2e-6);
      if (z_outer / r_outer >= 0.3) {
        const Vec3d n_front{p.x - c.x, p.y - axis_y, z_outer};
        const Vec3d n_back{p.x - c.x, p.y - axis_y, -z_outer};
        const double tolerance_deg =
            NormalToleranceDeg(vertex_deviation_deg, z_outer, z_inner, r_inner);
        const double front_error = AngleDeg(ToD3(front.normal), n_front);
        const double back_error = AngleDeg(ToD3(back.normal), n_back);
        EXPECT_LE(front_error, tolerance_deg) << i << "," << j;
        EXPECT_LE(back_error, tolerance_deg) << i << "," << j;
        max_normal_error_deg = std::max({max_normal_error_deg, front_error, back_error});
        ++checked;
      }
    }
  }
  EXPECT_LT(max_normal_error_deg, 3.0);  // "within a few degrees"
  std::printf(
      "[ capsule N=512 fitted ] sag %.3g m, vertex normal deviation %.3f deg, max normal "
      "error %.3f deg\n",
      sag, vertex_deviation_deg, max_normal_error_deg);
  EXPECT_GT(checked, 1000u);
}

}  // namespace
}  // namespace drape::bake

// The body-map camera: the near and far planes enclose the offset surface a margin away (nothing
// clipped), the back map is seen from behind without mirroring, the fitted window spends the same
// texel budget on smaller texels, triangles sharing edges leave no crack in the coverage, and the
// view axis is the one whose slab holds the least air.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "body_map/map_error.h"
#include "body_map_fixtures.h"
#include "drape/bake/body_map_baker.h"

namespace drape::bake {
namespace {

using namespace body_map_fixtures;

TEST(BodyMapBaker, NothingIsClippedAndThePlanesEncloseTheOffsetSurface) {
  const Vec3d c{0.0, 0.0, 0.4};
  const double r = 0.3;
  const Mesh sphere = MakeSphere(c, r, 50, 50);
  BodyMapOptions o = FloatOptions(256);
  o.epsilon = 0.02f;  // a large offset makes clipping visible if the box were not enlarged
  const BodyMapPose pose = BakeOrDie(sphere, o);
  const std::vector<Vec3d> q = OffsetVertices(sphere, o.epsilon, nullptr);
  double z_min = 1e9, z_max = -1e9;
  for (const Vec3d& p : q) {
    z_min = std::min(z_min, p.z);
    z_max = std::max(z_max, p.z);
  }
  // The planes sit margin beyond the offset surface, rounded outward to float.
  EXPECT_GE(double(pose.front_z), z_max + o.margin);
  EXPECT_LE(double(pose.front_z), z_max + o.margin + 1e-6);
  const double back_z = double(pose.front_z) - double(pose.depth_range);
  EXPECT_LE(back_z, z_min - o.margin);
  EXPECT_GE(back_z, z_min - o.margin - 2e-6);
  float min_front = 1e9f, min_back = 1e9f, max_depth = 0.f;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      for (int view = 0; view < 2; ++view) {
        const BodyMapTexel texel = ReadBodyMapTexel(pose, view, i, j);
        if (!texel.valid) continue;
        (view == 0 ? min_front : min_back) =
            std::min(view == 0 ? min_front : min_back, texel.depth);
        max_depth = std::max(max_depth, texel.depth);
      }
    }
  }
  // The extreme points of the offset sphere are in the maps, a margin away from each plane.
  const double sag = SphereSag(sphere, q, c, r + o.epsilon);
  EXPECT_GE(min_front, o.margin - 1e-6);
  EXPECT_LE(min_front, o.margin + sag + 1e-5);
  EXPECT_GE(min_back, o.margin - 1e-6);
  EXPECT_LE(min_back, o.margin + sag + 1e-5);
  EXPECT_LT(max_depth, pose.depth_range);
  // One texel of background border all around the stored rectangle, and covered texels next to it.
  bool border_valid = false, inner_row_valid = false;
  for (uint32_t i = 0; i < pose.width; ++i) {
    border_valid |= ReadBodyMapTexel(pose, 0, i, 0).valid;
    border_valid |= ReadBodyMapTexel(pose, 0, i, pose.height - 1).valid;
    inner_row_valid |= ReadBodyMapTexel(pose, 0, i, 1).valid;
  }
  for (uint32_t j = 0; j < pose.height; ++j) {
    border_valid |= ReadBodyMapTexel(pose, 0, 0, j).valid;
    border_valid |= ReadBodyMapTexel(pose, 0, pose.width - 1, j).valid;
  }
  EXPECT_FALSE(border_valid);
  EXPECT_TRUE(inner_row_valid);
}

TEST(BodyMapBaker, BackMapIsNotMirrored) {
  // Two boxes, the small one off to +x, nearer the front and deeper than the big one.
  Mesh mesh;
  const Vec3d big_lo{-0.3, -0.4, -0.1}, big_hi{-0.05, 0.4, 0.1};
  const Vec3d small_lo{0.1, 0.2, 0.0}, small_hi{0.2, 0.3, 0.3};
  AddSplitBox(&mesh, big_lo, big_hi);
  AddSplitBox(&mesh, small_lo, small_hi);
  const BodyMapOptions o = FloatOptions(256);
  const BodyMapPose pose = BakeOrDie(mesh, o);
  const double t = pose.texel_size, eps = o.epsilon;
  const double back_z = double(pose.front_z) - double(pose.depth_range);
  auto texel_at = [&](double x, double y, uint32_t* i, uint32_t* j) {
    *i = static_cast<uint32_t>(std::floor((x - pose.origin_x) / t));
    *j = static_cast<uint32_t>(std::floor((y - pose.origin_y) / t));
  };
  uint32_t i = 0, j = 0;
  texel_at(0.15, 0.25, &i, &j);  // over the small box
  BodyMapTexel front = ReadBodyMapTexel(pose, 0, i, j), back = ReadBodyMapTexel(pose, 1, i, j);
  ASSERT_TRUE(front.valid && back.valid);
  EXPECT_NEAR(front.depth, double(pose.front_z) - (0.3 + eps), 2e-6);
  EXPECT_NEAR(back.depth, (0.0 - eps) - back_z, 2e-6);
  EXPECT_LT(back.normal.z, -0.999f);
  texel_at(-0.2, -0.3, &i, &j);  // over the big box
  front = ReadBodyMapTexel(pose, 0, i, j);
  back = ReadBodyMapTexel(pose, 1, i, j);
  ASSERT_TRUE(front.valid && back.valid);
  EXPECT_NEAR(front.depth, double(pose.front_z) - (0.1 + eps), 2e-6);
  EXPECT_NEAR(back.depth, (-0.1 - eps) - back_z, 2e-6);
  // A back map mirrored about the box centre (x -> 2 c_x - x, c_x = -0.05) would show the small
  // box at x = -0.25; un-mirrored, that texel shows the big box's back face.
  texel_at(-0.25, 0.25, &i, &j);
  back = ReadBodyMapTexel(pose, 1, i, j);
  ASSERT_TRUE(back.valid);
  EXPECT_NEAR(back.depth, (-0.1 - eps) - back_z, 2e-6);
  // Every texel is valid in both maps or in neither.
  for (uint32_t jj = 0; jj < pose.height; ++jj) {
    for (uint32_t ii = 0; ii < pose.width; ++ii) {
      ASSERT_EQ(ReadBodyMapTexel(pose, 0, ii, jj).valid, ReadBodyMapTexel(pose, 1, ii, jj).valid);
    }
  }
  // The gap between the boxes at y = 0.25 is background in both maps.
  texel_at(0.025, 0.25, &i, &j);
  EXPECT_FALSE(ReadBodyMapTexel(pose, 0, i, j).valid);
  EXPECT_FALSE(ReadBodyMapTexel(pose, 1, i, j).valid);
}

TEST(BodyMapBaker, FittedWindowGivesSmallerTexelsForTheSameBudget) {
  const Mesh capsule = MakeCapsule({0.0, 0.9, 0.0}, 0.15, 0.6, 16, 32);
  BodyMapOptions square = FloatOptions(256), fitted = FloatOptions(256);
  fitted.fitted_window = true;
  BodyMapPoseStats square_stats, fitted_stats;
  const BodyMapPose a = BakeOrDie(capsule, square, &square_stats);
  const BodyMapPose b = BakeOrDie(capsule, fitted, &fitted_stats);
  EXPECT_LT(b.texel_size, 0.7f * a.texel_size);  // box 0.33 x 1.53 m: sqrt(0.33/1.53) = 0.46
  EXPECT_GT(fitted_stats.coverage, 1.5f * square_stats.coverage);
  EXPECT_GT(fitted_stats.valid_texels, 3 * square_stats.valid_texels);
}

TEST(BodyMapBaker, SharedEdgesLeaveNoCracks) {
  // A flat, jittered 40 x 40 grid of quads (3200 triangles sharing edges, mixed orientations):
  // every texel centre inside the outer square is covered, none outside. A crack in the
  // rasterizer's edge rule would leave background texels inside.
  Mesh grid;
  constexpr int kCells = 40;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  const double cell = 0.02;
  for (int y = 0; y <= kCells; ++y) {
    for (int x = 0; x <= kCells; ++x) {
      const bool interior = x > 0 && y > 0 && x < kCells && y < kCells;
      const double px = (x + (interior ? jitter(rng) : 0.0)) * cell;
      const double py = (y + (interior ? jitter(rng) : 0.0)) * cell;
      grid.positions.push_back({static_cast<float>(px), static_cast<float>(py), 0.25f});
    }
  }
  for (int y = 0; y < kCells; ++y) {
    for (int x = 0; x < kCells; ++x) {
      const uint32_t a = uint32_t(y * (kCells + 1) + x), b = a + 1, c = a + kCells + 1, e = c + 1;
      if ((x + y) % 2 == 0) {
        grid.triangles.insert(grid.triangles.end(), {a, b, e, a, e, c});
      } else {
        grid.triangles.insert(grid.triangles.end(), {a, c, b, b, c, e});  // clockwise ones too
      }
    }
  }
  BodyMapOptions o = FloatOptions(997);  // an odd N puts texel centres at arbitrary offsets
  o.epsilon = 0.f;                       // keep the grid flat (the normals are all +z anyway)
  BodyMapPoseStats stats;
  const BodyMapPose pose = BakeOrDie(grid, o, &stats);
  const double t = pose.texel_size, side = kCells * cell;
  const double lo_x = double(grid.positions.front().x), hi_x = double(grid.positions.back().x);
  const double lo_y = double(grid.positions.front().y), hi_y = double(grid.positions.back().y);
  ASSERT_NEAR(hi_x - lo_x, side, 1e-6);
  size_t inside = 0;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      const Vec3d p = TexelCentre(pose, i, j);
      const double inset = std::min({p.x - lo_x, hi_x - p.x, p.y - lo_y, hi_y - p.y});
      if (std::fabs(inset) < 1e-4 * t) continue;
      const BodyMapTexel texel = ReadBodyMapTexel(pose, 0, i, j);
      ASSERT_EQ(texel.valid, inset > 0) << i << "," << j;
      inside += inset > 0 ? 1 : 0;
      if (texel.valid) {
        ASSERT_NEAR(texel.depth, double(pose.front_z) - 0.25, 1e-6);
      }
    }
  }
  EXPECT_GT(inside, size_t(0.9 * side * side / (t * t)));
  EXPECT_EQ(stats.silhouette_conflicts, 0u);
}

// A four-legged table, 0.8 m long along `length`, legs 0.3 m down along -`up` (the other axis
// is its width): a quadruped's air under the belly, in any orientation.
Mesh Table(int length, int up) {
  const int width = 3 - length - up;
  const auto box = [&](double l0, double l1, double u0, double u1, double w0, double w1) {
    double lo[3], hi[3];
    lo[length] = l0, hi[length] = l1, lo[up] = u0, hi[up] = u1, lo[width] = w0, hi[width] = w1;
    return std::pair<Vec3d, Vec3d>{{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
  };
  Mesh m;
  const auto add = [&](std::pair<Vec3d, Vec3d> b) { AddSplitBox(&m, b.first, b.second); };
  add(box(-0.4, 0.4, 0.0, 0.1, -0.15, 0.15));  // the top
  for (double l : {-0.38, 0.32})
    for (double w : {-0.13, 0.07}) add(box(l, l + 0.06, -0.3, 0.0, w, w + 0.06));
  return m;
}

TEST(BodyMapBaker, TheViewAxisIsTheOneWithTheLeastAirInItsSlab) {
  BodyMapOptions options;
  options.resolution = 256;
  const BodyMapViewAxis axes[3] = {BodyMapViewAxis::kX, BodyMapViewAxis::kY, BodyMapViewAxis::kZ};
  for (int length = 0; length < 3; ++length) {
    for (int up = 0; up < 3; ++up) {
      if (up == length) continue;
      SCOPED_TRACE("length along " + std::to_string(length) + ", up along " + std::to_string(up));
      const Mesh table = Table(length, up);
      ViewAxisChoice choice;
      ASSERT_TRUE(ChooseBodyMapViewAxis(table.positions, table.triangles, options, &choice).ok());
      // Seen along `up` the slab holds the table and nothing else; along its length, the air
      // between the legs; across it, the air between near and far legs.
      EXPECT_EQ(choice.axis, axes[up]);
      const double body = 0.8 * 0.1 * 0.3 + 4 * 0.06 * 0.3 * 0.06;  // m^3
      const double along_up = choice.inside_volume[static_cast<int>(axes[up])];
      EXPECT_GT(along_up, body);
      EXPECT_LT(along_up, 1.25 * body);  // the 5 mm offset skin, no air
      const double along_length = choice.inside_volume[static_cast<int>(axes[length])];
      EXPECT_GT(along_length, along_up + 0.5 * 0.3 * 0.06 * 0.64);  // the air under the top
      // The maps baked along the chosen axis see no body under the top between the legs.
      BodyMapOptions chosen = options;
      chosen.view_axis = choice.axis;
      BodyMapPose pose;
      ASSERT_TRUE(BakeBodyMapPose(table.positions, table.triangles, chosen, &pose).ok());
      EXPECT_EQ(pose.view_axis, choice.axis);
      BodyMapCollider maps;
      ASSERT_TRUE(maps.Build(pose).ok());
      double under[3] = {0.0, 0.0, 0.0}, in_top[3] = {0.0, 0.0, 0.0};
      under[up] = -0.15;
      in_top[up] = 0.05;
      EXPECT_FALSE(maps.IsInside({float(under[0]), float(under[1]), float(under[2])}));
      EXPECT_TRUE(maps.IsInside({float(in_top[0]), float(in_top[1]), float(in_top[2])}));
    }
  }
}

// maps.max_error beyond reach: every setting tried, cheapest first, and the least error kept.
TEST(BodyMapBaker, AnUnreachableErrorBudgetKeepsTheBestSettingTried) {
  const Mesh table = Table(2, 1);
  BodyMapOptions options;
  MapSettingChoice choice;
  ASSERT_TRUE(ChooseMapSetting(table.positions, table.triangles, options, 1e-6, &choice).ok());
  EXPECT_FALSE(choice.within_budget);
  ASSERT_EQ(choice.tried.size(), 8u);
  double least = 1e300;
  for (size_t k = 0; k < choice.tried.size(); ++k) {
    least = std::min(least, choice.tried[k].error.p99_mm);
    if (k > 0) {
      EXPECT_GE(choice.tried[k].resolution, choice.tried[k - 1].resolution) << k;
    }
  }
  EXPECT_EQ(choice.error.p99_mm, least);
  EXPECT_EQ(choice.tried.front().resolution, 256u);
  EXPECT_EQ(choice.tried.back().resolution, 2048u);
  // A generous budget: the first setting.
  ASSERT_TRUE(ChooseMapSetting(table.positions, table.triangles, options, 1e3, &choice).ok());
  EXPECT_TRUE(choice.within_budget);
  EXPECT_EQ(choice.tried.size(), 1u);
  EXPECT_EQ(choice.resolution, 256u);
}

}  // namespace
}  // namespace drape::bake

// Bad input to the body-map bake: no triangles, bad indices, non-finite vertices, options out of
// range, an empty or flat coverage and a layer count outside [1, 4] return an error naming the
// reason and leave the pose as it was.

#include <gtest/gtest.h>

#include <limits>
#include <span>
#include <string>
#include <vector>

#include "body_map_fixtures.h"
#include "body_map_gap_fixtures.h"
#include "drape/bake/body_map_baker.h"

namespace drape::bake {
namespace {

using namespace body_map_fixtures;

TEST(BodyMapBaker, DegenerateInputReturnsAnErrorAndLeavesThePoseUnchanged) {
  const Mesh sphere = MakeSphere({0.0, 0.0, 0.0}, 0.3, 8, 8);
  BodyMapPose pose;
  pose.clip = 7;
  pose.width = 42;
  auto expect_error = [&](std::span<const Float3> positions, std::span<const uint32_t> tris,
                          const BodyMapOptions& o, const char* fragment) {
    const Status status = BakeBodyMapPose(positions, tris, o, &pose);
    EXPECT_FALSE(status.ok()) << fragment;
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << status.message();
    EXPECT_NE(status.message().find(fragment), std::string::npos) << status.message();
    EXPECT_EQ(pose.width, 42u);
    EXPECT_EQ(pose.clip, 7);
  };
  const BodyMapOptions o;
  expect_error(sphere.positions, {}, o, "no triangles");
  const std::vector<uint32_t> two = {0, 1};
  expect_error(sphere.positions, two, o, "multiple of 3");
  const std::vector<uint32_t> out_of_range = {0, 1, 9999};
  expect_error(sphere.positions, out_of_range, o, "vertex 9999");
  Mesh nan_mesh = sphere;
  nan_mesh.positions[5].y = std::numeric_limits<float>::quiet_NaN();
  expect_error(nan_mesh.positions, nan_mesh.triangles, o, "vertex 5");
  nan_mesh.positions[5].y = std::numeric_limits<float>::infinity();
  expect_error(nan_mesh.positions, nan_mesh.triangles, o, "non-finite");
  BodyMapOptions bad = o;
  bad.resolution = 8;
  expect_error(sphere.positions, sphere.triangles, bad, "resolution");
  bad.resolution = 9000;
  expect_error(sphere.positions, sphere.triangles, bad, "resolution");
  bad = o;
  bad.epsilon = -0.001f;
  expect_error(sphere.positions, sphere.triangles, bad, "epsilon");
  bad.epsilon = std::numeric_limits<float>::quiet_NaN();
  expect_error(sphere.positions, sphere.triangles, bad, "epsilon");
  bad = o;
  bad.margin = -1.f;
  expect_error(sphere.positions, sphere.triangles, bad, "margin");
  bad = o;
  bad.normal_encoding = static_cast<NormalEncoding>(9);
  expect_error(sphere.positions, sphere.triangles, bad, "normal encoding");
  // All triangles degenerate (collinear points): nothing is covered.
  const std::vector<Float3> line = {{0, 0, 0}, {0.1f, 0.1f, 0.1f}, {0.2f, 0.2f, 0.2f}};
  const std::vector<uint32_t> line_tri = {0, 1, 2, 2, 1, 0};
  expect_error(line, line_tri, o, "covers no texel");
  // A flat mesh with no offset and no margin has no depth range.
  const std::vector<Float3> flat = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<uint32_t> flat_tri = {0, 1, 2};
  BodyMapOptions zero = o;
  zero.epsilon = 0.f;
  zero.margin = 0.f;
  expect_error(flat, flat_tri, zero, "depth_range");
  // ... but with a margin it bakes (a single triangle), both views valid on the same texels.
  zero.margin = 0.01f;
  zero.resolution = 64;
  BodyMapPoseStats stats;
  const Status ok = BakeBodyMapPose(flat, flat_tri, zero, &pose, &stats);
  ASSERT_TRUE(ok.ok()) << ok.message();
  EXPECT_NEAR(stats.coverage, 0.5 * (1.0 / 1.02) * (1.0 / 1.02), 0.02);
  EXPECT_EQ(pose.clip, 7);  // clip and time are the caller's
  EXPECT_EQ(BakeBodyMapPose(flat, flat_tri, zero, nullptr).code(), StatusCode::kInvalidArgument);
}

TEST(BodyMapBaker, BadLayerCountsAreRefused) {
  const Mesh scene = GapScene();
  BodyMapPose pose;
  pose.width = 42;
  for (const int layers : {0, 5, 255}) {
    BodyMapOptions o;
    o.resolution = 64;
    o.layers = static_cast<uint8_t>(layers);
    const Status status = BakeBodyMapPose(scene.positions, scene.triangles, o, &pose);
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << layers;
    EXPECT_NE(status.message().find("layers " + std::to_string(layers) + " is outside [1, 4]"),
              std::string::npos)
        << status.message();
    EXPECT_EQ(pose.width, 42u);
  }
}

}  // namespace
}  // namespace drape::bake

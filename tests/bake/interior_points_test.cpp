// The points inside the body the bones' hulls hold (regions/interior_points.h), on a box body.
#include "regions/interior_points.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "drape/bake/mesh_reference.h"
#include "drape/bake/regions.h"
#include "drape/runtime/math.h"
#include "hull_fixtures.h"

namespace drape {
namespace {

// A closed box 0.4 x 0.6 x 0.2 m (the hull fixture's surface, wound outward); the vertices with
// x < 0 weighted to joint 0, the others to joint 1.
MeshData TwoBoneBox() {
  const HullColliderData box = test::MakeBox({0.2f, 0.3f, 0.1f});
  MeshData mesh;
  mesh.positions = box.vertices;
  mesh.triangles = box.triangles;
  for (uint32_t v = 0; v < mesh.positions.size(); ++v) {
    mesh.influence_offsets.push_back(v);
    mesh.influence_joints.push_back(mesh.positions[v].x < 0.f ? 0 : 1);
    mesh.influence_weights.push_back(1.f);
  }
  mesh.influence_offsets.push_back(static_cast<uint32_t>(mesh.positions.size()));
  return mesh;
}

TEST(InteriorPoints, TheGridFillsTheBodyAndGoesToTheBoneOfTheNearestSurface) {
  const MeshData mesh = TwoBoneBox();
  const bake::MeshReference body(mesh.positions, mesh.triangles);
  const float delta = 0.005f;
  const std::vector<std::vector<Float3>> interior =
      bake::BodyInteriorPoints(mesh.positions, bake::TriangleBones(mesh, 2), 2, body, delta);
  ASSERT_EQ(interior.size(), 2u);
  // Cells of 0.6 / 32 m: about 21 x 32 x 11 centres, all but a delta-thin rind inside.
  size_t total = 0;
  for (size_t j = 0; j < 2; ++j) {
    for (const Float3& p : interior[j]) {
      const double q[3] = {p.x, p.y, p.z};
      EXPECT_TRUE(body.Inside(q));
      EXPECT_GT(body.Distance(q), delta);
      // Nearest to an x face (the only faces whose corners all carry one bone): that bone.
      const float to_x = 0.2f - std::fabs(p.x);
      const float to_other = std::min(0.3f - std::fabs(p.y), 0.1f - std::fabs(p.z));
      if (to_x + 1e-3f < to_other) {
        EXPECT_EQ(j, p.x < 0.f ? 0u : 1u) << p.x << " " << p.y << " " << p.z;
      }
    }
    total += interior[j].size();
  }
  EXPECT_GT(total, 6000u);
  EXPECT_FALSE(interior[0].empty());
  EXPECT_FALSE(interior[1].empty());
}

TEST(InteriorPoints, AnEmptyOrFlatBodyHasNone) {
  MeshData mesh;
  const bake::MeshReference empty(mesh.positions, mesh.triangles);
  EXPECT_TRUE(bake::BodyInteriorPoints(mesh.positions, {}, 0, empty, 0.005f).empty());
  // One triangle: no inside.
  mesh.positions = {{0.f, 0.f, 0.f}, {1.f, 0.f, 0.f}, {0.f, 1.f, 0.f}};
  mesh.triangles = {0, 1, 2};
  mesh.influence_offsets = {0, 1, 2, 3};
  mesh.influence_joints = {0, 0, 0};
  mesh.influence_weights = {1.f, 1.f, 1.f};
  const bake::MeshReference flat(mesh.positions, mesh.triangles);
  const auto interior =
      bake::BodyInteriorPoints(mesh.positions, bake::TriangleBones(mesh, 1), 1, flat, 0.005f);
  ASSERT_EQ(interior.size(), 1u);
  EXPECT_TRUE(interior[0].empty());
}

}  // namespace
}  // namespace drape

// The procedural garment generators (drape/runtime/garments.h): each builds into a valid cloth
// with the expected counts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "drape/runtime/cloth.h"
#include "drape/runtime/garments.h"
#include "drape/runtime/math.h"

namespace drape {
namespace {

// Each generator gives a mesh that builds into a cloth with the expected counts: a grid of
// C x R cells has C(R+1) + R(C+1) edges plus C R diagonals; a closed ring of S segments and R
// cells has S(R+1) + 2 S R; every interior edge gives at most one bend spring.
TEST(Garments, GeneratorsBuildValidCloths) {
  struct Expect {
    const char* name;
    GarmentMesh mesh;
    uint32_t particles, stretch, held, boundary_edges;
  };
  std::vector<Expect> cases;
  {
    SheetShape s;
    s.columns = 7;
    s.rows = 5;
    Expect e{"sheet", {}, 8 * 6, 7 * 6 + 5 * 8 + 7 * 5, 8, 2 * 7 + 2 * 5};
    ASSERT_TRUE(MakeSheet(s, &e.mesh).ok());
    cases.push_back(e);
  }
  {
    SkirtShape s;
    s.segments = 12;
    s.rings = 4;
    Expect e{"skirt", {}, 12 * 5, 12 * 5 + 2 * 12 * 4, 12, 2 * 12};
    ASSERT_TRUE(MakeSkirt(s, &e.mesh).ok());
    cases.push_back(e);
  }
  {
    CapeShape s;
    s.columns = 6;
    s.rows = 9;
    Expect e{"cape", {}, 7 * 10, 6 * 10 + 9 * 7 + 6 * 9, 7, 2 * 6 + 2 * 9};
    ASSERT_TRUE(MakeCape(s, &e.mesh).ok());
    cases.push_back(e);
  }
  {
    SleeveShape s;
    s.segments = 10;
    s.rings = 6;
    Expect e{"sleeve", {}, 10 * 7, 10 * 7 + 2 * 10 * 6, 10, 2 * 10};
    ASSERT_TRUE(MakeSleeve(s, &e.mesh).ok());
    cases.push_back(e);
  }
  for (const Expect& e : cases) {
    SCOPED_TRACE(e.name);
    EXPECT_EQ(e.mesh.positions.size(), e.particles);
    EXPECT_EQ(e.mesh.held.size(), e.held);
    ClothDescription d;
    d.positions = e.mesh.positions;
    d.triangles = e.mesh.triangles;
    d.pinned = e.mesh.held;
    Cloth cloth;
    const Status s = BuildCloth(d, &cloth);
    ASSERT_TRUE(s.ok()) << s.message();
    const ClothBuildReport& r = cloth.build_report();
    EXPECT_EQ(r.dropped_triangles + r.zero_area_triangles + r.non_manifold_edges, 0u);
    // Springs between two held particles are dropped (both inverse masses are 0).
    uint32_t held_edges = 0;
    {
      ClothDescription free = d;
      free.pinned.clear();
      Cloth all;
      ASSERT_TRUE(BuildCloth(free, &all).ok());
      EXPECT_EQ(all.spring_count(SpringKind::kStretch), e.stretch);
      const uint32_t interior = e.stretch - e.boundary_edges;
      EXPECT_GT(all.spring_count(SpringKind::kBend), interior / 2);
      EXPECT_LE(all.spring_count(SpringKind::kBend), interior);
      held_edges =
          all.spring_count(SpringKind::kStretch) - cloth.spring_count(SpringKind::kStretch);
    }
    EXPECT_GE(held_edges, e.held - 1);
    EXPECT_NEAR(cloth.total_mass() + 0.f, cloth.total_mass(), 0.f);
    EXPECT_GT(cloth.total_mass(), 0.f);
    for (const uint32_t t : cloth.triangles()) EXPECT_LT(t, e.particles);
  }
  GarmentMesh mesh;
  SkirtShape bad_skirt;
  bad_skirt.segments = 2;
  EXPECT_EQ(MakeSkirt(bad_skirt, &mesh).code(), StatusCode::kInvalidArgument);
  SheetShape bad_sheet;
  bad_sheet.axis_v = bad_sheet.axis_u;
  EXPECT_EQ(MakeSheet(bad_sheet, &mesh).code(), StatusCode::kInvalidArgument);
  SleeveShape bad_sleeve;
  bad_sleeve.radius = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(MakeSleeve(bad_sleeve, &mesh).code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(mesh.positions.empty());
}

// Sleeve geometry: every particle is at `radius` from the axis and the held ring at the start.
TEST(Garments, SleeveIsATube) {
  SleeveShape s;
  s.start = {0.2f, 1.4f, 0.f};
  s.axis = {0.f, -0.6f, 0.8f};
  GarmentMesh mesh;
  ASSERT_TRUE(MakeSleeve(s, &mesh).ok());
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    const Float3 r = mesh.positions[i] - s.start;
    const float along = Dot(r, s.axis);
    EXPECT_NEAR(Length(r - s.axis * along), s.radius, 1e-5f);
    EXPECT_GE(along, -1e-5f);
    EXPECT_LE(along, s.length + 1e-5f);
  }
  for (const uint32_t p : mesh.held)
    EXPECT_NEAR(Dot(mesh.positions[p] - s.start, s.axis), 0.f, 1e-6f);
}

}  // namespace
}  // namespace drape

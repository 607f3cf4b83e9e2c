// BuildCloth: topology, masses, springs and their colouring into independent sets, and the
// validation of its input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "cloth_fixtures.h"
#include "drape/runtime/cloth.h"
#include "drape/runtime/garments.h"
#include "drape/runtime/math.h"

namespace drape {
namespace {

using test::SheetDescription;

// Two triangles sharing an edge: 5 stretch springs, 1 bend spring between the opposite corners,
// masses a third of each triangle's area times density.
TEST(BuildCloth, QuadTopologyAndMasses) {
  ClothDescription d;
  d.positions = {{0.f, 0.f, 0.f}, {1.f, 0.f, 0.f}, {1.f, 1.f, 0.f}, {0.f, 1.f, 0.f}};
  d.triangles = {0, 1, 2, 0, 2, 3};
  d.density = 0.3f;
  Cloth cloth;
  ASSERT_TRUE(BuildCloth(d, &cloth).ok());
  EXPECT_EQ(cloth.spring_count(SpringKind::kStretch), 5u);
  EXPECT_EQ(cloth.spring_count(SpringKind::kBend), 1u);
  EXPECT_NEAR(cloth.masses()[0], 0.3f * (0.5f / 3.f + 0.5f / 3.f), 1e-7f);
  EXPECT_NEAR(cloth.masses()[1], 0.3f * 0.5f / 3.f, 1e-7f);
  EXPECT_NEAR(cloth.total_mass(), 0.3f, 1e-6f);
  for (const ClothSpring& s : cloth.springs()) {
    if (s.a == 1 && s.b == 3) {
      EXPECT_NEAR(s.rest_length, std::sqrt(2.f), 1e-6f);
    }
    EXPECT_NEAR(s.weight_a + s.weight_b, 1.f, 1e-6f);
  }
  // total_mass rescales; pinning zeroes the inverse mass and the weights follow.
  d.total_mass = 2.f;
  d.pinned = {1};
  ASSERT_TRUE(BuildCloth(d, &cloth).ok());
  EXPECT_NEAR(cloth.masses()[0] + cloth.masses()[1] + cloth.masses()[2] + cloth.masses()[3], 2.f,
              1e-5f);
  EXPECT_EQ(cloth.inverse_masses()[1], 0.f);
  for (const ClothSpring& s : cloth.springs()) {
    if (s.a == 1) {
      EXPECT_EQ(s.weight_a, 0.f);
    }
    if (s.b == 1) {
      EXPECT_EQ(s.weight_b, 0.f);
    }
  }
  ASSERT_EQ(cloth.kinematic_particles().size(), 1u);
  EXPECT_EQ(cloth.kinematic_particles()[0], 1u);
}

TEST(BuildCloth, RejectsBadInput) {
  const ClothDescription good = SheetDescription(3, 1.f, {0.f, 0.f, 0.f});
  Cloth cloth;
  ASSERT_TRUE(BuildCloth(good, &cloth).ok());
  const auto expect_rejected = [&](const ClothDescription& d, const char* needle) {
    Cloth c;
    const Status s = BuildCloth(d, &c);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << needle;
    EXPECT_NE(s.message().find(needle), std::string::npos) << s.message();
    EXPECT_TRUE(c.empty());
  };
  ClothDescription d = good;
  d.triangles[7] = 16;  // 16 particles: index out of range
  expect_rejected(d, "triangles[2] corner 1 = 16");
  d = good;
  d.triangles.pop_back();
  expect_rejected(d, "not a multiple of 3");
  d = good;
  d.positions[5].x = std::numeric_limits<float>::quiet_NaN();
  expect_rejected(d, "positions[5]");
  d = good;
  d.masses.assign(d.positions.size(), 0.01f);
  d.masses[3] = -1.f;
  expect_rejected(d, "masses[3]");
  d = good;
  d.masses.assign(3, 0.01f);
  expect_rejected(d, "masses has 3 entries");
  d = good;
  d.density = -1.f;
  expect_rejected(d, "density");
  d = good;
  d.pinned = {99};
  expect_rejected(d, "pinned[0] = 99");
  d = good;
  d.attachments = {{2, 0, {}}, {2, 1, {}}};
  expect_rejected(d, "more than one attachment");
  d = good;
  d.attachments = {{2, -1, {}}};
  expect_rejected(d, "joint = -1");
  d = good;
  d.stretch.correction = 1.5f;
  expect_rejected(d, "correction");
  d = good;
  d.positions.push_back({5.f, 5.f, 5.f});  // in no triangle: no mass
  expect_rejected(d, "particle 16 gets no mass");
  d.pinned = {16};  // pinned, it needs none
  EXPECT_TRUE(BuildCloth(d, &cloth).ok());
  d = ClothDescription{};
  expect_rejected(d, "no particles");
}

// Degenerate triangles do not stop the build: repeated indices are dropped, zero-area ones keep
// their (non-zero) edges but carry no mass, zero-length edges give no spring.
TEST(BuildCloth, DegenerateTrianglesAreHandled) {
  ClothDescription d;
  d.positions = {{0.f, 0.f, 0.f},
                 {1.f, 0.f, 0.f},
                 {0.f, 1.f, 0.f},
                 {2.f, 0.f, 0.f},   // collinear with 0 and 1
                 {0.f, 0.f, 0.f}};  // coincides with 0
  d.triangles = {0, 1, 2,           // good
                 1, 1, 2,           // repeated index: dropped
                 0, 1, 3,           // zero area (collinear)
                 0, 4, 1,           // zero area, zero-length edge 0-4
                 4, 1, 2};          // 4 gets its mass here
  d.pinned = {3};                   // 3 has no area: it must be pinned to be accepted
  Cloth cloth;
  const Status s = BuildCloth(d, &cloth);
  ASSERT_TRUE(s.ok()) << s.message();
  const ClothBuildReport& r = cloth.build_report();
  EXPECT_EQ(r.dropped_triangles, 1u);
  EXPECT_EQ(r.zero_area_triangles, 2u);
  EXPECT_GE(r.dropped_springs, 1u);  // 0-4
  EXPECT_EQ(cloth.triangles().size(), 12u);
  for (const ClothSpring& spring : cloth.springs()) {
    EXPECT_GE(spring.rest_length, 1e-7f);
    EXPECT_FALSE(spring.a == 0 && spring.b == 4);
  }
  EXPECT_EQ(cloth.masses()[3], 0.f);
  EXPECT_NEAR(cloth.masses()[4], 0.15f * 0.5f / 3.f, 1e-7f);  // from 4-1-2 only
}

// Every colour is a set of springs with pairwise distinct particles, one kind each, and together
// the colours cover every spring once: on a skirt (valence 6) and on a fan of 300 triangles
// around one centre (valence 300: at least 300 stretch colours).
void ExpectIndependentColours(const Cloth& cloth) {
  std::vector<int> seen(cloth.particle_count(), -1);
  uint32_t covered = 0;
  for (size_t c = 0; c < cloth.colours().size(); ++c) {
    const SpringColour& colour = cloth.colours()[c];
    EXPECT_EQ(colour.begin, covered);
    covered = colour.end;
    for (uint32_t k = colour.begin; k < colour.end; ++k) {
      const ClothSpring& s = cloth.springs()[k];
      ASSERT_NE(seen[s.a], static_cast<int>(c));
      ASSERT_NE(seen[s.b], static_cast<int>(c));
      seen[s.a] = seen[s.b] = static_cast<int>(c);
    }
  }
  EXPECT_EQ(covered, cloth.springs().size());
  EXPECT_EQ(cloth.colours().size(),
            cloth.build_report().stretch_colours + cloth.build_report().bend_colours);
}

TEST(BuildCloth, ColoursAreIndependentSets) {
  SkirtShape shape;
  GarmentMesh mesh;
  ASSERT_TRUE(MakeSkirt(shape, &mesh).ok());
  ClothDescription d;
  d.positions = mesh.positions;
  d.triangles = mesh.triangles;
  Cloth cloth;
  ASSERT_TRUE(BuildCloth(d, &cloth).ok());
  ExpectIndependentColours(cloth);
  EXPECT_LE(cloth.build_report().stretch_colours, 11u);  // first fit: <= 2 * valence - 1

  ClothDescription fan;
  const uint32_t rim = 300;
  fan.positions.push_back({0.f, 0.f, 0.f});
  for (uint32_t i = 0; i < rim; ++i) {
    const float angle = 2.f * std::numbers::pi_v<float> * static_cast<float>(i) / rim;
    fan.positions.push_back({std::cos(angle), 0.f, std::sin(angle)});
    fan.triangles.insert(fan.triangles.end(), {0, 1 + i, 1 + (i + 1) % rim});
  }
  ASSERT_TRUE(BuildCloth(fan, &cloth).ok());
  ExpectIndependentColours(cloth);
  EXPECT_GE(cloth.build_report().stretch_colours, rim);
  EXPECT_EQ(cloth.spring_count(SpringKind::kStretch), 2 * rim);
  EXPECT_EQ(cloth.spring_count(SpringKind::kBend), rim);
}

}  // namespace
}  // namespace drape

// Runtime-only tests of drape::HullColliderSet (no bake headers: builds with
// -DDRAPE_BUILD_BAKE=OFF). The hull data is made by hand (tests/support/hull_fixtures.h): a box
// and a tessellated ellipsoid, planes with offsets rounded outward in the runtime's float
// arithmetic. Kirkpatrick-mode and map-table builder tests live in tests/bake (they need the
// builders).

#include "drape/runtime/hull_collider_set.h"
#include "workers.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "drape/runtime/math.h"
#include "hull/hull_collider_set_access.h"
#include "hull_fixtures.h"

namespace drape {
namespace {

// Hand-made hulls and helpers shared with the other hull tests (tests/support/hull_fixtures.h).
using test::MakeBox;
using test::MakeEllipsoid;
using test::MaxPlane;
using test::RandomIn;
using test::RotatedAxes;
using test::RotationAbout;

HullColliderSet BuildSet(const std::vector<HullColliderData>& hulls,
                         const std::vector<JointSphereData>& spheres, uint32_t joints,
                         const HullColliderOptions& options = {}) {
  HullColliderSet set;
  const Status s = set.Build(hulls, spheres, joints, options);
  EXPECT_TRUE(s.ok()) << s.message();
  return set;
}

// ---- Tests ----------------------------------------------------------------------------------

TEST(HullColliderTest, HandMadeHullsAreConvexAndContainTheirVertices) {
  Float3 axes[3];
  RotatedAxes(33.0, {1, 2, 3}, axes);
  for (const HullColliderData& h :
       {MakeBox({0.1f, 0.2f, 0.05f}),
        MakeEllipsoid({0.05f, 0.12f, 0.07f}, 1, {0.1f, 0.2f, 0.3f}, axes)}) {
    for (const Float3& v : h.vertices) EXPECT_LE(MaxPlane(h, v), 0.f);
    // Every plane has a vertex within float rounding of it (a real face, not a loose plane).
    for (const Plane& p : h.planes) {
      float best = -1e30f;
      for (const Float3& v : h.vertices) best = std::max(best, PlaneSignedDistance(p, v));
      EXPECT_GT(best, -1e-6f);
    }
  }
  EXPECT_EQ(MakeBox({0.1f, 0.2f, 0.05f}).planes.size(), 6u);
  EXPECT_EQ(MakeEllipsoid({0.05f, 0.12f, 0.07f}, 1, {}, axes).planes.size(), 80u);
}

TEST(HullColliderTest, ValidationRejectsBadData) {
  const HullColliderData good = MakeBox({0.1f, 0.1f, 0.1f});
  HullColliderSet set;
  ASSERT_TRUE(set.Build(std::vector<HullColliderData>{good}, {}, 1).ok());
  auto expect_rejected = [&](const HullColliderData& h, const char* what) {
    HullColliderSet s;
    const Status status = s.Build(std::vector<HullColliderData>{h}, {}, 1);
    EXPECT_FALSE(status.ok()) << what;
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << what;
    EXPECT_TRUE(s.empty()) << what;
  };
  HullColliderData h = good;
  h.triangles[4] = 8;
  expect_rejected(h, "triangle index out of range");
  h = good;
  h.triangle_planes[3] = 6;
  expect_rejected(h, "triangle plane out of range");
  h = good;
  h.joint = 1;
  expect_rejected(h, "joint out of range");
  h = good;
  h.planes[0].normal = {0.f, 0.f, 2.f};
  expect_rejected(h, "non-unit normal");
  h = good;
  h.planes[0].offset = std::nanf("");
  expect_rejected(h, "NaN offset");
  h = good;
  h.planes.clear();
  expect_rejected(h, "no planes");
  h = good;
  h.obb.axes[1] = {1.f, 0.f, 0.f};
  expect_rejected(h, "OBB axes not orthogonal");
  // Map table: offsets and indices.
  h = good;
  h.map.rows = 1;
  h.map.cols = 2;
  h.map.axis = {0, 0, 1};
  h.map.reference = {1, 0, 0};
  h.map.cell_offsets = {0, 1, 2};
  h.map.cell_triangles = {0, 12};
  expect_rejected(h, "map triangle out of range");
  h.map.cell_triangles = {0, 1};
  h.map.cell_offsets = {0, 2, 1};
  expect_rejected(h, "map offsets decreasing / wrong end");
  h.map.cell_offsets = {0, 1, 2};
  {
    HullColliderSet s;
    EXPECT_TRUE(s.Build(std::vector<HullColliderData>{h}, {}, 1).ok());
  }
  // Kirkpatrick hierarchy: a child index not below its parent, a vertex index out of range.
  h = good;
  h.projection_axis = {0, 0, 1};
  h.projection_u = {1, 0, 0};
  h.projection_v = {0, 1, 0};
  for (KirkpatrickHierarchy* k : {&h.upper, &h.lower}) {
    // The box's vertices projected along z (origin = OBB centre 0): (+-0.1, +-0.1).
    k->vertices_uv = {-0.1f, -0.1f, 0.1f, -0.1f, -0.1f, 0.1f, 0.1f, 0.1f};
    k->node_triangles = {0, 1, 2, 1, 3, 2, 0, 1, 2};
    k->child_offsets = {0, 0, 0, 2};
    k->children = {0, 1};
    k->leaf_planes = {0, 1, -1};
    k->root_begin = 2;
    k->root_end = 3;
  }
  {
    HullColliderSet s;
    EXPECT_TRUE(s.Build(std::vector<HullColliderData>{h}, {}, 1).ok());
  }
  HullColliderData bad = h;
  bad.upper.children = {0, 2};
  expect_rejected(bad, "child not below its parent");
  bad = h;
  bad.lower.node_triangles[4] = 4;
  expect_rejected(bad, "hierarchy vertex index out of range");
  bad = h;
  bad.upper.leaf_planes[0] = 6;
  expect_rejected(bad, "leaf plane out of range");
  bad = h;
  bad.upper.node_triangles = {0, 2, 1, 1, 3, 2, 0, 1, 2};
  expect_rejected(bad, "clockwise node");
  bad = h;
  bad.lower = KirkpatrickHierarchy{};
  expect_rejected(bad, "only one hierarchy");
  bad = h;
  bad.obb.center = {0.01f, 0.f, 0.f};  // the projection changed after the bake
  expect_rejected(bad, "stale hierarchy");
  // Options that need missing data.
  {
    HullColliderSet s;
    HullColliderOptions o;
    o.inside_test = InsideTest::kKirkpatrick;
    EXPECT_FALSE(s.Build(std::vector<HullColliderData>{good}, {}, 1, o).ok());
    o = HullColliderOptions{};
    o.response = HullResponse::kMapTableRay;
    EXPECT_FALSE(s.Build(std::vector<HullColliderData>{good}, {}, 1, o).ok());
    o = HullColliderOptions{};
    o.gauss_seidel_passes = 0;
    EXPECT_FALSE(s.Build(std::vector<HullColliderData>{good}, {}, 1, o).ok());
  }
  // Spheres.
  {
    HullColliderSet s;
    EXPECT_FALSE(s.Build({}, std::vector<JointSphereData>{{0, -1, {0, 0, 0}, 0.f}}, 1).ok());
    EXPECT_FALSE(s.Build({}, std::vector<JointSphereData>{{3, -1, {0, 0, 0}, 0.1f}}, 1).ok());
    EXPECT_TRUE(s.Build({}, std::vector<JointSphereData>{{0, -1, {0, 0, 0}, 0.1f}}, 1).ok());
  }
  // Poses.
  std::vector<Mat34> one(1);
  EXPECT_FALSE(set.SetPose({}, one).ok());
  one[0].m[5] = std::nanf("");
  EXPECT_FALSE(set.SetPose(one, one).ok());
  EXPECT_FALSE(set.SelectSubstep(0.6f, 0.5f).ok());
}

TEST(HullColliderTest, ObbRejectionIsConservative) {
  Float3 axes[3];
  RotatedAxes(40.0, {0.3f, -1.f, 0.5f}, axes);
  const HullColliderData h = MakeEllipsoid({0.06f, 0.15f, 0.04f}, 2, {0.02f, -0.1f, 0.3f}, axes);
  HullColliderSet set = BuildSet({h}, {}, 1);
  std::mt19937 rng(7);
  uint32_t inside = 0, rejected = 0;
  for (int i = 0; i < 200000; ++i) {
    const Float3 p = RandomIn(rng, {-0.2f, -0.35f, 0.1f}, {0.25f, 0.15f, 0.5f});
    const bool in = HullColliderSetAccess::InsideLocal(set, 0, p, InsideTest::kPlanes);
    const bool may = HullColliderSetAccess::ObbMayContainLocal(set, 0, p);
    if (in) {
      ++inside;
      EXPECT_TRUE(may);
    }
    if (!may) ++rejected;
  }
  EXPECT_GT(inside, 1000u);
  EXPECT_GT(rejected, 100000u);
  for (const Float3& v : h.vertices)
    EXPECT_TRUE(HullColliderSetAccess::ObbMayContainLocal(set, 0, v));
}

TEST(HullColliderTest, PushOutIsOnTheSurfaceAndMinimalForABox) {
  const Float3 he{0.1f, 0.2f, 0.05f};
  const HullColliderData box = MakeBox(he);
  HullColliderSet set = BuildSet({box}, {}, 1);
  std::mt19937 rng(1);
  for (int i = 0; i < 20000; ++i) {
    const Float3 p = RandomIn(rng, -he * 0.999f, he * 0.999f);
    const ContactQuery c = HullColliderSetAccess::QueryHullLocal(set, 0, p, p);
    ASSERT_TRUE(c.contact);
    EXPECT_TRUE(c.inside_end);
    EXPECT_TRUE(c.flags & kCollisionStartedInside);
    // On or outside the hull in the runtime's arithmetic.
    EXPECT_GE(HullColliderSetAccess::MaxPlaneDistanceLocal(set, 0, c.point), 0.f);
    // Minimal: the distance to the box boundary.
    const double exact = std::min({he.x - std::fabs(double(p.x)), he.y - std::fabs(double(p.y)),
                                   he.z - std::fabs(double(p.z))});
    const Float3 d = c.point - p;
    EXPECT_NEAR(Length(d), exact, 1e-6) << i;
    EXPECT_NEAR(c.depth, exact, 1e-6);
    // Along the normal.
    EXPECT_NEAR(Dot(d, c.normal), Length(d), 1e-6);
  }
}

// Grazing: segments parallel to a face, on it, a hair outside and a hair inside, and along an
// edge and through a vertex. On the surface counts as inside (both inside tests); a hair outside
// is free; nothing is non-finite and every response ends on or outside the box.
TEST(HullColliderTest, GrazingSegmentsAlongFacesEdgesAndVertices) {
  const Float3 he{0.1f, 0.2f, 0.05f};
  const HullColliderData box = MakeBox(he);
  HullColliderSet set = BuildSet({box}, {}, 1);
  const float top = he.z;
  const float out = top + 1e-6f,
              in = top - 1e-6f;  // a micrometre: beyond the planes' outward rounding
  struct Case {
    Float3 a, b;
    bool contact;
  };
  const Case cases[] = {
      {{-0.05f, 0.f, out}, {0.05f, 0.f, out}, false},  // a hair above the +z face
      {{-0.05f, 0.f, top}, {0.05f, 0.f, top}, true},   // on the face
      {{-0.05f, 0.f, in}, {0.05f, 0.f, in}, true},     // a hair below it
      {{-0.3f, 0.f, top}, {0.3f, 0.f, top}, true},     // along the face, through two edges
      {{-0.3f, he.y, top}, {0.3f, he.y, top}, true},   // along an edge
      {{-0.3f, -0.3f, top}, {he.x, he.y, top}, true},  // ending on a vertex
      {{-0.3f, he.y, out}, {0.3f, he.y, out}, false},  // a hair above an edge
  };
  for (size_t k = 0; k < std::size(cases); ++k) {
    const Case& c = cases[k];
    const ContactQuery q = HullColliderSetAccess::QueryHullLocal(set, 0, c.a, c.b);
    EXPECT_EQ(q.contact, c.contact) << "case " << k;
    EXPECT_TRUE(IsFinite(q.point) && IsFinite(q.normal)) << "case " << k;
    std::vector<Float3> previous = {c.a}, positions = {c.b}, velocities = {c.b - c.a};
    std::vector<uint8_t> flags(1);
    ASSERT_TRUE(set.CollideBatch(previous, positions, velocities, flags, ResponseParams{}).ok());
    EXPECT_EQ((flags[0] & kCollisionContact) != 0, c.contact) << "case " << k;
    EXPECT_TRUE(IsFinite(positions[0]) && IsFinite(velocities[0])) << "case " << k;
    EXPECT_GT(HullColliderSetAccess::MaxPlaneDistanceLocal(set, 0, positions[0]), 0.f)
        << "case " << k;
  }
}

TEST(HullColliderTest, PushOutOfARotatedEllipsoidIsOnTheFaceOfTheMaxPlane) {
  Float3 axes[3];
  RotatedAxes(71.0, {1.f, 0.2f, -0.4f}, axes);
  const HullColliderData h = MakeEllipsoid({0.08f, 0.05f, 0.2f}, 2, {0.3f, 1.1f, -0.2f}, axes);
  HullColliderSet set = BuildSet({h}, {}, 1);
  std::mt19937 rng(3);
  int tested = 0;
  for (int i = 0; i < 1000000 && tested < 10000; ++i) {
    const Float3 p = RandomIn(rng, {0.1f, 0.9f, -0.45f}, {0.5f, 1.3f, 0.05f});
    uint32_t plane;
    const float m = HullColliderSetAccess::MaxPlaneDistanceLocal(set, 0, p, &plane);
    if (m > 0.f) continue;
    ++tested;
    const ContactQuery c = HullColliderSetAccess::QueryHullLocal(set, 0, p, p);
    ASSERT_TRUE(c.contact);
    EXPECT_GE(HullColliderSetAccess::MaxPlaneDistanceLocal(set, 0, c.point), 0.f);
    // The projection lands on the face: every other plane still holds (up to rounding) and the
    // displacement equals the max-plane depth (the exact distance to the polytope's boundary).
    EXPECT_LE(HullColliderSetAccess::MaxPlaneDistanceLocal(set, 0, c.point), 2e-6f);
    EXPECT_NEAR(Length(c.point - p), -m, 2e-6f);
    EXPECT_NEAR(c.depth, -m, 1e-7f);
    EXPECT_EQ(c.normal.x, h.planes[plane].normal.x);
  }
  EXPECT_EQ(tested, 10000);
}

TEST(HullColliderTest, FastParticleCrossingAThinBoxIsCaught) {
  const HullColliderData thin = MakeBox({0.2f, 0.2f, 0.001f});
  for (EntryResponse entry : {EntryResponse::kProjectEnd, EntryResponse::kEntryPoint}) {
    HullColliderOptions options;
    options.entry_response = entry;
    HullColliderSet set = BuildSet({thin}, {}, 1, options);
    std::vector<Float3> previous = {
        {0.01f, 0.02f, 0.1f}, {-0.05f, 0.0f, -0.08f}, {0.3f, 0.f, 0.1f}};
    std::vector<Float3> positions = {
        {0.03f, 0.02f, -0.1f}, {-0.05f, 0.01f, 0.07f}, {0.3f, 0.f, -0.1f}};
    std::vector<Float3> velocities = {{0.2f, 0.f, -2.f}, {0.f, 0.1f, 1.5f}, {0.f, 0.f, -2.f}};
    std::vector<uint8_t> flags(3);
    ResponseParams params;
    params.friction = 0.f;
    params.separation = 1e-4f;
    params.friction_model = FrictionModel::kPaperA;  // frictionless: the tangential part kept
    uint32_t contacts = 0;
    ASSERT_TRUE(
        set.CollideBatch(previous, positions, velocities, flags, params, 0.f, 1.f, &contacts).ok());
    EXPECT_EQ(contacts, 2u);
    // Particle 0 came from above: it stays above the top face (z = 0.001), tangential motion kept
    // (kProjectEnd) or stopped at the entry point (kEntryPoint).
    EXPECT_NEAR(positions[0].z, 0.001f + 1e-4f, 2e-6f);
    EXPECT_NEAR(positions[0].x,
                entry == EntryResponse::kProjectEnd ? 0.03f : 0.01f + 0.02f * (0.099f / 0.2f),
                1e-5f);
    EXPECT_FLOAT_EQ(velocities[0].z, 0.f);  // restitution 0
    EXPECT_FLOAT_EQ(velocities[0].x, 0.2f);
    // Particle 1 came from below.
    EXPECT_NEAR(positions[1].z, -0.001f - 1e-4f, 2e-6f);
    // Particle 2 missed the box (x = 0.3 > 0.2).
    EXPECT_EQ(flags[2], kCollisionNone);
    EXPECT_FLOAT_EQ(positions[2].z, -0.1f);
    // The query reports the entry parameter.
    const ContactQuery q = set.Query({0.01f, 0.02f, 0.1f}, {0.03f, 0.02f, -0.1f});
    EXPECT_TRUE(q.contact);
    EXPECT_FALSE(q.inside_end);
    EXPECT_NEAR(q.t, 0.099f / 0.2f, 1e-5f);
    EXPECT_NEAR(q.normal.z, 1.f, 1e-6f);
  }
  // Without the continuous test the particle tunnels (paper B's endpoint test).
  HullColliderOptions discrete;
  discrete.continuous = false;
  HullColliderSet set = BuildSet({thin}, {}, 1, discrete);
  EXPECT_FALSE(set.Query({0.01f, 0.02f, 0.1f}, {0.03f, 0.02f, -0.1f}).contact);
}

TEST(HullColliderTest, BoneTurning90DegreesInOneStepLeavesNoParticleInside) {
  // A forearm-like box on joint 0 whose joint sits at the origin; the bone turns 90 degrees about
  // z within one step. Particles at rest in the swept region must all end outside the end pose.
  HullColliderData arm = MakeBox({0.15f, 0.04f, 0.04f}, {0.2f, 0.f, 0.f});
  HullColliderSet set = BuildSet({arm}, {}, 1);
  const std::vector<Mat34> start = {Mat34{}};
  const std::vector<Mat34> end = {RotationAbout(90.0, {0, 0, 1}, {0, 0, 0})};
  ASSERT_TRUE(set.SetPose(start, end).ok());
  // Screw interpolation pivots about the joint: the mid-step transform is the 45 degree rotation.
  const Mat34 mid = set.HullWorldTransform(0, 0.5f);
  const Mat34 expect_mid = RotationAbout(45.0, {0, 0, 1}, {0, 0, 0});
  for (int i = 0; i < 12; ++i) EXPECT_NEAR(mid.m[i], expect_mid.m[i], 1e-5f) << i;
  std::mt19937 rng(11);
  std::vector<Float3> previous, positions, velocities;
  for (int i = 0; i < 20000; ++i) {
    const Float3 p = RandomIn(rng, {-0.1f, -0.1f, -0.06f}, {0.4f, 0.4f, 0.06f});
    previous.push_back(p);
    positions.push_back(p);
    velocities.push_back({0.f, 0.f, 0.f});
  }
  std::vector<uint8_t> flags(previous.size());
  ResponseParams params;
  params.separation = 1e-5f;
  uint32_t contacts = 0;
  ASSERT_TRUE(
      set.CollideBatch(previous, positions, velocities, flags, params, 0.f, 1.f, &contacts).ok());
  EXPECT_GT(contacts, 1000u);
  const Mat34 to_local = InverseRigid(end[0]);
  uint32_t inside_before = 0;
  for (size_t i = 0; i < positions.size(); ++i) {
    const Float3 before = TransformPoint(to_local, previous[i]);
    if (MaxPlane(arm, before) <= 0.f) ++inside_before;
    EXPECT_GT(MaxPlane(arm, TransformPoint(to_local, positions[i])), 0.f) << i;
  }
  EXPECT_GT(inside_before, 500u);
}

TEST(HullColliderTest, JointSpherePushOutAndContinuousSegment) {
  const JointSphereData sphere{0, -1, {0.f, 1.f, 0.f}, 0.1f};
  HullColliderSet set = BuildSet({}, {sphere}, 1);
  ResponseParams params;
  params.friction_model = FrictionModel::kPaperA;  // frictionless: the tangential velocity kept
  params.separation = 1e-4f;
  params.friction = 0.f;
  // Resting particle inside: radial push-out.
  std::vector<Float3> previous = {{0.03f, 1.04f, 0.f}}, positions = previous,
                      velocities = {{0, 0, 0}};
  std::vector<uint8_t> flags(1);
  ASSERT_TRUE(set.CollideBatch(previous, positions, velocities, flags, params).ok());
  EXPECT_TRUE(flags[0] & kCollisionContact);
  EXPECT_TRUE(flags[0] & kCollisionStartedInside);
  const Float3 d = positions[0] - sphere.center;
  EXPECT_NEAR(Length(d), 0.1f + 1e-4f, 1e-6f);
  EXPECT_NEAR(d.x / Length(d), 0.6f, 1e-5f);
  EXPECT_NEAR(d.y / Length(d), 0.8f, 1e-5f);
  // A fast particle crossing the whole sphere is caught at the entry side.
  previous = {{-0.5f, 1.01f, 0.f}};
  positions = {{0.5f, 1.01f, 0.f}};
  velocities = {{10.f, 0.f, 0.f}};
  ASSERT_TRUE(set.CollideBatch(previous, positions, velocities, flags, params).ok());
  EXPECT_TRUE(flags[0] & kCollisionContact);
  EXPECT_LT(positions[0].x, -0.09f);
  EXPECT_GE(Length(positions[0] - sphere.center), 0.1f);
  // The normal part of the velocity is removed: N at the entry point (-sqrt(0.0099), 0.01)/0.1.
  const Float3 n{-std::sqrt(0.0099f) / 0.1f, 0.1f, 0.f};
  EXPECT_NEAR(Dot(velocities[0], n), 0.f, 1e-3f);
  EXPECT_NEAR(velocities[0].x, 10.f - 10.f * n.x * n.x, 1e-3f);
  // The sphere follows its joint: moved by +0.5 in x at the end of the step.
  std::vector<Mat34> start(1), end(1);
  end[0].m[3] = 0.5f;
  ASSERT_TRUE(set.SetPose(start, end).ok());
  const ContactQuery q = set.Query({0.52f, 1.f, 0.f}, {0.52f, 1.f, 0.f});
  EXPECT_TRUE(q.inside_end);
  EXPECT_NEAR(q.depth, 0.08f, 1e-6f);
  EXPECT_NEAR(set.SphereCenter(0, 0.5f).x, 0.25f, 1e-6f);
}

TEST(HullColliderTest, GaussSeidelLeavesParticlesOutsideTwoOverlappingBoxes) {
  // A = [-0.2, 0.2] x [-0.05, 0.05]^2 and B = A shifted by +0.3 in x: overlap x in [0.1, 0.2].
  const HullColliderData a = MakeBox({0.2f, 0.05f, 0.05f});
  const HullColliderData b = MakeBox({0.2f, 0.05f, 0.05f}, {0.3f, 0.f, 0.f});
  HullColliderSet set = BuildSet({a, b}, {}, 1);
  std::mt19937 rng(5);
  std::vector<Float3> previous, positions, velocities;
  for (int i = 0; i < 5000; ++i) {
    const Float3 p = RandomIn(rng, {0.1f, -0.049f, -0.049f}, {0.2f, 0.049f, 0.049f});
    previous.push_back(p);
    positions.push_back(p);
    velocities.push_back({0, 0, 0});
  }
  std::vector<uint8_t> flags(positions.size());
  ResponseParams params;
  params.separation = 1e-5f;
  ASSERT_TRUE(set.CollideBatch(previous, positions, velocities, flags, params).ok());
  for (size_t i = 0; i < positions.size(); ++i) {
    EXPECT_GT(MaxPlane(a, positions[i]), 0.f) << i;
    EXPECT_GT(MaxPlane(b, positions[i]), 0.f) << i;
    // Pushed out through the shared side (y or z), never farther than needed.
    EXPECT_LE(Length(positions[i] - previous[i]), 0.05f + 1e-3f);
  }
}

// A V of two slabs crossing at 60 degrees (a thigh against a thigh, an arm against the chest): a
// particle deep in their overlap is outside both after any number of passes, one included. Each
// response re-imposes the supporting planes the particle was already pushed out through, so it
// is never left in the collider it was pushed into.
TEST(HullColliderTest, ParticlesInAWedgeOfOverlappingCollidersEndOutsideBoth) {
  Float3 axes_a[3], axes_b[3];
  RotatedAxes(30.0, {0.f, 0.f, 1.f}, axes_a);
  RotatedAxes(-30.0, {0.f, 0.f, 1.f}, axes_b);
  const HullColliderData a = MakeBox({0.04f, 0.2f, 0.05f}, {-0.05f, 0.f, 0.f}, axes_a);
  const HullColliderData b = MakeBox({0.04f, 0.2f, 0.05f}, {0.05f, 0.f, 0.f}, axes_b);
  for (uint32_t passes : {1u, 2u, 4u}) {
    HullColliderOptions options;
    options.gauss_seidel_passes = passes;
    HullColliderSet set = BuildSet({a, b}, {}, 1, options);
    std::mt19937 rng(17);
    std::vector<Float3> previous, positions, velocities;
    while (positions.size() < 4000) {
      const Float3 p = RandomIn(rng, {-0.15f, -0.2f, -0.049f}, {0.15f, 0.2f, 0.049f});
      if (MaxPlane(a, p) > 0.f || MaxPlane(b, p) > 0.f) continue;  // in both
      previous.push_back(p);
      positions.push_back(p);
      velocities.push_back({0.f, -1.f, 0.f});
    }
    std::vector<uint8_t> flags(positions.size());
    ResponseParams params;
    params.separation = 1e-5f;
    ASSERT_TRUE(set.CollideBatch(previous, positions, velocities, flags, params).ok());
    for (size_t i = 0; i < positions.size(); ++i) {
      ASSERT_GT(MaxPlane(a, positions[i]), 0.f) << "passes " << passes << ", particle " << i;
      ASSERT_GT(MaxPlane(b, positions[i]), 0.f) << "passes " << passes << ", particle " << i;
      EXPECT_TRUE(flags[i] & kCollisionContact);
    }
  }
}

std::vector<HullColliderData> SceneHulls() {
  std::vector<HullColliderData> hulls;
  for (int i = 0; i < 6; ++i) {
    Float3 axes[3];
    RotatedAxes(20.0 * i, {1.f, float(i), 0.5f}, axes);
    HullColliderData h = MakeEllipsoid({0.05f, 0.12f + 0.01f * float(i), 0.06f}, 1,
                                       {0.12f * float(i), 0.f, 0.f}, axes);
    h.joint = i % 3;
    hulls.push_back(h);
  }
  hulls.push_back(MakeBox({0.1f, 0.1f, 0.02f}, {0.3f, 0.1f, 0.f}));
  return hulls;
}

// Two slabs that overlap by a centimetre and face each other 2 degrees off parallel (a thigh
// pressed against a thigh): their response planes meet in a line far away. The particle must
// not be thrown along it: it ends near where it started (the pinch has no room), finite.
// Two halves of a body that overlap by 2 cm across their cut, the cut faces not flagged (a bone's
// end buried in its neighbour looks the same). A particle at rest inside both, nearest to the
// cut faces: each one's exit lies inside the other, so pushing out of one and then the other
// leaves it inside. The nearest exit of the union is the shared face 30 mm away (within twice the
// sum of the depths, 8 + 12 mm), where CollideBatch and Query put it.
TEST(HullColliderTest, AParticleInsideTwoHalvesLeavesThroughTheirUnionsNearestFace) {
  const HullColliderData left = MakeBox({0.055f, 0.1f, 0.09f}, {-0.045f, 0.f, -0.01f});
  const HullColliderData right = MakeBox({0.055f, 0.1f, 0.09f}, {0.045f, 0.f, -0.01f});
  HullColliderSet set = BuildSet({left, right}, {}, 1);
  const Float3 p = {0.002f, 0.f, 0.05f};
  ASSERT_LT(MaxPlane(left, p), 0.f);
  ASSERT_LT(MaxPlane(right, p), 0.f);
  std::vector<Float3> previous = {p}, positions = {p}, velocities = {{0.f, 0.f, 0.f}};
  std::vector<uint8_t> flags(1);
  ASSERT_TRUE(set.CollideBatch(previous, positions, velocities, flags, ResponseParams{}).ok());
  EXPECT_TRUE(flags[0] & kCollisionContact);
  EXPECT_GT(MaxPlane(left, positions[0]), 0.f);
  EXPECT_GT(MaxPlane(right, positions[0]), 0.f);
  EXPECT_NEAR(positions[0].z, 0.08f, 1e-3f);
  EXPECT_NEAR(positions[0].x, p.x, 1e-3f);
  const ContactQuery c = set.Query(p, p);
  ASSERT_TRUE(c.contact);
  EXPECT_NEAR(c.point.z, 0.08f, 1e-3f);
  EXPECT_NEAR(c.normal.z, 1.f, 1e-5f);
}

TEST(HullColliderTest, NearlyOpposingCollidersDoNotThrowAParticleAway) {
  Float3 axes_b[3];
  RotatedAxes(2.0, {0.f, 0.f, 1.f}, axes_b);
  const HullColliderData a = MakeBox({0.05f, 0.2f, 0.05f}, {-0.045f, 0.f, 0.f});
  const HullColliderData b = MakeBox({0.05f, 0.2f, 0.05f}, {0.045f, 0.f, 0.f}, axes_b);
  HullColliderSet set = BuildSet({a, b}, {}, 1);
  std::mt19937 rng(23);
  std::vector<Float3> previous, positions, velocities;
  while (positions.size() < 2000) {
    const Float3 p = RandomIn(rng, {-0.01f, -0.15f, -0.04f}, {0.01f, 0.15f, 0.04f});
    if (MaxPlane(a, p) > 0.f || MaxPlane(b, p) > 0.f) continue;  // in both
    previous.push_back(p);
    positions.push_back(p);
    velocities.push_back({0.f, 0.f, 0.f});
  }
  std::vector<uint8_t> flags(positions.size());
  ASSERT_TRUE(set.CollideBatch(previous, positions, velocities, flags, ResponseParams{}).ok());
  for (size_t i = 0; i < positions.size(); ++i) {
    ASSERT_TRUE(IsFinite(positions[i]));
    // The overlap is 1 cm wide and 5 cm deep in z: no answer needs more than 6 cm.
    EXPECT_LT(Length(positions[i] - previous[i]), 0.06f) << i;
  }
}

TEST(HullColliderTest, BatchIsBitwiseIdenticalAtOneAndTwoThreads) {
  const std::vector<HullColliderData> hulls = SceneHulls();
  const std::vector<JointSphereData> spheres = {{1, 0, {0.2f, 0.05f, 0.f}, 0.06f},
                                                {2, 1, {0.5f, -0.05f, 0.f}, 0.05f}};
  HullColliderSet set = BuildSet(hulls, spheres, 3);
  const std::vector<Mat34> start = {Mat34{}, RotationAbout(-10, {0, 1, 0}, {0.2f, 0, 0}), Mat34{}};
  const std::vector<Mat34> end = {RotationAbout(15, {0, 0, 1}, {0, 0, 0}),
                                  RotationAbout(20, {0, 1, 0}, {0.2f, 0, 0}),
                                  RotationAbout(-30, {1, 0, 0}, {0.5f, 0, 0})};
  ASSERT_TRUE(set.SetPose(start, end).ok());
  std::mt19937 rng(9);
  std::vector<Float3> previous, positions, velocities;
  // 30 005 particles: the eight-particle broad phase ends on a partial group of five.
  for (int i = 0; i < 30005; ++i) {
    const Float3 p = RandomIn(rng, {-0.15f, -0.2f, -0.15f}, {0.75f, 0.25f, 0.15f});
    previous.push_back(p);
    positions.push_back(p + RandomIn(rng, {-0.02f, -0.02f, -0.02f}, {0.02f, 0.02f, 0.02f}));
    velocities.push_back(RandomIn(rng, {-1, -1, -1}, {1, 1, 1}));
  }
  positions[17].x = std::nanf("");
  velocities[30003].y = std::nanf("");  // an invalid lane in the partial group
  ResponseParams params;
  for (float s0 : {0.f, 0.25f}) {
    const float s1 = s0 == 0.f ? 1.f : 0.5f;
    std::vector<Float3> p1 = positions, v1 = velocities, p2 = positions, v2 = velocities;
    std::vector<uint8_t> f1(positions.size()), f2(positions.size());
    uint32_t c1 = 0, c2 = 0;
    test::UseWorkers(1);
    ASSERT_TRUE(set.CollideBatch(previous, p1, v1, f1, params, s0, s1, &c1).ok());
    test::UseWorkers(2);
    ASSERT_TRUE(set.CollideBatch(previous, p2, v2, f2, params, s0, s1, &c2).ok());
    EXPECT_EQ(c1, c2);
    EXPECT_GT(c1, 1000u);
    EXPECT_EQ(std::memcmp(p1.data(), p2.data(), p1.size() * sizeof(Float3)), 0);
    EXPECT_EQ(std::memcmp(v1.data(), v2.data(), v1.size() * sizeof(Float3)), 0);
    EXPECT_EQ(f1, f2);
    // The substep fast path (SelectSubstep) gives the same bits as the per-pair interpolation.
    ASSERT_TRUE(set.SelectSubstep(s0, s1).ok());
    std::vector<Float3> p3 = positions, v3 = velocities;
    std::vector<uint8_t> f3(positions.size());
    ASSERT_TRUE(set.CollideBatch(previous, p3, v3, f3, params, s0, s1).ok());
    EXPECT_EQ(std::memcmp(p1.data(), p3.data(), p1.size() * sizeof(Float3)), 0);
    EXPECT_EQ(f1, f3);
    ASSERT_TRUE(set.SelectSubstep(0.f, 1.f).ok());
    // Every instruction set's kernels (the scalar reference, 4-wide SSE2, 8-wide AVX2 where the
    // CPU has it) give the same bits, the group broad phase included.
    for (InstructionSet instruction_set :
         {InstructionSet::kScalar, InstructionSet::kSse2, InstructionSet::kAvx2}) {
      HullColliderOptions narrow;
      narrow.instruction_set = instruction_set;
      ASSERT_TRUE(set.SetOptions(narrow).ok());
      if (set.instruction_set() != instruction_set) continue;  // the CPU lacks it
      SCOPED_TRACE(ToString(instruction_set));
      std::vector<Float3> p4 = positions, v4 = velocities;
      std::vector<uint8_t> f4(positions.size());
      ASSERT_TRUE(set.CollideBatch(previous, p4, v4, f4, params, s0, s1).ok());
      EXPECT_EQ(std::memcmp(p1.data(), p4.data(), p1.size() * sizeof(Float3)), 0);
      EXPECT_EQ(std::memcmp(v1.data(), v4.data(), v1.size() * sizeof(Float3)), 0);
      EXPECT_EQ(f1, f4);
    }
    ASSERT_TRUE(set.SetOptions(HullColliderOptions{}).ok());
  }
}

// 78 colliders (two and a half words of the grouped broad phase's masks), crowded so that the
// particles in the middle reach more than kMaxCandidates of them: the grouped first broad phase
// (selected substep) keeps exactly the candidates of each particle's own broad phase (other
// fractions), at every instruction set.
// Collides previous -> positions over [s0, s1] through the per-particle path (fractions not
// selected), then through the grouped path of every lane pack the CPU runs, and expects the same
// bits. `per_pack` runs with each pack selected, before its batch. Returns the contacts.
template <class PerPack>
uint32_t ExpectGroupedAsPerParticle(HullColliderSet& set, const std::vector<Float3>& previous,
                                    const std::vector<Float3>& positions,
                                    const std::vector<Float3>& velocities, float s0, float s1,
                                    const PerPack& per_pack) {
  const ResponseParams params;
  std::vector<Float3> p1 = positions, v1 = velocities;
  std::vector<uint8_t> f1(positions.size());
  uint32_t c1 = 0;
  EXPECT_TRUE(set.CollideBatch(previous, p1, v1, f1, params, s0, s1, &c1).ok());  // per particle
  for (InstructionSet instruction_set :
       {InstructionSet::kScalar, InstructionSet::kSse2, InstructionSet::kAvx2}) {
    HullColliderOptions options;
    options.instruction_set = instruction_set;
    EXPECT_TRUE(set.SetOptions(options).ok());
    if (set.instruction_set() != instruction_set) continue;  // the CPU lacks it
    SCOPED_TRACE(ToString(instruction_set));
    EXPECT_TRUE(set.SelectSubstep(s0, s1).ok());
    per_pack();
    std::vector<Float3> p2 = positions, v2 = velocities;
    std::vector<uint8_t> f2(positions.size());
    uint32_t c2 = 0;
    EXPECT_TRUE(set.CollideBatch(previous, p2, v2, f2, params, s0, s1, &c2).ok());  // grouped
    EXPECT_EQ(c1, c2);
    EXPECT_EQ(std::memcmp(p1.data(), p2.data(), p1.size() * sizeof(Float3)), 0);
    EXPECT_EQ(std::memcmp(v1.data(), v2.data(), v1.size() * sizeof(Float3)), 0);
    EXPECT_EQ(f1, f2);
    EXPECT_TRUE(set.SelectSubstep(0.f, 1.f).ok());
  }
  return c1;
}

TEST(HullColliderTest, GroupedBroadPhaseOfManyCollidersMatchesThePerParticleOne) {
  std::mt19937 rng(21);
  std::vector<HullColliderData> hulls;
  for (int i = 0; i < 48; ++i) {
    Float3 axes[3];
    RotatedAxes(7.5 * i, {1.f, float(i % 5), 0.5f}, axes);
    HullColliderData h =
        MakeEllipsoid({0.04f, 0.08f, 0.05f}, 1,
                      RandomIn(rng, {-0.06f, -0.06f, -0.06f}, {0.06f, 0.06f, 0.06f}), axes);
    h.joint = i % 3;
    hulls.push_back(h);
  }
  std::vector<JointSphereData> spheres;
  for (int i = 0; i < 30; ++i) {
    spheres.push_back({i % 3, -1, RandomIn(rng, {-0.03f, -0.03f, -0.03f}, {0.03f, 0.03f, 0.03f}),
                       0.05f + 0.001f * float(i)});
  }
  HullColliderSet set = BuildSet(hulls, spheres, 3);
  const std::vector<Mat34> start = {Mat34{}, RotationAbout(-10, {0, 1, 0}, {0.1f, 0, 0}), Mat34{}};
  const std::vector<Mat34> end = {RotationAbout(5, {0, 0, 1}, {0, 0, 0}),
                                  RotationAbout(10, {0, 1, 0}, {0.1f, 0, 0}),
                                  RotationAbout(-8, {1, 0, 0}, {0.f, 0.1f, 0})};
  ASSERT_TRUE(set.SetPose(start, end).ok());
  std::vector<Float3> previous, positions, velocities;
  for (int i = 0; i < 6003; ++i) {
    const Float3 p = RandomIn(rng, {-0.2f, -0.2f, -0.2f}, {0.2f, 0.2f, 0.2f});
    previous.push_back(p);
    positions.push_back(p + RandomIn(rng, {-0.03f, -0.03f, -0.03f}, {0.03f, 0.03f, 0.03f}));
    velocities.push_back(RandomIn(rng, {-1, -1, -1}, {1, 1, 1}));
  }
  EXPECT_GT(ExpectGroupedAsPerParticle(set, previous, positions, velocities, 0.25f, 0.5f, [] {}),
            400u);
}

// A cloth's neighbouring particles share their candidates, so the batch tests the hulls' boxes
// for a whole group at once and drops the candidates a box rejects (most, near limbs whose
// bounding spheres overlap). The contacts must come out as the per-particle path gives them.
TEST(HullColliderTest, TheGroupBoxFilterKeepsASheetsContacts) {
  // Twelve thin limb-like hulls in a column of pairs, turning a little over the step.
  std::vector<HullColliderData> hulls;
  for (int i = 0; i < 12; ++i) {
    Float3 axes[3];
    RotatedAxes(9.0 * i, {0.3f, 1.f, 0.2f}, axes);
    const Float3 centre{i % 2 == 0 ? -0.04f : 0.04f, 0.12f * float(i / 2), 0.f};
    HullColliderData h = MakeEllipsoid({0.015f, 0.06f, 0.015f}, 1, centre, axes);
    h.joint = i % 2;
    hulls.push_back(h);
  }
  const std::vector<JointSphereData> spheres = {{0, -1, {-0.04f, 0.3f, 0.f}, 0.02f},
                                                {1, -1, {0.04f, 0.3f, 0.f}, 0.02f}};
  HullColliderSet set = BuildSet(hulls, spheres, 2);
  const std::vector<Mat34> start = {Mat34{}, Mat34{}};
  const std::vector<Mat34> end = {RotationAbout(4, {1, 0, 0}, {0, 0.7f, 0}),
                                  RotationAbout(-4, {1, 0, 0}, {0, 0.7f, 0})};
  ASSERT_TRUE(set.SetPose(start, end).ok());
  // A 120 x 60 sheet in grid order wrapped half round the column, falling 1 cm and pushed 3 to
  // 9 cm towards it: many segments cross a hull and end beyond it.
  std::vector<Float3> previous, positions, velocities;
  for (int j = 0; j < 60; ++j) {
    for (int i = 0; i < 120; ++i) {
      const float angle = 3.14159f * float(i) / 119.f, radius = 0.08f + 0.002f * float(i % 7);
      const Float3 out{std::cos(angle), 0.f, std::sin(angle)};
      const Float3 p = out * radius + Float3{0.f, 0.012f * float(j) - 0.02f, 0.f};
      const float push = 0.03f + 0.01f * float((i + j) % 7);
      previous.push_back(p);
      positions.push_back(p + Float3{0.f, -0.01f, 0.f} - out * push);
      velocities.push_back((positions.back() - p) * 60.f);
    }
  }
  // The filter runs: the lanes share their hulls, and many candidates are beyond a box.
  const auto filter_runs = [&] {
    EXPECT_GT(HullColliderSetAccess::GroupBoxRejections(set, previous, positions),
              positions.size() / 2);
  };
  EXPECT_GT(
      ExpectGroupedAsPerParticle(set, previous, positions, velocities, 0.25f, 0.75f, filter_runs),
      200u);
}

TEST(HullColliderTest, InvalidInputIsFlaggedAndLeftUntouched) {
  HullColliderSet set = BuildSet({MakeBox({0.1f, 0.1f, 0.1f})}, {}, 1);
  const float nan = std::nanf(""), inf = std::numeric_limits<float>::infinity();
  std::vector<Float3> previous = {{0, 0, 0}, {nan, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  std::vector<Float3> positions = {{0, 0, inf}, {0.01f, 0, 0}, {0.f, 0.f, 0.f}, {0.02f, 0, 0}};
  std::vector<Float3> velocities = {{0, 0, 0}, {0, 0, 0}, {0, nan, 0}, {0, 0, 0}};
  const std::vector<Float3> positions_before = positions;
  std::vector<uint8_t> flags(4);
  uint32_t contacts = 0;
  ASSERT_TRUE(set.CollideBatch(previous, positions, velocities, flags, ResponseParams{}, 0.f, 1.f,
                               &contacts)
                  .ok());
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(flags[i], kCollisionInvalidInput);
    EXPECT_EQ(std::memcmp(&positions[i], &positions_before[i], sizeof(Float3)), 0);
  }
  EXPECT_TRUE(flags[3] & kCollisionContact);
  EXPECT_EQ(contacts, 1u);
  EXPECT_EQ(set.Query({nan, 0, 0}, {0, 0, 0}).flags, kCollisionInvalidInput);
  // Argument errors.
  std::vector<uint8_t> short_flags(3);
  EXPECT_FALSE(
      set.CollideBatch(previous, positions, velocities, short_flags, ResponseParams{}).ok());
  ResponseParams bad;
  bad.friction = 2.f;
  EXPECT_FALSE(set.CollideBatch(previous, positions, velocities, flags, bad).ok());
  EXPECT_FALSE(
      set.CollideBatch(previous, positions, velocities, flags, ResponseParams{}, 0.5f, 0.2f).ok());
}

TEST(HullColliderTest, ResponseAppliesFrictionAndRestitutionOnlyWhenApproaching) {
  HullColliderSet set = BuildSet({MakeBox({0.1f, 0.1f, 0.1f})}, {}, 1);
  ResponseParams params;
  params.friction = 0.25f;
  params.restitution = 0.5f;
  params.separation = 0.f;
  params.friction_model = FrictionModel::kPaperA;
  std::vector<Float3> previous = {{0.f, 0.2f, 0.f}, {0.05f, 0.05f, 0.f}};
  std::vector<Float3> positions = {{0.02f, 0.09f, 0.f}, {0.05f, 0.09f, 0.f}};
  std::vector<Float3> velocities = {{1.f, -2.f, 0.f}, {1.f, 2.f, 0.f}};  // approaching, separating
  std::vector<uint8_t> flags(2);
  ASSERT_TRUE(set.CollideBatch(previous, positions, velocities, flags, params).ok());
  EXPECT_NEAR(positions[0].y, 0.1f, 1e-6f);
  EXPECT_NEAR(positions[0].x, 0.02f, 1e-6f);  // projected end: tangential motion kept
  EXPECT_NEAR(velocities[0].x, 0.75f, 1e-6f);
  EXPECT_NEAR(velocities[0].y, 1.f, 1e-6f);  // -(-2) * 0.5
  EXPECT_TRUE(flags[1] & kCollisionStartedInside);
  EXPECT_NEAR(positions[1].y, 0.1f, 1e-6f);  // pushed out through the nearest face (y)
  EXPECT_FLOAT_EQ(velocities[1].x, 1.f);     // separating: unchanged
  EXPECT_FLOAT_EQ(velocities[1].y, 2.f);
}

TEST(HullColliderTest, MapTableRayResponseAndFallback) {
  HullColliderData box = MakeBox({0.1f, 0.2f, 0.05f});
  // A trivially conservative one-cell table: every triangle listed.
  box.map.kind = MapTableKind::kSphere;
  box.map.rows = 1;
  box.map.cols = 1;
  box.map.origin = {0.01f, 0.02f, 0.f};
  box.map.axis = {0, 0, 1};
  box.map.reference = {1, 0, 0};
  box.map.cell_offsets = {0, 12};
  for (uint32_t t = 0; t < 12; ++t) box.map.cell_triangles.push_back(t);
  HullColliderOptions options;
  options.response = HullResponse::kMapTableRay;
  HullColliderSet set = BuildSet({box}, {}, 1, options);
  std::mt19937 rng(2);
  for (int i = 0; i < 5000; ++i) {
    const Float3 p = RandomIn(rng, {-0.099f, -0.199f, -0.049f}, {0.099f, 0.199f, 0.049f});
    const ContactQuery c = HullColliderSetAccess::QueryHullLocal(set, 0, p, p);
    ASSERT_TRUE(c.contact);
    EXPECT_FALSE(c.flags & kCollisionFallback) << i;
    EXPECT_GE(HullColliderSetAccess::MaxPlaneDistanceLocal(set, 0, c.point), 0.f);
    EXPECT_LE(HullColliderSetAccess::MaxPlaneDistanceLocal(set, 0, c.point), 1e-6f);
    // On the ray from the source through p, beyond p.
    const Float3 d = p - box.map.origin, e = c.point - box.map.origin;
    EXPECT_LE(Length(Cross(d, e)), 1e-6f * Length(e));
    EXPECT_GE(Dot(d, e), Dot(d, d));
  }
  // An empty table: every response falls back to the push-out and says so.
  box.map.cell_offsets = {0, 0};
  box.map.cell_triangles.clear();
  HullColliderSet empty = BuildSet({box}, {}, 1, options);
  const ContactQuery c =
      HullColliderSetAccess::QueryHullLocal(empty, 0, {0.f, 0.f, 0.04f}, {0.f, 0.f, 0.04f});
  EXPECT_TRUE(c.contact);
  EXPECT_TRUE(c.flags & kCollisionFallback);
  EXPECT_NEAR(c.point.z, 0.05f, 1e-6f);
}

TEST(HullColliderTest, QueryReportsInsideDepthAndKinds) {
  HullColliderSet set =
      BuildSet({MakeBox({0.1f, 0.1f, 0.1f})}, {{0, -1, {1.f, 0.f, 0.f}, 0.2f}}, 1);
  ContactQuery q = set.Query({0.f, 0.f, 0.07f}, {0.f, 0.f, 0.07f});
  EXPECT_TRUE(q.inside_end);
  EXPECT_TRUE(q.contact);
  EXPECT_NEAR(q.depth, 0.03f, 1e-6f);
  EXPECT_NEAR(q.point.z, 0.1f, 1e-6f);
  EXPECT_FALSE(set.Query({0.f, 0.f, 0.07f}, {0.f, 0.f, 0.07f}, kColliderSpheres).contact);
  q = set.Query({1.f, 0.1f, 0.f}, {1.f, 0.1f, 0.f}, kColliderSpheres);
  EXPECT_TRUE(q.inside_end);
  EXPECT_NEAR(q.depth, 0.1f, 1e-6f);
  EXPECT_FALSE(set.Query({0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f}).contact);
  EXPECT_GT(set.memory_bytes(), 0u);
}

TEST(HullColliderTest, BindFrameAndSkinningPlaceTheCollider) {
  // Collider frame -> asset at bind: translate by (1, 0, 0); skinning rotates 90 degrees about y
  // through the origin: the box centre goes to (0, 0, -1).
  HullColliderData box = MakeBox({0.1f, 0.1f, 0.1f});
  box.bind_frame.m[3] = 1.f;
  HullColliderSet set = BuildSet({box}, {}, 1);
  const std::vector<Mat34> pose = {RotationAbout(90.0, {0, 1, 0}, {0, 0, 0})};
  ASSERT_TRUE(set.SetPose(pose, pose).ok());
  EXPECT_TRUE(set.Query({0.f, 0.f, -1.05f}, {0.f, 0.f, -1.05f}).inside_end);
  EXPECT_FALSE(set.Query({1.f, 0.f, 0.f}, {1.f, 0.f, 0.f}).inside_end);
}

TEST(HullColliderTest, SelectingTheSameSubstepAgainFollowsANewPose) {
  // SelectSubstep skips the work when the fractions are the selected ones for the current pose
  // (SetPose selects [0, 1]); a new pose must still be the one CollideBatch meets.
  HullColliderSet set = BuildSet({MakeBox({0.1f, 0.1f, 0.1f})}, {}, 1);
  const std::vector<Mat34> here = {Mat34{}};
  std::vector<Mat34> there = {Mat34{}};
  there[0].m[3] = 1.f;  // the box 1 m along x
  for (const float s1 : {1.f, 0.5f}) {
    SCOPED_TRACE(s1);
    ASSERT_TRUE(set.SetPose(here, here).ok());
    ASSERT_TRUE(set.SelectSubstep(0.f, s1).ok());
    ASSERT_TRUE(set.SetPose(there, there).ok());
    ASSERT_TRUE(set.SelectSubstep(0.f, s1).ok());
    std::vector<Float3> previous = {{1.f, 0.5f, 0.f}}, positions = {{1.f, 0.05f, 0.f}};
    std::vector<Float3> velocities = {{0.f, -1.f, 0.f}};
    std::vector<uint8_t> flags(1);
    ASSERT_TRUE(
        set.CollideBatch(previous, positions, velocities, flags, ResponseParams{}, 0.f, s1).ok());
    EXPECT_TRUE(flags[0] & kCollisionContact);
    EXPECT_GE(positions[0].y, 0.1f);  // on the moved box's top face
  }
}

}  // namespace
}  // namespace drape

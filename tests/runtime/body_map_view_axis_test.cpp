// Body maps seen along x or y (BodyMapViewAxis): the collider answers in the asset frame exactly
// as the z-view collider of the same maps answers the permuted inputs, bit for bit, in every
// call (IsInside, Query, InsideBatch, CollideBatch at every lane width and task system); the
// renderer draws along the axis it is given.

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "body_map/body_map_collider_access.h"
#include "body_map_test_fixtures.h"
#include "drape/runtime/body_map_renderer.h"
#include "drape/runtime/math.h"
#include "skinned_spheres.h"
#include "workers.h"

namespace drape {
namespace {

using test::Bits;
using test::ExpectSameAnswer;
using test::ExpectSameBits;

constexpr BodyMapViewAxis kOtherAxes[] = {BodyMapViewAxis::kX, BodyMapViewAxis::kY};

ContactQuery FromView(BodyMapViewAxis axis, ContactQuery q) {
  q.point = FromBodyMapView(axis, q.point);
  q.normal = FromBodyMapView(axis, q.normal);
  return q;
}

// The sphere and the box fixtures, one layer; the permutation must not care which.
std::vector<BodyMapPose> Poses() {
  return {test::MakePose(test::SphereGrid(), test::Sphere),
          test::MakePose(test::BoxGrid(), test::Box)};
}

TEST(BodyMapViewAxis, QueriesAreThePermutedZViewAnswers) {
  for (const BodyMapPose& z_pose : Poses()) {
    const BodyMapCollider z_view = test::BuildOrDie(z_pose);
    for (BodyMapViewAxis axis : kOtherAxes) {
      BodyMapPose pose = z_pose;
      pose.view_axis = axis;
      const BodyMapCollider maps = test::BuildOrDie(pose);
      SCOPED_TRACE(BodyMapViewAxisName(axis));
      EXPECT_EQ(maps.view_axis(), axis);
      ExpectSameBits(maps.bounds_min(), FromBodyMapView(axis, z_view.bounds_min()), "min", 0);
      ExpectSameBits(maps.bounds_max(), FromBodyMapView(axis, z_view.bounds_max()), "max", 0);
      std::mt19937 rng(17);
      int contacts = 0;
      for (int k = 0; k < 4000; ++k) {
        Float3 v0, v1;  // view frame
        test::RandomSegment(rng, k, &v0, &v1);
        const Float3 p0 = FromBodyMapView(axis, v0), p1 = FromBodyMapView(axis, v1);
        const ContactQuery want = FromView(axis, z_view.Query(v0, v1));
        ExpectSameAnswer(maps.Query(p0, p1), want, k);
        EXPECT_EQ(maps.IsInside(p1), z_view.IsInside(v1)) << k;
        contacts += want.contact ? 1 : 0;
      }
      EXPECT_GT(contacts, 400);  // the segments do reach the body
    }
  }
}

TEST(BodyMapViewAxis, BatchesAreThePermutedZViewBatches) {
  const BodyMapPose z_pose = test::MakePose(test::SphereGrid(), test::Sphere);
  // More particles than one chunk (1024) and than one stack piece (256), not a multiple of either.
  constexpr int kParticles = 2600;
  std::mt19937 rng(3);
  std::vector<Float3> view_previous(kParticles), view_positions(kParticles);
  std::vector<Float3> view_velocities(kParticles);
  std::uniform_real_distribution<float> speed(-2.f, 2.f);
  for (int k = 0; k < kParticles; ++k) {
    test::RandomSegment(rng, k, &view_previous[k], &view_positions[k]);
    view_velocities[k] = {speed(rng), speed(rng), speed(rng)};
  }
  const ResponseParams params;
  for (BodyMapViewAxis axis : kOtherAxes) {
    BodyMapPose pose = z_pose;
    pose.view_axis = axis;
    for (InstructionSet lanes : test::kEveryLanes) {
      BodyMapCollider z_view = test::BuildOrDie(z_pose), maps = test::BuildOrDie(pose);
      if (!test::UseLanes(&z_view, lanes) || !test::UseLanes(&maps, lanes)) continue;
      SCOPED_TRACE(std::string(BodyMapViewAxisName(axis)) + " " + test::LanesName(lanes));
      std::vector<Float3> want_positions = view_positions, want_velocities = view_velocities;
      std::vector<uint8_t> want_flags(kParticles);
      uint32_t want_contacts = 0;
      ASSERT_TRUE(z_view
                      .CollideBatch(view_previous, want_positions, want_velocities, want_flags,
                                    params, &want_contacts)
                      .ok());
      std::vector<Float3> previous(kParticles), positions(kParticles), velocities(kParticles);
      for (int k = 0; k < kParticles; ++k) {
        previous[k] = FromBodyMapView(axis, view_previous[k]);
        positions[k] = FromBodyMapView(axis, view_positions[k]);
        velocities[k] = FromBodyMapView(axis, view_velocities[k]);
      }
      for (const test::TaskSystemCase& tasks : test::AllTaskSystems()) {
        tasks.Use();
        SCOPED_TRACE(tasks.name);
        std::vector<Float3> got_positions = positions, got_velocities = velocities;
        std::vector<uint8_t> flags(kParticles);
        uint32_t contacts = 0;
        ASSERT_TRUE(
            maps.CollideBatch(previous, got_positions, got_velocities, flags, params, &contacts)
                .ok());
        EXPECT_EQ(contacts, want_contacts);
        EXPECT_GT(contacts, 200u);
        for (int k = 0; k < kParticles; ++k) {
          ExpectSameBits(got_positions[k], FromBodyMapView(axis, want_positions[k]), "position", k);
          ExpectSameBits(got_velocities[k], FromBodyMapView(axis, want_velocities[k]), "velocity",
                         k);
          EXPECT_EQ(flags[k], want_flags[k]) << k;
        }
      }
      test::UseDefaultWorkers();
      std::vector<uint8_t> inside(kParticles), want_inside(kParticles);
      ASSERT_TRUE(maps.InsideBatch(positions, inside).ok());
      ASSERT_TRUE(z_view.InsideBatch(view_positions, want_inside).ok());
      EXPECT_EQ(inside, want_inside);
    }
  }
}

TEST(BodyMapViewAxis, AnUnknownAxisIsRefusedNamingIt) {
  BodyMapPose pose = test::MakePose(test::BoxGrid(), test::Box);
  pose.view_axis = static_cast<BodyMapViewAxis>(3);
  BodyMapCollider maps;
  const Status s = maps.Build(pose);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("view_axis = 3"), std::string::npos) << s.message();
  EXPECT_TRUE(maps.empty());
  BodyMapRenderOptions options;
  options.view_axis = static_cast<BodyMapViewAxis>(7);
  const MeshData mesh = test::TwoSkinnedSpheres(0.1f);
  BodyMapRenderer renderer;
  EXPECT_NE(renderer.Init(mesh, options).message().find("view_axis 7"), std::string::npos);
}

// The renderer along y draws what it draws along z for the mesh turned so that y becomes z: the
// same grid and, up to the normals' rounding (their lengths sum in another order), the same slabs.
TEST(BodyMapViewAxis, TheRendererDrawsAlongItsAxis) {
  const MeshData mesh = test::TwoSkinnedSpheres(0.1f);
  MeshData turned = mesh;
  for (Float3& p : turned.positions) p = ToBodyMapView(BodyMapViewAxis::kY, p);
  BodyMapRenderOptions options;
  options.texel_size = 0.002f;
  BodyMapRenderer along_y, along_z;
  options.view_axis = BodyMapViewAxis::kY;
  ASSERT_TRUE(along_y.Init(mesh, options).ok());
  options.view_axis = BodyMapViewAxis::kZ;
  ASSERT_TRUE(along_z.Init(turned, options).ok());
  // The second sphere's joint moved along asset y (the view axis) and x.
  const Mat34 pose[2] = {Mat34{}, TranslationMatrix({0.05f, 0.3f, 0.f})};
  const Mat34 turned_pose[2] = {
      Mat34{}, TranslationMatrix(ToBodyMapView(BodyMapViewAxis::kY, {0.05f, 0.3f, 0.f}))};
  BodyMapCollider maps_y, maps_z;
  ASSERT_TRUE(along_y.Render(pose, &maps_y).ok());
  ASSERT_TRUE(along_z.Render(turned_pose, &maps_z).ok());
  EXPECT_EQ(maps_y.view_axis(), BodyMapViewAxis::kY);
  ASSERT_EQ(maps_y.width(), maps_z.width());
  ASSERT_EQ(maps_y.height(), maps_z.height());
  EXPECT_EQ(Bits(maps_y.origin_x()), Bits(maps_z.origin_x()));
  EXPECT_EQ(Bits(maps_y.origin_y()), Bits(maps_z.origin_y()));
  int valid = 0;
  for (uint32_t j = 0; j < maps_y.height(); ++j) {
    for (uint32_t i = 0; i < maps_y.width(); ++i) {
      float top_y = 0.f, bottom_y = 0.f, top_z = 0.f, bottom_z = 0.f;
      const bool in_y = BodyMapColliderAccess::TexelSlab(maps_y, i, j, &top_y, &bottom_y);
      const bool in_z = BodyMapColliderAccess::TexelSlab(maps_z, i, j, &top_z, &bottom_z);
      ASSERT_EQ(in_y, in_z) << i << ", " << j;
      if (!in_y) continue;
      ++valid;
      EXPECT_NEAR(top_y, top_z, 1e-6f);
      EXPECT_NEAR(bottom_y, bottom_z, 1e-6f);
    }
  }
  EXPECT_GT(valid, 1000);
  // The moved sphere (bind centre (0.5, 0, 0)): its centre is inside, a point beyond it along
  // asset y is not.
  EXPECT_TRUE(maps_y.IsInside({0.55f, 0.3f, 0.f}));
  EXPECT_FALSE(maps_y.IsInside({0.55f, 0.42f, 0.f}));
  EXPECT_TRUE(maps_y.IsInside({0.f, 0.f, 0.09f}));
  // Maps the engine rendered along x: normals in the asset frame, depths along x.
  const float front[1] = {0.2f}, back[1] = {-0.2f};
  const Float3 front_normal[1] = {{1.f, 0.f, 0.f}}, back_normal[1] = {{-1.f, 0.f, 0.f}};
  RenderedMapsView view;
  view.width = view.height = 1;
  view.origin_x = view.origin_y = -0.5f;
  view.texel_size = 1.f;
  view.front_z = front;
  view.back_z = back;
  view.front_normals = front_normal;
  view.back_normals = back_normal;
  view.view_axis = BodyMapViewAxis::kX;
  BodyMapCollider loaded;
  ASSERT_TRUE(BodyMapRenderer::Load(view, &loaded).ok());
  EXPECT_TRUE(loaded.IsInside({0.1f, 0.4f, -0.4f}));
  EXPECT_FALSE(loaded.IsInside({0.3f, 0.f, 0.f}));
  const ContactQuery q = loaded.Query({0.5f, 0.f, 0.f}, {0.f, 0.f, 0.f});
  ASSERT_TRUE(q.contact);
  EXPECT_NEAR(q.point.x, 0.2f, 1e-6f);
  EXPECT_NEAR(q.normal.x, 1.f, 1e-3f);
}

}  // namespace
}  // namespace drape

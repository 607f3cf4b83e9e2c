// The C API (drape/drape.h): a garment driven from C (garment_scenario.c) ends with the same bits
// as the same scenario through the C++ API, under any task system set through C; and bad input
// gets a status and a message naming it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "drape/drape.h"
#include "drape/formats/asset_file.h"
#include "drape/runtime/capsule_colliders.h"
#include "drape/runtime/cloth_solver.h"
#include "drape/runtime/math.h"
#include "drape/runtime/shape_collider_set.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/task_system.h"
#include "garment_scenario.h"

namespace drape {
namespace {

const std::string kAsset = std::string(DRAPE_GOLDEN_DIR) + "/mannequin_colliders_v2.drape";
constexpr int kFrames = 60;

// The scenario of garment_scenario.c through the C++ API.
std::vector<Float3> RunCpp(uint32_t* contacts, uint32_t* overstretched) {
  CharacterAsset asset;
  EXPECT_TRUE(ReadAssetFile(kAsset, &asset).ok());
  SkeletonPose pose;
  HullColliderSet colliders;
  EXPECT_TRUE(pose.Init(asset.skeleton).ok());
  const uint32_t joints = asset.skeleton.joint_count();
  EXPECT_TRUE(colliders.Build(asset.hulls, asset.joint_spheres, joints).ok());
  Mat34 root;
  EXPECT_TRUE(InverseAffine(asset.skeleton.inverse_bind[0], &root));
  ClothDescription d;
  d.positions.resize(kScenarioParticles);
  d.triangles.resize(3 * kScenarioTriangles);
  const float top[3] = {root.m[3], root.m[7] + 0.03f, root.m[11]};
  scenario_skirt_mesh(top, 0.19f, 0.6f, &d.positions[0].x, d.triangles.data());
  d.skin.assign(kScenarioParticles, ClothSkinWeights{});
  for (ClothSkinWeights& w : d.skin) w.weights[0] = 1.f;
  d.max_distance.assign(kScenarioParticles, 0.15f);
  for (int i = 0; i < kScenarioSegments; ++i) d.max_distance[i] = 0.f;
  Cloth cloth;
  EXPECT_TRUE(BuildCloth(d, &cloth).ok());
  ClothSolverSettings settings;
  settings.substeps = 2;
  ClothSolver solver;
  EXPECT_TRUE(solver.Init(cloth, settings).ok());
  ClothState state;
  state.Reset(cloth);
  ShapeColliderSet shapes;
  shapes.Reserve(2 + static_cast<uint32_t>(asset.capsules.size()), 0);
  ClothColliders hit;
  hit.hulls = &colliders;
  hit.shapes = &shapes;
  hit.response.friction = 0.3f;
  std::vector<Mat34> start(joints), end(joints);
  const float dt = 1.f / 60.f;
  for (int frame = 0; frame <= kFrames; ++frame) {
    EXPECT_TRUE(pose.SampleClip(asset.clips[0], static_cast<float>(frame) * dt, true).ok());
    end.assign(pose.skinning().begin(), pose.skinning().end());
    if (frame == 0) {
      start = end;
      EXPECT_TRUE(solver.Reset(&state, ClothColliders{.response = hit.response}, end).ok());
      continue;
    }
    Mat34 staff_start, staff_end;
    scenario_staff(root.m, frame - 1, staff_start.m);
    scenario_staff(root.m, frame, staff_end.m);
    shapes.Clear();
    EXPECT_TRUE(shapes.AddPlane(Mat34{}, Mat34{}).ok());
    EXPECT_TRUE(shapes.AddCapsule(staff_start, staff_end, 0.3f, 0.03f, 0.03f).ok());
    EXPECT_TRUE(AddCapsuleColliders(asset.capsules, start, end, &shapes).ok());
    ClothStepStats stats;
    EXPECT_TRUE(solver.Step(&state, hit, {dt, start, end}, &stats).ok());
    *contacts = stats.contacts;
    *overstretched = stats.overstretched_springs;
    start = end;
  }
  return state.positions;
}

std::vector<float> RunC(uint32_t* contacts, uint32_t* overstretched) {
  std::vector<float> positions(3 * kScenarioParticles);
  const int status =
      scenario_run(kAsset.c_str(), kFrames, positions.data(), contacts, overstretched);
  EXPECT_EQ(status, DRAPE_OK) << drape_last_error();
  return positions;
}

// A C job system: runs the chunks on drape's pool of 2 (standing in for an engine's).
void PoolParallelFor(uint32_t chunk_count, drape_task_fn run, void* context, void* user) {
  static_cast<ThreadPoolTaskSystem*>(user)->ParallelFor(chunk_count, run, context);
}

TEST(CApi, GarmentMatchesTheCppApiBitForBit) {
  SetTaskSystem(&SerialTaskSystem());
  uint32_t cpp_contacts = 0, c_contacts = 0, cpp_overstretched = 0, c_overstretched = 0;
  const std::vector<Float3> cpp = RunCpp(&cpp_contacts, &cpp_overstretched);
  const std::vector<float> c = RunC(&c_contacts, &c_overstretched);
  ASSERT_EQ(c.size(), 3 * cpp.size());
  EXPECT_EQ(std::memcmp(c.data(), cpp.data(), c.size() * sizeof(float)), 0);
  EXPECT_EQ(c_contacts, cpp_contacts);
  EXPECT_EQ(c_overstretched, cpp_overstretched);
  EXPECT_GT(c_contacts, 0u);       // the skirt touches the legs, the floor or the staff
  EXPECT_GT(c_overstretched, 0u);  // a field the C API left at 0 would not match
  for (const float v : c) ASSERT_TRUE(std::isfinite(v));

  // The same through a job system set from C.
  ThreadPoolTaskSystem pool(2);
  drape_set_task_system(PoolParallelFor, 2, &pool);
  uint32_t pooled_contacts = 0, pooled_overstretched = 0;
  EXPECT_EQ(RunC(&pooled_contacts, &pooled_overstretched), c);
  EXPECT_EQ(pooled_contacts, c_contacts);
  EXPECT_EQ(pooled_overstretched, c_overstretched);
  drape_set_task_system(nullptr, 0, nullptr);
  EXPECT_EQ(&GetTaskSystem(),
            OpenMpTaskSystem() != nullptr ? OpenMpTaskSystem() : &SerialTaskSystem());
}

TEST(CApi, BadInputGetsAStatusAndAMessage) {
  drape_asset* asset = nullptr;
  EXPECT_EQ(drape_asset_load("/nonexistent/hero.drape", &asset), DRAPE_IO_ERROR);
  EXPECT_NE(std::string(drape_last_error()).find("/nonexistent/hero.drape"), std::string::npos)
      << drape_last_error();
  EXPECT_EQ(asset, nullptr);
  const std::string garbage = testing::TempDir() + "/c_api_garbage.drape";
  std::ofstream(garbage) << "not a drape file at all, but long enough to have a header";
  EXPECT_EQ(drape_asset_load(garbage.c_str(), &asset), DRAPE_BAD_MAGIC) << drape_last_error();
  EXPECT_EQ(drape_asset_load(nullptr, &asset), DRAPE_INVALID_ARGUMENT);
  EXPECT_NE(std::string(drape_last_error()).find("path is NULL"), std::string::npos);

  ASSERT_EQ(drape_asset_load(kAsset.c_str(), &asset), DRAPE_OK);
  EXPECT_EQ(drape_asset_find_joint(asset, "no such joint"), -1);
  float m[12];
  EXPECT_EQ(drape_asset_bind_matrix(asset, 100000, m), DRAPE_INVALID_ARGUMENT);
  drape_pose* pose = nullptr;
  ASSERT_EQ(drape_pose_create(asset, &pose), DRAPE_OK);
  EXPECT_EQ(drape_pose_sample_clip(pose, 99, 0.f, 1), DRAPE_INVALID_ARGUMENT);
  std::vector<float> world(12 * drape_asset_joint_count(asset), std::nanf(""));
  EXPECT_EQ(drape_pose_set_world_matrices(pose, world.data(), drape_asset_joint_count(asset)),
            DRAPE_INVALID_ARGUMENT);

  // A cloth with a bad setting, then a step with a bad frame.
  const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const uint32_t triangles[3] = {0, 1, 2};
  drape_cloth_desc desc;
  drape_cloth_desc_default(&desc);
  desc.positions = positions;
  desc.particle_count = 3;
  desc.triangles = triangles;
  desc.triangle_count = 1;
  drape_solver_settings settings;
  drape_solver_settings_default(&settings);
  settings.substeps = 0;
  drape_cloth* cloth = nullptr;
  EXPECT_EQ(drape_cloth_create(&desc, &settings, &cloth), DRAPE_INVALID_ARGUMENT);
  EXPECT_NE(std::string(drape_last_error()).find("substeps"), std::string::npos);
  EXPECT_EQ(cloth, nullptr);
  drape_solver_settings_default(&settings);
  settings.friction = 2.f;
  EXPECT_EQ(drape_cloth_create(&desc, &settings, &cloth), DRAPE_INVALID_ARGUMENT);
  drape_solver_settings_default(&settings);
  ASSERT_EQ(drape_cloth_create(&desc, &settings, &cloth), DRAPE_OK);
  EXPECT_EQ(drape_cloth_particle_count(cloth), 3u);
  EXPECT_EQ(drape_cloth_step(cloth, -1.f, nullptr, nullptr, 0, nullptr, nullptr, nullptr),
            DRAPE_INVALID_ARGUMENT);
  EXPECT_EQ(drape_cloth_step(cloth, 1.f / 60.f, nullptr, nullptr, 0, nullptr, nullptr, nullptr),
            DRAPE_OK);
  const float shear[12] = {2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  EXPECT_EQ(drape_cloth_teleport(cloth, shear), DRAPE_INVALID_ARGUMENT);
  drape_shapes* shapes = nullptr;
  ASSERT_EQ(drape_shapes_create(1, &shapes), DRAPE_OK);
  EXPECT_EQ(drape_shapes_add_sphere(shapes, shear, shear, 0.1f), DRAPE_INVALID_ARGUMENT);
  EXPECT_EQ(drape_shapes_add_sphere(shapes, nullptr, shear, 0.1f), DRAPE_INVALID_ARGUMENT);
  EXPECT_EQ(drape_shapes_add_asset_capsules(shapes, asset, nullptr, shear), DRAPE_INVALID_ARGUMENT);
  EXPECT_EQ(drape_asset_capsule_count(nullptr), 0u);
  drape_shapes_destroy(shapes);
  drape_cloth_destroy(cloth);
  drape_pose_destroy(pose);
  drape_asset_destroy(asset);
  drape_asset_destroy(nullptr);  // ignored
}

}  // namespace
}  // namespace drape

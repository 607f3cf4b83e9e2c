// What a game engine does with drape, through the installed runtime alone: load a .drape, then
// every frame hand the runtime the engine's own joint world matrices (here sampled from the
// file's first clip, standing in for the engine's animation system) and step a skirt skinned to
// the root joint (its waistband follows the skin exactly, the rest within 15 cm of it) against
// the hull and sphere colliders and the engine's own shapes: a floor and a capsule (a staff the
// engine swings through the skirt). drape runs its stages on the engine's own job system
// (engine_jobs.h: two threads here) through drape::TaskSystem.   Usage: engine_sample FILE.drape
#include <cmath>
#include <cstdio>
#include <vector>

#include "drape/formats/asset_file.h"
#include "drape/runtime/cloth_solver.h"
#include "drape/runtime/garments.h"
#include "drape/runtime/math.h"
#include "drape/runtime/shape_collider_set.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/task_system.h"
#include "engine_jobs.h"

static bool Check(const drape::Status& s) {
  if (!s.ok()) std::fprintf(stderr, "engine_sample: %s\n", s.message().c_str());
  return s.ok();
}

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: engine_sample FILE.drape\n");
    return 2;
  }
  // At start-up: drape runs in parallel only through the engine's job system.
  EngineJobs jobs(2);
  drape::SetTaskSystem(&jobs);
  struct Unset {
    ~Unset() { drape::SetTaskSystem(nullptr); }  // before `jobs` goes
  } unset;
  drape::CharacterAsset asset;
  if (!Check(drape::ReadAssetFile(argv[1], &asset))) return 1;
  if (asset.clips.empty()) {
    std::fprintf(stderr,
                 "engine_sample: %s: no clip to animate the skeleton with (this sample stands in "
                 "for an engine's animation with the file's first clip)\n",
                 argv[1]);
    return 1;
  }
  drape::SkeletonPose engine_animation, pose;  // the engine's animation; drape's view of it
  drape::HullColliderSet colliders;
  const uint32_t joints = asset.skeleton.joint_count();
  if (!Check(engine_animation.Init(asset.skeleton)) || !Check(pose.Init(asset.skeleton)) ||
      !Check(colliders.Build(asset.hulls, asset.joint_spheres, joints)))
    return 1;
  // A skirt whose waistband is held by the root joint, 3 cm above it in the bind pose.
  drape::Mat34 root;
  drape::InverseAffine(asset.skeleton.inverse_bind[0], &root);
  drape::SkirtShape shape;
  shape.top_center = {root.m[3], root.m[7] + 0.03f, root.m[11]};
  shape.top_radius = 0.19f;
  drape::GarmentMesh mesh;
  if (!Check(drape::MakeSkirt(shape, &mesh))) return 1;
  // Skinned: every particle carried by the root joint (weight 1), the waistband exactly (max
  // distance 0), the rest free within 15 cm of where the skin puts it.
  drape::ClothDescription description;
  description.positions = mesh.positions;
  description.triangles = mesh.triangles;
  description.skin.assign(mesh.positions.size(), drape::ClothSkinWeights{});
  for (drape::ClothSkinWeights& w : description.skin) w.weights[0] = 1.f;
  description.max_distance.assign(mesh.positions.size(), 0.15f);
  for (const uint32_t waist : mesh.held) description.max_distance[waist] = 0.f;
  drape::Cloth cloth;
  drape::ClothSolver solver;
  drape::ClothSolverSettings settings;  // tethers, a 10 % strain limit, Verlet
  settings.substeps = 4;
  if (!Check(drape::BuildCloth(description, &cloth)) || !Check(solver.Init(cloth, settings)))
    return 1;
  drape::ClothState state;
  state.Reset(cloth);
  // The engine's own colliders, re-posed every frame: room for two, allocated once.
  drape::ShapeColliderSet engine_shapes;
  engine_shapes.Reserve(2, 0);
  const auto staff_at = [&](int frame) {  // a 0.6 m capsule sweeping side to side at knee height
    drape::Mat34 m;
    m.m[3] = root.m[3] + 0.4f * std::sin(0.05f * static_cast<float>(frame));
    m.m[7] = root.m[7] * 0.5f;
    m.m[11] = root.m[11] + 0.25f;
    return m;
  };
  const float dt = 1.f / 60.f;
  std::vector<drape::Mat34> start(joints), end(joints);
  for (int frame = 0; frame <= 120; ++frame) {
    // The engine poses its skeleton and hands drape the joint world matrices (asset frame).
    if (!Check(engine_animation.SampleClip(asset.clips[0], static_cast<float>(frame) * dt, true)) ||
        !Check(pose.SetJointWorldMatrices(engine_animation.world())))
      return 1;
    end.assign(pose.skinning().begin(), pose.skinning().end());
    if (frame == 0) {
      start = end;
      if (!Check(solver.Reset(&state, {}, end))) return 1;  // at the skinned positions
    }
    engine_shapes.Clear();
    if (!Check(engine_shapes.AddPlane(drape::Mat34{}, drape::Mat34{})) ||  // the floor, y = 0
        !Check(engine_shapes.AddCapsule(staff_at(frame - 1), staff_at(frame), 0.3f, 0.03f, 0.03f)))
      return 1;
    drape::ClothColliders hit;
    hit.hulls = &colliders;
    hit.shapes = &engine_shapes;
    drape::ClothStepStats stats;
    if (!Check(solver.Step(&state, hit, {dt, start, end}, &stats))) return 1;
    if (frame % 30 == 0)
      std::printf(
          "engine_sample: frame %3d  contacts %4u (staff and floor %3u)  max stretch %.3f\n", frame,
          stats.contacts, stats.shape_contacts, static_cast<double>(stats.max_stretch));
    start = end;
  }
  return 0;
}

// What a game engine does with drape, through the installed runtime alone: load a .drape, then
// every frame hand the runtime the engine's own joint world matrices (here sampled from the
// file's first clip, standing in for the engine's animation system) and step a skirt held at the
// root joint against the hull and sphere colliders.   Usage: engine_sample FILE.drape
#include <cstdio>
#include <vector>

#include "drape/formats/asset_file.h"
#include "drape/runtime/cloth_solver.h"
#include "drape/runtime/garments.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"

static bool Check(const drape::Status& s) {
  if (!s.ok()) std::fprintf(stderr, "engine_sample: %s\n", s.message().c_str());
  return s.ok();
}

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: engine_sample FILE.drape\n");
    return 2;
  }
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
  drape::ClothDescription description = drape::DescribeAttachedGarment(mesh, 0);
  drape::Cloth cloth;
  drape::ClothSolver solver;
  drape::ClothSolverSettings settings = drape::ClothSolverSettings::PaperB();
  settings.substeps = 4;
  if (!Check(drape::BuildCloth(description, &cloth)) || !Check(solver.Init(cloth, settings)))
    return 1;
  drape::ClothState state;
  state.Reset(cloth);
  const float dt = 1.f / 60.f;
  std::vector<drape::Mat34> start(joints), end(joints);
  for (int frame = 0; frame <= 120; ++frame) {
    // The engine poses its skeleton and hands drape the joint world matrices (asset frame).
    if (!Check(engine_animation.SampleClip(asset.clips[0], static_cast<float>(frame) * dt, true)) ||
        !Check(pose.SetJointWorldMatrices(engine_animation.world())))
      return 1;
    end.assign(pose.skinning().begin(), pose.skinning().end());
    if (frame == 0) start = end;
    drape::ClothColliders hit{nullptr, &colliders, {}};
    drape::ClothStepStats stats;
    if (!Check(solver.Step(&state, hit, {dt, start, end}, &stats))) return 1;
    if (frame % 30 == 0)
      std::printf("engine_sample: frame %3d  contacts %4u  max stretch %.3f\n", frame,
                  stats.contacts, static_cast<double>(stats.max_stretch));
    start = end;
  }
  return 0;
}

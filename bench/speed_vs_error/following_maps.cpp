// The maps that follow a pose no bake saw, on the posed bodies: rendered at run time from the
// skinned mesh (BodyMapRenderer) and per-bone local maps baked once (BoneMapCollider), beside
// the rest pose's maps, which do not follow.

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "drape/bake/bake_config.h"
#include "drape/bake/body_map_baker.h"
#include "drape/bake/bone_map_baker.h"
#include "drape/bake/render_mesh.h"
#include "drape/runtime/body_map_renderer.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"
#include "measurement.h"
#include "sweep.h"

namespace drape::bench {
namespace {

// The least wall time of a few renders on one thread, milliseconds.
double RenderMilliseconds(BodyMapRenderer* renderer, std::span<const Mat34> skinning,
                          BodyMapCollider* maps) {
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  double best = 1e30;
  for (int k = 0; k < 5; ++k) {
    const auto start = std::chrono::steady_clock::now();
    (void)renderer->Render(skinning, maps);
    best = std::min(
        best, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                  .count());
  }
  omp_set_num_threads(threads);
  return best;
}

}  // namespace

void Measurement::MeasureFollowingMaps(const Context& context, const bake::Character& character,
                                       std::span<const Mat34> skinning) {
  const std::string& label = context.spec.label;
  const std::vector<uint32_t>& triangles = character.mesh.triangles;
  SkeletonPose pose;
  std::vector<Float3> rest(character.mesh.vertex_count());
  if (!pose.Init(character.skeleton).ok()) Fail(label + ": cannot pose the skeleton");
  pose.SetRest();
  if (!SkinMesh(character.mesh, pose.skinning(), rest).ok()) Fail(label + ": cannot skin");
  const std::vector<Mat34> rest_skinning(pose.skinning().begin(), pose.skinning().end());

  // The rest pose's maps, as a default bake holds them.
  const bake::BodyMapOptions o = BodyMapOptionsFor(MapSetting{}, view_axis_);
  BodyMapPose rest_maps;
  bake::BodyMapPoseStats stats;
  if (!bake::BakeBodyMapPose(rest, triangles, o, &rest_maps, &stats).ok())
    Fail(label + ": cannot bake the rest pose's maps");
  Measure(context, *MakeBodyMapMethod(rest_maps, DepthSampling::kNearest,
                                      "the rest pose's maps (N = 1024), not following the pose",
                                      stats.bytes));

  // Rendered from the skinned render mesh a default bake stores (the bind mesh when it keeps
  // none) on the rest maps' grid, at its texel and at 2x and 4x it (N = 1024, 512, 256 over the
  // body): the error each render millisecond buys.
  MeshData render_mesh;
  bake::RenderMeshReport simplified;
  if (!bake::SimplifyRenderMesh(character.mesh, bake::BakeConfig{}.maps_render_tolerance,
                                &render_mesh, &simplified)
           .ok())
    Fail(label + ": cannot simplify the render mesh");
  const MeshData& drawn = simplified.kept ? render_mesh : character.mesh;
  for (const int coarser : {1, 2, 4}) {
    BodyMapRenderOptions render;
    render.texel_size = rest_maps.texel_size * static_cast<float>(coarser);
    render.epsilon = o.epsilon;
    render.grid_x = rest_maps.origin_x;
    render.grid_y = rest_maps.origin_y;
    render.view_axis = rest_maps.view_axis;
    BodyMapRenderer renderer;
    BodyMapCollider rendered;
    if (!renderer.Init(drawn, render).ok()) Fail(label + ": cannot set up the renderer");
    const double ms = RenderMilliseconds(&renderer, skinning, &rendered);
    char setting[200];
    std::snprintf(setting, sizeof(setting),
                  "rendered from the skinned mesh (%.1f mm texel, whole body: %.2f ms per pose, "
                  "1 thread; %u of %u triangles)",
                  render.texel_size * 1e3, ms, drawn.triangle_count(),
                  character.mesh.triangle_count());
    Measure(context, *MakeBodyMapMethod(std::move(rendered), setting, 0));
  }

  // Per-bone local maps, baked once at the bind pose.
  bake::BoneMapOptions bones;
  bones.texel_size = bake::AutomaticBoneMapTexel(rest);
  BoneMapSet bone_maps;
  std::vector<bake::BoneMapStats> bone_stats;
  if (!bake::BakeBoneMaps(character.mesh, character.skeleton, rest_skinning, bones, &bone_maps,
                          &bone_stats)
           .ok()) {
    Fail(label + ": cannot bake bone maps");
  }
  size_t bytes = 0;
  for (const bake::BoneMapStats& b : bone_stats) bytes += b.bytes;
  char setting[160];
  std::snprintf(setting, sizeof(setting), "per-bone local maps (%.1f mm texel, %zu bones)",
                bones.texel_size * 1e3, bone_maps.maps.size());
  Measure(context, *MakeBoneMapMethod(bone_maps, character.skeleton.joint_count(), skinning,
                                      setting, bytes));
}

}  // namespace drape::bench

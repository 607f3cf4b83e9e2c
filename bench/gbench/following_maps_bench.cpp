// The body maps that follow any pose, on the mannequin (samples/mannequin) at its walk clip
// between keys: the cost of rendering the maps of a pose, and of the per-bone local maps' batch.
//
//  BM_RenderMaps/<region>/<threads>/<texel>/<mesh>
//                                     BodyMapRenderer::Render at the rest maps' texel (N = 1024
//                                     over the body: 1.7 mm) times <texel> (4: 7 mm, where the
//                                     people meet the error targets in drape-speed-vs-error);
//                                     region 0: the whole body, 1: a skirt's reach (hips to
//                                     knees, 0.6 x 0.7 x 0.6 m); mesh 0: the bind mesh (7 584
//                                     triangles), 1: its render mesh (SimplifyRenderMesh at the
//                                     bake's default tolerance), 2: the mannequin subdivided
//                                     (30 336 triangles, a dense game character), 3: that one's
//                                     render mesh. Reported: ms per pose, triangles drawn
//  BM_BoneMapsBatch/<threads>         BoneMapCollider::CollideBatch (SetPose included) on 10k
//                                     particles within 2 cm of the posed surface moving 5 mm;
//                                     ns_per_particle
//  BM_RenderedMapsBatch/<threads>     BodyMapCollider::CollideBatch on the rendered maps, the
//                                     same particles; ns_per_particle
//
// Built by bench/gbench/CMakeLists.txt with -DDRAPE_BUILD_BENCH=ON (bench_following_maps).

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <vector>

#include "drape/bake/bake_config.h"
#include "drape/bake/bone_map_baker.h"
#include "drape/bake/importer.h"
#include "drape/bake/render_mesh.h"
#include "drape/runtime/body_map_renderer.h"
#include "drape/runtime/bone_map_collider.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"
#include "subdivided_mesh.h"
#include "test_support.h"
#include "workers.h"

namespace drape {
namespace {

// The render mesh a default bake stores for `mesh`, or `mesh` when it keeps none.
MeshData RenderMesh(const MeshData& mesh) {
  MeshData out;
  bake::RenderMeshReport report;
  if (!bake::SimplifyRenderMesh(mesh, bake::BakeConfig{}.maps_render_tolerance, &out, &report).ok())
    std::abort();
  return report.kept ? out : mesh;
}

struct Scene {
  bake::Character character;
  MeshData meshes[4];           // BM_RenderMaps' <mesh>: bind, render, subdivided, its render mesh
  std::vector<Mat34> skinning;  // the walk between keys
  BoneMapSet bone_maps;
  float texel = 0.f;  // metres: the N = 1024 rest maps' texel
  std::vector<Float3> previous, current;
};

const Scene& TheScene() {
  static const Scene scene = [] {
    Scene s;
    if (!bake::ImportCharacter(test::MannequinPath(), bake::ImportOptions{}, &s.character).ok())
      std::abort();
    SkeletonPose pose;
    if (!pose.Init(s.character.skeleton).ok()) std::abort();
    pose.SetRest();
    std::vector<Float3> rest(s.character.mesh.vertex_count());
    (void)SkinMesh(s.character.mesh, pose.skinning(), rest);
    const std::vector<Mat34> rest_skinning(pose.skinning().begin(), pose.skinning().end());
    bake::BoneMapOptions options;
    options.texel_size = bake::AutomaticBoneMapTexel(rest);
    if (!bake::BakeBoneMaps(s.character.mesh, s.character.skeleton, rest_skinning, options,
                            &s.bone_maps)
             .ok())
      std::abort();
    s.meshes[0] = s.character.mesh;
    s.meshes[1] = RenderMesh(s.meshes[0]);
    s.meshes[2] = test::SubdividedMesh(s.meshes[0]);
    s.meshes[3] = RenderMesh(s.meshes[2]);
    float height = 0.f;
    for (const Float3& p : rest) height = std::max(height, p.y);
    s.texel = height / 1024.f;
    const ClipData& clip = s.character.clips.front();
    (void)pose.SampleClip(clip, 0.37f * clip.duration, false);
    s.skinning.assign(pose.skinning().begin(), pose.skinning().end());
    std::vector<Float3> posed(s.character.mesh.vertex_count());
    (void)SkinMesh(s.character.mesh, s.skinning, posed);
    std::mt19937 random(11);
    std::uniform_int_distribution<size_t> vertex(0, posed.size() - 1);
    std::uniform_real_distribution<float> offset(-0.02f, 0.02f), step(-0.005f, 0.005f);
    for (int k = 0; k < 10000; ++k) {
      const Float3 p =
          posed[vertex(random)] + Float3{offset(random), offset(random), offset(random)};
      s.previous.push_back(p);
      s.current.push_back(p + Float3{step(random), step(random), step(random)});
    }
    return s;
  }();
  return scene;
}

// The runtime's std::thread pool on `threads` workers (the serial task system for 1), the way an
// engine or drape-sim runs the runtime; the default again when it goes.
struct Workers {
  explicit Workers(int64_t threads) { test::UseWorkers(static_cast<int>(threads)); }
  ~Workers() { test::UseDefaultWorkers(); }
};

RenderRegion Region(int which) {
  RenderRegion r;
  if (which == 1) {
    r.min = {-0.3f, 0.45f, -0.3f};
    r.max = {0.3f, 1.15f, 0.3f};
  }
  return r;
}

void BM_RenderMaps(benchmark::State& state) {
  const Scene& s = TheScene();
  const Workers workers(state.range(1));
  BodyMapRenderOptions options;
  options.texel_size = s.texel * static_cast<float>(state.range(2));
  BodyMapRenderer renderer;
  if (!renderer.Init(s.meshes[state.range(3)], options).ok()) state.SkipWithError("init");
  BodyMapCollider maps;
  const RenderRegion region = Region(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    if (!renderer.Render(s.skinning, &maps, &region).ok()) state.SkipWithError("render");
    benchmark::DoNotOptimize(maps.stats().valid_texels);
  }
  state.counters["texels"] = static_cast<double>(renderer.stats().width) * renderer.stats().height;
  state.counters["triangles"] = static_cast<double>(s.meshes[state.range(3)].triangle_count());
  state.counters["ms_per_pose"] =
      benchmark::Counter(1e-3 * static_cast<double>(state.iterations()),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_RenderMaps)
    ->ArgsProduct({{0, 1}, {1, 2}, {1, 4}, {0, 1}})
    ->ArgsProduct({{0}, {1, 2}, {4}, {2, 3}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

template <class Collide>
void RunBatch(benchmark::State& state, const Scene& s, const Collide& collide) {
  std::vector<Float3> positions, velocities(s.current.size(), Float3{0.f, 0.f, 0.f});
  std::vector<uint8_t> flags(s.current.size());
  for (auto _ : state) {
    positions = s.current;
    collide(positions, velocities, flags);
    benchmark::DoNotOptimize(positions.data());
  }
  state.counters["ns_per_particle"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * static_cast<double>(s.current.size()) * 1e-9,
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_BoneMapsBatch(benchmark::State& state) {
  const Scene& s = TheScene();
  const Workers workers(state.range(0));
  BoneMapCollider bones;
  if (!bones.Build(s.bone_maps, s.character.skeleton.joint_count()).ok())
    state.SkipWithError("build");
  RunBatch(state, s, [&](std::vector<Float3>& p, std::vector<Float3>& v, std::vector<uint8_t>& f) {
    (void)bones.SetPose(s.skinning, s.skinning);
    (void)bones.CollideBatch(s.previous, p, v, f, ResponseParams{});
  });
}
BENCHMARK(BM_BoneMapsBatch)->Arg(1)->Arg(2)->UseRealTime();

void BM_RenderedMapsBatch(benchmark::State& state) {
  const Scene& s = TheScene();
  const Workers workers(state.range(0));
  BodyMapRenderOptions options;
  options.texel_size = s.texel;
  BodyMapRenderer renderer;
  BodyMapCollider maps;
  if (!renderer.Init(s.character.mesh, options).ok() || !renderer.Render(s.skinning, &maps).ok())
    state.SkipWithError("render");
  RunBatch(state, s, [&](std::vector<Float3>& p, std::vector<Float3>& v, std::vector<uint8_t>& f) {
    (void)maps.CollideBatch(s.previous, p, v, f, ResponseParams{});
  });
}
BENCHMARK(BM_RenderedMapsBatch)->Arg(1)->Arg(2)->UseRealTime();

}  // namespace
}  // namespace drape

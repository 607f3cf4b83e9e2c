// One 1/60 s frame of a 10 100-particle skirt (100 segments x 101 rings, waistband attached to
// the hips) on a walking pair of legs made of 20 colliders (4 box hulls: thighs and shins; 16
// joint spheres: hips, belly, thighs, knees, shins), with continuous collision and friction.
// Arguments: workers (1: the serial task system; 2: drape's std::thread pool of 2, or OpenMP's
// team of 2 with openmp = 1), substeps, colliders on (1) or off (0: the solver alone, the skirt
// then falls freely below its waistband), engine defaults (1: long-range tethers and the 10 %
// strain limit; 0: paper B's solver), openmp, stretch (1: ClothSolverSettings::measure_stretch,
// the worst-spring measure after each frame; 0: off, max_stretch_pct then reads 0), guard (1:
// ClothSolverSettings::guard_blowups, the per-substep backup and finite check; 0: off); 5
// spring-correction iterations per substep (Verlet). max_stretch_pct: the worst stretch spring over
// the timed frames. overstretched_per_frame: the stretch springs beyond the strain limit (10 %
// for paper B's solver) after a frame, the mean over the timed frames.
// BM_BulletSkirt is the peer: Bullet's soft body (bench/peers) on the same skirt mesh, masses and
// waistband, against the same 4 boxes (btConvexHullShape of their 8 corners)
// and 16 spheres posed by the same walk, 5 position iterations per substep, single-threaded.
// Both report the penetration of the particles into the boxes and spheres after each timed frame
// (measured outside the timed region): max_depth_mm over all frames, frame_max_depth_mm the mean
// of each frame's deepest particle, inside_per_frame the particles inside any collider. drape
// measures it on one worker only: the bits are the same at any worker count, and the pause lets
// a pool's idle workers fall asleep, so that every timed frame would pay to wake them.
// Run: build-<name>/bin/bench_cloth_step --benchmark_repetitions=5
//        --benchmark_report_aggregates_only=true

#include <benchmark/benchmark.h>
#if defined(_OPENMP)
#include <omp.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <span>
#include <vector>

#include "bullet_cloth_peer.h"
#include "walking_legs.h"

#include "drape/formats/hull_collider_data.h"
#include "drape/runtime/cloth.h"
#include "drape/runtime/cloth_solver.h"
#include "drape/runtime/garments.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"
#include "drape/runtime/task_system.h"

namespace drape {
namespace {

using test::kJoints;
using test::Penetration;
using test::WalkPose;
constexpr float kFrame = 1.f / 60.f;
struct Scene {
  Cloth cloth;
  HullColliderSet hulls;
  size_t collider_count = 0;
  GarmentMesh mesh;  // the skirt the cloth was built from (for the peer)
  // The colliders in their bind frame (for the peer and the penetration measure).
  test::WalkingLegs legs = test::MakeWalkingLegs();

  Scene() {
    collider_count = legs.size();
    Status s = hulls.Build(legs.boxes, legs.spheres, kJoints);
    if (!s.ok()) {
      std::fprintf(stderr, "hulls: %s\n", s.message().c_str());
      std::abort();
    }
    if (!MakeSkirt(test::WalkingSkirt(0.6f, 100, 100), &mesh).ok()) std::abort();
    ClothDescription d = DescribeAttachedGarment(mesh, 0);
    s = BuildCloth(d, &cloth);
    if (!s.ok()) {
      std::fprintf(stderr, "cloth: %s\n", s.message().c_str());
      std::abort();
    }
  }
};

Scene& GetScene() {
  static Scene scene;
  return scene;
}

// Accumulates Penetration over the timed frames and writes the counters.
struct PenetrationCounters {
  float max_depth = 0.f;
  double sum_frame_max = 0.0, sum_inside = 0.0;
  int frames = 0;
  void Add(const Penetration& p) {
    max_depth = std::max(max_depth, p.max_depth);
    sum_frame_max += p.max_depth;
    sum_inside += p.inside;
    ++frames;
  }
  void Report(benchmark::State& state) const {
    const double n = frames > 0 ? frames : 1;
    state.counters["max_depth_mm"] = 1000.0 * max_depth;
    state.counters["frame_max_depth_mm"] = 1000.0 * sum_frame_max / n;
    state.counters["inside_per_frame"] = sum_inside / n;
  }
};

void BM_ClothStep(benchmark::State& state) {
  const uint32_t workers = static_cast<uint32_t>(state.range(0));
  ThreadPoolTaskSystem pool(workers);
  TaskSystem* tasks = workers == 1 ? &SerialTaskSystem() : &pool;
  if (state.range(4) != 0) {
    tasks = OpenMpTaskSystem();
    if (tasks == nullptr) return state.SkipWithError("built without OpenMP");
#if defined(_OPENMP)
    omp_set_num_threads(static_cast<int>(workers));
#endif
  }
  SetTaskSystem(tasks);
  Scene& scene = GetScene();
  ClothSolverSettings settings = ClothSolverSettings::PaperB();
  settings.iterations = 5;
  settings.substeps = static_cast<uint32_t>(state.range(1));
  settings.damping = 0.2f;
  settings.measure_stages = true;
  settings.measure_stretch = state.range(5) != 0;
  settings.guard_blowups = state.range(6) != 0;
  if (state.range(3) != 0) {
    const ClothSolverSettings engine;
    settings.tethers = engine.tethers;
    settings.max_stretch = engine.max_stretch;
  }
  ClothSolver solver;
  if (!solver.Init(scene.cloth, settings).ok()) std::abort();
  ClothState cloth_state;
  cloth_state.Reset(scene.cloth);
  ClothColliders colliders;
  if (state.range(2) != 0) colliders.hulls = &scene.hulls;
  colliders.response.friction = 0.3f;
  Mat34 start[kJoints], end[kJoints];
  ClothFrame frame;
  frame.dt = kFrame;
  frame.skinning_start = start;
  frame.skinning_end = end;
  int step = 0;
  uint64_t contacts = 0, overstretched = 0;
  float worst_stretch = 0.f;
  ClothStageSeconds stages;
  const auto advance = [&]() {
    WalkPose(static_cast<float>(step) * kFrame, start);
    WalkPose(static_cast<float>(step + 1) * kFrame, end);
    ClothStepStats stats;
    const Status s = solver.Step(&cloth_state, colliders, frame, &stats);
    if (!s.ok()) {
      state.SkipWithError(s.message().c_str());
      return false;
    }
    contacts += stats.contacts;
    stages.integrate += stats.stage_seconds.integrate;
    stages.springs += stats.stage_seconds.springs;
    stages.constraints += stats.stage_seconds.constraints;
    stages.collide += stats.stage_seconds.collide;
    stages.bookkeeping += stats.stage_seconds.bookkeeping;
    worst_stretch = std::max(worst_stretch, stats.max_stretch);
    overstretched += stats.overstretched_springs;
    ++step;
    return true;
  };
  for (int warm = 0; warm < 60; ++warm)
    if (!advance()) return;  // one second: the skirt settles onto the legs
  contacts = 0;
  overstretched = 0;
  worst_stretch = 0.f;
  stages = ClothStageSeconds{};
  int timed = 0;
  PenetrationCounters penetration;
  const bool measure_depth = workers == 1 && state.range(4) == 0;
  for (auto _ : state) {
    if (!advance()) return;
    ++timed;
    if (!measure_depth) continue;
    state.PauseTiming();
    penetration.Add(test::MeasurePenetration(scene.legs, end, cloth_state.positions));
    state.ResumeTiming();
  }
  state.counters["particles"] = static_cast<double>(scene.cloth.particle_count());
  state.counters["springs"] = static_cast<double>(scene.cloth.springs().size());
  state.counters["colliders"] = static_cast<double>(scene.collider_count);
  state.counters["contacts_per_frame"] = timed > 0 ? static_cast<double>(contacts) / timed : 0.0;
  state.counters["max_stretch_pct"] = 100.0 * worst_stretch;
  state.counters["overstretched_per_frame"] =
      timed > 0 ? static_cast<double>(overstretched) / timed : 0.0;
  // Stage times, ms per frame (ClothSolverSettings::measure_stages).
  const double per_frame_ms = timed > 0 ? 1e3 / timed : 0.0;
  state.counters["integrate_ms"] = stages.integrate * per_frame_ms;
  state.counters["springs_ms"] = stages.springs * per_frame_ms;
  state.counters["constraints_ms"] = stages.constraints * per_frame_ms;
  state.counters["collide_ms"] = stages.collide * per_frame_ms;
  state.counters["bookkeeping_ms"] = stages.bookkeeping * per_frame_ms;
  if (measure_depth) penetration.Report(state);
  SetTaskSystem(nullptr);
}
BENCHMARK(BM_ClothStep)
    ->ArgNames({"workers", "substeps", "colliders", "engine", "openmp", "stretch", "guard"})
    ->Args({1, 1, 1, 0, 0, 1, 1})
    ->Args({2, 1, 1, 0, 0, 1, 1})
    ->Args({2, 1, 1, 0, 1, 1, 1})
    ->Args({1, 2, 1, 0, 0, 1, 1})
    ->Args({2, 2, 1, 0, 0, 1, 1})
    ->Args({1, 1, 0, 0, 0, 1, 1})
    ->Args({1, 1, 0, 0, 0, 0, 1})
    ->Args({1, 1, 1, 0, 0, 0, 1})
    ->Args({1, 1, 1, 0, 0, 0, 0})
    ->Args({1, 1, 0, 0, 0, 0, 0})
    ->Args({2, 1, 1, 0, 0, 0, 0})
    ->Args({2, 1, 0, 0, 0, 0, 0})
    ->Args({2, 1, 0, 0, 0, 1, 1})
    ->Args({2, 1, 0, 0, 1, 1, 1})
    ->Args({1, 1, 1, 1, 0, 1, 1})
    ->Args({2, 1, 1, 1, 0, 1, 1})
    ->Args({1, 1, 0, 1, 0, 1, 1})
    ->Args({2, 1, 0, 1, 0, 1, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The same frame in Bullet. Mapping of the drape settings: the same particle masses (inverse
// mass 0 for the waistband, driven to hips * bind position), stretch links with full correction
// (kLST 1) and Bullet's distance-2 bending links with drape's bend correction (kLST 0.2), the
// velocity damping of 0.2 1/s as kDP = 1 - exp(-0.2 h) per substep of h seconds, friction 0.3
// (kDF), contact hardness 1 (kKHR: Bullet's 0.1 lets the cloth sink through), soft body margin
// 2 mm, a 5 mm SDF voxel. Argument: substeps.
void BM_BulletSkirt(benchmark::State& state) {
  Scene& scene = GetScene();
  const uint32_t substeps = static_cast<uint32_t>(state.range(0));
  peers::BulletClothSetup setup;
  setup.positions = scene.mesh.positions;
  setup.triangles = scene.mesh.triangles;
  const std::span<const float> inverse_masses = scene.cloth.inverse_masses();
  setup.inverse_masses.assign(inverse_masses.begin(), inverse_masses.end());
  setup.iterations = 5;
  setup.substeps = substeps;
  setup.damping = 1.f - std::exp(-0.2f * kFrame / static_cast<float>(substeps));
  setup.friction = 0.3f;
  setup.stretch_stiffness = scene.cloth.material(SpringKind::kStretch).correction;
  setup.bend_stiffness = scene.cloth.material(SpringKind::kBend).correction;
  std::vector<peers::BulletHullShape> hulls;
  for (const HullColliderData& box : scene.legs.boxes) hulls.push_back({box.vertices});
  std::vector<float> radii;
  for (const JointSphereData& sphere : scene.legs.spheres) radii.push_back(sphere.radius);
  peers::BulletClothPeer peer;
  Status s = peer.Build(setup, hulls, radii);
  if (!s.ok()) {
    state.SkipWithError(s.message().c_str());
    return;
  }
  // The attached particles in index order (Cloth::attachments() is sorted by particle) and
  // their bind positions: their targets are skinning(joint) * bind_position.
  const std::span<const ClothAttachment> attachments = scene.cloth.attachments();
  if (attachments.size() != peer.attached_count()) {
    state.SkipWithError("attachments and zero inverse masses differ");
    return;
  }
  Mat34 skinning[kJoints];
  std::vector<Mat34> hull_world(scene.legs.boxes.size());
  std::vector<Float3> sphere_centres(scene.legs.spheres.size()), targets(attachments.size());
  std::vector<Float3> positions(peer.particle_count());
  const auto pose = [&](int frame) {
    WalkPose(static_cast<float>(frame) * kFrame, skinning);
    for (size_t b = 0; b < scene.legs.boxes.size(); ++b)
      hull_world[b] = Multiply(skinning[scene.legs.boxes[b].joint], scene.legs.boxes[b].bind_frame);
    for (size_t c = 0; c < scene.legs.spheres.size(); ++c)
      sphere_centres[c] =
          TransformPoint(skinning[scene.legs.spheres[c].joint], scene.legs.spheres[c].center);
    for (size_t a = 0; a < attachments.size(); ++a)
      targets[a] = TransformPoint(skinning[attachments[a].joint], attachments[a].bind_position);
  };
  pose(0);
  s = peer.SetInitialPose(hull_world, sphere_centres);
  int step = 0;
  uint64_t contacts = 0;
  const auto advance = [&]() {
    pose(step + 1);  // the end of the frame
    const Status st = peer.Step(hull_world, sphere_centres, targets, kFrame);
    if (!st.ok()) {
      state.SkipWithError(st.message().c_str());
      return false;
    }
    contacts += peer.last_contact_count();
    ++step;
    return true;
  };
  if (!s.ok()) {
    state.SkipWithError(s.message().c_str());
    return;
  }
  for (int warm = 0; warm < 60; ++warm)
    if (!advance()) return;
  contacts = 0;
  int timed = 0;
  PenetrationCounters penetration;
  for (auto _ : state) {
    if (!advance()) return;
    ++timed;
    state.PauseTiming();
    peer.CopyPositions(positions);
    penetration.Add(test::MeasurePenetration(scene.legs, skinning, positions));
    state.ResumeTiming();
  }
  state.counters["particles"] = static_cast<double>(peer.particle_count());
  state.counters["springs"] = static_cast<double>(peer.link_count());  // edge + bending links
  state.counters["colliders"] = static_cast<double>(scene.collider_count);
  // Bullet's node contacts of the last substep of each frame.
  state.counters["contacts_per_frame"] = timed > 0 ? static_cast<double>(contacts) / timed : 0.0;
  penetration.Report(state);
}
BENCHMARK(BM_BulletSkirt)
    ->ArgNames({"substeps"})
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace drape

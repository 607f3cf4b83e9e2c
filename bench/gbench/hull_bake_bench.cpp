// Bake cost of the per-bone convex collider (bake/include/drape/bake/hull_builder.h).
//  BM_HullBake/<points>/<simplify mode>/<triangle budget>: one limb-like bone (points on a
//    tapered capsule, 25 cm x 3.5 cm, like a forearm), delta 5 mm, max_growth 5 mm (50 mm for
//    the budget sweep so that the budget, not the bound, stops it). Counters: growth_mm (surface
//    beyond the inflated hull), tris/planes after, H0 tris, budget_reached.
//    Modes: 0 = edge collapse (default), 1 = plane removal, 2 = none.
//  BM_HullBakeObb/<obb mode>: the same 400-point bone with the covariance or the CGAL OBB.
//  BM_CesiumManHulls: every bone of CesiumMan (rigid threshold 0.99), one thread, default options.
//  BM_WholeBake/<character>: BakeCharacter with the default config, wall time on the bake's
//    OpenMP team: 0 Animated_Human rescaled to 1.75 m (import.unit_scale), 1 Animated_Human as
//    its file gives it (5.3 m tall: max_bloat is in metres, so more convex pieces), 2 CesiumMan.
//  BM_KirkpatrickBuild/<levels>: both point-location hierarchies of a tilted ellipsoid hull
//    (icosphere subdivided `levels` times: 80, 320, 1280 faces; default options, so the auto axis
//    builds all three). Counters: levels and nodes per side, mean_tests (node tests per location).
//  BM_MapTableBuild/<levels>/<rows>: the map cylinder of the same hull with rows x rows cells.
//    Counters: mean_list, max_list, empty_cells (a conservative table has none).

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "drape/bake/bake_config.h"
#include "drape/bake/bake_pipeline.h"
#include "drape/bake/hull_builder.h"
#include "drape/bake/importer.h"
#include "drape/bake/kirkpatrick_builder.h"
#include "drape/bake/map_table_builder.h"
#include "drape/bake/regions.h"
#include "drape/runtime/math.h"
#include "hull_fixtures.h"
#include "test_support.h"

namespace drape::bake {
namespace {

double Uniform(uint64_t* state, double lo, double hi) {
  uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  z ^= z >> 31;
  return lo + (hi - lo) * static_cast<double>(z >> 11) * 0x1.0p-53;
}

std::vector<Float3> LimbCloud(int count) {
  uint64_t state = 12345;
  std::vector<Float3> points;
  const double length = 0.25, radius = 0.035;
  for (int i = 0; i < count; ++i) {
    const double t = Uniform(&state, 0.0, length);
    const double angle = Uniform(&state, 0.0, 2.0 * M_PI);
    const double r = radius * (1.0 - 0.2 * t / length) * Uniform(&state, 0.9, 1.0);
    points.push_back({static_cast<float>(t), static_cast<float>(0.02 + r * std::cos(angle)),
                      static_cast<float>(-0.01 + r * std::sin(angle))});
  }
  return points;
}

void Report(benchmark::State& state, const HullStats& stats) {
  state.counters["growth_mm"] = stats.growth_mm;
  state.counters["tris"] = stats.triangles_after;
  state.counters["planes"] = stats.planes_after;
  state.counters["h0_tris"] = stats.hull_triangles_before;
  state.counters["budget_reached"] = stats.budget_reached ? 1 : 0;
}

void BM_HullBake(benchmark::State& state) {
  const std::vector<Float3> points = LimbCloud(static_cast<int>(state.range(0)));
  HullOptions options;
  options.simplify = static_cast<SimplifyMode>(state.range(1));
  options.max_triangles = static_cast<uint32_t>(state.range(2));
  if (state.range(3) != 0) options.max_growth = 0.05f;
  HullStats stats;
  for (auto _ : state) {
    HullColliderData collider;
    const Status status = BuildHullGeometry(points, options, &collider, &stats);
    if (!status.ok()) {
      state.SkipWithError(status.message().c_str());
      break;
    }
    benchmark::DoNotOptimize(collider.planes.data());
  }
  Report(state, stats);
}
// Time per bone against cloud size, every simplification mode, budget 100.
BENCHMARK(BM_HullBake)
    ->ArgNames({"points", "mode", "budget", "loose"})
    ->ArgsProduct({{50, 200, 400}, {0, 1, 2}, {100}, {0}})
    ->Unit(benchmark::kMillisecond);
// Growth against the triangle budget (max_growth 50 mm so the budget decides).
BENCHMARK(BM_HullBake)
    ->ArgNames({"points", "mode", "budget", "loose"})
    ->ArgsProduct({{400}, {0, 1}, {16, 25, 50, 100, 200, 400}, {1}})
    ->Unit(benchmark::kMillisecond);

void BM_HullBakeObb(benchmark::State& state) {
  const std::vector<Float3> points = LimbCloud(400);
  HullOptions options;
  options.obb = static_cast<ObbMode>(state.range(0));
  HullStats stats;
  for (auto _ : state) {
    HullColliderData collider;
    const Status status = BuildHullGeometry(points, options, &collider, &stats);
    if (!status.ok()) {
      state.SkipWithError(status.message().c_str());
      break;
    }
    benchmark::DoNotOptimize(collider.obb);
  }
  Report(state, stats);
  state.counters["obb_cm3"] = stats.obb_volume * 1e6;
  state.counters["obb_ms"] = stats.obb_ms;
}
BENCHMARK(BM_HullBakeObb)->ArgName("obb")->DenseRange(0, 1)->Unit(benchmark::kMillisecond);

// Every bone of CesiumMan, as the bake pipeline feeds them with its default config (rigid and
// shaping vertices in the collider frame).
void BM_CesiumManHulls(benchmark::State& state) {
  const std::string path = test::CharacterPath("CesiumMan/CesiumMan.glb");
  if (!std::filesystem::exists(path)) {
    state.SkipWithError(("shared asset absent: " + path).c_str());
    return;
  }
  Character character;
  Regions regions;
  if (!ImportCharacter(path, ImportOptions{}, &character).ok() ||
      !SplitRegions(character, BakeConfig{}.rigid_threshold, &regions, BakeConfig{}.shape_threshold)
           .ok()) {
    state.SkipWithError("CesiumMan import or region split failed");
    return;
  }
  std::vector<std::vector<Float3>> bones;
  for (size_t j = 0; j < regions.rigid_vertices.size(); ++j) {
    const Mat34 to_collider = InverseRigid(regions.collider_frames[j]);
    std::vector<Float3> points;
    for (uint32_t v : regions.rigid_vertices[j]) {
      points.push_back(TransformPoint(to_collider, regions.rest_positions[v]));
    }
    for (uint32_t v : regions.shaping_vertices[j]) {
      points.push_back(TransformPoint(to_collider, regions.rest_positions[v]));
    }
    if (!points.empty()) bones.push_back(std::move(points));
  }
  const HullOptions options;
  double built = 0, skipped = 0, max_ms = 0, max_growth = 0, triangles = 0, points_total = 0;
  for (auto _ : state) {
    built = skipped = max_ms = max_growth = triangles = points_total = 0;
    for (const std::vector<Float3>& points : bones) {
      HullColliderData collider;
      HullStats stats;
      points_total += static_cast<double>(points.size());
      if (BuildHullGeometry(points, options, &collider, &stats).ok()) {
        ++built;
        max_ms = std::max(max_ms, stats.ms);
        max_growth = std::max(max_growth, static_cast<double>(stats.growth_mm));
        triangles += stats.triangles_after;
      } else {
        ++skipped;
      }
    }
  }
  state.counters["bones"] = built;
  state.counters["skipped"] = skipped;
  state.counters["points"] = points_total;
  state.counters["max_bone_ms"] = max_ms;
  state.counters["max_growth_mm"] = max_growth;
  state.counters["mean_tris"] = built > 0 ? triangles / built : 0.0;
}
BENCHMARK(BM_CesiumManHulls)->Unit(benchmark::kMillisecond)->Iterations(3);

// The whole bake of a shared character (import, regions, maps, hulls and their convex pieces,
// spheres, capsules, the fit measure, validation) with the default config.
void BM_WholeBake(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0));
  const std::string path = test::CharacterPath(
      which == 2 ? "CesiumMan/CesiumMan.glb" : "QuaterniusAnimatedHuman/Animated_Human.fbx");
  if (!std::filesystem::exists(path)) {
    state.SkipWithError(("shared asset absent: " + path).c_str());
    return;
  }
  BakeConfig config;
  // The FBX's units give a 5.26 m body at unit_scale 0.01; this makes it 1.75 m.
  if (which == 0) config.import.unit_scale = 0.01 * 1.75 / 5.2596;
  BakeResult result;
  for (auto _ : state) {
    if (!BakeCharacter(path, config, &result).ok()) {
      state.SkipWithError(("bake failed: " + path).c_str());
      return;
    }
  }
  state.counters["joints"] = static_cast<double>(result.asset.skeleton.joint_count());
  state.counters["hulls"] = static_cast<double>(result.asset.hulls.size());
}
BENCHMARK(BM_WholeBake)
    ->ArgName("character")
    ->DenseRange(0, 2)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->UseRealTime();

// The elongated hull of the Kirkpatrick and map-table tests: a tilted ellipsoid 12 x 50 x 16 cm.
HullColliderData TiltedEllipsoid(int levels) {
  Float3 axes[3];
  test::RotatedAxes(21.0, {0.2f, 1.f, -0.7f}, axes);
  return test::MakeEllipsoid({0.06f, 0.25f, 0.08f}, levels, {0.f, 0.4f, 0.f}, axes);
}

void BM_KirkpatrickBuild(benchmark::State& state) {
  const HullColliderData hull = TiltedEllipsoid(static_cast<int>(state.range(0)));
  KirkpatrickStats stats;
  for (auto _ : state) {
    HullColliderData h = hull;
    const Status status = BuildKirkpatrick(&h, KirkpatrickOptions{}, &stats);
    if (!status.ok()) {
      state.SkipWithError(status.message().c_str());
      break;
    }
    benchmark::DoNotOptimize(h.upper.children.data());
  }
  state.counters["faces"] = static_cast<double>(hull.triangles.size() / 3);
  state.counters["upper_levels"] = stats.upper.levels;
  state.counters["lower_levels"] = stats.lower.levels;
  state.counters["upper_nodes"] = stats.upper.nodes;
  state.counters["lower_nodes"] = stats.lower.nodes;
  state.counters["mean_tests"] = stats.mean_tests;
}
BENCHMARK(BM_KirkpatrickBuild)->ArgName("levels")->DenseRange(1, 3)->Unit(benchmark::kMillisecond);

void BM_MapTableBuild(benchmark::State& state) {
  const HullColliderData hull = TiltedEllipsoid(static_cast<int>(state.range(0)));
  MapTableOptions options;
  options.cylinder_rows = static_cast<uint32_t>(state.range(1));
  options.cylinder_cols = static_cast<uint32_t>(state.range(1));
  MapTableStats stats;
  for (auto _ : state) {
    HullColliderData h = hull;
    const Status status = BuildMapTable(&h, options, &stats);
    if (!status.ok()) {
      state.SkipWithError(status.message().c_str());
      break;
    }
    benchmark::DoNotOptimize(h.map.cell_triangles.data());
  }
  state.counters["faces"] = static_cast<double>(hull.triangles.size() / 3);
  state.counters["cylinder"] = stats.kind == MapTableKind::kCylinder ? 1 : 0;
  state.counters["mean_list"] = stats.mean_list;
  state.counters["max_list"] = stats.max_list;
  state.counters["empty_cells"] = stats.empty_cells;
}
BENCHMARK(BM_MapTableBuild)
    ->ArgNames({"levels", "rows"})
    ->ArgsProduct({{1, 3}, {16, 64}})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace drape::bake

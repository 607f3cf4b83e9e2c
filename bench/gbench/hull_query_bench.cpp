// Paper B's proxy colliders at run time (drape/runtime/hull_collider_set.h): cost of the per-pair
// steps and of a whole character-like scene. Hulls are tessellated ellipsoids (icosphere,
// `levels` subdivisions: 0 -> 20 faces, 1 -> 80, 2 -> 320; every face its own plane) and a box,
// hierarchies and map tables from the bake builders. Reported: ns_per_particle (or per query).
//
//  BM_ObbRejection                  ObbMayContainLocal, points in a box 3x the OBB (87 % outside)
//  BM_PlaneInside/<levels>          InsideLocal(kPlanes): SSE max over the planes, points 50 %
//                                   uniform in the OBB + 50 % within 5 mm of the surface
//  BM_KirkpatrickInside/<levels>    InsideLocal(kKirkpatrick): both hierarchies + two planes
//  BM_KirkpatrickLocate/<levels>    LocateLocal (upper hierarchy only)
//  BM_Response/<levels>/<mode>      QueryHullLocal(p, p) for points inside the hull: the whole
//                                   narrow phase (dual plane kernel + response); mode 0 push-out,
//                                   1 map-table ray
//  BM_MapTableRay/<levels>          MapTableRayLocal alone: cell lookup + watertight ray tests
//  BM_Segment/<levels>              QueryHullLocal(a, b) for 2 cm segments near the surface
//                                   (continuous test; about a third enter the hull)
//  BM_Scene/<threads>/<mode>/<dist> CollideBatch of 100k particles around a 1.7 m figure of 14
//                                   hulls (80 faces each) and 6 joint spheres, bone motion over
//                                   the step; mode 0 push-out, 1 map-table ray, 2 Kirkpatrick;
//                                   dist 0: within 3 cm of a hull surface (~40 % in contact),
//                                   1: uniform in the figure's box grown by 10 cm, 2: 5 m away
//                                   (broad phase and loop overhead only)
//
// Built by bench/gbench/CMakeLists.txt with -DDRAPE_BUILD_BENCH=ON (bench_hull_query; links
// drape_bake for the builders). Run: build-X/bin/bench_hull_query --benchmark_min_time=0.2

#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "drape/bake/kirkpatrick_builder.h"
#include "drape/bake/map_table_builder.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"
#include "hull/hull_collider_set_access.h"
#include "hull_fixtures.h"

namespace drape {
namespace {

// Hand-made hulls and helpers shared with the other hull tests (tests/support/hull_fixtures.h).
using test::MakeEllipsoid;
using test::RotatedAxes;
using test::RotationAbout;

// A baked test hull: tilted ellipsoid with hierarchies and a map table.
HullColliderData BakedHull(int levels) {
  Float3 axes[3];
  RotatedAxes(37.0, {1.f, 2.f, 3.f}, axes);
  HullColliderData h = MakeEllipsoid({0.05f, 0.14f, 0.06f}, levels, {0.1f, 0.3f, -0.05f}, axes);
  bake::BuildKirkpatrick(&h).message();
  bake::BuildMapTable(&h).message();
  return h;
}

struct Single {
  HullColliderData data;
  HullColliderSet set;
  std::vector<Float3> mixed;   // 50 % uniform in the OBB, 50 % within 5 mm of the surface
  std::vector<Float3> inside;  // inside the hull
  std::vector<Float3> seg_a, seg_b;
};

const Single& GetSingle(int levels) {
  static Single cache[3];
  Single& s = cache[levels];
  if (!s.mixed.empty()) return s;
  s.data = BakedHull(levels);
  HullColliderOptions all;
  all.inside_test = InsideTest::kPlanes;
  s.set.Build(std::vector<HullColliderData>{s.data}, {}, 1, all).message();
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.f, 1.f), near(-0.005f, 0.005f), unit(0.f, 1.f);
  const HullColliderData& h = s.data;
  auto in_obb = [&](float grow) {
    return h.obb.center + h.obb.axes[0] * (u(rng) * grow * h.obb.half_extents.x) +
           h.obb.axes[1] * (u(rng) * grow * h.obb.half_extents.y) +
           h.obb.axes[2] * (u(rng) * grow * h.obb.half_extents.z);
  };
  auto near_surface = [&]() {
    const uint32_t t = static_cast<uint32_t>(rng() % (h.triangles.size() / 3));
    float r1 = unit(rng), r2 = unit(rng);
    if (r1 + r2 > 1.f) r1 = 1.f - r1, r2 = 1.f - r2;
    const Float3 a = h.vertices[h.triangles[3 * t]], b = h.vertices[h.triangles[3 * t + 1]],
                 c = h.vertices[h.triangles[3 * t + 2]];
    return a + (b - a) * r1 + (c - a) * r2 + h.planes[h.triangle_planes[t]].normal * near(rng);
  };
  while (s.mixed.size() < 65536)
    s.mixed.push_back(s.mixed.size() % 2 ? in_obb(1.f) : near_surface());
  std::shuffle(s.mixed.begin(), s.mixed.end(), rng);
  while (s.inside.size() < 65536) {
    const Float3 p = in_obb(1.f);
    if (HullColliderSetAccess::InsideLocal(s.set, 0, p, InsideTest::kPlanes)) s.inside.push_back(p);
  }
  std::uniform_real_distribution<float> step(-0.02f, 0.02f);
  while (s.seg_a.size() < 65536) {
    const Float3 a = near_surface();
    s.seg_a.push_back(a);
    s.seg_b.push_back(a + Float3{step(rng), step(rng), step(rng)});
  }
  return s;
}

void SetPerParticle(benchmark::State& state, size_t particles) {
  state.counters["ns_per_particle"] = benchmark::Counter(
      static_cast<double>(particles) * 1e-9,
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_ObbRejection(benchmark::State& state) {
  const Single& s = GetSingle(1);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-3.f, 3.f);
  const HullColliderData& h = s.data;
  std::vector<Float3> points;
  for (int i = 0; i < 65536; ++i)
    points.push_back(h.obb.center + h.obb.axes[0] * (u(rng) * h.obb.half_extents.x) +
                     h.obb.axes[1] * (u(rng) * h.obb.half_extents.y) +
                     h.obb.axes[2] * (u(rng) * h.obb.half_extents.z));
  uint32_t kept = 0;
  for (auto _ : state) {
    for (const Float3& p : points)
      kept += HullColliderSetAccess::ObbMayContainLocal(s.set, 0, p) ? 1u : 0u;
    benchmark::DoNotOptimize(kept);
  }
  SetPerParticle(state, points.size());
}
BENCHMARK(BM_ObbRejection);

void BM_PlaneInside(benchmark::State& state) {
  const Single& s = GetSingle(static_cast<int>(state.range(0)));
  uint32_t inside = 0;
  for (auto _ : state) {
    for (const Float3& p : s.mixed)
      inside += HullColliderSetAccess::InsideLocal(s.set, 0, p, InsideTest::kPlanes) ? 1u : 0u;
    benchmark::DoNotOptimize(inside);
  }
  SetPerParticle(state, s.mixed.size());
  state.counters["planes"] = s.set.plane_count(0);
}
BENCHMARK(BM_PlaneInside)->Arg(0)->Arg(1)->Arg(2);

void BM_KirkpatrickInside(benchmark::State& state) {
  const Single& s = GetSingle(static_cast<int>(state.range(0)));
  uint32_t inside = 0;
  for (auto _ : state) {
    for (const Float3& p : s.mixed)
      inside += HullColliderSetAccess::InsideLocal(s.set, 0, p, InsideTest::kKirkpatrick) ? 1u : 0u;
    benchmark::DoNotOptimize(inside);
  }
  SetPerParticle(state, s.mixed.size());
}
BENCHMARK(BM_KirkpatrickInside)->Arg(0)->Arg(1)->Arg(2);

void BM_KirkpatrickLocate(benchmark::State& state) {
  const Single& s = GetSingle(static_cast<int>(state.range(0)));
  int64_t sum = 0;
  uint64_t steps_total = 0;
  for (auto _ : state) {
    for (const Float3& p : s.mixed) {
      uint32_t steps;
      sum += HullColliderSetAccess::LocateLocal(s.set, 0, p, true, &steps);
      steps_total += steps;
    }
    benchmark::DoNotOptimize(sum);
  }
  SetPerParticle(state, s.mixed.size());
  state.counters["node_tests"] =
      static_cast<double>(steps_total) /
      (static_cast<double>(state.iterations()) * static_cast<double>(s.mixed.size()));
}
BENCHMARK(BM_KirkpatrickLocate)->Arg(0)->Arg(1)->Arg(2);

void BM_Response(benchmark::State& state) {
  const Single& s = GetSingle(static_cast<int>(state.range(0)));
  HullColliderSet set;
  HullColliderOptions o;
  o.response = state.range(1) == 0 ? HullResponse::kPushOut : HullResponse::kMapTableRay;
  set.Build(std::vector<HullColliderData>{s.data}, {}, 1, o).message();
  float sum = 0.f;
  uint32_t fallbacks = 0;
  for (auto _ : state) {
    for (const Float3& p : s.inside) {
      const ContactQuery c = HullColliderSetAccess::QueryHullLocal(set, 0, p, p);
      sum += c.point.x;
      fallbacks += (c.flags & kCollisionFallback) ? 1u : 0u;
    }
    benchmark::DoNotOptimize(sum);
  }
  SetPerParticle(state, s.inside.size());
  state.counters["fallbacks"] = fallbacks;
}
BENCHMARK(BM_Response)->Args({1, 0})->Args({1, 1})->Args({2, 0})->Args({2, 1});

// The map-table ray alone (cell lookup + watertight tests of the cell's list), no detection.
void BM_MapTableRay(benchmark::State& state) {
  const Single& s = GetSingle(static_cast<int>(state.range(0)));
  float sum = 0.f;
  for (auto _ : state) {
    for (const Float3& p : s.inside) {
      Float3 point, normal;
      HullColliderSetAccess::MapTableRayLocal(s.set, 0, p, &point, &normal);
      sum += point.x;
    }
    benchmark::DoNotOptimize(sum);
  }
  SetPerParticle(state, s.inside.size());
}
BENCHMARK(BM_MapTableRay)->Arg(1)->Arg(2);

void BM_Segment(benchmark::State& state) {
  const Single& s = GetSingle(static_cast<int>(state.range(0)));
  uint32_t contacts = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < s.seg_a.size(); ++i)
      contacts += HullColliderSetAccess::QueryHullLocal(s.set, 0, s.seg_a[i], s.seg_b[i]).contact;
    benchmark::DoNotOptimize(contacts);
  }
  SetPerParticle(state, s.seg_a.size());
  state.counters["contact_fraction"] =
      static_cast<double>(contacts) /
      (static_cast<double>(state.iterations()) * static_cast<double>(s.seg_a.size()));
}
BENCHMARK(BM_Segment)->Arg(1)->Arg(2);

// ---- The scene: a 1.7 m figure of 14 hulls on 14 joints plus 6 joint spheres.
struct Scene {
  std::vector<HullColliderData> hulls;
  std::vector<JointSphereData> spheres;
  std::vector<Mat34> start, end;
  // [0]: within 3 cm of a hull's surface (cloth resting on the body; about 40 % in contact),
  // [1]: uniform in the figure's box grown by 10 cm, [2]: 5 m away (the broad phase alone).
  std::vector<Float3> previous[3], positions[3], velocities[3];
};

const Scene& GetScene() {
  static Scene scene;
  if (!scene.hulls.empty()) return scene;
  struct Part {
    Float3 a, b;
    float radius;
  };
  // Torso (2), head, upper/lower arms, hands, thighs, shins.
  const std::vector<Part> parts = {{{0.f, 0.95f, 0.f}, {0.f, 1.15f, 0.f}, 0.15f},
                                   {{0.f, 1.15f, 0.f}, {0.f, 1.4f, 0.f}, 0.17f},
                                   {{0.f, 1.52f, 0.f}, {0.f, 1.68f, 0.f}, 0.1f},
                                   {{-0.2f, 1.38f, 0.f}, {-0.45f, 1.15f, 0.f}, 0.055f},
                                   {{0.2f, 1.38f, 0.f}, {0.45f, 1.15f, 0.f}, 0.055f},
                                   {{-0.45f, 1.15f, 0.f}, {-0.62f, 0.92f, 0.f}, 0.045f},
                                   {{0.45f, 1.15f, 0.f}, {0.62f, 0.92f, 0.f}, 0.045f},
                                   {{-0.62f, 0.92f, 0.f}, {-0.68f, 0.8f, 0.f}, 0.04f},
                                   {{0.62f, 0.92f, 0.f}, {0.68f, 0.8f, 0.f}, 0.04f},
                                   {{-0.1f, 0.85f, 0.f}, {-0.12f, 0.47f, 0.f}, 0.08f},
                                   {{0.1f, 0.85f, 0.f}, {0.12f, 0.47f, 0.f}, 0.08f},
                                   {{-0.12f, 0.47f, 0.f}, {-0.13f, 0.06f, 0.f}, 0.055f},
                                   {{0.12f, 0.47f, 0.f}, {0.13f, 0.06f, 0.f}, 0.055f},
                                   {{0.f, 0.8f, 0.f}, {0.f, 0.95f, 0.f}, 0.16f}};
  for (size_t i = 0; i < parts.size(); ++i) {
    const Part& p = parts[i];
    const Float3 d = p.b - p.a;
    const float half = Length(d) * 0.5f;
    Float3 axes[3];
    axes[1] = d * (1.f / Length(d));
    axes[2] = {0.f, 0.f, 1.f};
    axes[0] = Cross(axes[1], axes[2]);
    HullColliderData h = MakeEllipsoid({p.radius, half + 0.3f * p.radius, p.radius * 0.9f}, 1,
                                       (p.a + p.b) * 0.5f, axes);
    h.joint = static_cast<int32_t>(i);
    bake::BuildKirkpatrick(&h).message();
    bake::BuildMapTable(&h).message();
    scene.hulls.push_back(h);
  }
  const std::vector<std::pair<int, Float3>> joints = {
      {3, {-0.2f, 1.38f, 0.f}}, {4, {0.2f, 1.38f, 0.f}},    {5, {-0.45f, 1.15f, 0.f}},
      {6, {0.45f, 1.15f, 0.f}}, {11, {-0.12f, 0.47f, 0.f}}, {12, {0.12f, 0.47f, 0.f}}};
  for (const auto& [joint, c] : joints) scene.spheres.push_back({joint, -1, c, 0.07f});
  // Motion over the step: the arms swing 6 degrees about the shoulders, the body turns 2 degrees.
  for (size_t j = 0; j < parts.size(); ++j) {
    scene.start.push_back(RotationAbout(-1.0, {0, 1, 0}, {0, 0, 0}));
    const bool arm = j >= 3 && j <= 8;
    const Float3 shoulder = j % 2 == 1 ? Float3{-0.2f, 1.38f, 0.f} : Float3{0.2f, 1.38f, 0.f};
    scene.end.push_back(arm ? Multiply(RotationAbout(1.0, {0, 1, 0}, {0, 0, 0}),
                                       RotationAbout(6.0, {1, 0, 0}, shoulder))
                            : RotationAbout(1.0, {0, 1, 0}, {0, 0, 0}));
  }
  // 100k particles around the figure, moving up to 1 cm.
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> unit(0.f, 1.f), offset(-0.01f, 0.03f), step(-0.01f, 0.01f);
  while (scene.positions[0].size() < 100000) {
    const HullColliderData& h = scene.hulls[rng() % scene.hulls.size()];
    const uint32_t t = static_cast<uint32_t>(rng() % (h.triangles.size() / 3));
    float r1 = unit(rng), r2 = unit(rng);
    if (r1 + r2 > 1.f) r1 = 1.f - r1, r2 = 1.f - r2;
    const Float3 a = h.vertices[h.triangles[3 * t]], b = h.vertices[h.triangles[3 * t + 1]],
                 c = h.vertices[h.triangles[3 * t + 2]];
    const Float3 p =
        a + (b - a) * r1 + (c - a) * r2 + h.planes[h.triangle_planes[t]].normal * offset(rng);
    scene.positions[0].push_back(p);
    scene.previous[0].push_back(p - Float3{step(rng), step(rng), step(rng)});
    scene.velocities[0].push_back({0.f, -0.5f, 0.f});
  }
  const Float3 lo{-0.85f, -0.1f, -0.3f}, hi{0.85f, 1.85f, 0.3f};
  while (scene.positions[2].size() < 100000) {  // far from every collider: the broad phase alone
    const Float3 p{5.f + unit(rng), unit(rng), unit(rng)};
    scene.positions[2].push_back(p);
    scene.previous[2].push_back(p - Float3{step(rng), step(rng), step(rng)});
    scene.velocities[2].push_back({0.f, -0.5f, 0.f});
  }
  while (scene.positions[1].size() < 100000) {
    const Float3 p{lo.x + (hi.x - lo.x) * unit(rng), lo.y + (hi.y - lo.y) * unit(rng),
                   lo.z + (hi.z - lo.z) * unit(rng)};
    scene.positions[1].push_back(p);
    scene.previous[1].push_back(p - Float3{step(rng), step(rng), step(rng)});
    scene.velocities[1].push_back({0.f, -0.5f, 0.f});
  }
  return scene;
}

void BM_Scene(benchmark::State& state) {
  const Scene& scene = GetScene();
  const int distribution = static_cast<int>(state.range(2));
  HullColliderOptions o;
  if (state.range(1) == 1) o.response = HullResponse::kMapTableRay;
  if (state.range(1) == 2) o.inside_test = InsideTest::kKirkpatrick;
  HullColliderSet set;
  set.Build(scene.hulls, scene.spheres, static_cast<uint32_t>(scene.hulls.size()), o).message();
  set.SetPose(scene.start, scene.end).message();
  omp_set_num_threads(static_cast<int>(state.range(0)));
  std::vector<Float3> positions, velocities;
  std::vector<uint8_t> flags(scene.positions[distribution].size());
  uint32_t contacts = 0;
  for (auto _ : state) {
    state.PauseTiming();
    positions = scene.positions[distribution];
    velocities = scene.velocities[distribution];
    state.ResumeTiming();
    set.CollideBatch(scene.previous[distribution], positions, velocities, flags, ResponseParams{},
                     0.f, 1.f, &contacts)
        .message();
  }
  omp_set_num_threads(omp_get_num_procs());
  SetPerParticle(state, positions.size());
  state.counters["colliders"] = static_cast<double>(scene.hulls.size() + scene.spheres.size());
  state.counters["contact_fraction"] =
      static_cast<double>(contacts) / static_cast<double>(positions.size());
}
// Args: threads, mode (0 push-out, 1 map-table ray, 2 Kirkpatrick), distribution (0 near, 1 around,
// 2 far).
BENCHMARK(BM_Scene)
    ->Args({1, 0, 0})
    ->Args({2, 0, 0})
    ->Args({1, 1, 0})
    ->Args({2, 1, 0})
    ->Args({1, 2, 0})
    ->Args({2, 2, 0})
    ->Args({1, 0, 1})
    ->Args({2, 0, 1})
    ->Args({1, 1, 1})
    ->Args({2, 1, 1})
    ->Args({1, 2, 1})
    ->Args({2, 2, 1})
    ->Args({1, 0, 2})
    ->Args({2, 0, 2})
    ->UseRealTime();

}  // namespace
}  // namespace drape

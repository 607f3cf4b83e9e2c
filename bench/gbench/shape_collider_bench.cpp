// Engine-supplied shapes at run time (drape/runtime/shape_collider_set.h): CollideBatch of 10,000
// particles against 16 spheres, 4 tapered capsules, a floor plane and 2 boxes, each moving 1 cm
// and turning 2 degrees over the frame, one substep of 1/60 s. Reported: ns_per_particle and the
// fraction of particles in contact.
//
//  BM_ShapeScene/<threads>/<dist>   dist 0: half the particles within 3 cm of a shape's surface
//                                   (a third of them inside), half uniform in the scene's box;
//                                   1: uniform in the scene's box; 2: 5 m above the floor (the
//                                   broad phase, the floor's test and the loop only); 3: a
//                                   100 x 100 sheet (1.6 m square, row by row as a garment's
//                                   particles) slanting through the shapes from 0.3 to 1.3 m
//
// Built by bench/gbench/CMakeLists.txt with -DDRAPE_BUILD_BENCH=ON (bench_shape_collider). Run:
// OMP_WAIT_POLICY=passive build-X/bin/bench_shape_collider --benchmark_min_time=0.2

#include <benchmark/benchmark.h>
#include <omp.h>

#include <cmath>
#include <random>
#include <vector>

#include "rigid_poses.h"

#include "drape/runtime/math.h"
#include "drape/runtime/shape_collider_set.h"

namespace drape {
namespace {

constexpr float kFrame = 1.f / 60.f;  // seconds
constexpr size_t kParticles = 10000;

using test::Pose;

struct Scene {
  ShapeColliderSet set;
  // Per distribution: particles' previous and current positions and velocities.
  std::vector<Float3> previous[4], positions[4], velocities[4];
};

const Scene& GetScene() {
  static Scene scene;
  if (!scene.positions[0].empty()) return scene;
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(-1.f, 1.f), unit(0.f, 1.f);
  const auto axis = [&]() { return NormalizeOr({u(rng), u(rng), u(rng)}, {0.f, 1.f, 0.f}); };
  // A shape's start and end pose: 1 cm apart, turned by 2 degrees about a random axis.
  const auto add = [&](Float3 at, auto add_shape) {
    const Float3 tilt = axis();
    const double angle = 90.0 * u(rng);
    const Mat34 start = Pose(at, tilt, angle);
    const Mat34 end = Pose(at + axis() * 0.01f, tilt, angle + 2.0);
    add_shape(start, end).message();
  };
  ShapeColliderSet& set = scene.set;
  set.Reserve(23, 0);
  for (int i = 0; i < 16; ++i) {
    const Float3 at{-0.6f + 0.4f * float(i % 4), 0.4f + 0.8f * unit(rng),
                    -0.6f + 0.4f * float(i / 4)};
    const float radius = 0.06f + 0.09f * unit(rng);
    add(at, [&](const Mat34& a, const Mat34& b) { return set.AddSphere(a, b, radius); });
  }
  for (int i = 0; i < 4; ++i) {
    const Float3 at{0.5f * u(rng), 0.3f + 0.8f * unit(rng), 0.5f * u(rng)};
    add(at,
        [&](const Mat34& a, const Mat34& b) { return set.AddCapsule(a, b, 0.2f, 0.06f, 0.04f); });
  }
  const Mat34 floor = Pose({}, {1.f, 0.f, 0.f}, 0.0);
  set.AddPlane(floor, floor).message();
  for (int i = 0; i < 2; ++i) {
    const Float3 at{0.4f * u(rng), 0.5f + 0.3f * unit(rng), 0.4f * u(rng)};
    add(at, [&](const Mat34& a, const Mat34& b) { return set.AddBox(a, b, {0.15f, 0.08f, 0.1f}); });
  }
  // Particles: a motion of up to 1 cm plus gravity over the frame.
  const Float3 g{0.f, -9.81f, 0.f};
  const auto push = [&](int dist, Float3 p) {
    const Float3 v{0.6f * u(rng), 0.6f * u(rng), 0.6f * u(rng)};
    scene.previous[dist].push_back(p);
    scene.positions[dist].push_back(p + v * kFrame + g * (kFrame * kFrame));
    scene.velocities[dist].push_back(v + g * kFrame);
  };
  const auto uniform = [&]() { return Float3{0.9f * u(rng), 1.5f * unit(rng), 0.9f * u(rng)}; };
  for (size_t i = 0; i < kParticles; ++i) {
    if (i % 2 == 0) {
      // Near a random shape (not the floor): its world centre plus a direction times its reach,
      // found by bisection on Query's inside test, then -1..+3 cm off the surface.
      const uint32_t shape = static_cast<uint32_t>(unit(rng) * 22.99f);
      const uint32_t k = shape < 20 ? shape : shape + 1;
      const Mat34 w = set.WorldTransform(k, 0.f);
      const Float3 c{w.m[3], w.m[7], w.m[11]}, dir = axis();
      float lo = 0.f, hi = 0.5f;
      for (int step = 0; step < 30; ++step) {
        const float mid = 0.5f * (lo + hi);
        const Float3 p = c + dir * mid;
        (set.Query(p, p, 0.f, 0.f).inside_end ? lo : hi) = mid;
      }
      push(0, c + dir * (lo - 0.01f + 0.04f * unit(rng)));
    } else {
      push(0, uniform());
    }
    push(1, uniform());
    push(2, uniform() + Float3{0.f, 5.f, 0.f});
    const float row = float(i / 100) / 99.f, col = float(i % 100) / 99.f;
    push(3, {-0.8f + 1.6f * col, 0.3f + 1.0f * row, -0.8f + 1.6f * row});
  }
  return scene;
}

void BM_ShapeScene(benchmark::State& state) {
  const Scene& scene = GetScene();
  const int dist = static_cast<int>(state.range(1));
  omp_set_num_threads(static_cast<int>(state.range(0)));
  std::vector<Float3> positions, velocities;
  std::vector<uint8_t> flags(kParticles);
  uint32_t contacts = 0;
  for (auto _ : state) {
    state.PauseTiming();
    positions = scene.positions[dist];
    velocities = scene.velocities[dist];
    state.ResumeTiming();
    scene.set
        .CollideBatch(scene.previous[dist], positions, velocities, flags, ResponseParams{}, 0.f,
                      1.f, kFrame, &contacts)
        .message();
  }
  omp_set_num_threads(omp_get_num_procs());
  state.counters["ns_per_particle"] = benchmark::Counter(
      static_cast<double>(kParticles) * 1e-9,
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["contact_fraction"] =
      static_cast<double>(contacts) / static_cast<double>(kParticles);
}
// Args: threads, distribution (0 near the shapes, 1 uniform in the scene's box, 2 far above,
// 3 a sheet through the shapes).
BENCHMARK(BM_ShapeScene)->Args({1, 0})->Args({1, 1})->Args({1, 2})->Args({1, 3})->Args({2, 0});

}  // namespace
}  // namespace drape

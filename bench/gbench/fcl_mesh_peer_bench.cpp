// The cost of the FCL peer's point distance (bench/peers/fcl_mesh_peer.h), the BVH query that
// paper A compares its body maps against, on an icosphere of radius 0.5 m subdivided 5 times
// (20480 triangles), one thread.
//
//  BM_FclDistance/<band mm>/<closest>  FclMeshPeer::Distance for 20000 points at radius
//                                      0.5 m +- band (inside and outside, near the surface as
//                                      cloth particles are); closest 1 also asks for the closest
//                                      point. Counters: ns_per_query, triangles, memory_kb
//
// Built with -DDRAPE_BUILD_BENCH=ON (bench_fcl_mesh_peer). Run: build-X/bin/bench_fcl_mesh_peer

#include <benchmark/benchmark.h>

#include <cstdint>
#include <random>
#include <vector>

#include "drape/runtime/math.h"
#include "fcl_mesh_peer.h"
#include "reference_meshes.h"

namespace drape::peers {
namespace {

// 20000 points at radius 0.5 +- band, directions uniform (rejection from the unit ball).
std::vector<Float3> SphereBandPoints(float band, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> unit(-1.f, 1.f), radius(0.5f - band, 0.5f + band);
  std::vector<Float3> points;
  while (points.size() < 20000) {
    const Float3 d{unit(rng), unit(rng), unit(rng)};
    const float len = Length(d);
    if (len < 0.1f || len > 1.f) continue;
    points.push_back(d * (radius(rng) / len));
  }
  return points;
}

void BM_FclDistance(benchmark::State& state) {
  static const test::Mesh sphere = test::MakeIcosphere(5, 0.5);
  static const FclMeshPeer peer(sphere.positions, sphere.triangles);
  const float band = static_cast<float>(state.range(0)) * 1e-3f;
  const bool with_closest = state.range(1) != 0;
  const std::vector<Float3> points = SphereBandPoints(band, 7);
  double sum = 0.0;
  Float3 closest;
  for (auto _ : state) {
    for (const Float3& p : points) sum += peer.Distance(p, with_closest ? &closest : nullptr);
    benchmark::DoNotOptimize(sum);
  }
  state.counters["ns_per_query"] = benchmark::Counter(
      static_cast<double>(points.size()) * 1e-9,
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["triangles"] = static_cast<double>(peer.triangle_count());
  state.counters["memory_kb"] = static_cast<double>(peer.memory_bytes()) / 1e3;
}
BENCHMARK(BM_FclDistance)->ArgNames({"band_mm", "closest"})->ArgsProduct({{10, 150}, {0, 1}});

}  // namespace
}  // namespace drape::peers

// Time to bake paper A's body maps of one pose (drape/bake/body_map_baker.h): a UV sphere of
// radius 0.3 m and a capsule mannequin, each with ~5k and ~80k triangles, at N = 512, 1024, 2048,
// with the CPU rasterizer and the OSMesa (llvmpipe) renderer. The wall time covers the whole bake
// (normals, offset, both views, encoding); the counters front_ms / back_ms are the mean per-view
// render times the baker reports (CPU: rasterize + normals; OSMesa: upload + clear + draw + finish
// + readback), front_min_ms / back_min_ms the fastest iteration's (the least disturbed figure on
// a shared machine). The OSMesa context and its shader JIT (~60 ms) are warmed up before timing.
// The last argument is BodyMapOptions::layers: with 3 the bake adds the gap layers' CPU fragment
// pass (body_map_baker.h step 8), whichever renderer drew layer 0; gap_ms / gap_min_ms are its
// mean and fastest time (included in the wall time and, half each, in front_ms / back_ms), and
// gap_texels the texels that got a gap.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "drape/bake/body_map_baker.h"

namespace {

struct Mesh {
  std::vector<drape::Float3> positions;
  std::vector<uint32_t> triangles;
};

struct Vec3 {
  double x, y, z;
};

// Appends a UV capsule: hemispheres of radius r joined by a cylinder of half-length `half`
// (0: a sphere) around the unit axis `axis` through `centre`; `stacks` (even) rings pole to
// pole, `slices` around; counter-clockwise seen from outside.
void AddCapsule(Mesh* m, Vec3 centre, Vec3 axis, double r, double half, int stacks, int slices) {
  constexpr double kPi = 3.14159265358979323846;
  // An orthonormal frame (u, axis, w).
  const Vec3 helper = std::fabs(axis.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 0, 1};
  Vec3 u{helper.y * axis.z - helper.z * axis.y, helper.z * axis.x - helper.x * axis.z,
         helper.x * axis.y - helper.y * axis.x};
  const double lu = std::sqrt(u.x * u.x + u.y * u.y + u.z * u.z);
  u = {u.x / lu, u.y / lu, u.z / lu};
  const Vec3 w{axis.y * u.z - axis.z * u.y, axis.z * u.x - axis.x * u.z,
               axis.x * u.y - axis.y * u.x};
  const uint32_t base = static_cast<uint32_t>(m->positions.size());
  auto add = [&](double a, double b, double c) {  // a along u, b along axis, c along w
    m->positions.push_back({static_cast<float>(centre.x + a * u.x + b * axis.x + c * w.x),
                            static_cast<float>(centre.y + a * u.y + b * axis.y + c * w.y),
                            static_cast<float>(centre.z + a * u.z + b * axis.z + c * w.z)});
  };
  add(0, r + half, 0);
  int rings = 0;
  for (int k = 1; k < stacks; ++k) {
    const double theta = kPi * k / stacks;
    const int copies = (half > 0.0 && 2 * k == stacks) ? 2 : 1;
    for (int copy = 0; copy < copies; ++copy) {
      const double shift = (2 * k < stacks || (copies == 2 && copy == 0)) ? half : -half;
      for (int s = 0; s < slices; ++s) {
        const double phi = 2 * kPi * s / slices;
        add(r * std::sin(theta) * std::cos(phi), r * std::cos(theta) + shift,
            -r * std::sin(theta) * std::sin(phi));
      }
      ++rings;
    }
  }
  add(0, -r - half, 0);
  const uint32_t n = static_cast<uint32_t>(slices);
  const uint32_t last_ring = static_cast<uint32_t>(rings - 1);
  const uint32_t bottom = base + 1 + static_cast<uint32_t>(rings) * n;
  auto ring = [&](uint32_t k, uint32_t s) { return base + 1 + k * n + s % n; };
  auto tri = [&](uint32_t a, uint32_t b, uint32_t c) {
    m->triangles.insert(m->triangles.end(), {a, b, c});
  };
  for (uint32_t s = 0; s < n; ++s) tri(base, ring(0, s), ring(0, s + 1));
  for (uint32_t k = 0; k < last_ring; ++k) {
    for (uint32_t s = 0; s < n; ++s) {
      tri(ring(k, s), ring(k + 1, s), ring(k + 1, s + 1));
      tri(ring(k, s), ring(k + 1, s + 1), ring(k, s + 1));
    }
  }
  for (uint32_t s = 0; s < n; ++s) tri(bottom, ring(last_ring, s + 1), ring(last_ring, s));
}

// Sphere of radius 0.3 m: 2 t (t - 1) triangles (t = 50: 4,900; t = 200: 79,600). It covers
// 74 % of the square window: a fill-rate worst case.
Mesh MakeSphere(int t) {
  Mesh m;
  AddCapsule(&m, {0, 0, 0}, {0, 1, 0}, 0.3, 0.0, t, t);
  return m;
}

// A 1.75 m capsule mannequin in an A-pose (torso, head, two arms, two legs), about 4 t^2
// triangles per part (t = 14: 4,648 in all; t = 58: 80,504). It covers about 20 % of the square
// window, like a real character (notes: H54 17 %).
Mesh MakeMannequin(int t) {
  Mesh m;
  const double tilt = 20.0 * 3.14159265358979323846 / 180.0;
  AddCapsule(&m, {0, 1.15, 0}, {0, 1, 0}, 0.16, 0.22, t, 2 * t);    // torso
  AddCapsule(&m, {0, 1.64, 0.01}, {0, 1, 0}, 0.11, 0.0, t, 2 * t);  // head
  for (double side : {-1.0, 1.0}) {
    AddCapsule(&m, {side * 0.31, 1.14, 0}, {-side * std::sin(tilt), std::cos(tilt), 0}, 0.05, 0.28,
               t, 2 * t);                                                      // arm
    AddCapsule(&m, {side * 0.09, 0.47, 0}, {0, 1, 0}, 0.075, 0.36, t, 2 * t);  // leg
  }
  return m;
}

// Arguments: mesh (0 sphere, 1 mannequin), size (0: ~5k triangles, 1: ~80k), N, renderer
// (0 CPU, 1 OSMesa), layers (1: paper A's slab; 3: up to two gaps).
void BM_BodyMapBake(benchmark::State& state) {
  const bool mannequin = state.range(0) == 1;
  const bool large = state.range(1) == 1;
  const Mesh mesh = mannequin ? MakeMannequin(large ? 58 : 14) : MakeSphere(large ? 200 : 50);
  drape::bake::BodyMapOptions options;
  options.resolution = static_cast<uint32_t>(state.range(2));
  options.renderer =
      state.range(3) == 0 ? drape::bake::MapRenderer::kCpu : drape::bake::MapRenderer::kOsMesa;
  options.layers = static_cast<uint8_t>(state.range(4));
  if (options.renderer == drape::bake::MapRenderer::kOsMesa &&
      !drape::bake::OsMesaRendererAvailable()) {
    state.SkipWithError("OSMesa renderer not available in this build");
    return;
  }
  drape::BodyMapPose pose;
  drape::bake::BodyMapPoseStats stats;
  // Warm-up: context creation and shader JIT for OSMesa, page faults for both.
  if (!drape::bake::BakeBodyMapPose(mesh.positions, mesh.triangles, options, &pose, &stats).ok()) {
    state.SkipWithError("bake failed");
    return;
  }
  double front_ms = 0.0, back_ms = 0.0;
  double front_min_ms = 1e300, back_min_ms = 1e300;  // the least disturbed view on a busy machine
  double gap_ms = 0.0, gap_min_ms = 1e300;
  int64_t bakes = 0;
  for (auto _ : state) {
    const drape::Status status =
        drape::bake::BakeBodyMapPose(mesh.positions, mesh.triangles, options, &pose, &stats);
    if (!status.ok()) {
      state.SkipWithError(status.message().c_str());
      return;
    }
    front_ms += stats.render_ms_front;
    back_ms += stats.render_ms_back;
    front_min_ms = std::min(front_min_ms, stats.render_ms_front);
    back_min_ms = std::min(back_min_ms, stats.render_ms_back);
    gap_ms += stats.gap_ms;
    gap_min_ms = std::min(gap_min_ms, stats.gap_ms);
    ++bakes;
    benchmark::DoNotOptimize(pose.depth_f32[0].data());
  }
  state.counters["triangles"] = static_cast<double>(mesh.triangles.size() / 3);
  state.counters["front_ms"] = front_ms / static_cast<double>(bakes);
  state.counters["back_ms"] = back_ms / static_cast<double>(bakes);
  state.counters["front_min_ms"] = front_min_ms;
  state.counters["back_min_ms"] = back_min_ms;
  state.counters["coverage"] = stats.coverage;
  state.counters["gap_ms"] = gap_ms / static_cast<double>(bakes);
  state.counters["gap_min_ms"] = gap_min_ms;
  state.counters["gap_texels"] = static_cast<double>(stats.gap_texels);
  state.SetLabel(stats.renderer);
}

BENCHMARK(BM_BodyMapBake)
    ->ArgNames({"mannequin", "80k", "N", "osmesa", "layers"})
    ->ArgsProduct({{0, 1}, {0, 1}, {512, 1024, 2048}, {0, 1}, {1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
// The gap layers' cost: the ~80k-triangle meshes at N = 1024 with up to two gaps (compare with
// the layers:1 rows above).
BENCHMARK(BM_BodyMapBake)
    ->ArgNames({"mannequin", "80k", "N", "osmesa", "layers"})
    ->ArgsProduct({{0, 1}, {1}, {1024}, {0, 1}, {3}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

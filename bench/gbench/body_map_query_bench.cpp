// Paper A's image-space collider at run time: discrete and continuous query cost on analytic maps
// (shape 0: a sphere of radius 0.3 m; shape 1: a "capsule man" of 10 capsules, 1.7 m tall) in a
// 1.8 m square window of N = 512 or 1024 texels. Reported: ns_per_particle, wall time.
//
//  BM_Inside/<shape>/<N>/<order>         IsInside over a 256^2 cloth sheet on the front surface
//                                        (+-5 mm), in sheet order (0) or shuffled (1); 1 thread
//  BM_InsideBatch/<shape>/<N>/<threads>  InsideBatch (OpenMP) on the sheet, 1 or 2 threads
//  BM_Continuous/<shape>/<N>/<sampling>/<motion>
//                                        Query, 1 thread, on particles 2 mm in front of the
//                                        surface, half of them moving through it; sampling 0
//                                        nearest, 1 bilinear; motion 0: 0.1-0.5 texels
//                                        sideways, 1: 1-2 texels, 2: up to 0.02 texels
//                                        (cloth resting on the body)
//  BM_CollideBatch/<shape>/<N>/<threads>/<motion>/<lanes>
//                                        the same segments through CollideBatch (+ response);
//                                        lanes 8: AVX2 where the CPU has it, 4: SSE2 forced
//  BM_SegmentLength/<texels>/<sampling>  Query on horizontal segments of 1..256 texels at a
//                                        random depth inside the body's z range, N = 1024 man
//
// Built by bench/gbench/CMakeLists.txt with -DDRAPE_BUILD_BENCH=ON (bench_body_map_query); alone:
// g++ -std=c++20 -O3 -fopenmp -ffp-contract=off -Iruntime/include -Iformats/include THIS_FILE
// build-X/lib/libdrape_runtime.a build-X/lib/libdrape_formats.a -lbenchmark_main -lbenchmark

#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

#include "drape/runtime/body_map_collider.h"
#include "drape/runtime/normal_encoding.h"

namespace drape {
namespace {

struct Capsule {
  float ax, ay, bx, by, radius;  // axis in the z = 0 plane
};

// A standing figure in metres: torso, head, upper and lower arms, thighs, shins.
const std::vector<Capsule>& CapsuleMan() {
  static const std::vector<Capsule> parts = {
      {0.f, 0.95f, 0.f, 1.35f, 0.16f},        {0.f, 1.58f, 0.f, 1.62f, 0.11f},
      {-0.2f, 1.38f, -0.45f, 1.15f, 0.055f},  {0.2f, 1.38f, 0.45f, 1.15f, 0.055f},
      {-0.45f, 1.15f, -0.62f, 0.92f, 0.045f}, {0.45f, 1.15f, 0.62f, 0.92f, 0.045f},
      {-0.1f, 0.85f, -0.12f, 0.47f, 0.08f},   {0.1f, 0.85f, 0.12f, 0.47f, 0.08f},
      {-0.12f, 0.47f, -0.13f, 0.06f, 0.055f}, {0.12f, 0.47f, 0.13f, 0.06f, 0.055f}};
  return parts;
}

struct Surface {
  bool valid = false;
  float top = 0.f, bottom = 0.f;
  Float3 front_normal, back_normal;
};

Surface SampleShape(int shape, float x, float y) {
  Surface s;
  if (shape == 0) {  // sphere, radius 0.3 m, centre (0, 0.9, 0)
    const float dx = x, dy = y - 0.9f, r2 = 0.09f - dx * dx - dy * dy;
    if (r2 <= 0.f) return s;
    const float h = std::sqrt(r2);
    s = {true, h, -h, {dx / 0.3f, dy / 0.3f, h / 0.3f}, {dx / 0.3f, dy / 0.3f, -h / 0.3f}};
    return s;
  }
  for (const Capsule& c : CapsuleMan()) {
    const float ex = c.bx - c.ax, ey = c.by - c.ay;
    const float t = std::clamp(((x - c.ax) * ex + (y - c.ay) * ey) / (ex * ex + ey * ey), 0.f, 1.f);
    const float dx = x - (c.ax + ex * t), dy = y - (c.ay + ey * t);
    const float r2 = c.radius * c.radius - dx * dx - dy * dy;
    if (r2 <= 0.f) continue;
    const float h = std::sqrt(r2);
    if (!s.valid || h > s.top) {
      s.top = h;
      s.front_normal = {dx / c.radius, dy / c.radius, h / c.radius};
    }
    if (!s.valid || -h < s.bottom) {
      s.bottom = -h;
      s.back_normal = {dx / c.radius, dy / c.radius, -h / c.radius};
    }
    s.valid = true;
  }
  return s;
}

// Square window of side 1.8 m around the figure (paper A's square camera), N x N texels.
BodyMapPose MakePose(int shape, uint32_t n) {
  BodyMapPose pose;
  pose.width = pose.height = n;
  pose.texel_size = 1.8f / static_cast<float>(n);
  pose.origin_x = -0.9f;
  pose.origin_y = -0.05f;
  pose.front_z = 0.5f;
  pose.depth_range = 1.f;
  pose.depth_encoding = DepthEncoding::kFloat32;
  pose.normal_encoding = NormalEncoding::kOct16;
  const size_t count = static_cast<size_t>(n) * n;
  for (int v = 0; v < 2; ++v) {
    pose.depth_f32[v].assign(count, pose.depth_range);
    pose.normal_oct16[v].assign(2 * count, 0);
  }
  for (uint32_t j = 0; j < n; ++j) {
    for (uint32_t i = 0; i < n; ++i) {
      const float x = pose.origin_x + (static_cast<float>(i) + 0.5f) * pose.texel_size;
      const float y = pose.origin_y + (static_cast<float>(j) + 0.5f) * pose.texel_size;
      const Surface s = SampleShape(shape, x, y);
      if (!s.valid) continue;
      const size_t k = static_cast<size_t>(j) * n + i;
      pose.depth_f32[0][k] = pose.front_z - s.top;
      pose.depth_f32[1][k] = s.bottom - (pose.front_z - pose.depth_range);
      const std::array<uint16_t, 2> f = EncodeOct16(s.front_normal), b = EncodeOct16(s.back_normal);
      pose.normal_oct16[0][2 * k] = f[0];
      pose.normal_oct16[0][2 * k + 1] = f[1];
      pose.normal_oct16[1][2 * k] = b[0];
      pose.normal_oct16[1][2 * k + 1] = b[1];
    }
  }
  return pose;
}

BodyMapCollider& Collider(int shape, uint32_t n, DepthSampling sampling) {
  static std::unique_ptr<BodyMapCollider> cache[2][2][2];
  std::unique_ptr<BodyMapCollider>& slot =
      cache[shape][n == 1024 ? 1 : 0][sampling == DepthSampling::kBilinear ? 1 : 0];
  if (!slot) {
    slot = std::make_unique<BodyMapCollider>();
    const Status status = slot->Build(MakePose(shape, n), sampling);
    if (!status.ok()) std::fprintf(stderr, "build failed: %s\n", status.message().c_str());
    std::fprintf(stderr, "# shape %d N=%u %s: %u valid texels, %zu bytes\n", shape, n,
                 sampling == DepthSampling::kBilinear ? "bilinear" : "nearest",
                 slot->stats().valid_texels, slot->memory_bytes());
  }
  return *slot;
}

constexpr int kSheet = 256;  // particles per side of the cloth sheet

// Cloth-like particles: a 256 x 256 sheet over the figure's front, on the front surface +-5 mm.
std::vector<Float3> SheetPoints(int shape, bool shuffled) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> jitter(-0.005f, 0.005f);
  std::vector<Float3> points;
  points.reserve(kSheet * kSheet);
  for (int j = 0; j < kSheet; ++j) {
    for (int i = 0; i < kSheet; ++i) {
      const float x = -0.7f + 1.4f * (static_cast<float>(i) + 0.5f) / kSheet;
      const float y = 0.f + 1.75f * (static_cast<float>(j) + 0.5f) / kSheet;
      const Surface s = SampleShape(shape, x, y);
      points.push_back({x, y, (s.valid ? s.top : 0.f) + jitter(rng)});
    }
  }
  if (shuffled) std::shuffle(points.begin(), points.end(), rng);
  return points;
}

// Particles 2 mm in front of the surface, in sheet order over the figure (a 512 x 512 grid over
// its box, background points dropped), each moving sideways by 0.1-0.5 texels (motion 0, a
// sliding cloth), 1-2 texels (motion 1) or up to 0.02 texels (motion 2, a resting cloth); every
// other one also moves 4 mm towards -z, ending 2 mm inside (half free, half colliding).
void SheetSegments(int shape, float texel, int motion, std::vector<Float3>* from,
                   std::vector<Float3>* to) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> angle(0.f, 6.2831853f);
  constexpr float kLength[3][2] = {{0.1f, 0.5f}, {1.f, 2.f}, {0.f, 0.02f}};  // texels
  std::uniform_real_distribution<float> length(kLength[motion][0], kLength[motion][1]);
  from->clear();
  to->clear();
  const float x_lo = shape == 0 ? -0.3f : -0.7f, x_hi = -x_lo;
  const float y_lo = shape == 0 ? 0.6f : 0.f, y_hi = shape == 0 ? 1.2f : 1.75f;
  constexpr int kGrid = 512;
  size_t kept = 0;
  for (int j = 0; j < kGrid; ++j) {
    for (int i = 0; i < kGrid; ++i) {
      const float x = x_lo + (x_hi - x_lo) * (static_cast<float>(i) + 0.5f) / kGrid;
      const float y = y_lo + (y_hi - y_lo) * (static_cast<float>(j) + 0.5f) / kGrid;
      const Surface s = SampleShape(shape, x, y);
      const float a = angle(rng), d = length(rng) * texel;
      if (!s.valid) continue;
      const Float3 p0{x, y, s.top + 0.002f};
      const float dz = kept++ % 2 == 0 ? -0.004f : 0.f;
      from->push_back(p0);
      to->push_back({x + d * std::cos(a), y + d * std::sin(a), p0.z + dz});
    }
  }
}

void SetPerParticle(benchmark::State& state, size_t particles) {
  state.counters["ns_per_particle"] = benchmark::Counter(
      static_cast<double>(particles) * 1e-9,
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_Inside(benchmark::State& state) {
  const int shape = static_cast<int>(state.range(0));
  const BodyMapCollider& c =
      Collider(shape, static_cast<uint32_t>(state.range(1)), DepthSampling::kNearest);
  const std::vector<Float3> points = SheetPoints(shape, state.range(2) != 0);
  size_t inside = 0;
  for (auto _ : state) {
    for (const Float3& p : points) inside += c.IsInside(p) ? 1 : 0;
    benchmark::DoNotOptimize(inside);
  }
  SetPerParticle(state, points.size());
}
BENCHMARK(BM_Inside)->ArgsProduct({{0, 1}, {512, 1024}, {0, 1}});

void BM_InsideBatch(benchmark::State& state) {
  const int shape = static_cast<int>(state.range(0));
  const BodyMapCollider& c =
      Collider(shape, static_cast<uint32_t>(state.range(1)), DepthSampling::kNearest);
  const std::vector<Float3> points = SheetPoints(shape, false);
  std::vector<uint8_t> inside(points.size());
  omp_set_num_threads(static_cast<int>(state.range(2)));
  for (auto _ : state) {
    const Status status = c.InsideBatch(points, inside);
    benchmark::DoNotOptimize(status.ok());
    benchmark::DoNotOptimize(inside.data());
  }
  omp_set_num_threads(omp_get_num_procs());
  SetPerParticle(state, points.size());
}
BENCHMARK(BM_InsideBatch)->ArgsProduct({{0, 1}, {512, 1024}, {1, 2}})->UseRealTime();

void BM_Continuous(benchmark::State& state) {
  const int shape = static_cast<int>(state.range(0));
  const DepthSampling sampling =
      state.range(2) ? DepthSampling::kBilinear : DepthSampling::kNearest;
  const BodyMapCollider& c = Collider(shape, static_cast<uint32_t>(state.range(1)), sampling);
  std::vector<Float3> from, to;
  SheetSegments(shape, c.texel_size(), static_cast<int>(state.range(3)), &from, &to);
  size_t contacts = 0;
  for (auto _ : state) {
    for (size_t k = 0; k < from.size(); ++k) contacts += c.Query(from[k], to[k]).contact ? 1 : 0;
    benchmark::DoNotOptimize(contacts);
  }
  state.counters["contact_fraction"] =
      static_cast<double>(contacts) / static_cast<double>(from.size() * state.iterations());
  SetPerParticle(state, from.size());
}
BENCHMARK(BM_Continuous)->ArgsProduct({{0, 1}, {512, 1024}, {0, 1}, {0, 1, 2}});

void BM_CollideBatch(benchmark::State& state) {
  const int shape = static_cast<int>(state.range(0));
  BodyMapCollider& c =
      Collider(shape, static_cast<uint32_t>(state.range(1)), DepthSampling::kNearest);
  // Eight lanes are AVX2's, four SSE2's (drape-replay-maps --lanes also runs the scalar pack).
  c.LimitInstructionSet(state.range(4) == 8 ? InstructionSet::kAvx2 : InstructionSet::kSse2);
  if (state.range(4) == 8 && c.instruction_set() != InstructionSet::kAvx2) {
    state.SkipWithError("this CPU has no AVX2");
    return;
  }
  std::vector<Float3> from, to;
  SheetSegments(shape, c.texel_size(), static_cast<int>(state.range(3)), &from, &to);
  std::vector<Float3> positions(to.size()), velocities(to.size());
  std::vector<uint8_t> flags(to.size());
  omp_set_num_threads(static_cast<int>(state.range(2)));
  const ResponseParams params;
  for (auto _ : state) {
    state.PauseTiming();
    positions = to;
    std::fill(velocities.begin(), velocities.end(), Float3{0.f, 0.f, -1.f});
    state.ResumeTiming();
    uint32_t contacts = 0;
    const Status status = c.CollideBatch(from, positions, velocities, flags, params, &contacts);
    benchmark::DoNotOptimize(status.ok());
    benchmark::DoNotOptimize(contacts);
  }
  omp_set_num_threads(omp_get_num_procs());
  SetPerParticle(state, from.size());
}
BENCHMARK(BM_CollideBatch)
    ->ArgsProduct({{0, 1}, {512, 1024}, {1, 2}, {0, 1, 2}, {8, 4}})
    ->UseRealTime();

// Horizontal segments of a fixed length in texels, random start over the figure's box and a
// random depth inside its z range: the walk runs until the first entry or the end.
void BM_SegmentLength(benchmark::State& state) {
  const float length_texels = static_cast<float>(state.range(0));
  const DepthSampling sampling =
      state.range(1) ? DepthSampling::kBilinear : DepthSampling::kNearest;
  const BodyMapCollider& c = Collider(1, 1024, sampling);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> x(-0.7f, 0.7f), y(0.f, 1.75f), z(-0.15f, 0.15f),
      angle(0.f, 6.2831853f);
  constexpr int kCount = 1 << 14;
  std::vector<Float3> from(kCount), to(kCount);
  for (int k = 0; k < kCount; ++k) {
    const float a = angle(rng), d = length_texels * c.texel_size();
    from[k] = {x(rng), y(rng), z(rng)};
    to[k] = {from[k].x + d * std::cos(a), from[k].y + d * std::sin(a), from[k].z};
  }
  size_t contacts = 0;
  for (auto _ : state) {
    for (int k = 0; k < kCount; ++k) contacts += c.Query(from[k], to[k]).contact ? 1 : 0;
    benchmark::DoNotOptimize(contacts);
  }
  state.counters["contact_fraction"] =
      static_cast<double>(contacts) / static_cast<double>(kCount * state.iterations());
  SetPerParticle(state, kCount);
}
BENCHMARK(BM_SegmentLength)->ArgsProduct({{1, 4, 16, 64, 256}, {0, 1}});

}  // namespace
}  // namespace drape

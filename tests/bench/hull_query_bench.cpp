// Paper B's proxy colliders at run time (drape/runtime/hull_collider.h): cost of the per-pair
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
// Built by tests/bench/CMakeLists.txt with -DDRAPE_BUILD_BENCH=ON (bench_hull_query; links
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
#include "drape/runtime/hull_collider.h"
#include "drape/runtime/math.h"

namespace drape {
namespace {

constexpr double kPi = 3.14159265358979323846;

// ---- Hull making (as in the tests): faces outward, coplanar faces merged, offsets rounded out.
HullColliderData MakeHull(const std::vector<Float3>& vertices,
                          std::vector<std::array<uint32_t, 3>> faces, const Obb& obb) {
  HullColliderData h;
  h.joint = 0;
  h.vertices = vertices;
  h.obb = obb;
  double cx = 0, cy = 0, cz = 0;
  for (const Float3& v : vertices) cx += v.x, cy += v.y, cz += v.z;
  cx /= double(vertices.size()), cy /= double(vertices.size()), cz /= double(vertices.size());
  for (auto& f : faces) {
    const Float3 a = vertices[f[0]], b = vertices[f[1]], c = vertices[f[2]];
    const double ux = double(b.x) - a.x, uy = double(b.y) - a.y, uz = double(b.z) - a.z;
    const double vx = double(c.x) - a.x, vy = double(c.y) - a.y, vz = double(c.z) - a.z;
    double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    const double mx = (double(a.x) + b.x + c.x) / 3 - cx, my = (double(a.y) + b.y + c.y) / 3 - cy,
                 mz = (double(a.z) + b.z + c.z) / 3 - cz;
    if (nx * mx + ny * my + nz * mz < 0) {
      std::swap(f[1], f[2]);
      nx = -nx, ny = -ny, nz = -nz;
    }
    const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
    const Float3 n{float(nx / len), float(ny / len), float(nz / len)};
    const double offset = (double(n.x) * a.x + double(n.y) * a.y + double(n.z) * a.z);
    int32_t plane = -1;
    for (size_t p = 0; p < h.planes.size(); ++p) {
      const Float3 q = h.planes[p].normal;
      if (std::fabs(q.x - n.x) + std::fabs(q.y - n.y) + std::fabs(q.z - n.z) < 1e-6f &&
          std::fabs(double(q.x) * a.x + double(q.y) * a.y + double(q.z) * a.z - offset) < 1e-6)
        plane = int32_t(p);
    }
    if (plane < 0) {
      plane = int32_t(h.planes.size());
      h.planes.push_back({n, 0.f});
    }
    h.triangles.insert(h.triangles.end(), {f[0], f[1], f[2]});
    h.triangle_planes.push_back(uint32_t(plane));
  }
  for (Plane& p : h.planes) {
    double worst = -std::numeric_limits<double>::infinity();
    for (const Float3& v : vertices) {
      const double nx = double(p.normal.x) * v.x, ny = double(p.normal.y) * v.y,
                   nz = double(p.normal.z) * v.z;
      worst = std::max(worst, nx + ny + nz +
                                  3.0 * std::numeric_limits<float>::epsilon() *
                                      (std::fabs(nx) + std::fabs(ny) + std::fabs(nz)));
    }
    float d = static_cast<float>(worst);
    if (double(d) < worst) d = std::nextafter(d, std::numeric_limits<float>::infinity());
    p.offset = std::nextafter(d, std::numeric_limits<float>::infinity());
  }
  return h;
}

Float3 Rotate(const Float3 axes[3], Float3 local) {
  return axes[0] * local.x + axes[1] * local.y + axes[2] * local.z;
}

HullColliderData MakeEllipsoid(Float3 r, int levels, Float3 center, const Float3 axes[3]) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<std::array<double, 3>> p = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                          {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                          {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<uint32_t, 3>> f = {
      {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& q : p) {
    const double l = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    for (double& x : q) x /= l;
  }
  for (int level = 0; level < levels; ++level) {
    std::vector<std::array<uint32_t, 3>> next;
    std::vector<std::pair<uint64_t, uint32_t>> cache;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      const uint64_t key = (uint64_t(std::min(a, b)) << 32) | std::max(a, b);
      for (auto& [k, v] : cache)
        if (k == key) return v;
      std::array<double, 3> m = {p[a][0] + p[b][0], p[a][1] + p[b][1], p[a][2] + p[b][2]};
      const double l = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
      for (double& x : m) x /= l;
      p.push_back(m);
      cache.push_back({key, uint32_t(p.size() - 1)});
      return uint32_t(p.size() - 1);
    };
    for (const auto& tri : f) {
      const uint32_t a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]),
                     c = midpoint(tri[2], tri[0]);
      next.push_back({tri[0], a, c});
      next.push_back({tri[1], b, a});
      next.push_back({tri[2], c, b});
      next.push_back({a, b, c});
    }
    f = next;
  }
  std::vector<Float3> v;
  for (const auto& q : p)
    v.push_back(center +
                Rotate(axes, Float3{float(q[0] * r.x), float(q[1] * r.y), float(q[2] * r.z)}));
  Obb obb;
  obb.center = center;
  for (int k = 0; k < 3; ++k) obb.axes[k] = axes[k];
  obb.half_extents = r;
  return MakeHull(v, f, obb);
}

void RotatedAxes(double angle_deg, Float3 axis, Float3 out[3]) {
  const double a = angle_deg * kPi / 180.0;
  const double l =
      std::sqrt(double(axis.x) * axis.x + double(axis.y) * axis.y + double(axis.z) * axis.z);
  const double x = axis.x / l, y = axis.y / l, z = axis.z / l, c = std::cos(a), s = std::sin(a);
  const double m[3][3] = {{c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s},
                          {y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s},
                          {z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)}};
  for (int k = 0; k < 3; ++k) out[k] = {float(m[0][k]), float(m[1][k]), float(m[2][k])};
}

Mat34 RotationAbout(double angle_deg, Float3 axis, Float3 pivot) {
  Float3 cols[3];
  RotatedAxes(angle_deg, axis, cols);
  Mat34 m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m.m[4 * r + c] = (&cols[c].x)[r];
  const Float3 rp = TransformVector(m, pivot);
  m.m[3] = pivot.x - rp.x;
  m.m[7] = pivot.y - rp.y;
  m.m[11] = pivot.z - rp.z;
  return m;
}

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
    if (s.set.InsideLocal(0, p, InsideTest::kPlanes)) s.inside.push_back(p);
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
    for (const Float3& p : points) kept += s.set.ObbMayContainLocal(0, p) ? 1u : 0u;
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
      inside += s.set.InsideLocal(0, p, InsideTest::kPlanes) ? 1u : 0u;
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
      inside += s.set.InsideLocal(0, p, InsideTest::kKirkpatrick) ? 1u : 0u;
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
      sum += s.set.LocateLocal(0, p, true, &steps);
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
      const ContactQuery c = set.QueryHullLocal(0, p, p);
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
      s.set.MapTableRayLocal(0, p, &point, &normal);
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
      contacts += s.set.QueryHullLocal(0, s.seg_a[i], s.seg_b[i]).contact;
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

// The exact reference's cost (bake/include/drape/bake/mesh_reference.h) on the
// meshes its tests check it on (tests/bake/mesh_reference_test.cpp): mesh 0 is an icosphere
// (5120 triangles; 1280 for BM_Distance), 1 the built-in mannequin's rest pose (7584), 2
// CesiumMan's (4672, skipped when ../shared is absent). Points: half uniform in the mesh's box
// inflated by 10 %, half within 1 cm of the surface (5 mm on the small icosphere), fixed seeds.
//
//  BM_WindingSetting/<mesh>/<beta x 10>  MeshReference::WindingNumber at expansion order 2, leaf
//                                        size 4 and the given beta: how the default was chosen.
//                                        Counters: ns_per_query, max_error (|fast - brute| over
//                                        the points), clear_disagreements (Inside differs where
//                                        the brute force is farther than 0.1 from 1/2; the tests
//                                        hold it to 0)
//  BM_BruteWindingNumber/<mesh>          ExactMesh::WindingNumber, every triangle's solid angle
//  BM_Distance/<mesh>/<method>           distance to the surface: 0 CGAL's AABB tree
//                                        (MeshReference), 1 brute force (ExactMesh)
//  BM_Build/<mesh>                       MeshReference's constructor (BVH, AABB tree, KD-tree);
//                                        counters memory_mb, bvh_nodes
//
// Built with -DDRAPE_BUILD_BENCH=ON (bench_mesh_reference). Run: build-X/bin/bench_mesh_reference

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "drape/bake/mesh_queries.h"
#include "drape/bake/mesh_reference.h"
#include "reference_meshes.h"
#include "test_support.h"

namespace drape {
namespace {

using bake::ExactMesh;
using bake::MeshReference;
using bake::WindingNumberOptions;
using test::BoxPoints;
using test::LoadRestPose;
using test::MakeIcosphere;
using test::Mesh;
using test::NearSurfacePoints;
using test::Ptr;
using test::V3;

// The mesh of index `which` (0 icosphere, 1 mannequin, 2 CesiumMan), or false when its file is
// absent or does not import. `small` makes the icosphere the distance tests' coarser one.
bool LoadMesh(int which, bool small, Mesh* mesh, std::string* why) {
  if (which == 0) {
    *mesh =
        small ? MakeIcosphere(3, 0.25, {-0.1, 0.4, 0.2}) : MakeIcosphere(4, 0.3, {0.1, -0.2, 0.05});
    return true;
  }
  const std::string path =
      which == 1 ? test::MannequinPath() : test::CharacterPath("CesiumMan/CesiumMan.glb");
  if (!std::filesystem::exists(path)) {
    *why = "shared asset absent: " + path;
    return false;
  }
  if (!LoadRestPose(path, mesh)) {
    *why = path + ": import failed";
    return false;
  }
  return true;
}

// The mesh, its points and the brute-force winding numbers there, made once per mesh.
struct WindingCase {
  Mesh mesh;
  std::vector<V3> points;
  std::vector<double> brute;  // ExactMesh::WindingNumber at each point
  std::string error;          // non-empty: the mesh is unavailable
};

const WindingCase& GetWindingCase(int which) {
  static WindingCase cache[3];
  static bool made[3] = {false, false, false};
  WindingCase& c = cache[which];
  if (made[which]) return c;
  made[which] = true;
  if (!LoadMesh(which, false, &c.mesh, &c.error)) return c;
  c.points = BoxPoints(c.mesh, 1000, 31);
  const std::vector<V3> near = NearSurfacePoints(c.mesh, 1000, 0.01, 32);
  c.points.insert(c.points.end(), near.begin(), near.end());
  const ExactMesh brute(c.mesh.positions, c.mesh.triangles);
  for (const V3& p : c.points) c.brute.push_back(brute.WindingNumber(Ptr(p)));
  return c;
}

void SetPerQuery(benchmark::State& state, size_t queries) {
  state.counters["ns_per_query"] = benchmark::Counter(
      static_cast<double>(queries) * 1e-9,
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_WindingSetting(benchmark::State& state) {
  const WindingCase& c = GetWindingCase(static_cast<int>(state.range(0)));
  if (!c.error.empty()) {
    state.SkipWithError(c.error.c_str());
    return;
  }
  WindingNumberOptions options;
  options.beta = static_cast<double>(state.range(1)) / 10.0;
  options.expansion_order = 2;
  options.leaf_size = 4;
  const MeshReference fast(c.mesh.positions, c.mesh.triangles, options);
  std::vector<double> w(c.points.size());
  for (auto _ : state) {
    for (size_t i = 0; i < c.points.size(); ++i) w[i] = fast.WindingNumber(Ptr(c.points[i]));
    benchmark::DoNotOptimize(w.data());
  }
  double max_error = 0.0;
  size_t clear_disagreements = 0;
  for (size_t i = 0; i < c.points.size(); ++i) {
    max_error = std::max(max_error, std::fabs(w[i] - c.brute[i]));
    clear_disagreements +=
        (w[i] > 0.5) != (c.brute[i] > 0.5) && std::fabs(c.brute[i] - 0.5) > 0.1 ? 1 : 0;
  }
  SetPerQuery(state, c.points.size());
  state.counters["max_error"] = max_error;
  state.counters["clear_disagreements"] = static_cast<double>(clear_disagreements);
}
BENCHMARK(BM_WindingSetting)
    ->ArgNames({"mesh", "beta10"})
    ->ArgsProduct({{0, 1, 2}, {20, 30, 35, 40}});

void BM_BruteWindingNumber(benchmark::State& state) {
  const WindingCase& c = GetWindingCase(static_cast<int>(state.range(0)));
  if (!c.error.empty()) {
    state.SkipWithError(c.error.c_str());
    return;
  }
  const ExactMesh brute(c.mesh.positions, c.mesh.triangles);
  double sum = 0.0;
  for (auto _ : state) {
    for (const V3& p : c.points) sum += brute.WindingNumber(Ptr(p));
    benchmark::DoNotOptimize(sum);
  }
  SetPerQuery(state, c.points.size());
}
BENCHMARK(BM_BruteWindingNumber)->ArgName("mesh")->DenseRange(0, 2);

void BM_Distance(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0));
  Mesh mesh;
  std::string why;
  if (!LoadMesh(which, true, &mesh, &why)) {
    state.SkipWithError(why.c_str());
    return;
  }
  std::vector<V3> points = BoxPoints(mesh, 1000, which == 0 ? 41 : 51);
  const std::vector<V3> near = which == 0 ? NearSurfacePoints(mesh, 500, 0.005, 42)
                                          : NearSurfacePoints(mesh, 1000, 0.01, 52);
  points.insert(points.end(), near.begin(), near.end());
  const MeshReference fast(mesh.positions, mesh.triangles);
  const ExactMesh brute(mesh.positions, mesh.triangles);
  const bool aabb_tree = state.range(1) == 0;
  double sum = 0.0;
  for (auto _ : state) {
    for (const V3& p : points) sum += aabb_tree ? fast.Distance(Ptr(p)) : brute.Distance(Ptr(p));
    benchmark::DoNotOptimize(sum);
  }
  SetPerQuery(state, points.size());
  state.counters["triangles"] = static_cast<double>(mesh.triangles.size() / 3);
}
BENCHMARK(BM_Distance)->ArgNames({"mesh", "method"})->ArgsProduct({{0, 1}, {0, 1}});

void BM_Build(benchmark::State& state) {
  Mesh mesh;
  std::string why;
  if (!LoadMesh(static_cast<int>(state.range(0)), false, &mesh, &why)) {
    state.SkipWithError(why.c_str());
    return;
  }
  size_t bytes = 0, nodes = 0;
  for (auto _ : state) {
    const MeshReference reference(mesh.positions, mesh.triangles);
    bytes = reference.memory_bytes();
    nodes = reference.bvh_node_count();
    benchmark::DoNotOptimize(bytes);
  }
  state.counters["memory_mb"] = static_cast<double>(bytes) / 1e6;
  state.counters["bvh_nodes"] = static_cast<double>(nodes);
}
BENCHMARK(BM_Build)->ArgName("mesh")->DenseRange(0, 2)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace drape

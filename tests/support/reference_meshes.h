#pragma once
// Meshes and query points for the tests and benchmarks of the exact reference and the peers
// (bench/): an icosphere computed in double and stored in float, a character's rest pose skinned
// by the runtime, points uniform in a mesh's inflated box and points near its surface, from
// fixed seeds. Header-only; needs Eigen and the bake's importer.

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "drape/bake/importer.h"
#include "drape/formats/types.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"

namespace drape::test {

struct Mesh {
  std::vector<Float3> positions;
  std::vector<uint32_t> triangles;
};

using V3 = Eigen::Vector3d;  // metres, double: the brute-force references' arithmetic
inline V3 ToV3(Float3 f) { return {f.x, f.y, f.z}; }
inline V3 Corner(const Mesh& m, size_t t, int c) {
  return ToV3(m.positions[m.triangles[3 * t + c]]);
}

// Icosphere of radius `radius` about `centre`, outward counter-clockwise; `subdivisions` splits
// every triangle in four, vertices pushed to the sphere (in float: the stored precision).
inline Mesh MakeIcosphere(int subdivisions, double radius, V3 centre = V3::Zero()) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<V3> v = {{-1, g, 0},  {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                       {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
  std::vector<uint32_t> f = {0, 11, 5,  0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
                             4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3,  4,  2, 3, 2, 6, 3,
                             6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6,  2, 10, 8,  6, 7, 9, 8, 1};
  for (V3& p : v) p = p * (1.0 / p.norm());
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoint;
    auto mid = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      const V3 m = (v[a] + v[b]) * 0.5;
      v.push_back(m * (1.0 / m.norm()));
      const uint32_t index = static_cast<uint32_t>(v.size() - 1);
      midpoint.emplace(key, index);
      return index;
    };
    std::vector<uint32_t> next;
    for (size_t t = 0; t < f.size(); t += 3) {
      const uint32_t a = f[t], b = f[t + 1], c = f[t + 2];
      const uint32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    f = std::move(next);
  }
  Mesh mesh;
  for (const V3& p : v) {
    const V3 q = centre + (p * radius);
    mesh.positions.push_back(
        {static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z())});
  }
  mesh.triangles = std::move(f);
  return mesh;
}

// The character's rest pose skinned by the runtime (linear blend skinning), or false if the
// import fails.
inline bool LoadRestPose(const std::string& path, Mesh* mesh) {
  bake::Character character;
  if (!bake::ImportCharacter(path, bake::ImportOptions{}, &character).ok()) return false;
  SkeletonPose pose;
  if (!pose.Init(character.skeleton).ok()) return false;
  pose.SetRest();
  mesh->positions.assign(character.mesh.positions.size(), Float3{});
  if (!SkinMesh(character.mesh, pose.skinning(), mesh->positions).ok()) return false;
  mesh->triangles = character.mesh.triangles;
  return true;
}

struct Bounds {
  V3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
};
inline Bounds BoundsOf(const Mesh& m) {
  Bounds b;
  for (const Float3& f : m.positions) {
    b.lo = b.lo.cwiseMin(ToV3(f));
    b.hi = b.hi.cwiseMax(ToV3(f));
  }
  return b;
}

// `count` points uniform in the bounding box inflated by 10 % of its extent on every side.
inline std::vector<V3> BoxPoints(const Mesh& m, size_t count, uint64_t seed) {
  const Bounds b = BoundsOf(m);
  const V3 margin = (b.hi - b.lo) * 0.1;
  const V3 lo = b.lo - margin, hi = b.hi + margin;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> x(lo.x(), hi.x()), y(lo.y(), hi.y()), z(lo.z(), hi.z());
  std::vector<V3> points(count);
  for (V3& p : points) p = {x(rng), y(rng), z(rng)};
  return points;
}

// `count` points near the surface: a random point of a random triangle, moved along its normal by
// up to `offset` metres either way.
inline std::vector<V3> NearSurfacePoints(const Mesh& m, size_t count, double offset,
                                         uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<size_t> pick(0, m.triangles.size() / 3 - 1);
  std::uniform_real_distribution<double> unit(0.0, 1.0), along(-offset, offset);
  std::vector<V3> points;
  while (points.size() < count) {
    const size_t t = pick(rng);
    const V3 a = Corner(m, t, 0), b = Corner(m, t, 1), c = Corner(m, t, 2);
    const V3 n = (b - a).cross(c - a);
    if (n.norm() == 0.0) continue;
    double u = unit(rng), v = unit(rng);
    if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
    const V3 on = a + ((b - a) * u + (c - a) * v);
    points.push_back(on + n * (along(rng) / n.norm()));
  }
  return points;
}

inline const double* Ptr(const V3& v) { return v.data(); }

}  // namespace drape::test

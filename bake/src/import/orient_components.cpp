#include "import/orient_components.h"

#include <Eigen/Dense>
#include <algorithm>
#include <map>
#include <utility>
#include <vector>

namespace drape::bake::detail {

size_t OrientComponentsOutward(MeshData* mesh) {
  using Vec3 = Eigen::Vector3d;
  const uint32_t vertex_count = mesh->vertex_count();
  std::vector<uint32_t> root(vertex_count);
  for (uint32_t v = 0; v < vertex_count; ++v) root[v] = v;
  auto find = [&](uint32_t v) {
    while (root[v] != v) v = root[v] = root[root[v]];
    return v;
  };
  const size_t triangles = mesh->triangles.size() / 3;
  for (size_t t = 0; t < triangles; ++t) {
    const uint32_t a = find(mesh->triangles[3 * t]);
    for (int k = 1; k < 3; ++k) {
      const uint32_t b = find(mesh->triangles[3 * t + k]);
      if (a != b) root[std::max(a, b)] = std::min(a, b);
    }
  }
  std::map<uint32_t, std::pair<Vec3, double>> centroid;  // component -> (sum, count)
  for (uint32_t v = 0; v < vertex_count; ++v) {
    auto& c = centroid.try_emplace(find(v), Vec3::Zero(), 0.0).first->second;
    c.first += Vec3(mesh->positions[v].x, mesh->positions[v].y, mesh->positions[v].z);
    c.second += 1.0;
  }
  std::map<uint32_t, double> volume;
  for (size_t t = 0; t < triangles; ++t) {
    const uint32_t component = find(mesh->triangles[3 * t]);
    const auto& c = centroid[component];
    const Vec3 origin = c.first / c.second;
    Vec3 p[3];
    for (int k = 0; k < 3; ++k) {
      const Float3 q = mesh->positions[mesh->triangles[3 * t + k]];
      p[k] = Vec3(q.x, q.y, q.z) - origin;
    }
    volume[component] += p[0].dot(p[1].cross(p[2])) / 6.0;
  }
  size_t flipped = 0;
  for (const auto& [component, v] : volume) flipped += v < 0.0;
  for (size_t t = 0; t < triangles; ++t) {
    if (volume[find(mesh->triangles[3 * t])] < 0.0)
      std::swap(mesh->triangles[3 * t + 1], mesh->triangles[3 * t + 2]);
  }
  return flipped;
}

}  // namespace drape::bake::detail

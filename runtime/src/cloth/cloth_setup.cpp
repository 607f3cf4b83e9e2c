#include "cloth/cloth_setup.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <utility>

#include "drape/runtime/math.h"

namespace drape::detail {

std::vector<ClothTether> BuildTethers(std::span<const Float3> positions,
                                      std::span<const uint32_t> triangles,
                                      std::span<const uint8_t> kinematic,
                                      std::span<const float> stretch_per_particle, float stretch,
                                      uint32_t* untethered) {
  const uint32_t n = static_cast<uint32_t>(positions.size());
  // Adjacency of the triangles' edges (compressed rows, neighbours sorted and unique).
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  edges.reserve(triangles.size() * 2);
  for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = triangles[t + e], b = triangles[t + (e + 1) % 3];
      if (a == b) continue;
      edges.emplace_back(a, b);
      edges.emplace_back(b, a);
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  std::vector<uint32_t> row(n + 1, 0);
  for (const auto& e : edges) ++row[e.first + 1];
  for (uint32_t i = 0; i < n; ++i) row[i + 1] += row[i];

  constexpr double kUnreached = std::numeric_limits<double>::infinity();
  std::vector<double> distance(n, kUnreached);
  std::vector<uint32_t> anchor(n, 0);
  using Entry = std::pair<double, uint32_t>;  // (distance, particle): ties by index
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  for (uint32_t i = 0; i < n; ++i) {
    if (!kinematic[i]) continue;
    distance[i] = 0.0;
    anchor[i] = i;
    open.emplace(0.0, i);
  }
  while (!open.empty()) {
    const auto [d, i] = open.top();
    open.pop();
    if (d > distance[i]) continue;  // a stale entry
    for (uint32_t k = row[i]; k < row[i + 1]; ++k) {
      const uint32_t j = edges[k].second;
      if (kinematic[j]) continue;
      const Float3 a = positions[i], b = positions[j];
      const double dx = double(b.x) - a.x, dy = double(b.y) - a.y, dz = double(b.z) - a.z;
      const double through = d + std::sqrt(dx * dx + dy * dy + dz * dz);
      if (through < distance[j] || (through == distance[j] && anchor[i] < anchor[j])) {
        distance[j] = through;
        anchor[j] = anchor[i];
        open.emplace(through, j);
      }
    }
  }
  std::vector<ClothTether> tethers;
  *untethered = 0;
  for (uint32_t i = 0; i < n; ++i) {
    if (kinematic[i]) continue;
    if (distance[i] == kUnreached) {
      ++*untethered;
      continue;
    }
    const double limit = stretch_per_particle.empty() ? stretch : stretch_per_particle[i];
    const float length = static_cast<float>(distance[i] * (1.0 + limit));
    if (!(length > 0.f)) continue;  // a particle on top of its anchor: nothing to bound
    tethers.push_back({i, anchor[i], length});
  }
  return tethers;
}

std::vector<Float3> VertexNormals(std::span<const Float3> positions,
                                  std::span<const uint32_t> triangles) {
  std::vector<Float3> normals(positions.size(), Float3{});
  for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
    const uint32_t i = triangles[t], j = triangles[t + 1], k = triangles[t + 2];
    // |cross| is twice the area: the sum is area weighted.
    const Float3 n = Cross(positions[j] - positions[i], positions[k] - positions[i]);
    normals[i] += n;
    normals[j] += n;
    normals[k] += n;
  }
  for (Float3& n : normals) n = NormalizeOr(n, {0.f, 1.f, 0.f});
  return normals;
}

}  // namespace drape::detail

#pragma once
// A unit sphere for test fixtures: an octahedron subdivided `levels` times (every triangle split
// in four, the midpoints pushed onto the sphere). Square roots only, so the same positions on
// every IEEE machine; counter-clockwise seen from outside; shared vertices. Fixtures scale, move
// or snap it. Header-only.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

namespace drape::test {

struct UnitSphereMesh {
  std::vector<std::array<double, 3>> positions;    // unit length
  std::vector<std::array<uint32_t, 3>> triangles;  // 8 * 4^levels
};

inline UnitSphereMesh OctahedronSphere(int levels) {
  UnitSphereMesh m;
  m.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                 {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  std::vector<std::array<double, 3>>& p = m.positions;
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;
    const auto mid = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      if (const auto found = midpoints.find(key); found != midpoints.end()) return found->second;
      std::array<double, 3> q = {p[a][0] + p[b][0], p[a][1] + p[b][1], p[a][2] + p[b][2]};
      const double length = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
      for (double& c : q) c /= length;
      p.push_back(q);
      midpoints.emplace(key, static_cast<uint32_t>(p.size() - 1));
      return static_cast<uint32_t>(p.size() - 1);
    };
    std::vector<std::array<uint32_t, 3>> finer;
    for (const auto& f : m.triangles) {
      const uint32_t ab = mid(f[0], f[1]), bc = mid(f[1], f[2]), ca = mid(f[2], f[0]);
      finer.insert(finer.end(), {{f[0], ab, ca}, {ab, f[1], bc}, {ca, bc, f[2]}, {ab, bc, ca}});
    }
    m.triangles = std::move(finer);
  }
  return m;
}

}  // namespace drape::test

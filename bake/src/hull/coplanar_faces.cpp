#include "hull/coplanar_faces.h"

#include "hull/hull_kernel.h"  // first of the CGAL headers

#include <algorithm>
#include <array>
#include <numeric>
#include <utility>

namespace drape::bake::detail {
namespace {

// Edge-adjacent triangle pairs (t, t2) with the apex of t2 opposite the shared edge.
struct Adjacency {
  uint32_t t, t2, apex2;
};
std::vector<Adjacency> TriangleAdjacency(const Mesh& mesh) {
  std::vector<std::pair<uint64_t, uint32_t>> directed;  // (a << 32 | b, triangle)
  for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      directed.push_back({(static_cast<uint64_t>(tri[static_cast<size_t>(k)]) << 32) |
                              tri[static_cast<size_t>((k + 1) % 3)],
                          t});
    }
  }
  std::sort(directed.begin(), directed.end());
  std::vector<Adjacency> out;
  for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tri[static_cast<size_t>(k)], b = tri[static_cast<size_t>((k + 1) % 3)];
      const uint64_t reverse = (static_cast<uint64_t>(b) << 32) | a;
      const auto it =
          std::lower_bound(directed.begin(), directed.end(), std::make_pair(reverse, uint32_t{0}));
      if (it == directed.end() || it->first != reverse) continue;
      const auto& other = mesh.triangles[it->second];
      uint32_t apex = other[0];
      for (uint32_t c : other) {
        if (c != a && c != b) apex = c;
      }
      out.push_back({t, it->second, apex});
    }
  }
  return out;
}

}  // namespace

uint32_t Find(std::vector<uint32_t>& parent, uint32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}
void Union(std::vector<uint32_t>& parent, uint32_t a, uint32_t b) {
  a = Find(parent, a);
  b = Find(parent, b);
  if (a == b) return;
  if (a < b) {
    parent[b] = a;
  } else {
    parent[a] = b;
  }
}

std::vector<uint32_t> GroupCoplanar(const Mesh& mesh, uint32_t* group_count,
                                    std::vector<uint32_t>* parent_out) {
  const uint32_t n = static_cast<uint32_t>(mesh.triangles.size());
  std::vector<uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  for (const Adjacency& adj : TriangleAdjacency(mesh)) {
    if (adj.t2 < adj.t) continue;
    const auto& tri = mesh.triangles[adj.t];
    if (CGAL::orientation(ToPoint(mesh.points[tri[0]]), ToPoint(mesh.points[tri[1]]),
                          ToPoint(mesh.points[tri[2]]),
                          ToPoint(mesh.points[adj.apex2])) == CGAL::COPLANAR) {
      Union(parent, adj.t, adj.t2);
    }
  }
  if (parent_out) *parent_out = parent;
  std::vector<uint32_t> group(n), root_group(n, UINT32_MAX);
  uint32_t count = 0;
  for (uint32_t t = 0; t < n; ++t) {
    const uint32_t root = Find(parent, t);
    if (root_group[root] == UINT32_MAX) root_group[root] = count++;
    group[t] = root_group[root];
  }
  *group_count = count;
  return group;
}

bool CanonicalTriangulation(Mesh* mesh) {
  uint32_t group_count = 0;
  const std::vector<uint32_t> group = GroupCoplanar(*mesh, &group_count);
  std::vector<std::vector<uint32_t>> members(group_count);
  for (uint32_t t = 0; t < mesh->triangles.size(); ++t) members[group[t]].push_back(t);
  std::vector<std::array<uint32_t, 3>> out;
  out.reserve(mesh->triangles.size());
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  std::vector<uint32_t> cycle;
  for (const std::vector<uint32_t>& face : members) {
    if (face.size() == 1) {
      out.push_back(mesh->triangles[face[0]]);
      continue;
    }
    edges.clear();
    for (uint32_t t : face) {
      const auto& tri = mesh->triangles[t];
      for (int k = 0; k < 3; ++k) edges.push_back({tri[k], tri[(k + 1) % 3]});
    }
    std::sort(edges.begin(), edges.end());
    // Boundary: directed edges whose reverse is not in the face.
    std::vector<std::pair<uint32_t, uint32_t>> boundary;
    for (const auto& e : edges) {
      if (!std::binary_search(edges.begin(), edges.end(), std::make_pair(e.second, e.first))) {
        boundary.push_back(e);
      }
    }
    // Not a disk without inner vertices, or no valid fan: keep CGAL's triangles for this face.
    auto keep = [&]() {
      for (uint32_t t : face) out.push_back(mesh->triangles[t]);
    };
    if (boundary.size() != face.size() + 2) {
      keep();
      continue;
    }
    cycle.clear();
    uint32_t current = boundary[0].first;  // sorted: the smallest vertex index
    for (size_t step = 0; step < boundary.size(); ++step) {
      cycle.push_back(current);
      const auto it =
          std::lower_bound(boundary.begin(), boundary.end(), std::make_pair(current, uint32_t{0}));
      if (it == boundary.end() || it->first != current) break;
      current = it->second;
    }
    if (cycle.size() != boundary.size() || current != cycle[0]) {
      keep();
      continue;
    }
    const size_t m = cycle.size();
    bool done = false;
    for (size_t apex = 0; apex < m && !done; ++apex) {
      bool ok = true;
      for (size_t i = 1; i + 1 < m && ok; ++i) {
        ok = !CGAL::collinear(ToPoint(mesh->points[cycle[apex]]),
                              ToPoint(mesh->points[cycle[(apex + i) % m]]),
                              ToPoint(mesh->points[cycle[(apex + i + 1) % m]]));
      }
      if (!ok) continue;
      for (size_t i = 1; i + 1 < m; ++i) {
        out.push_back({cycle[apex], cycle[(apex + i) % m], cycle[(apex + i + 1) % m]});
      }
      done = true;
    }
    if (!done) keep();
  }
  for (auto& tri : out) {
    while (tri[0] > tri[1] || tri[0] > tri[2]) tri = {tri[1], tri[2], tri[0]};
  }
  std::sort(out.begin(), out.end());
  mesh->triangles = std::move(out);
  return true;
}

}  // namespace drape::bake::detail

#include "drape/bake/kirkpatrick_builder.h"

#include "drape/runtime/exact_orientation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "drape/runtime/hull_collider_set.h"

namespace drape::bake {
namespace {

Status Fail(const std::string& what) {
  return Status(StatusCode::kInvalidArgument, "Kirkpatrick: " + what);
}

struct Point {
  float u = 0.f, v = 0.f;
};
// Sign of the signed area of (a, b, c): > 0 counter-clockwise.
int Orient(const Point& a, const Point& b, const Point& c) {
  return Orient2dExact(a.u, a.v, b.u, b.v, c.u, c.v);
}
double Area2(const Point& a, const Point& b, const Point& c) {  // approximate, for ranking only
  return (double(b.u) - a.u) * (double(c.v) - a.v) - (double(b.v) - a.v) * (double(c.u) - a.u);
}

using Tri = std::array<uint32_t, 3>;

// Interiors of two counter-clockwise triangles intersect (positive-area overlap): no edge line of
// either separates them (touching counts as separated).
bool OverlapPositiveArea(const std::vector<Point>& p, const Tri& a, const Tri& b) {
  auto separates = [&](const Tri& s, const Tri& t) {
    for (int e = 0; e < 3; ++e) {
      const Point& e0 = p[s[e]];
      const Point& e1 = p[s[(e + 1) % 3]];
      if (Orient(e0, e1, p[t[0]]) <= 0 && Orient(e0, e1, p[t[1]]) <= 0 &&
          Orient(e0, e1, p[t[2]]) <= 0)
        return true;
    }
    return false;
  };
  return !separates(a, b) && !separates(b, a);
}

// Directed-edge key.
uint64_t EdgeKey(uint32_t a, uint32_t b) { return (uint64_t(a) << 32) | b; }

// Checks that `tris` is a proper triangulation of the triangle (c0, c1, c2): every triangle
// strictly counter-clockwise, every directed edge once, unmatched edges exactly the three sides.
bool IsTriangulationOfTriangle(const std::vector<Point>& p, const std::vector<Tri>& tris,
                               uint32_t c0, uint32_t c1, uint32_t c2, std::string* why) {
  std::vector<uint64_t> edges;
  edges.reserve(tris.size() * 3);
  for (const Tri& t : tris) {
    if (Orient(p[t[0]], p[t[1]], p[t[2]]) <= 0) {
      *why = "a triangle is not strictly counter-clockwise";
      return false;
    }
    for (int e = 0; e < 3; ++e) edges.push_back(EdgeKey(t[e], t[(e + 1) % 3]));
  }
  std::sort(edges.begin(), edges.end());
  if (std::adjacent_find(edges.begin(), edges.end()) != edges.end()) {
    *why = "a directed edge is used twice (overlapping triangles)";
    return false;
  }
  std::vector<uint64_t> unmatched;
  for (uint64_t e : edges) {
    const uint64_t reverse = ((e & 0xffffffffu) << 32) | (e >> 32);
    if (!std::binary_search(edges.begin(), edges.end(), reverse)) unmatched.push_back(e);
  }
  std::vector<uint64_t> expected = {EdgeKey(c0, c1), EdgeKey(c1, c2), EdgeKey(c2, c0)};
  std::sort(expected.begin(), expected.end());
  if (unmatched != expected) {
    *why = "the triangles do not tile the enclosing triangle";
    return false;
  }
  return true;
}

// Ear clipping of a simple counter-clockwise polygon (a star-shaped hole). Appends the triangles;
// false if no valid ear is found (never for a simple polygon in exact arithmetic).
bool EarClip(const std::vector<Point>& p, std::vector<uint32_t> polygon, std::vector<Tri>* out) {
  while (polygon.size() > 3) {
    const size_t k = polygon.size();
    size_t best = k;
    double best_quality = -1.0;
    for (size_t i = 0; i < k; ++i) {
      const uint32_t a = polygon[(i + k - 1) % k], b = polygon[i], c = polygon[(i + 1) % k];
      if (Orient(p[a], p[b], p[c]) <= 0) continue;
      bool empty = true;
      for (size_t j = 0; j < k && empty; ++j) {
        const uint32_t w = polygon[j];
        if (w == a || w == b || w == c) continue;
        if (Orient(p[a], p[b], p[w]) >= 0 && Orient(p[b], p[c], p[w]) >= 0 &&
            Orient(p[c], p[a], p[w]) >= 0)
          empty = false;
      }
      if (!empty) continue;
      // Shape quality: 4 sqrt(3) area / sum of squared edge lengths (1 for equilateral).
      auto len2 = [&](uint32_t x, uint32_t y) {
        const double du = double(p[x].u) - p[y].u, dv = double(p[x].v) - p[y].v;
        return du * du + dv * dv;
      };
      const double perimeter2 = len2(a, b) + len2(b, c) + len2(c, a);
      const double quality =
          perimeter2 > 0.0 ? 2.0 * std::sqrt(3.0) * Area2(p[a], p[b], p[c]) / perimeter2 : 0.0;
      if (quality > best_quality) {
        best_quality = quality;
        best = i;
      }
    }
    if (best == k) return false;
    out->push_back({polygon[(best + k - 1) % k], polygon[best], polygon[(best + 1) % k]});
    polygon.erase(polygon.begin() + static_cast<std::ptrdiff_t>(best));
  }
  if (Orient(p[polygon[0]], p[polygon[1]], p[polygon[2]]) <= 0) return false;
  out->push_back({polygon[0], polygon[1], polygon[2]});
  return true;
}

}  // namespace

Status BuildPlanarHierarchy(std::span<const float> vertices_uv, std::span<const uint32_t> triangles,
                            std::span<const int32_t> labels, const KirkpatrickOptions& options,
                            KirkpatrickHierarchy* out, KirkpatrickSideStats* stats) {
  *out = KirkpatrickHierarchy{};
  KirkpatrickSideStats local_stats;
  if (stats == nullptr) stats = &local_stats;
  *stats = KirkpatrickSideStats{};
  if (options.max_removal_degree < 3 || options.max_removal_degree > 64)
    return Fail("max_removal_degree is not in [3, 64]");
  if (!(options.bounding_scale >= 2.f && options.bounding_scale <= 1e4f))
    return Fail("bounding_scale is not in [2, 1e4]");
  if (vertices_uv.size() % 2 != 0) return Fail("vertices_uv size is odd");
  if (triangles.empty() || triangles.size() % 3 != 0)
    return Fail("triangle list is empty or not a multiple of 3");
  const size_t tri_count = triangles.size() / 3;
  if (labels.size() != tri_count) return Fail("labels size is not the triangle count");
  const uint32_t input_vertices = static_cast<uint32_t>(vertices_uv.size() / 2);
  for (uint32_t index : triangles)
    if (index >= input_vertices) return Fail("a triangle index is out of range");
  for (int32_t label : labels)
    if (label < -1) return Fail("a label is below -1");
  for (float x : vertices_uv)
    if (!std::isfinite(x)) return Fail("a vertex is not finite");

  // Compact the used vertices (in index order).
  std::vector<uint32_t> remap(input_vertices, UINT32_MAX);
  std::vector<Point> points;
  for (uint32_t index : triangles) remap[index] = 0;
  for (uint32_t v = 0; v < input_vertices; ++v)
    if (remap[v] == 0) {
      remap[v] = static_cast<uint32_t>(points.size());
      points.push_back({vertices_uv[2 * v], vertices_uv[2 * v + 1]});
    }
  const uint32_t face_vertices = static_cast<uint32_t>(points.size());
  std::vector<Tri> tris(tri_count);
  std::vector<int32_t> tri_labels(labels.begin(), labels.end());
  stats->min_face_area = std::numeric_limits<double>::infinity();
  for (size_t t = 0; t < tri_count; ++t) {
    tris[t] = {remap[triangles[3 * t]], remap[triangles[3 * t + 1]], remap[triangles[3 * t + 2]]};
    if (Orient(points[tris[t][0]], points[tris[t][1]], points[tris[t][2]]) <= 0)
      return Fail("face triangle " + std::to_string(t) +
                  " is not strictly counter-clockwise in (u, v)");
    stats->min_face_area =
        std::min(stats->min_face_area,
                 0.5 * Area2(points[tris[t][0]], points[tris[t][1]], points[tris[t][2]]));
  }
  stats->faces = static_cast<uint32_t>(tri_count);

  // Boundary cycle: directed edges whose reverse is missing.
  std::vector<uint64_t> edges;
  for (const Tri& t : tris)
    for (int e = 0; e < 3; ++e) edges.push_back(EdgeKey(t[e], t[(e + 1) % 3]));
  std::sort(edges.begin(), edges.end());
  if (std::adjacent_find(edges.begin(), edges.end()) != edges.end())
    return Fail("the faces use a directed edge twice (folded projection)");
  std::vector<uint32_t> next(face_vertices, UINT32_MAX);
  size_t boundary_edges = 0;
  for (uint64_t e : edges) {
    const uint32_t a = static_cast<uint32_t>(e >> 32), b = static_cast<uint32_t>(e & 0xffffffffu);
    if (std::binary_search(edges.begin(), edges.end(), EdgeKey(b, a))) continue;
    if (next[a] != UINT32_MAX) return Fail("the shadow boundary touches itself at a vertex");
    next[a] = b;
    ++boundary_edges;
  }
  if (boundary_edges < 3) return Fail("the faces have no boundary (not a disk)");
  uint32_t start = 0;
  while (next[start] == UINT32_MAX) ++start;
  std::vector<uint32_t> cycle;
  for (uint32_t v = start;;) {
    cycle.push_back(v);
    v = next[v];
    if (v == UINT32_MAX) return Fail("the shadow boundary is not closed");
    if (v == start) break;
    if (cycle.size() > boundary_edges) return Fail("the shadow boundary is not one cycle");
  }
  if (cycle.size() != boundary_edges) return Fail("the shadow boundary is not one simple cycle");
  stats->boundary_vertices = static_cast<uint32_t>(cycle.size());

  // Enclosing triangle around the boundary's centroid.
  double cu = 0.0, cv = 0.0;
  for (uint32_t v : cycle) {
    cu += points[v].u;
    cv += points[v].v;
  }
  cu /= static_cast<double>(cycle.size());
  cv /= static_cast<double>(cycle.size());
  double radius = 0.0;
  for (uint32_t v : cycle)
    radius = std::max(radius, std::hypot(points[v].u - cu, points[v].v - cv));
  if (!(radius > 0.0)) return Fail("the shadow has zero extent");
  const uint32_t corner0 = face_vertices;
  for (int k = 0; k < 3; ++k) {
    const double angle = 3.14159265358979323846 * (0.5 + 2.0 * k / 3.0);
    points.push_back({static_cast<float>(cu + options.bounding_scale * radius * std::cos(angle)),
                      static_cast<float>(cv + options.bounding_scale * radius * std::sin(angle))});
  }
  // Fill the annulus: edge i (cycle[i] -> cycle[i+1]) to the corner farthest along its outward
  // normal, corner wedges where the assignment advances.
  const size_t m = cycle.size();
  std::vector<int> corner_of(m);
  for (size_t i = 0; i < m; ++i) {
    const Point& a = points[cycle[i]];
    const Point& b = points[cycle[(i + 1) % m]];
    const double nu = double(b.v) - a.v, nv = -(double(b.u) - a.u);
    int best = 0;
    double best_dot = -std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
      const double dot = (points[corner0 + k].u - cu) * nu + (points[corner0 + k].v - cv) * nv;
      if (dot > best_dot) {
        best_dot = dot;
        best = k;
      }
    }
    corner_of[i] = best;
  }
  std::vector<Tri> all = tris;
  int steps = 0;
  for (size_t i = 0; i < m; ++i) {
    const uint32_t a = cycle[i], b = cycle[(i + 1) % m];
    all.push_back({b, a, corner0 + static_cast<uint32_t>(corner_of[i])});
    // Wedges at a, from the previous edge's corner to this edge's corner.
    int k = corner_of[(i + m - 1) % m];
    while (k != corner_of[i]) {
      const int k1 = (k + 1) % 3;
      all.push_back({corner0 + static_cast<uint32_t>(k), corner0 + static_cast<uint32_t>(k1), a});
      k = k1;
      if (++steps > 3) return Fail("the corner assignment of the fill is not monotone");
    }
  }
  stats->fill_triangles = static_cast<uint32_t>(all.size() - tri_count);
  std::string why;
  if (!IsTriangulationOfTriangle(points, all, corner0, corner0 + 1, corner0 + 2, &why))
    return Fail("invalid planar subdivision: " + why);
  for (size_t t = tri_count; t < all.size(); ++t) tri_labels.push_back(-1);

  // ---- The hierarchy.
  const uint32_t vertex_count = static_cast<uint32_t>(points.size());
  std::vector<Tri> nodes = all;
  std::vector<uint32_t> child_offsets = {0};
  std::vector<uint32_t> children;
  for (size_t n = 0; n < all.size(); ++n) child_offsets.push_back(0);
  std::vector<std::vector<uint32_t>> incident(vertex_count);
  for (uint32_t n = 0; n < nodes.size(); ++n)
    for (uint32_t v : nodes[n]) incident[v].push_back(n);
  std::vector<bool> removed(vertex_count, false);
  uint32_t remaining = face_vertices;  // non-corner vertices left
  uint32_t levels = 1;
  uint32_t max_children = 0;
  uint32_t degree_limit = options.max_removal_degree;
  while (remaining > 0) {
    // Candidates: lowest degree first, then lowest index.
    std::vector<std::pair<uint32_t, uint32_t>> candidates;
    for (uint32_t v = 0; v < face_vertices; ++v)
      if (!removed[v] && incident[v].size() <= degree_limit)
        candidates.push_back({static_cast<uint32_t>(incident[v].size()), v});
    if (candidates.empty()) {
      if (degree_limit >= vertex_count) return Fail("no removable vertex (internal error)");
      ++degree_limit;
      continue;
    }
    std::sort(candidates.begin(), candidates.end());
    std::vector<bool> blocked(vertex_count, false);
    uint32_t removed_this_level = 0;
    for (const auto& [degree, v] : candidates) {
      if (blocked[v]) continue;
      // Link polygon: (v, a, b) in each incident triangle gives the link edge a -> b.
      std::vector<std::pair<uint32_t, uint32_t>> link;
      for (uint32_t n : incident[v]) {
        const Tri& t = nodes[n];
        const int at = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
        link.push_back({t[(at + 1) % 3], t[(at + 2) % 3]});
      }
      std::sort(link.begin(), link.end());
      std::vector<uint32_t> polygon;
      bool closed = true;
      for (uint32_t w = link[0].first;;) {
        polygon.push_back(w);
        auto it = std::lower_bound(link.begin(), link.end(), std::make_pair(w, 0u));
        if (it == link.end() || it->first != w) {
          closed = false;
          break;
        }
        w = it->second;
        if (w == link[0].first) break;
        if (polygon.size() > link.size()) {
          closed = false;
          break;
        }
      }
      if (!closed || polygon.size() != link.size())
        return Fail("a vertex star is not a closed fan");
      std::vector<Tri> patch;
      if (!EarClip(points, polygon, &patch)) continue;  // keep v for a later level
      blocked[v] = true;
      for (uint32_t w : polygon) blocked[w] = true;
      const std::vector<uint32_t> star = incident[v];
      for (const Tri& t : patch) {
        nodes.push_back(t);
        std::vector<uint32_t> kids;
        for (uint32_t old : star)
          if (OverlapPositiveArea(points, t, nodes[old])) kids.push_back(old);
        if (kids.empty()) return Fail("a new triangle overlaps no old one (internal error)");
        std::stable_sort(kids.begin(), kids.end(), [&](uint32_t x, uint32_t y) {
          return Area2(points[nodes[x][0]], points[nodes[x][1]], points[nodes[x][2]]) >
                 Area2(points[nodes[y][0]], points[nodes[y][1]], points[nodes[y][2]]);
        });
        children.insert(children.end(), kids.begin(), kids.end());
        child_offsets.push_back(static_cast<uint32_t>(children.size()));
        max_children = std::max(max_children, static_cast<uint32_t>(kids.size()));
        tri_labels.push_back(-1);
      }
      // Retire the star, register the patch.
      for (uint32_t old : star)
        for (uint32_t w : nodes[old]) {
          auto& list = incident[w];
          list.erase(std::remove(list.begin(), list.end(), old), list.end());
        }
      const uint32_t first_new = static_cast<uint32_t>(nodes.size() - patch.size());
      for (uint32_t n = first_new; n < nodes.size(); ++n)
        for (uint32_t w : nodes[n]) incident[w].push_back(n);
      removed[v] = true;
      --remaining;
      ++removed_this_level;
    }
    if (removed_this_level == 0) {
      if (degree_limit >= vertex_count) return Fail("no vertex could be removed (internal error)");
      ++degree_limit;
      continue;
    }
    ++levels;
    degree_limit = options.max_removal_degree;
  }
  // The child offsets of the leaves were pushed as 0 placeholders; they are all empty.
  // child_offsets = [0, 0 x leaves, then one per new node].
  if (incident[corner0].size() != 1)
    return Fail("the hierarchy did not end in one root (internal error)");
  const uint32_t root = incident[corner0][0];
  if (root + 1 != nodes.size()) return Fail("the root is not the last node (internal error)");

  out->vertices_uv.reserve(2 * points.size());
  for (const Point& p : points) {
    out->vertices_uv.push_back(p.u);
    out->vertices_uv.push_back(p.v);
  }
  out->node_triangles.reserve(3 * nodes.size());
  for (const Tri& t : nodes)
    out->node_triangles.insert(out->node_triangles.end(), t.begin(), t.end());
  out->child_offsets = std::move(child_offsets);
  out->children = std::move(children);
  out->leaf_planes = std::move(tri_labels);
  out->root_begin = root;
  out->root_end = root + 1;
  stats->nodes = static_cast<uint32_t>(nodes.size());
  stats->levels = levels;
  stats->max_children = max_children;
  return Status::Ok();
}

namespace {

// Node tests of one location walk (exact predicates; ties accepted: a cost estimate only).
uint32_t WalkCost(const KirkpatrickHierarchy& k, Point q) {
  auto point = [&](uint32_t v) { return Point{k.vertices_uv[2 * v], k.vertices_uv[2 * v + 1]}; };
  auto accept = [&](uint32_t n) {
    const uint32_t* t = &k.node_triangles[3 * n];
    for (int e = 0; e < 3; ++e)
      if (Orient(point(t[e]), point(t[(e + 1) % 3]), q) < 0) return false;
    return true;
  };
  uint32_t tests = 0;
  uint32_t node = k.root_begin;
  for (uint32_t r = k.root_begin; r < k.root_end; ++r) {
    ++tests;
    if (accept(r)) {
      node = r;
      break;
    }
  }
  while (k.child_offsets[node + 1] > k.child_offsets[node]) {
    uint32_t chosen = k.children[k.child_offsets[node]];
    for (uint32_t e = k.child_offsets[node]; e < k.child_offsets[node + 1]; ++e) {
      ++tests;
      if (accept(k.children[e])) {
        chosen = k.children[e];
        break;
      }
    }
    node = chosen;
  }
  return tests;
}

// SplitMix64: a fixed-seed generator with the same sequence on every platform.
struct SplitMix {
  uint64_t state;
  double Uniform() {  // [0, 1)
    uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return static_cast<double>(z >> 11) * (1.0 / 9007199254740992.0);
  }
};

struct AxisResult {
  bool ok = false;
  std::string error;
  float tau = 0.f;
  Float3 axis, u, v;
  KirkpatrickHierarchy upper, lower;
  KirkpatrickSideStats upper_stats, lower_stats;
  double mean_tests = 0.0;
};

AxisResult BuildForAxis(const HullColliderData& hull, int axis_index,
                        const KirkpatrickOptions& options) {
  AxisResult r;
  const Obb& obb = hull.obb;
  r.axis = obb.axes[axis_index];
  r.u = obb.axes[(axis_index + 1) % 3];
  r.v = obb.axes[(axis_index + 2) % 3];
  if (Dot(Cross(r.u, r.v), r.axis) < 0.f) r.v = -r.v;
  std::vector<float> uv(2 * hull.vertices.size());
  std::vector<Point> points(hull.vertices.size());
  for (size_t i = 0; i < hull.vertices.size(); ++i) {
    const HullUv q = ProjectHullUv(hull.vertices[i], obb.center, r.u, r.v);
    uv[2 * i] = q.u;
    uv[2 * i + 1] = q.v;
    points[i] = {q.u, q.v};
  }
  const size_t tri_count = hull.triangles.size() / 3;
  // Tolerance ladder: the requested tau, then tenfold steps from 1e-6 up to 1e-3.
  std::vector<float> ladder = {options.vertical_tolerance};
  for (float t = std::max(options.vertical_tolerance * 10.f, 1e-6f); t <= 1.0001e-3f; t *= 10.f)
    ladder.push_back(t);
  for (float tau : ladder) {
    std::vector<uint32_t> side_tris[2];
    std::vector<int32_t> side_labels[2];
    for (size_t t = 0; t < tri_count; ++t) {
      const uint32_t a = hull.triangles[3 * t], b = hull.triangles[3 * t + 1],
                     c = hull.triangles[3 * t + 2];
      const Float3 n = hull.planes[hull.triangle_planes[t]].normal;
      const double along = double(n.x) * r.axis.x + double(n.y) * r.axis.y + double(n.z) * r.axis.z;
      const int orientation = Orient(points[a], points[b], points[c]);
      const int32_t label = static_cast<int32_t>(hull.triangle_planes[t]);
      if (along > tau && orientation > 0) {
        side_tris[0].insert(side_tris[0].end(), {a, b, c});
        side_labels[0].push_back(label);
      } else if (along < -tau && orientation < 0) {
        side_tris[1].insert(side_tris[1].end(), {a, c, b});
        side_labels[1].push_back(label);
      }
    }
    const Status su =
        BuildPlanarHierarchy(uv, side_tris[0], side_labels[0], options, &r.upper, &r.upper_stats);
    const Status sl = su.ok() ? BuildPlanarHierarchy(uv, side_tris[1], side_labels[1], options,
                                                     &r.lower, &r.lower_stats)
                              : Status::Ok();
    if (su.ok() && sl.ok()) {
      r.ok = true;
      r.tau = tau;
      break;
    }
    r.error = "axis " + std::to_string(axis_index) + " " + (su.ok() ? "lower" : "upper") +
              " side: " + (su.ok() ? sl.message() : su.message());
  }
  if (!r.ok) return r;
  // Measured location cost on points uniform in the OBB (fixed seed).
  SplitMix rng{0x5eed0000ull + static_cast<uint64_t>(axis_index)};
  uint64_t tests = 0;
  for (uint32_t s = 0; s < options.auto_samples; ++s) {
    Float3 p = obb.center;
    const float h[3] = {obb.half_extents.x, obb.half_extents.y, obb.half_extents.z};
    for (int k = 0; k < 3; ++k)
      p = p + obb.axes[k] * static_cast<float>((2.0 * rng.Uniform() - 1.0) * h[k]);
    const HullUv q = ProjectHullUv(p, obb.center, r.u, r.v);
    tests += WalkCost(r.upper, {q.u, q.v}) + WalkCost(r.lower, {q.u, q.v});
  }
  r.mean_tests = static_cast<double>(tests) / std::max(1u, options.auto_samples);
  return r;
}

Status ValidateHullInput(const HullColliderData& hull) {
  if (hull.vertices.size() < 4) return Fail("the hull has fewer than 4 vertices");
  for (const Float3& v : hull.vertices)
    if (!IsFinite(v)) return Fail("a hull vertex is not finite");
  if (hull.triangles.size() < 12 || hull.triangles.size() % 3 != 0)
    return Fail("the hull has fewer than 4 triangles or a partial triangle");
  for (uint32_t i : hull.triangles)
    if (i >= hull.vertices.size()) return Fail("a triangle index is out of range");
  if (hull.triangle_planes.size() != hull.triangles.size() / 3)
    return Fail("triangle_planes size is not the triangle count");
  for (uint32_t p : hull.triangle_planes)
    if (p >= hull.planes.size()) return Fail("a triangle plane index is out of range");
  for (const Plane& p : hull.planes)
    if (!IsFinite(p.normal) || !std::isfinite(p.offset) ||
        std::fabs(Length(p.normal) - 1.f) > 1e-3f)
      return Fail("a plane is not finite or its normal is not unit length");
  const Obb& o = hull.obb;
  if (!IsFinite(o.center) || !IsFinite(o.half_extents)) return Fail("the OBB is not finite");
  for (int a = 0; a < 3; ++a) {
    if (!IsFinite(o.axes[a]) || std::fabs(Length(o.axes[a]) - 1.f) > 1e-3f)
      return Fail("an OBB axis is not unit length");
    for (int b = a + 1; b < 3; ++b)
      if (std::fabs(Dot(o.axes[a], o.axes[b])) > 1e-3f)
        return Fail("the OBB axes are not orthogonal");
  }
  // Closed and consistently oriented: every directed edge once, with its reverse.
  std::vector<uint64_t> edges;
  const size_t tri_count = hull.triangles.size() / 3;
  for (size_t t = 0; t < tri_count; ++t)
    for (int e = 0; e < 3; ++e)
      edges.push_back(EdgeKey(hull.triangles[3 * t + e], hull.triangles[3 * t + (e + 1) % 3]));
  std::sort(edges.begin(), edges.end());
  if (std::adjacent_find(edges.begin(), edges.end()) != edges.end())
    return Fail("the hull mesh uses a directed edge twice (not consistently oriented)");
  for (uint64_t e : edges) {
    const uint64_t reverse = ((e & 0xffffffffu) << 32) | (e >> 32);
    if (!std::binary_search(edges.begin(), edges.end(), reverse))
      return Fail("the hull mesh is not closed");
  }
  return Status::Ok();
}

}  // namespace

Status BuildKirkpatrick(HullColliderData* hull, const KirkpatrickOptions& options,
                        KirkpatrickStats* stats) {
  KirkpatrickStats local_stats;
  if (stats == nullptr) stats = &local_stats;
  *stats = KirkpatrickStats{};
  hull->upper = KirkpatrickHierarchy{};
  hull->lower = KirkpatrickHierarchy{};
  if (!(options.vertical_tolerance >= 0.f && options.vertical_tolerance <= 1e-3f))
    return Fail("vertical_tolerance is not in [0, 1e-3]");
  if (options.auto_samples < 16 || options.auto_samples > 1000000)
    return Fail("auto_samples is not in [16, 1e6]");
  Status status = ValidateHullInput(*hull);
  if (!status.ok()) return status;

  const float h[3] = {hull->obb.half_extents.x, hull->obb.half_extents.y, hull->obb.half_extents.z};
  int longest = 0, shortest = 0;
  for (int k = 1; k < 3; ++k) {
    if (h[k] > h[longest]) longest = k;
    if (h[k] < h[shortest]) shortest = k;
  }
  // Axes in preference order for ties: shortest, the middle one, longest.
  int order[3] = {shortest, 3 - shortest - longest, longest};
  if (shortest == longest) order[1] = (shortest + 1) % 3, order[2] = (shortest + 2) % 3;
  AxisResult results[3];
  bool built[3] = {false, false, false};
  auto build = [&](int k) {
    if (!built[k]) {
      results[k] = BuildForAxis(*hull, k, options);
      built[k] = true;
      stats->axis_mean_tests[k] = results[k].ok ? results[k].mean_tests : -1.0;
    }
    return results[k].ok;
  };
  int chosen = -1;
  if (options.axis == ProjectionAxis::kLongest && build(longest)) chosen = longest;
  if (options.axis == ProjectionAxis::kShortest && build(shortest)) chosen = shortest;
  if (chosen < 0) {
    stats->axis_fallback = options.axis != ProjectionAxis::kAuto;
    for (int i = 0; i < 3; ++i) {
      const int k = order[i];
      if (build(k) && (chosen < 0 || results[k].mean_tests < results[chosen].mean_tests))
        chosen = k;
    }
  }
  if (chosen < 0) {
    std::string reasons;
    for (int k = 0; k < 3; ++k) reasons += (k ? "; " : "") + results[k].error;
    return Fail("no OBB axis gives a valid projection: " + reasons);
  }
  AxisResult& r = results[chosen];
  hull->projection_axis = r.axis;
  hull->projection_u = r.u;
  hull->projection_v = r.v;
  hull->upper = std::move(r.upper);
  hull->lower = std::move(r.lower);
  stats->axis_index = chosen;
  stats->vertical_tolerance = r.tau;
  stats->upper = r.upper_stats;
  stats->lower = r.lower_stats;
  stats->mean_tests = r.mean_tests;
  return Status::Ok();
}

}  // namespace drape::bake

// BuildPlanarHierarchy (drape/bake/kirkpatrick_builder.h): the planar subdivision of an enclosing
// triangle (the faces, their shadow's boundary, the fill between the two), then Kirkpatrick's
// coarsening of it to the enclosing triangle.

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "drape/bake/kirkpatrick_builder.h"
#include "kirkpatrick/planar_geometry.h"

namespace drape::bake {
namespace {

using detail::Area2;
using detail::EdgeKey;
using detail::Fail;
using detail::Orient;
using detail::Point;
using detail::Tri;

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

Status ValidatePlanarInput(std::span<const float> vertices_uv, std::span<const uint32_t> triangles,
                           std::span<const int32_t> labels, const KirkpatrickOptions& options) {
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
  return Status::Ok();
}

// The faces over the used vertices only: points (in index order) and triangles, each strictly
// counter-clockwise.
struct PlanarFaces {
  std::vector<Point> points;   // the used vertices; the enclosing triangle's corners follow them
  uint32_t face_vertices = 0;  // points that are face vertices (the corners are not)
  std::vector<Tri> tris;
};

Status CompactFaces(std::span<const float> vertices_uv, std::span<const uint32_t> triangles,
                    PlanarFaces* faces, KirkpatrickSideStats* stats) {
  const size_t tri_count = triangles.size() / 3;
  const uint32_t input_vertices = static_cast<uint32_t>(vertices_uv.size() / 2);
  std::vector<uint32_t> remap(input_vertices, UINT32_MAX);
  std::vector<Point>& points = faces->points;
  for (uint32_t index : triangles) remap[index] = 0;
  for (uint32_t v = 0; v < input_vertices; ++v)
    if (remap[v] == 0) {
      remap[v] = static_cast<uint32_t>(points.size());
      points.push_back({vertices_uv[2 * v], vertices_uv[2 * v + 1]});
    }
  faces->face_vertices = static_cast<uint32_t>(points.size());
  std::vector<Tri>& tris = faces->tris;
  tris.resize(tri_count);
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
  return Status::Ok();
}

// The boundary cycle of the faces (directed edges whose reverse is missing): the faces must form
// a disk.
Status TraceBoundary(const PlanarFaces& faces, std::vector<uint32_t>* cycle) {
  std::vector<uint64_t> edges;
  for (const Tri& t : faces.tris)
    for (int e = 0; e < 3; ++e) edges.push_back(EdgeKey(t[e], t[(e + 1) % 3]));
  std::sort(edges.begin(), edges.end());
  if (std::adjacent_find(edges.begin(), edges.end()) != edges.end())
    return Fail("the faces use a directed edge twice (folded projection)");
  std::vector<uint32_t> next(faces.face_vertices, UINT32_MAX);
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
  for (uint32_t v = start;;) {
    cycle->push_back(v);
    v = next[v];
    if (v == UINT32_MAX) return Fail("the shadow boundary is not closed");
    if (v == start) break;
    if (cycle->size() > boundary_edges) return Fail("the shadow boundary is not one cycle");
  }
  if (cycle->size() != boundary_edges) return Fail("the shadow boundary is not one simple cycle");
  return Status::Ok();
}

// Appends the corners of the enclosing triangle around the boundary's centroid (cu, cv), at
// bounding_scale times the boundary's radius.
Status AddEnclosingTriangle(const std::vector<uint32_t>& cycle, const KirkpatrickOptions& options,
                            PlanarFaces* faces, double* centroid_u, double* centroid_v) {
  std::vector<Point>& points = faces->points;
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
  for (int k = 0; k < 3; ++k) {
    const double angle = 3.14159265358979323846 * (0.5 + 2.0 * k / 3.0);
    points.push_back({static_cast<float>(cu + options.bounding_scale * radius * std::cos(angle)),
                      static_cast<float>(cv + options.bounding_scale * radius * std::sin(angle))});
  }
  *centroid_u = cu;
  *centroid_v = cv;
  return Status::Ok();
}

// The faces followed by the fill of the annulus between the boundary and the enclosing triangle:
// edge i (cycle[i] -> cycle[i+1]) to the corner farthest along its outward normal, corner wedges
// where the assignment advances.
Status FillAnnulus(const PlanarFaces& faces, const std::vector<uint32_t>& cycle, double cu,
                   double cv, std::vector<Tri>* all) {
  const std::vector<Point>& points = faces.points;
  const uint32_t corner0 = faces.face_vertices;
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
  *all = faces.tris;
  int steps = 0;
  for (size_t i = 0; i < m; ++i) {
    const uint32_t a = cycle[i], b = cycle[(i + 1) % m];
    all->push_back({b, a, corner0 + static_cast<uint32_t>(corner_of[i])});
    // Wedges at a, from the previous edge's corner to this edge's corner.
    int k = corner_of[(i + m - 1) % m];
    while (k != corner_of[i]) {
      const int k1 = (k + 1) % 3;
      all->push_back({corner0 + static_cast<uint32_t>(k), corner0 + static_cast<uint32_t>(k1), a});
      k = k1;
      if (++steps > 3) return Fail("the corner assignment of the fill is not monotone");
    }
  }
  return Status::Ok();
}

// The hierarchy while it is coarsened: its nodes (the leaves, then each level's new triangles)
// with their children and labels, and per vertex the nodes of the current level that use it.
struct Hierarchy {
  std::vector<Tri> nodes;
  std::vector<uint32_t> child_offsets = {0};  // [0, 0 x leaves, then one per new node]
  std::vector<uint32_t> children;
  std::vector<int32_t> labels;  // the faces' labels, -1 for every other node
  std::vector<std::vector<uint32_t>> incident;
  uint32_t max_children = 0;
};

// The leaves: the faces and the fill, each without children.
Hierarchy StartHierarchy(const std::vector<Tri>& all, std::vector<int32_t> labels,
                         uint32_t vertex_count) {
  Hierarchy h;
  h.nodes = all;
  // The child offsets of the leaves are pushed as 0 placeholders; they are all empty.
  for (size_t n = 0; n < all.size(); ++n) h.child_offsets.push_back(0);
  h.incident.resize(vertex_count);
  for (uint32_t n = 0; n < h.nodes.size(); ++n)
    for (uint32_t v : h.nodes[n]) h.incident[v].push_back(n);
  h.labels = std::move(labels);
  return h;
}

// The link polygon of v: (v, a, b) in each triangle of its star gives the link edge a -> b,
// chained counter-clockwise. The star must be a closed fan.
Status LinkPolygon(const Hierarchy& h, uint32_t v, std::vector<uint32_t>* polygon) {
  std::vector<std::pair<uint32_t, uint32_t>> link;
  for (uint32_t n : h.incident[v]) {
    const Tri& t = h.nodes[n];
    const int at = t[0] == v ? 0 : (t[1] == v ? 1 : 2);
    link.push_back({t[(at + 1) % 3], t[(at + 2) % 3]});
  }
  std::sort(link.begin(), link.end());
  bool closed = true;
  for (uint32_t w = link[0].first;;) {
    polygon->push_back(w);
    auto it = std::lower_bound(link.begin(), link.end(), std::make_pair(w, 0u));
    if (it == link.end() || it->first != w) {
      closed = false;
      break;
    }
    w = it->second;
    if (w == link[0].first) break;
    if (polygon->size() > link.size()) {
      closed = false;
      break;
    }
  }
  if (!closed || polygon->size() != link.size()) return Fail("a vertex star is not a closed fan");
  return Status::Ok();
}

// Replaces the star of v by `patch`: each new node's children are the star's triangles it
// overlaps with positive area, largest first.
Status ReplaceStar(const std::vector<Point>& points, uint32_t v, const std::vector<Tri>& patch,
                   Hierarchy* h) {
  std::vector<Tri>& nodes = h->nodes;
  const std::vector<uint32_t> star = h->incident[v];
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
    h->children.insert(h->children.end(), kids.begin(), kids.end());
    h->child_offsets.push_back(static_cast<uint32_t>(h->children.size()));
    h->max_children = std::max(h->max_children, static_cast<uint32_t>(kids.size()));
    h->labels.push_back(-1);
  }
  // Retire the star, register the patch.
  for (uint32_t old : star)
    for (uint32_t w : nodes[old]) {
      auto& list = h->incident[w];
      list.erase(std::remove(list.begin(), list.end(), old), list.end());
    }
  const uint32_t first_new = static_cast<uint32_t>(nodes.size() - patch.size());
  for (uint32_t n = first_new; n < nodes.size(); ++n)
    for (uint32_t w : nodes[n]) h->incident[w].push_back(n);
  return Status::Ok();
}

// One level: removes an independent set of the candidates (a removed vertex blocks its link
// polygon's vertices until the next level) whose link polygons can be ear-clipped.
Status RemoveIndependentSet(const std::vector<Point>& points,
                            const std::vector<std::pair<uint32_t, uint32_t>>& candidates,
                            Hierarchy* h, std::vector<bool>* removed, uint32_t* removed_count) {
  std::vector<bool> blocked(points.size(), false);
  for (const auto& [degree, v] : candidates) {
    if (blocked[v]) continue;
    std::vector<uint32_t> polygon;
    if (Status s = LinkPolygon(*h, v, &polygon); !s.ok()) return s;
    std::vector<Tri> patch;
    if (!EarClip(points, polygon, &patch)) continue;  // keep v for a later level
    blocked[v] = true;
    for (uint32_t w : polygon) blocked[w] = true;
    if (Status s = ReplaceStar(points, v, patch, h); !s.ok()) return s;
    (*removed)[v] = true;
    ++*removed_count;
  }
  return Status::Ok();
}

// Removes the face vertices level by level (lowest degree first, then lowest index, up to
// max_removal_degree, raised for a level that could remove none) until only the enclosing
// triangle is left. *levels counts the leaf and root levels.
Status CoarsenToRoot(const std::vector<Point>& points, uint32_t face_vertices,
                     const KirkpatrickOptions& options, Hierarchy* h, uint32_t* levels) {
  const uint32_t vertex_count = static_cast<uint32_t>(points.size());
  std::vector<bool> removed(vertex_count, false);
  uint32_t remaining = face_vertices;  // non-corner vertices left
  *levels = 1;
  uint32_t degree_limit = options.max_removal_degree;
  while (remaining > 0) {
    // Candidates: lowest degree first, then lowest index.
    std::vector<std::pair<uint32_t, uint32_t>> candidates;
    for (uint32_t v = 0; v < face_vertices; ++v)
      if (!removed[v] && h->incident[v].size() <= degree_limit)
        candidates.push_back({static_cast<uint32_t>(h->incident[v].size()), v});
    if (candidates.empty()) {
      if (degree_limit >= vertex_count) return Fail("no removable vertex (internal error)");
      ++degree_limit;
      continue;
    }
    std::sort(candidates.begin(), candidates.end());
    uint32_t removed_this_level = 0;
    if (Status s = RemoveIndependentSet(points, candidates, h, &removed, &removed_this_level);
        !s.ok()) {
      return s;
    }
    remaining -= removed_this_level;
    if (removed_this_level == 0) {
      if (degree_limit >= vertex_count) return Fail("no vertex could be removed (internal error)");
      ++degree_limit;
      continue;
    }
    ++*levels;
    degree_limit = options.max_removal_degree;
  }
  return Status::Ok();
}

// The finished hierarchy into *out: it must end in one root, the last node, made of the corners.
Status EmitHierarchy(const std::vector<Point>& points, uint32_t corner0, uint32_t levels,
                     Hierarchy* h, KirkpatrickHierarchy* out, KirkpatrickSideStats* stats) {
  const std::vector<Tri>& nodes = h->nodes;
  if (h->incident[corner0].size() != 1)
    return Fail("the hierarchy did not end in one root (internal error)");
  const uint32_t root = h->incident[corner0][0];
  if (root + 1 != nodes.size()) return Fail("the root is not the last node (internal error)");

  out->vertices_uv.reserve(2 * points.size());
  for (const Point& p : points) {
    out->vertices_uv.push_back(p.u);
    out->vertices_uv.push_back(p.v);
  }
  out->node_triangles.reserve(3 * nodes.size());
  for (const Tri& t : nodes)
    out->node_triangles.insert(out->node_triangles.end(), t.begin(), t.end());
  out->child_offsets = std::move(h->child_offsets);
  out->children = std::move(h->children);
  out->leaf_planes = std::move(h->labels);
  out->root_begin = root;
  out->root_end = root + 1;
  stats->nodes = static_cast<uint32_t>(nodes.size());
  stats->levels = levels;
  stats->max_children = h->max_children;
  return Status::Ok();
}

}  // namespace

Status BuildPlanarHierarchy(std::span<const float> vertices_uv, std::span<const uint32_t> triangles,
                            std::span<const int32_t> labels, const KirkpatrickOptions& options,
                            KirkpatrickHierarchy* out, KirkpatrickSideStats* stats) {
  *out = KirkpatrickHierarchy{};
  KirkpatrickSideStats local_stats;
  if (stats == nullptr) stats = &local_stats;
  *stats = KirkpatrickSideStats{};
  if (Status s = ValidatePlanarInput(vertices_uv, triangles, labels, options); !s.ok()) return s;

  // The planar subdivision of the enclosing triangle: the faces, the boundary of their shadow,
  // the enclosing triangle's corners and the fill between the two.
  PlanarFaces faces;
  if (Status s = CompactFaces(vertices_uv, triangles, &faces, stats); !s.ok()) return s;
  std::vector<uint32_t> cycle;
  if (Status s = TraceBoundary(faces, &cycle); !s.ok()) return s;
  stats->boundary_vertices = static_cast<uint32_t>(cycle.size());
  double cu = 0.0, cv = 0.0;
  if (Status s = AddEnclosingTriangle(cycle, options, &faces, &cu, &cv); !s.ok()) return s;
  std::vector<Tri> all;
  if (Status s = FillAnnulus(faces, cycle, cu, cv, &all); !s.ok()) return s;
  const size_t tri_count = faces.tris.size();
  stats->fill_triangles = static_cast<uint32_t>(all.size() - tri_count);
  const uint32_t corner0 = faces.face_vertices;
  std::string why;
  if (!IsTriangulationOfTriangle(faces.points, all, corner0, corner0 + 1, corner0 + 2, &why))
    return Fail("invalid planar subdivision: " + why);
  std::vector<int32_t> tri_labels(labels.begin(), labels.end());
  for (size_t t = tri_count; t < all.size(); ++t) tri_labels.push_back(-1);

  // The hierarchy, from the subdivision's triangles up to the enclosing triangle.
  Hierarchy h =
      StartHierarchy(all, std::move(tri_labels), static_cast<uint32_t>(faces.points.size()));
  uint32_t levels = 1;
  if (Status s = CoarsenToRoot(faces.points, faces.face_vertices, options, &h, &levels); !s.ok())
    return s;
  return EmitHierarchy(faces.points, corner0, levels, &h, out, stats);
}

}  // namespace drape::bake

#include "hull/convex_hull.h"

#include "hull/hull_kernel.h"  // first of the CGAL headers

#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <algorithm>
#include <numeric>
#include <tuple>

#include "hull/coplanar_faces.h"

namespace drape::bake::detail {

bool ConvexHull(const std::vector<Vec3>& points, Mesh* out) {
  out->points.clear();
  out->triangles.clear();
  if (points.size() < 4) return false;
  std::vector<Point> cgal_points;
  cgal_points.reserve(points.size());
  for (const Vec3& p : points) cgal_points.push_back(ToPoint(p));
  CGAL::Surface_mesh<Point> mesh;
  CGAL::convex_hull_3(cgal_points.begin(), cgal_points.end(), mesh);
  if (mesh.number_of_faces() < 4 || !CGAL::is_closed(mesh)) return false;
  std::vector<uint32_t> index(mesh.num_vertices(), UINT32_MAX);
  for (auto v : mesh.vertices()) {
    index[static_cast<size_t>(v.idx())] = static_cast<uint32_t>(out->points.size());
    const Point& p = mesh.point(v);
    out->points.push_back({p.x(), p.y(), p.z()});
  }
  for (auto f : mesh.faces()) {
    std::array<uint32_t, 3> tri{};
    int corner = 0;
    for (auto h : CGAL::halfedges_around_face(mesh.halfedge(f), mesh)) {
      if (corner == 3) return false;  // not a triangle (cannot happen for convex_hull_3)
      tri[static_cast<size_t>(corner++)] = index[static_cast<size_t>(mesh.target(h).idx())];
    }
    if (corner != 3) return false;
    out->triangles.push_back(tri);
  }
  // convex_hull_3's vertex and face order depends on memory addresses (measured: repeated calls
  // on the same input differ), so put the mesh in a canonical order: vertices sorted by
  // coordinates, each triangle rotated to start at its smallest index, triangles sorted.
  const size_t n = out->points.size();
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    const Vec3& p = out->points[a];
    const Vec3& q = out->points[b];
    return std::tie(p.x, p.y, p.z) < std::tie(q.x, q.y, q.z);
  });
  std::vector<uint32_t> rank(n);
  std::vector<Vec3> sorted_points(n);
  for (uint32_t i = 0; i < n; ++i) {
    rank[order[i]] = i;
    sorted_points[i] = out->points[order[i]];
  }
  out->points = std::move(sorted_points);
  for (auto& tri : out->triangles) {
    for (uint32_t& corner : tri) corner = rank[corner];
  }
  return CanonicalTriangulation(out);
}

}  // namespace drape::bake::detail

#include "hull/plane_remover.h"

#include "hull/hull_kernel.h"  // first of the CGAL headers

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <utility>

#include "hull/convex_hull.h"
#include "hull/lp_solver.h"

namespace drape::bake::detail {
namespace {

class PlaneRemover {
 public:
  PlaneRemover(const Mesh& h0, const std::vector<uint32_t>& groups, uint32_t group_count,
               const GrowthReference& reference, double max_growth, uint32_t max_triangles)
      : reference_(reference), max_growth_(max_growth), max_triangles_(max_triangles) {
    normals_.assign(group_count, Vec3{});
    offsets_.assign(group_count, -std::numeric_limits<double>::infinity());
    for (size_t t = 0; t < h0.triangles.size(); ++t) {
      const auto& tri = h0.triangles[t];
      normals_[groups[t]] = normals_[groups[t]] + Cross(h0.points[tri[1]] - h0.points[tri[0]],
                                                        h0.points[tri[2]] - h0.points[tri[0]]);
    }
    for (Vec3& n : normals_) n = n * (1.0 / Norm(n));
    for (size_t t = 0; t < h0.triangles.size(); ++t) {
      for (uint32_t c : h0.triangles[t]) {
        offsets_[groups[t]] = std::max(offsets_[groups[t]], Dot(normals_[groups[t]], h0.points[c]));
      }
    }
    Vec3 sum{};
    double extent = 0.0;
    for (const Vec3& p : h0.points) sum = sum + p;
    center_ = sum * (1.0 / static_cast<double>(h0.points.size()));
    for (const Vec3& p : h0.points) extent = std::max(extent, Norm(p - center_));
    extent_ = extent;
    max_abs_ = 0.0;
    for (const Vec3& p : h0.points) max_abs_ = std::max(max_abs_, MaxAbs(p));
    alive_.assign(group_count, 1);
  }

  bool Run(PlaneRemovalResult* result) {
    if (!DualHull()) return false;
    using Item = std::pair<double, uint32_t>;  // (cost, plane), smallest first
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
    std::vector<double> cost(normals_.size());
    for (uint32_t j = 0; j < normals_.size(); ++j) {
      if (!alive_[j]) continue;
      cost[j] = Cost(j);
      queue.push({cost[j], j});
    }
    std::vector<double> queued_cost(cost);
    while (EstimatedTriangles() > max_triangles_ && !queue.empty()) {
      const auto [c, j] = queue.top();
      queue.pop();
      if (!alive_[j] || c != queued_cost[j]) continue;
      // The final vertices are pushed out by BuildMesh's margin: keep room for it.
      if (!(c + 64.0 * FLT_EPSILON * max_abs_ <= max_growth_)) break;
      const std::vector<uint32_t> neighbours = neighbours_[j];
      alive_[j] = 0;
      if (!DropLocally(j) && !DualHull()) {  // cannot happen for a bounded polytope; undo
        alive_[j] = 1;
        if (!DualHull()) return false;
        break;
      }
      ++result->dropped;
      for (uint32_t k : neighbours) {
        if (!alive_[k]) continue;
        queued_cost[k] = Cost(k);
        queue.push({queued_cost[k], k});
      }
    }
    result->budget_reached = EstimatedTriangles() <= max_triangles_;
    for (uint32_t j = 0; j < normals_.size(); ++j) {
      if (!alive_[j]) continue;
      result->kept_normals.push_back(normals_[j]);
      result->kept_offsets.push_back(offsets_[j]);
    }
    return BuildMesh(result);
  }

 private:
  uint32_t EstimatedTriangles() const { return 2 * dual_facets_ - 4; }

  // Dual hull of the alive planes: adjacency (neighbours_) and facets (primal vertices).
  bool DualHull() {
    std::vector<Vec3> dual;
    std::vector<std::pair<std::array<double, 3>, uint32_t>> lookup;
    for (uint32_t j = 0; j < normals_.size(); ++j) {
      if (!alive_[j]) continue;
      const double height = offsets_[j] - Dot(normals_[j], center_);
      if (!(height > 0.0)) return false;
      const Vec3 q = DualPoint(j);
      dual.push_back(q);
      lookup.push_back({{q.x, q.y, q.z}, j});
    }
    std::sort(lookup.begin(), lookup.end());
    Mesh mesh;  // canonical order and triangulation: deterministic
    if (!ConvexHull(dual, &mesh)) return false;
    std::vector<uint32_t> plane_of(mesh.points.size(), UINT32_MAX);
    for (size_t v = 0; v < mesh.points.size(); ++v) {
      const std::array<double, 3> key{mesh.points[v].x, mesh.points[v].y, mesh.points[v].z};
      const auto it =
          std::lower_bound(lookup.begin(), lookup.end(), std::make_pair(key, uint32_t{0}));
      if (it == lookup.end() || it->first != key) return false;
      plane_of[v] = it->second;
    }
    // Planes whose dual point is not extreme are redundant: they no longer bound anything.
    std::vector<uint8_t> on_hull(normals_.size(), 0);
    for (uint32_t j : plane_of) on_hull[j] = 1;
    for (uint32_t j = 0; j < normals_.size(); ++j) {
      if (alive_[j] && !on_hull[j]) alive_[j] = 0;
    }
    neighbours_.assign(normals_.size(), {});
    facets_.clear();
    for (const auto& tri : mesh.triangles) {
      std::array<uint32_t, 3> facet{plane_of[tri[0]], plane_of[tri[1]], plane_of[tri[2]]};
      for (int e = 0; e < 3; ++e) {
        neighbours_[facet[e]].push_back(facet[(e + 1) % 3]);
        neighbours_[facet[(e + 1) % 3]].push_back(facet[e]);
      }
      std::sort(facet.begin(), facet.end());  // canonical: the plane intersection is symmetric
      facets_.push_back(facet);
    }
    for (auto& list : neighbours_) {
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
    }
    std::sort(facets_.begin(), facets_.end());
    dual_facets_ = static_cast<uint32_t>(facets_.size());
    return true;
  }

  Vec3 DualPoint(uint32_t j) const {
    return normals_[j] * (1.0 / (offsets_[j] - Dot(normals_[j], center_)));
  }

  // Removing dual vertex q_j replaces its star by the faces of conv(link of q_j) that q_j sees
  // (they triangulate the link polygon with link vertices only). False when that local hull is
  // degenerate or does not close up; the caller then re-hulls everything.
  bool DropLocally(uint32_t j) {
    const std::vector<uint32_t> link = neighbours_[j];
    if (link.size() < 3) return false;
    std::vector<Vec3> points;
    for (uint32_t k : link) points.push_back(DualPoint(k));
    Mesh local;
    if (!ConvexHull(points, &local) || local.points.size() != link.size()) return false;
    // ConvexHull sorts its vertices: map them back to planes by coordinates.
    std::vector<uint32_t> plane_of(local.points.size());
    for (size_t i = 0; i < local.points.size(); ++i) {
      const auto it = std::find_if(points.begin(), points.end(), [&](const Vec3& q) {
        return q.x == local.points[i].x && q.y == local.points[i].y && q.z == local.points[i].z;
      });
      if (it == points.end()) return false;
      plane_of[i] = link[static_cast<size_t>(it - points.begin())];
    }
    const Point qj = ToPoint(DualPoint(j));
    std::vector<std::array<uint32_t, 3>> added;
    for (const auto& tri : local.triangles) {
      if (CGAL::orientation(ToPoint(local.points[tri[0]]), ToPoint(local.points[tri[1]]),
                            ToPoint(local.points[tri[2]]), qj) != CGAL::POSITIVE) {
        continue;
      }
      std::array<uint32_t, 3> facet{plane_of[tri[0]], plane_of[tri[1]], plane_of[tri[2]]};
      std::sort(facet.begin(), facet.end());
      added.push_back(facet);
    }
    if (added.size() + 2 != link.size()) return false;  // a disk on the link polygon
    for (uint32_t k : link) {
      auto& list = neighbours_[k];
      list.erase(std::remove(list.begin(), list.end(), j), list.end());
    }
    neighbours_[j].clear();
    for (const auto& f : added) {
      for (int e = 0; e < 3; ++e) {
        const uint32_t a = f[static_cast<size_t>(e)], b = f[static_cast<size_t>((e + 1) % 3)];
        auto& la = neighbours_[a];
        if (!std::binary_search(la.begin(), la.end(), b))
          la.insert(std::lower_bound(la.begin(), la.end(), b), b);
        auto& lb = neighbours_[b];
        if (!std::binary_search(lb.begin(), lb.end(), a))
          lb.insert(std::lower_bound(lb.begin(), lb.end(), a), a);
      }
    }
    facets_.erase(std::remove_if(facets_.begin(), facets_.end(),
                                 [&](const std::array<uint32_t, 3>& f) {
                                   return f[0] == j || f[1] == j || f[2] == j;
                                 }),
                  facets_.end());
    facets_.insert(facets_.end(), added.begin(), added.end());
    std::sort(facets_.begin(), facets_.end());
    dual_facets_ = static_cast<uint32_t>(facets_.size());
    return true;
  }

  // Intersection of three planes (offsets + shift); false if (nearly) singular.
  bool Intersect(uint32_t a, uint32_t b, uint32_t c, double shift, Vec3* x) const {
    const Vec3 na = normals_[a], nb = normals_[b], nc = normals_[c];
    const Vec3 bc = Cross(nb, nc);
    const double det = Dot(na, bc);
    if (std::fabs(det) < 1e-12) return false;
    const double da = offsets_[a] + shift - Dot(na, center_);
    const double db = offsets_[b] + shift - Dot(nb, center_);
    const double dc = offsets_[c] + shift - Dot(nc, center_);
    const Vec3 local = (bc * da + Cross(nc, na) * db + Cross(na, nb) * dc) * (1.0 / det);
    *x = center_ + local;
    return true;
  }

  // Growth of dropping plane j: the largest growth lower bound over the vertices of the cap it
  // exposes (triple intersections of its neighbours inside all of them), +inf if unbounded.
  double Cost(uint32_t j) {
    const std::vector<uint32_t>& nb = neighbours_[j];
    if (nb.size() < 3) return std::numeric_limits<double>::infinity();
    // Bounded iff the LP max n_j.x over the neighbours' half-spaces stays off the box.
    constraints_.clear();
    for (uint32_t k : nb)
      constraints_.push_back({normals_[k], offsets_[k] - Dot(normals_[k], center_)});
    const double bound = 4.0 * extent_ + 4.0 * max_growth_;
    Vec3 top;
    if (!lp_.Solve3(constraints_, normals_[j] * -1.0, bound, 1e-12 * bound, &top)) {
      return std::numeric_limits<double>::infinity();
    }
    if (MaxAbs(top) > 0.999 * bound) return std::numeric_limits<double>::infinity();
    double worst = reference_.Distance(center_ + top);
    const double tol = 1e-9 * (extent_ + 1.0);
    for (size_t a = 0; a < nb.size(); ++a) {
      for (size_t b = a + 1; b < nb.size(); ++b) {
        for (size_t c = b + 1; c < nb.size(); ++c) {
          Vec3 x;
          if (!Intersect(nb[a], nb[b], nb[c], 0.0, &x)) continue;
          if (Dot(normals_[j], x) < offsets_[j] - tol) continue;
          bool inside = true;
          for (uint32_t k : nb) {
            if (Dot(normals_[k], x) > offsets_[k] + tol) {
              inside = false;
              break;
            }
          }
          if (inside) worst = std::max(worst, reference_.Distance(x));
        }
      }
    }
    return worst;
  }

  // Vertices of the kept planes' polytope, every plane pushed out by a small margin so that the
  // float-rounded vertices still enclose H0 (checked exactly by the caller); hulled again.
  bool BuildMesh(PlaneRemovalResult* result) {
    for (int attempt = 0; attempt < 6; ++attempt) {
      const double margin = 8.0 * FLT_EPSILON * max_abs_ * std::pow(4.0, attempt);
      std::vector<Vec3> points;
      for (const auto& f : facets_) {
        Vec3 x;
        if (!Intersect(f[0], f[1], f[2], margin, &x)) continue;
        points.push_back(RoundToFloat(x));
      }
      SortUnique(&points);
      if (!ConvexHull(points, &result->mesh)) continue;
      result->kept_offsets.clear();
      for (uint32_t j = 0; j < normals_.size(); ++j) {
        if (alive_[j]) result->kept_offsets.push_back(offsets_[j] + margin);
      }
      return true;
    }
    return false;
  }

  const GrowthReference& reference_;
  const double max_growth_;
  const uint32_t max_triangles_;
  std::vector<Vec3> normals_;
  std::vector<double> offsets_;
  std::vector<uint8_t> alive_;
  std::vector<std::vector<uint32_t>> neighbours_;
  std::vector<std::array<uint32_t, 3>> facets_;
  uint32_t dual_facets_ = 0;
  Vec3 center_;
  double extent_ = 0.0, max_abs_ = 0.0;
  LpSolver lp_;
  std::vector<Halfspace3> constraints_;
};

}  // namespace

bool RemovePlanes(const Mesh& h0, const std::vector<uint32_t>& groups, uint32_t group_count,
                  const GrowthReference& reference, double max_growth, uint32_t max_triangles,
                  PlaneRemovalResult* result) {
  PlaneRemover remover(h0, groups, group_count, reference, max_growth, max_triangles);
  return remover.Run(result);
}

}  // namespace drape::bake::detail

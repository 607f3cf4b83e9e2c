#include "hull/edge_collapser.h"

#include "hull/hull_kernel.h"  // first of the CGAL headers

#include <algorithm>
#include <array>
#include <cfloat>
#include <queue>
#include <unordered_map>
#include <utility>
#include <vector>

#include "hull/lp_solver.h"

namespace drape::bake::detail {
namespace {

class EdgeCollapser {
 public:
  EdgeCollapser(const Mesh& h0, const GrowthReference& reference, double max_growth,
                uint32_t max_triangles, bool global_checks)
      : reference_(reference),
        max_growth_(max_growth),
        max_triangles_(max_triangles),
        global_checks_(global_checks),
        pos_(h0.points),
        tris_(h0.triangles),
        tri_alive_(h0.triangles.size(), 1),
        vtris_(h0.points.size()),
        valive_(h0.points.size(), 1),
        stamp_(h0.points.size(), 0),
        alive_triangles_(static_cast<uint32_t>(h0.triangles.size())) {
    for (uint32_t t = 0; t < tris_.size(); ++t) {
      for (uint32_t corner : tris_[t]) vtris_[corner].push_back(t);
    }
  }

  void Run(HullStats* stats) {
    std::vector<uint64_t> keys;
    for (const auto& tri : tris_) {
      for (int k = 0; k < 3; ++k) keys.push_back(EdgeKey(tri[k], tri[(k + 1) % 3]));
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    for (uint64_t key : keys) Push(key);

    Link link;
    while (alive_triangles_ > max_triangles_ && !queue_.empty()) {
      const Entry entry = queue_.top();
      queue_.pop();
      EdgeState& state = edges_[entry.key];
      if (state.version != entry.version) continue;  // superseded by a newer evaluation
      state.live = false;
      const uint32_t u = static_cast<uint32_t>(entry.key >> 32);
      const uint32_t v = static_cast<uint32_t>(entry.key & 0xffffffffu);
      if (!valive_[u] || !valive_[v]) continue;
      // Lazy re-evaluation: a neighbouring collapse changed this edge's link since it was
      // evaluated. Its old growth is usually an underestimate (growth accumulates), so it
      // surfaces early and goes back in at its new place.
      if (stamp_[u] != entry.stamp_u || stamp_[v] != entry.stamp_v) {
        Push(entry.key);
        continue;
      }
      // Fresh entries are ordered by a lower bound of the growth: nothing later can pass.
      if (entry.growth > max_growth_) break;
      if (!BuildLink(u, v, &link)) continue;
      const Vec3 p{entry.p[0], entry.p[1], entry.p[2]};
      if (!ExactAccept(u, v, link, p)) {
        ++rejected_;
        continue;
      }
      Collapse(u, v, p, link);
      ++collapses_;
      Reevaluate(u, link);
    }
    if (stats) {
      stats->collapses = collapses_;
      stats->rejected = rejected_;
      stats->evaluations = evaluations_;
    }
  }

  Mesh Extract() const {
    Mesh out;
    std::vector<uint32_t> remap(pos_.size(), UINT32_MAX);
    for (uint32_t t = 0; t < tris_.size(); ++t) {
      if (!tri_alive_[t]) continue;
      std::array<uint32_t, 3> tri{};
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = tris_[t][static_cast<size_t>(k)];
        if (remap[v] == UINT32_MAX) {
          remap[v] = static_cast<uint32_t>(out.points.size());
          out.points.push_back(pos_[v]);
        }
        tri[static_cast<size_t>(k)] = remap[v];
      }
      out.triangles.push_back(tri);
    }
    return out;
  }

 private:
  static constexpr size_t kMaxLink = 48;  // larger links are not collapsed (LP size, degree)

  struct Link {
    std::vector<uint32_t> w;  // link polygon, counter-clockwise seen from outside
    std::vector<uint32_t> x;  // x[i]: apex of the outer triangle across edge (w[i], w[i+1])
    std::vector<std::pair<uint32_t, uint32_t>> edges;  // scratch
    std::vector<uint32_t> ring_u, ring_v;              // scratch
  };

  struct Entry {
    double growth = 0.0;  // metres, lower bound of the distance of p beyond H0
    double volume = 0.0;  // added volume (scaled), tie-breaker
    uint64_t key = 0;
    uint32_t version = 0;
    uint32_t stamp_u = 0, stamp_v = 0;  // vertex stamps at evaluation time
    float p[3] = {0.f, 0.f, 0.f};
  };
  struct EntryAfter {  // priority_queue puts the "largest" first: invert
    bool operator()(const Entry& a, const Entry& b) const {
      if (a.growth != b.growth) return a.growth > b.growth;
      if (a.volume != b.volume) return a.volume > b.volume;
      return a.key > b.key;
    }
  };

  // Corner order of triangle t rotated so that it starts at vertex `first`.
  std::array<uint32_t, 3> Rotated(uint32_t t, uint32_t first) const {
    const auto& tri = tris_[t];
    if (tri[0] == first) return tri;
    if (tri[1] == first) return {tri[1], tri[2], tri[0]};
    return {tri[2], tri[0], tri[1]};
  }

  void Ring(uint32_t a, std::vector<uint32_t>* ring) const {
    ring->clear();
    for (uint32_t t : vtris_[a]) {
      const auto r = Rotated(t, a);
      ring->push_back(r[1]);
    }
    std::sort(ring->begin(), ring->end());
  }

  // The link polygon of edge (u, v) and the apexes of the outer triangles. False when the
  // collapse would break the 2-manifold (link condition) or the link is too small or too large.
  bool BuildLink(uint32_t u, uint32_t v, Link* link) const {
    link->w.clear();
    link->x.clear();
    link->edges.clear();
    int shared = 0;
    for (uint32_t t : vtris_[u]) {
      const auto r = Rotated(t, u);
      if (r[1] == v || r[2] == v) {
        ++shared;
        continue;
      }
      link->edges.push_back({r[1], r[2]});
    }
    for (uint32_t t : vtris_[v]) {
      const auto r = Rotated(t, v);
      if (r[1] == u || r[2] == u) continue;
      link->edges.push_back({r[1], r[2]});
    }
    const size_t k = link->edges.size();
    if (shared != 2 || k < 3 || k > kMaxLink) return false;
    // Link condition: the rings of u and v share exactly the two apexes of the shared triangles.
    Ring(u, &link->ring_u);
    Ring(v, &link->ring_v);
    size_t common = 0;
    for (size_t i = 0, j = 0; i < link->ring_u.size() && j < link->ring_v.size();) {
      if (link->ring_u[i] < link->ring_v[j]) {
        ++i;
      } else if (link->ring_u[i] > link->ring_v[j]) {
        ++j;
      } else {
        ++common;
        ++i;
        ++j;
      }
    }
    if (common != 2) return false;
    // Chain the directed link edges into one cycle, starting at the smallest vertex id.
    std::sort(link->edges.begin(), link->edges.end());
    for (size_t i = 1; i < k; ++i) {
      if (link->edges[i].first == link->edges[i - 1].first) return false;
    }
    uint32_t current = link->edges[0].first;
    for (size_t step = 0; step < k; ++step) {
      link->w.push_back(current);
      const auto it = std::lower_bound(link->edges.begin(), link->edges.end(),
                                       std::make_pair(current, uint32_t{0}));
      if (it == link->edges.end() || it->first != current) return false;
      current = it->second;
    }
    if (current != link->w[0]) return false;
    // Outer triangles: the triangle holding the reversed link edge (w[i+1], w[i]).
    for (size_t i = 0; i < k; ++i) {
      const uint32_t a = link->w[i], b = link->w[(i + 1) % k];
      uint32_t apex = UINT32_MAX;
      for (uint32_t t : vtris_[b]) {
        const auto r = Rotated(t, b);
        if (r[1] == a) {
          apex = r[2];
          break;
        }
      }
      if (apex == UINT32_MAX || apex == u || apex == v) return false;
      link->x.push_back(apex);
    }
    // A vertex may not appear twice in the link (would pinch the surface).
    link->ring_u.assign(link->w.begin(), link->w.end());
    std::sort(link->ring_u.begin(), link->ring_u.end());
    if (std::adjacent_find(link->ring_u.begin(), link->ring_u.end()) != link->ring_u.end()) {
      return false;
    }
    return true;
  }

  // Computes the best admissible placement of edge (u, v) in double; true if one exists.
  bool Evaluate(uint32_t u, uint32_t v, Entry* entry) {
    ++evaluations_;
    if (!BuildLink(u, v, &link_)) return false;
    const size_t k = link_.w.size();
    const Vec3 origin = (pos_[u] + pos_[v]) * 0.5;
    const Vec3 lu = pos_[u] - origin, lv = pos_[v] - origin;
    local_w_.resize(k);
    double radius = std::max(Norm(lu), Norm(lv));
    for (size_t i = 0; i < k; ++i) {
      local_w_[i] = pos_[link_.w[i]] - origin;
      radius = std::max(radius, Norm(local_w_[i]));
    }
    // Constraints a.p <= b (local coordinates, unit a).
    constraints_.clear();
    auto add = [&](Vec3 a, double b) {
      const double len = Norm(a);
      if (!(len > 1e-300)) return;  // degenerate (collinear): decided by the exact test
      constraints_.push_back({a * (1.0 / len), b / len});
    };
    for (size_t i = 0; i < k; ++i) {
      const Vec3 wi = local_w_[i], wj = local_w_[(i + 1) % k];
      const Vec3 wh = local_w_[(i + k - 1) % k];
      // Containment: u and v below the fan triangle (p, w_i, w_i+1), i.e. p on or above the
      // plane (s, w_i, w_i+1): m.(p - s) >= 0 with m = (w_i - s) x (w_i+1 - s).
      for (const Vec3& s : {lu, lv}) {
        const Vec3 m = Cross(wi - s, wj - s);
        add(m * -1.0, -Dot(m, s));
      }
      // Link-edge convexity: p below the outer triangle (w_i+1, w_i, x_i).
      const Vec3 xi = pos_[link_.x[i]] - origin;
      const Vec3 n_outer = Cross(wi - wj, xi - wj);
      add(n_outer, Dot(n_outer, wj));
      // Spoke convexity at (p, w_i): w_i+1 below plane (p, w_i-1, w_i), i.e. p on or above the
      // plane (w_i-1, w_i, w_i+1).
      const Vec3 m = Cross(wh - wj, wi - wj);
      add(m * -1.0, -Dot(m, wj));
    }
    // Objective: the new fan's volume, p . sum(w_i x w_i+1) / 6 up to a constant.
    Vec3 area{};
    for (size_t i = 0; i < k; ++i) area = area + Cross(local_w_[i], local_w_[(i + 1) % k]);
    const double bound = 4.0 * radius + max_growth_;
    // p is rounded to float after the LP: keep it this far inside every constraint.
    const double margin = 2.0 * FLT_EPSILON * (MaxAbs(origin) + 2.0 * bound) + 1e-12 * bound;
    const double tol = 1e-12 * bound;
    // Seidel's LP is expected linear only in random constraint order; a fixed-seed shuffle keeps
    // it deterministic (the given order, box corner first, violates nearly every constraint).
    shifted_.resize(constraints_.size());
    for (size_t i = 0; i < constraints_.size(); ++i) {
      shifted_[i] = {constraints_[i].a, constraints_[i].b - margin};
    }
    uint64_t state = 0x9e3779b97f4a7c15ull;
    for (size_t i = shifted_.size(); i > 1; --i) {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      std::swap(shifted_[i - 1], shifted_[(state >> 33) % i]);
    }
    bool found = false;
    auto consider = [&](Vec3 candidate) {
      const Vec3 local = candidate - origin;
      for (const Halfspace3& h : constraints_) {
        if (Dot(h.a, local) > h.b + tol) return;
      }
      const double growth = reference_.LowerBound(candidate);
      const double volume = Dot(area, local);
      if (!found || growth < entry->growth || (growth == entry->growth && volume < entry->volume)) {
        found = true;
        entry->growth = growth;
        entry->volume = volume;
        const Float3 f = ToFloat3(candidate);
        entry->p[0] = f.x;
        entry->p[1] = f.y;
        entry->p[2] = f.z;
      }
    };
    Vec3 solution;
    if (lp_.Solve3(shifted_, area, bound, tol, &solution)) {
      consider(RoundToFloat(origin + solution));
    }
    consider(pos_[u]);  // half-edge collapses: exact in flat regions
    consider(pos_[v]);
    return found;
  }

  // Evaluates edge `key` now and queues it if it has an admissible placement.
  void Push(uint64_t key) {
    EdgeState& state = edges_[key];
    ++state.version;
    state.live = false;
    const uint32_t u = static_cast<uint32_t>(key >> 32);
    const uint32_t v = static_cast<uint32_t>(key & 0xffffffffu);
    Entry entry;
    if (!Evaluate(u, v, &entry)) return;
    entry.key = key;
    entry.version = state.version;
    entry.stamp_u = stamp_[u];
    entry.stamp_v = stamp_[v];
    state.live = true;
    queue_.push(entry);
  }

  // Exact acceptance on the float coordinates: fan triangles non-degenerate; u and v on or
  // below every fan plane; every spoke and link edge convex (coplanar allowed if not folded);
  // growth within the bound. With global_checks_ also every vertex vs every fan plane and p vs
  // every other triangle (the fallback if the local test ever let a non-convex mesh through).
  bool ExactAccept(uint32_t u, uint32_t v, const Link& link, Vec3 p) const {
    const size_t k = link.w.size();
    const Point pp = ToPoint(p), pu = ToPoint(pos_[u]), pv = ToPoint(pos_[v]);
    for (size_t i = 0; i < k; ++i) {
      const Point wi = ToPoint(pos_[link.w[i]]);
      const Point wj = ToPoint(pos_[link.w[(i + 1) % k]]);
      if (CGAL::collinear(pp, wi, wj)) return false;
      if (CGAL::orientation(pp, wi, wj, pu) == CGAL::POSITIVE) return false;
      if (CGAL::orientation(pp, wi, wj, pv) == CGAL::POSITIVE) return false;
      const Point xi = ToPoint(pos_[link.x[i]]);
      const CGAL::Orientation outer = CGAL::orientation(pp, wi, wj, xi);
      if (outer == CGAL::POSITIVE) return false;
      if (outer == CGAL::COPLANAR && CGAL::coplanar_orientation(wi, wj, pp, xi) != CGAL::NEGATIVE) {
        return false;
      }
    }
    for (size_t i = 0; i < k; ++i) {
      const Point wh = ToPoint(pos_[link.w[(i + k - 1) % k]]);
      const Point wi = ToPoint(pos_[link.w[i]]);
      const Point wj = ToPoint(pos_[link.w[(i + 1) % k]]);
      const CGAL::Orientation spoke = CGAL::orientation(pp, wh, wi, wj);
      if (spoke == CGAL::POSITIVE) return false;
      if (spoke == CGAL::COPLANAR && CGAL::coplanar_orientation(pp, wi, wh, wj) != CGAL::NEGATIVE) {
        return false;
      }
    }
    if (global_checks_) {
      for (size_t i = 0; i < k; ++i) {
        const Point wi = ToPoint(pos_[link.w[i]]);
        const Point wj = ToPoint(pos_[link.w[(i + 1) % k]]);
        for (uint32_t q = 0; q < pos_.size(); ++q) {
          if (!valive_[q]) continue;
          if (CGAL::orientation(pp, wi, wj, ToPoint(pos_[q])) == CGAL::POSITIVE) return false;
        }
      }
      for (uint32_t t = 0; t < tris_.size(); ++t) {
        if (!tri_alive_[t]) continue;
        const auto& tri = tris_[t];
        if (tri[0] == u || tri[1] == u || tri[2] == u || tri[0] == v || tri[1] == v ||
            tri[2] == v) {
          continue;
        }
        if (CGAL::orientation(ToPoint(pos_[tri[0]]), ToPoint(pos_[tri[1]]), ToPoint(pos_[tri[2]]),
                              pp) == CGAL::POSITIVE) {
          return false;
        }
      }
    }
    return reference_.Distance(p) <= max_growth_;
  }

  void RemoveTriangleFrom(uint32_t vertex, uint32_t t) {
    auto& list = vtris_[vertex];
    list.erase(std::remove(list.begin(), list.end(), t), list.end());
  }

  // Merges v into u, moves u to p. The fan (p, w_i, w_i+1) is what remains of the two stars.
  void Collapse(uint32_t u, uint32_t v, Vec3 p, const Link& link) {
    (void)link;
    std::vector<uint32_t> merged;
    merged.reserve(vtris_[u].size() + vtris_[v].size());
    for (uint32_t t : vtris_[u]) {
      const auto& tri = tris_[t];
      if (tri[0] == v || tri[1] == v || tri[2] == v) {
        tri_alive_[t] = 0;
        --alive_triangles_;
        for (uint32_t corner : tri) {
          if (corner != u && corner != v) RemoveTriangleFrom(corner, t);
        }
      } else {
        merged.push_back(t);
      }
    }
    for (uint32_t t : vtris_[v]) {
      if (!tri_alive_[t]) continue;
      auto& tri = tris_[t];
      for (uint32_t& corner : tri) {
        if (corner == v) corner = u;
      }
      merged.push_back(t);
    }
    vtris_[u] = std::move(merged);
    vtris_[v].clear();
    valive_[v] = 0;
    pos_[u] = p;
  }

  // A collapse changes the evaluation of every edge touching p, the link vertices or the apexes
  // of the outer triangles (their link constraints changed): their stamps move on, so queued
  // entries of those edges become stale and are re-evaluated when they surface. Edges without a
  // queued entry (new edges, or ones that had no admissible placement) are evaluated now.
  void Reevaluate(uint32_t p, const Link& link) {
    touched_.clear();
    touched_.push_back(p);
    touched_.insert(touched_.end(), link.w.begin(), link.w.end());
    touched_.insert(touched_.end(), link.x.begin(), link.x.end());
    for (uint32_t a : touched_) ++stamp_[a];
    keys_.clear();
    for (uint32_t a : touched_) {
      for (uint32_t t : vtris_[a]) {
        const auto r = Rotated(t, a);
        keys_.push_back(EdgeKey(a, r[1]));
      }
    }
    std::sort(keys_.begin(), keys_.end());
    keys_.erase(std::unique(keys_.begin(), keys_.end()), keys_.end());
    for (uint64_t key : keys_) {
      if (!edges_[key].live) Push(key);
    }
  }

  const GrowthReference& reference_;
  const double max_growth_;
  const uint32_t max_triangles_;
  const bool global_checks_;
  std::vector<Vec3> pos_;
  std::vector<std::array<uint32_t, 3>> tris_;
  std::vector<uint8_t> tri_alive_;
  std::vector<std::vector<uint32_t>> vtris_;  // alive triangles per vertex
  std::vector<uint8_t> valive_;
  std::vector<uint32_t> stamp_;  // per vertex, bumped whenever its edges' evaluations change
  uint32_t alive_triangles_;
  struct EdgeState {
    uint32_t version = 0;  // of the newest queued entry; older entries are ignored
    bool live = false;     // that entry is still in the queue
  };
  std::unordered_map<uint64_t, EdgeState> edges_;  // lookups only, never iterated
  std::priority_queue<Entry, std::vector<Entry>, EntryAfter> queue_;
  uint32_t collapses_ = 0, rejected_ = 0, evaluations_ = 0;
  // Scratch.
  Link link_;
  LpSolver lp_;
  std::vector<Vec3> local_w_;
  std::vector<Halfspace3> constraints_, shifted_;
  std::vector<uint32_t> touched_;
  std::vector<uint64_t> keys_;
};

}  // namespace

Mesh CollapseEdges(const Mesh& h0, const GrowthReference& reference, double max_growth,
                   uint32_t max_triangles, bool global_checks, HullStats* stats) {
  EdgeCollapser collapser(h0, reference, max_growth, max_triangles, global_checks);
  collapser.Run(stats);
  return collapser.Extract();
}

}  // namespace drape::bake::detail

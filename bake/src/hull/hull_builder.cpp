#include "drape/bake/hull_builder.h"

// All CGAL code of the hull stage lives in this one translation unit (each CGAL TU costs 20-45 s
// to compile). Kernel: EPICK. Its predicates are exact; nothing here relies on its constructions.
#define CGAL_EIGEN3_ENABLED 1
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Exact_rational.h>
#include <CGAL/Interval_nt.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>
#include <CGAL/optimal_bounding_box.h>

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numeric>
#include <queue>
#include <span>
#include <string>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include "drape/runtime/math.h"

namespace drape::bake {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Clock = std::chrono::steady_clock;

double MillisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// ---------------------------------------------------------------------------------------------
// Small double vector algebra (bake-side; the stored data is float).

struct Vec3 {
  double x = 0.0, y = 0.0, z = 0.0;
};
inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator*(Vec3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline double Dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 Cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double Norm(Vec3 a) { return std::sqrt(Dot(a, a)); }
inline double MaxAbs(Vec3 a) { return std::max({std::fabs(a.x), std::fabs(a.y), std::fabs(a.z)}); }
inline Vec3 ToVec3(Float3 f) { return {f.x, f.y, f.z}; }
// Round to float through a volatile: GCC 12.2 at -O2/-O3 folds an SLP-vectorised pair of
// (double)(float)x round trips back to x (measured on this toolchain; -O1 is correct), which
// would silently keep double coordinates where the stored float ones are meant.
inline float ToFloat(double v) {
  volatile float f = static_cast<float>(v);
  return f;
}
inline Float3 ToFloat3(Vec3 v) { return {ToFloat(v.x), ToFloat(v.y), ToFloat(v.z)}; }
// Rounds each coordinate to the nearest float: the stored precision.
inline Vec3 RoundToFloat(Vec3 v) { return ToVec3(ToFloat3(v)); }
inline Point ToPoint(Vec3 v) { return Point(v.x, v.y, v.z); }
inline double AbsDot(Vec3 a, Vec3 b) {
  return std::fabs(a.x) * std::fabs(b.x) + std::fabs(a.y) * std::fabs(b.y) +
         std::fabs(a.z) * std::fabs(b.z);
}

// Worst-case relative error of a float dot product of 3 terms in any order (gamma_3 for unit
// roundoff u = 2^-24) plus the rounding of the double evaluation that replaces it here.
constexpr double kFloatDot3Error =
    3.0 * 5.9604644775390625e-08 / (1.0 - 3.0 * 5.9604644775390625e-08) + 1e-15;

// Smallest float >= value (value finite).
float RoundUpToFloat(double value) {
  float f = ToFloat(value);
  if (static_cast<double>(f) < value) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

uint64_t EdgeKey(uint32_t a, uint32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<uint64_t>(a) << 32) | b;
}

// An indexed triangle mesh whose coordinates are exactly representable in float.
struct Mesh {
  std::vector<Vec3> points;
  std::vector<std::array<uint32_t, 3>> triangles;  // counter-clockwise seen from outside
};

// Defined below: groups of edge-adjacent, exactly coplanar triangles.
std::vector<uint32_t> GroupCoplanar(const Mesh& mesh, uint32_t* group_count,
                                    std::vector<uint32_t>* parent_out = nullptr);
bool CanonicalTriangulation(Mesh* mesh);

// Sorts the points lexicographically and removes exact duplicates (a deterministic input order
// for the hull, whatever order the points were made in).
void SortUnique(std::vector<Vec3>* points) {
  std::sort(points->begin(), points->end(), [](const Vec3& a, const Vec3& b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  });
  points->erase(std::unique(points->begin(), points->end(),
                            [](const Vec3& a, const Vec3& b) {
                              return a.x == b.x && a.y == b.y && a.z == b.z;
                            }),
                points->end());
}

// ---------------------------------------------------------------------------------------------
// Convex hull (CGAL). Returns false unless the hull is a closed polytope with >= 4 faces, i.e. the
// points are not all coplanar.

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

// ---------------------------------------------------------------------------------------------
// Distance to the inflated hull H0 (the reference for "growth").

class GrowthReference {
 public:
  explicit GrowthReference(const Mesh& h0) {
    const size_t n = h0.triangles.size();
    nx_.resize(n);
    ny_.resize(n);
    nz_.resize(n);
    d_.resize(n);
    a_.resize(n);
    b_.resize(n);
    c_.resize(n);
    for (size_t t = 0; t < n; ++t) {
      const Vec3 a = h0.points[h0.triangles[t][0]];
      const Vec3 b = h0.points[h0.triangles[t][1]];
      const Vec3 c = h0.points[h0.triangles[t][2]];
      Vec3 normal = Cross(b - a, c - a);
      const double len = Norm(normal);
      normal = len > 0.0 ? normal * (1.0 / len) : Vec3{};
      nx_[t] = normal.x;
      ny_[t] = normal.y;
      nz_[t] = normal.z;
      d_[t] = std::max({Dot(normal, a), Dot(normal, b), Dot(normal, c)});
      a_[t] = a;
      b_[t] = b;
      c_[t] = c;
    }
  }

  // max over H0's triangle planes of the signed height of p, clamped at 0: a lower bound of
  // Distance(p) (exact up to double rounding).
  double LowerBound(Vec3 p) const {
    double best = 0.0;
    const size_t n = d_.size();
    for (size_t t = 0; t < n; ++t) {
      const double h = nx_[t] * p.x + ny_[t] * p.y + nz_[t] * p.z - d_[t];
      best = h > best ? h : best;
    }
    return best;
  }

  // Euclidean distance from p to the polytope H0 (0 inside). For p outside, the nearest point
  // lies on a triangle whose plane has p strictly on its outer side.
  double Distance(Vec3 p) const {
    // Outside p: the nearest boundary point q lies on a triangle T with n_T.(p - q) >= 0, i.e.
    // h_T(p) >= 0. Triangles with h slightly below 0 (rounding) are kept: extra candidates are
    // harmless, a missing one is not (a point on the surface must find its own triangle).
    const double tol = 1e-12 * (1.0 + MaxAbs(p));
    if (LowerBound(p) <= 0.0) return 0.0;
    double best = std::numeric_limits<double>::infinity();
    for (size_t t = 0; t < d_.size(); ++t) {
      const double h = nx_[t] * p.x + ny_[t] * p.y + nz_[t] * p.z - d_[t];
      if (h < -tol || h >= best) continue;
      best = std::min(best, PointTriangleDistance(p, a_[t], b_[t], c_[t]));
    }
    return best;
  }

 private:
  // Ericson, Real-Time Collision Detection, 5.1.5.
  static double PointTriangleDistance(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = Dot(ab, ap), d2 = Dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return Norm(p - a);
    const Vec3 bp = p - b;
    const double d3 = Dot(ab, bp), d4 = Dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return Norm(p - b);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
      const double v = d1 / (d1 - d3);
      return Norm(p - (a + ab * v));
    }
    const Vec3 cp = p - c;
    const double d5 = Dot(ab, cp), d6 = Dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return Norm(p - c);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
      const double w = d2 / (d2 - d6);
      return Norm(p - (a + ac * w));
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
      const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
      return Norm(p - (b + (c - b) * w));
    }
    const double denom = 1.0 / (va + vb + vc);
    const double v = vb * denom, w = vc * denom;
    return Norm(p - (a + ab * v + ac * w));
  }

  std::vector<double> nx_, ny_, nz_, d_;
  std::vector<Vec3> a_, b_, c_;
};

// ---------------------------------------------------------------------------------------------
// Seidel's incremental LP in 3, 2 and 1 variables, deterministic order (the constraint order as
// given). Minimises c.x subject to a_i.x <= b_i (|a_i| = 1) and the box |x_j| <= bound. A
// constraint counts as violated when a.x > b + tol. Floating point: the answer is a candidate
// that the exact predicates accept or refuse later, so tolerances only need to be sensible.

struct Halfspace3 {
  Vec3 a;
  double b = 0.0;
};
struct Halfspace2 {
  double a0 = 0.0, a1 = 0.0, b = 0.0;
};

class LpSolver {
 public:
  bool Solve3(const std::vector<Halfspace3>& hs, Vec3 c, double bound, double tol, Vec3* x) {
    Vec3 cur{c.x > 0.0 ? -bound : (c.x < 0.0 ? bound : 0.0),
             c.y > 0.0 ? -bound : (c.y < 0.0 ? bound : 0.0),
             c.z > 0.0 ? -bound : (c.z < 0.0 ? bound : 0.0)};
    for (size_t i = 0; i < hs.size(); ++i) {
      const Halfspace3& h = hs[i];
      if (Dot(h.a, cur) <= h.b + tol) continue;
      // The optimum of the first i+1 constraints lies on plane i: solve there in 2D.
      const Vec3 origin = h.a * h.b;
      const Vec3 helper =
          std::fabs(h.a.x) <= std::fabs(h.a.y) && std::fabs(h.a.x) <= std::fabs(h.a.z)
              ? Vec3{1, 0, 0}
              : (std::fabs(h.a.y) <= std::fabs(h.a.z) ? Vec3{0, 1, 0} : Vec3{0, 0, 1});
      Vec3 e1 = Cross(h.a, helper);
      e1 = e1 * (1.0 / Norm(e1));
      const Vec3 e2 = Cross(h.a, e1);
      plane_.clear();
      auto project = [&](Vec3 a, double b) {
        const double p0 = Dot(a, e1), p1 = Dot(a, e2);
        const double rhs = b - Dot(a, origin);
        const double len = std::sqrt(p0 * p0 + p1 * p1);
        if (len < 1e-9) return rhs >= -tol;  // parallel: all or nothing
        plane_.push_back({p0 / len, p1 / len, rhs / len});
        return true;
      };
      // Box faces first: the 2D start is a corner of an even larger box, so they bind early.
      const Vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
      for (const Vec3& axis : axes) {
        if (!project(axis, bound) || !project(axis * -1.0, bound)) return false;
      }
      for (size_t j = 0; j < i; ++j) {
        if (!project(hs[j].a, hs[j].b)) return false;
      }
      double y0 = 0.0, y1 = 0.0;
      if (!Solve2(Dot(c, e1), Dot(c, e2), 2.0 * bound + std::fabs(h.b), tol, &y0, &y1)) {
        return false;
      }
      cur = origin + e1 * y0 + e2 * y1;
    }
    *x = cur;
    return true;
  }

 private:
  // Over plane_ (2D halfspaces) and the box |y_j| <= bound.
  bool Solve2(double c0, double c1, double bound, double tol, double* y0, double* y1) const {
    double x0 = c0 > 0.0 ? -bound : (c0 < 0.0 ? bound : 0.0);
    double x1 = c1 > 0.0 ? -bound : (c1 < 0.0 ? bound : 0.0);
    for (size_t i = 0; i < plane_.size(); ++i) {
      const Halfspace2& h = plane_[i];
      if (h.a0 * x0 + h.a1 * x1 <= h.b + tol) continue;
      // On the line h: o + t e.
      const double o0 = h.a0 * h.b, o1 = h.a1 * h.b;
      const double e0 = -h.a1, e1 = h.a0;
      const double line_bound = 2.0 * bound + std::fabs(h.b);
      double lo = -line_bound, hi = line_bound;
      auto clip = [&](double a0, double a1, double b) {
        const double alpha = a0 * e0 + a1 * e1;
        const double beta = b - (a0 * o0 + a1 * o1);
        if (std::fabs(alpha) < 1e-12) return beta >= -tol;
        if (alpha > 0.0) {
          hi = std::min(hi, beta / alpha);
        } else {
          lo = std::max(lo, beta / alpha);
        }
        return true;
      };
      for (size_t j = 0; j < i; ++j) {
        if (!clip(plane_[j].a0, plane_[j].a1, plane_[j].b)) return false;
      }
      if (!clip(1, 0, bound) || !clip(-1, 0, bound) || !clip(0, 1, bound) || !clip(0, -1, bound)) {
        return false;
      }
      if (lo > hi + tol) return false;
      const double ce = c0 * e0 + c1 * e1;
      double t;
      if (lo > hi) {
        t = 0.5 * (lo + hi);
      } else if (ce > 0.0) {
        t = lo;
      } else if (ce < 0.0) {
        t = hi;
      } else {
        t = std::clamp(0.0, lo, hi);
      }
      x0 = o0 + t * e0;
      x1 = o1 + t * e1;
    }
    *y0 = x0;
    *y1 = x1;
    return true;
  }

  std::vector<Halfspace2> plane_;
};

// ---------------------------------------------------------------------------------------------
// Exact predicates on stored coordinates.

// Closed ball B(x, r) inside the closed half-space below the oriented plane of (a, b, c):
// with n = (b - a) x (c - a): n.(a - x) >= r |n|. Interval filter, then exact rationals.
bool BallBelowPlane(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& x, double r) {
  if (r <= 0.0) {
    return CGAL::orientation(ToPoint(a), ToPoint(b), ToPoint(c), ToPoint(x)) != CGAL::POSITIVE;
  }
  {
    using I = CGAL::Interval_nt<false>;
    CGAL::Protect_FPU_rounding<true> protect;
    const I abx = I(b.x) - I(a.x), aby = I(b.y) - I(a.y), abz = I(b.z) - I(a.z);
    const I acx = I(c.x) - I(a.x), acy = I(c.y) - I(a.y), acz = I(c.z) - I(a.z);
    const I nx = aby * acz - abz * acy, ny = abz * acx - abx * acz, nz = abx * acy - aby * acx;
    const I s = nx * (I(a.x) - I(x.x)) + ny * (I(a.y) - I(x.y)) + nz * (I(a.z) - I(x.z));
    const I len2 = nx * nx + ny * ny + nz * nz;
    const I rr = I(r) * I(r);
    const I margin = s * s - rr * len2;
    if (s.sup() < 0.0 || margin.sup() < 0.0) return false;
    if (s.inf() > 0.0 && margin.inf() > 0.0) return true;
  }
  using Q = CGAL::Exact_rational;
  const Q abx = Q(b.x) - Q(a.x), aby = Q(b.y) - Q(a.y), abz = Q(b.z) - Q(a.z);
  const Q acx = Q(c.x) - Q(a.x), acy = Q(c.y) - Q(a.y), acz = Q(c.z) - Q(a.z);
  const Q nx = aby * acz - abz * acy, ny = abz * acx - abx * acz, nz = abx * acy - aby * acx;
  const Q s = nx * (Q(a.x) - Q(x.x)) + ny * (Q(a.y) - Q(x.y)) + nz * (Q(a.z) - Q(x.z));
  if (s < 0) return false;
  const Q len2 = nx * nx + ny * ny + nz * nz;
  return s * s >= Q(r) * Q(r) * len2;
}

// ---------------------------------------------------------------------------------------------
// Greedy edge collapse with constrained placement (notes section 2.3).

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

// ---------------------------------------------------------------------------------------------
// Coplanar merging (union-find over edge-adjacent, exactly coplanar triangles).

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

// Group id per triangle, ids numbered in order of each group's first triangle.
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

// The triangulation of a coplanar face (a parallelogram of the Minkowski sum, a cube side) is
// CGAL's choice and varies between calls. Re-triangulate every face with more than one triangle
// canonically: its boundary cycle starting at the smallest vertex index, fanned from the first
// vertex that gives no collinear triangle (faces are convex polygons). Then rotate each triangle
// to start at its smallest index and sort them. Returns true (kept for the hull's signature).
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

// ---------------------------------------------------------------------------------------------
// Plane removal (dual collapse, ablation).

struct PlaneRemovalResult {
  Mesh mesh;
  std::vector<Vec3> kept_normals;    // unit, double
  std::vector<double> kept_offsets;  // planes the mesh's faces lie on (before the margin)
  uint32_t dropped = 0;
  bool budget_reached = false;
};

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

// ---------------------------------------------------------------------------------------------
// Inflation.

// Unit-circumradius icosahedron vertices (12) and the inradius of that icosahedron.
std::array<Vec3, 12> Icosahedron(double* inradius) {
  const double phi = (1.0 + std::sqrt(5.0)) / 2.0;
  const double s = 1.0 / std::sqrt(1.0 + phi * phi);
  const double a = s, b = phi * s;
  *inradius = phi * phi / (std::sqrt(3.0) * std::sqrt(1.0 + phi * phi));
  return {Vec3{0, a, b}, Vec3{0, -a, b}, Vec3{0, a, -b}, Vec3{0, -a, -b},
          Vec3{a, b, 0}, Vec3{-a, b, 0}, Vec3{a, -b, 0}, Vec3{-a, -b, 0},
          Vec3{b, 0, a}, Vec3{-b, 0, a}, Vec3{b, 0, -a}, Vec3{-b, 0, -a}};
}

// H0 = hull of the float-rounded points {x + r u_k}, r = (delta + margin) / inradius.
bool InflateMinkowski(const std::vector<Vec3>& base, double delta, double margin, Mesh* h0) {
  double inradius = 0.0;
  const std::array<Vec3, 12> ico = Icosahedron(&inradius);
  // 1e-12: the double icosahedron is not exact; err on the large side.
  const double radius = (delta + margin) / inradius * (1.0 + 1e-12);
  std::vector<Vec3> points;
  points.reserve(base.size() * 12);
  for (const Vec3& x : base) {
    for (const Vec3& u : ico) points.push_back(RoundToFloat(x + u * radius));
  }
  SortUnique(&points);
  return ConvexHull(points, h0);
}

// Paper B: every hull vertex moved by delta along its normal, hulled again. Angle-weighted
// vertex normals (Thuermer and Wuethrich): unlike area weights they do not depend on how a flat
// face happens to be triangulated.
bool InflateVertexNormals(const Mesh& hull, double delta, Mesh* h0) {
  std::vector<Vec3> normals(hull.points.size());
  for (const auto& tri : hull.triangles) {
    Vec3 n =
        Cross(hull.points[tri[1]] - hull.points[tri[0]], hull.points[tri[2]] - hull.points[tri[0]]);
    const double len = Norm(n);
    if (!(len > 0.0)) continue;
    n = n * (1.0 / len);
    for (int k = 0; k < 3; ++k) {
      const Vec3 p = hull.points[tri[k]];
      const Vec3 a = hull.points[tri[(k + 1) % 3]] - p, b = hull.points[tri[(k + 2) % 3]] - p;
      const double angle = std::atan2(Norm(Cross(a, b)), Dot(a, b));
      normals[tri[k]] = normals[tri[k]] + n * angle;
    }
  }
  std::vector<Vec3> points;
  points.reserve(hull.points.size());
  for (size_t i = 0; i < hull.points.size(); ++i) {
    const double len = Norm(normals[i]);
    const Vec3 n = len > 0.0 ? normals[i] * (1.0 / len) : Vec3{};
    points.push_back(RoundToFloat(hull.points[i] + n * delta));
  }
  return ConvexHull(points, h0);
}

// ---------------------------------------------------------------------------------------------
// Exact checks on a Mesh (the same predicates as the public functions).

bool MeshIsConvex(const Mesh& mesh, uint32_t* violations) {
  *violations = 0;
  const size_t n = mesh.points.size(), t = mesh.triangles.size();
  if (n < 4 || t < 4) return false;
  for (const Vec3& p : mesh.points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) return false;
  }
  std::vector<uint64_t> directed;
  std::vector<uint8_t> used(n, 0);
  for (const auto& tri : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tri[static_cast<size_t>(k)], b = tri[static_cast<size_t>((k + 1) % 3)];
      if (a >= n || b >= n || a == b) return false;
      used[a] = 1;
      directed.push_back((static_cast<uint64_t>(a) << 32) | b);
    }
  }
  for (uint8_t u : used) {
    if (!u) return false;
  }
  std::sort(directed.begin(), directed.end());
  if (std::adjacent_find(directed.begin(), directed.end()) != directed.end()) return false;
  for (uint64_t e : directed) {
    const uint64_t reverse = (e << 32) | (e >> 32);
    if (!std::binary_search(directed.begin(), directed.end(), reverse)) return false;
  }
  // Euler characteristic of a sphere.
  const long long euler = static_cast<long long>(n) - static_cast<long long>(directed.size() / 2) +
                          static_cast<long long>(t);
  if (euler != 2) return false;
  std::vector<Point> points;
  points.reserve(n);
  for (const Vec3& p : mesh.points) points.push_back(ToPoint(p));
  bool strictly_below_somewhere = false;
  for (const auto& tri : mesh.triangles) {
    const Point& a = points[tri[0]];
    const Point& b = points[tri[1]];
    const Point& c = points[tri[2]];
    if (CGAL::collinear(a, b, c)) return false;
    for (const Point& q : points) {
      const CGAL::Orientation o = CGAL::orientation(a, b, c, q);
      if (o == CGAL::POSITIVE) ++*violations;
      if (o == CGAL::NEGATIVE) strictly_below_somewhere = true;
    }
  }
  if (*violations != 0 || !strictly_below_somewhere) return false;
  // A closed sphere whose triangles all support the polytope could still cover its boundary
  // twice (a branched cover); its enclosed volume would then be a multiple of the hull's.
  Mesh hull;
  if (!ConvexHull(mesh.points, &hull)) return false;
  auto volume = [](const Mesh& m) {
    const Vec3 o = m.points[0];
    double v = 0.0;
    for (const auto& tri : m.triangles) {
      v += Dot(m.points[tri[0]] - o, Cross(m.points[tri[1]] - o, m.points[tri[2]] - o));
    }
    return v / 6.0;
  };
  const double mesh_volume = volume(mesh), hull_volume = volume(hull);
  return mesh_volume > 0.0 && std::fabs(mesh_volume - hull_volume) <= 1e-6 * hull_volume;
}

Mesh MeshFromCollider(const HullColliderData& collider) {
  Mesh mesh;
  mesh.points.reserve(collider.vertices.size());
  for (const Float3& v : collider.vertices) mesh.points.push_back(ToVec3(v));
  for (size_t i = 0; i + 2 < collider.triangles.size(); i += 3) {
    mesh.triangles.push_back(
        {collider.triangles[i], collider.triangles[i + 1], collider.triangles[i + 2]});
  }
  return mesh;
}

bool PointBallInside(const Mesh& mesh, const Vec3& x, double radius) {
  for (const auto& tri : mesh.triangles) {
    if (!BallBelowPlane(mesh.points[tri[0]], mesh.points[tri[1]], mesh.points[tri[2]], x, radius)) {
      return false;
    }
  }
  return true;
}

// Approximate (double) amount by which the ball B(x, radius) pokes out of the mesh, metres.
double BallDeficit(const Mesh& mesh, const Vec3& x, double radius) {
  double worst = -std::numeric_limits<double>::infinity();
  for (const auto& tri : mesh.triangles) {
    const Vec3 a = mesh.points[tri[0]];
    Vec3 n = Cross(mesh.points[tri[1]] - a, mesh.points[tri[2]] - a);
    const double len = Norm(n);
    if (!(len > 0.0)) continue;
    n = n * (1.0 / len);
    worst = std::max(worst, Dot(n, x - a) + radius);
  }
  return worst;
}

// ---------------------------------------------------------------------------------------------
// Planes and OBB.

struct PlaneGroups {
  std::vector<uint32_t> triangle_group;
  std::vector<Vec3> normals;  // unit, double (before rounding)
};

// Exact coplanar merging; with `hint` planes (plane removal) triangles lying on one hint plane
// within `hint_tolerance` also share it and take its normal.
PlaneGroups BuildPlaneGroups(const Mesh& mesh, const std::vector<Vec3>* hint_normals,
                             const std::vector<double>* hint_offsets, double hint_tolerance) {
  PlaneGroups out;
  const uint32_t n = static_cast<uint32_t>(mesh.triangles.size());
  uint32_t count = 0;
  std::vector<uint32_t> parent;
  GroupCoplanar(mesh, &count, &parent);
  std::vector<uint32_t> hint_of(n, UINT32_MAX);
  if (hint_normals) {
    std::vector<uint32_t> first_with_hint(hint_normals->size(), UINT32_MAX);
    for (uint32_t t = 0; t < n; ++t) {
      const auto& tri = mesh.triangles[t];
      const Vec3 a = mesh.points[tri[0]], b = mesh.points[tri[1]], c = mesh.points[tri[2]];
      Vec3 normal = Cross(b - a, c - a);
      normal = normal * (1.0 / Norm(normal));
      double best = hint_tolerance;
      for (uint32_t j = 0; j < hint_normals->size(); ++j) {
        const Vec3 hn = (*hint_normals)[j];
        if (Dot(hn, normal) < 0.5) continue;
        const double dev = std::max({std::fabs(Dot(hn, a) - (*hint_offsets)[j]),
                                     std::fabs(Dot(hn, b) - (*hint_offsets)[j]),
                                     std::fabs(Dot(hn, c) - (*hint_offsets)[j])});
        if (dev <= best) {
          best = dev;
          hint_of[t] = j;
        }
      }
      if (hint_of[t] != UINT32_MAX) {
        uint32_t& first = first_with_hint[hint_of[t]];
        if (first == UINT32_MAX) {
          first = t;
        } else {
          Union(parent, first, t);
        }
      }
    }
  }
  out.triangle_group.resize(n);
  std::vector<uint32_t> root_group(n, UINT32_MAX);
  count = 0;
  for (uint32_t t = 0; t < n; ++t) {
    const uint32_t root = Find(parent, t);
    if (root_group[root] == UINT32_MAX) root_group[root] = count++;
    out.triangle_group[t] = root_group[root];
  }
  // Normal: area-weighted sum of the group's triangle normals (local origin for accuracy), or
  // the hint plane's normal.
  std::vector<Vec3> sums(count);
  std::vector<uint32_t> hint_of_group(count, UINT32_MAX);
  for (uint32_t t = 0; t < n; ++t) {
    const auto& tri = mesh.triangles[t];
    const Vec3 a = mesh.points[tri[0]];
    const uint32_t g = out.triangle_group[t];
    sums[g] = sums[g] + Cross(mesh.points[tri[1]] - a, mesh.points[tri[2]] - a);
    if (hint_of[t] != UINT32_MAX) hint_of_group[g] = hint_of[t];
  }
  out.normals.resize(count);
  for (uint32_t g = 0; g < count; ++g) {
    out.normals[g] = hint_of_group[g] != UINT32_MAX ? (*hint_normals)[hint_of_group[g]]
                                                    : sums[g] * (1.0 / Norm(sums[g]));
  }
  return out;
}

// Float plane offsets that contain, in the runtime's float arithmetic, every collider vertex
// and every float point within delta of an input point (header, step 5).
void FillPlanes(const Mesh& mesh, const PlaneGroups& groups, const std::vector<Vec3>& inputs,
                double delta, HullColliderData* collider) {
  collider->planes.clear();
  for (const Vec3& normal_double : groups.normals) {
    const Float3 nf = ToFloat3(normal_double);
    const Vec3 n = ToVec3(nf);
    const double n_len = Norm(n);
    double d = -std::numeric_limits<double>::infinity();
    for (const Vec3& v : mesh.points) d = std::max(d, Dot(n, v) + kFloatDot3Error * AbsDot(n, v));
    for (const Vec3& x : inputs) {
      const double ball = delta * n_len;
      d = std::max(d, Dot(n, x) + ball + kFloatDot3Error * (AbsDot(n, x) + std::sqrt(3.0) * ball));
    }
    Plane plane;
    plane.normal = nf;
    plane.offset = std::nextafter(RoundUpToFloat(d), std::numeric_limits<float>::infinity());
    collider->planes.push_back(plane);
  }
  collider->triangle_planes = groups.triangle_group;
}

// Orthonormal right-handed axes (rows) -> OBB covering the collider vertices and the input
// delta-balls in float arithmetic; axes sorted by extent, longest first.
Obb FitObb(const std::array<Vec3, 3>& axes_in, const Mesh& mesh, const std::vector<Vec3>& inputs,
           double delta) {
  // Orthonormalise (Gram-Schmidt), then project.
  std::array<Vec3, 3> axes = axes_in;
  axes[0] = axes[0] * (1.0 / Norm(axes[0]));
  axes[1] = axes[1] - axes[0] * Dot(axes[0], axes[1]);
  axes[1] = axes[1] * (1.0 / Norm(axes[1]));
  axes[2] = Cross(axes[0], axes[1]);
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k) {
    lo[k] = std::numeric_limits<double>::infinity();
    hi[k] = -lo[k];
    for (const Vec3& v : mesh.points) {
      lo[k] = std::min(lo[k], Dot(axes[static_cast<size_t>(k)], v));
      hi[k] = std::max(hi[k], Dot(axes[static_cast<size_t>(k)], v));
    }
    for (const Vec3& x : inputs) {
      lo[k] = std::min(lo[k], Dot(axes[static_cast<size_t>(k)], x) - delta);
      hi[k] = std::max(hi[k], Dot(axes[static_cast<size_t>(k)], x) + delta);
    }
  }
  // Longest first, then right-handed.
  std::array<int, 3> order{0, 1, 2};
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return hi[a] - lo[a] > hi[b] - lo[b]; });
  std::array<Vec3, 3> sorted{axes[static_cast<size_t>(order[0])],
                             axes[static_cast<size_t>(order[1])],
                             axes[static_cast<size_t>(order[2])]};
  // Canonical signs: the largest component of axes 0 and 1 positive.
  for (int k = 0; k < 2; ++k) {
    const Vec3 a = sorted[static_cast<size_t>(k)];
    const double big = std::fabs(a.x) >= std::fabs(a.y) && std::fabs(a.x) >= std::fabs(a.z)
                           ? a.x
                           : (std::fabs(a.y) >= std::fabs(a.z) ? a.y : a.z);
    if (big < 0.0) sorted[static_cast<size_t>(k)] = a * -1.0;
  }
  sorted[2] = Cross(sorted[0], sorted[1]);
  // The centre does not depend on the order or signs of the axes.
  Vec3 center{};
  for (int k = 0; k < 3; ++k)
    center = center + axes[static_cast<size_t>(k)] * (0.5 * (lo[k] + hi[k]));
  Obb obb;
  obb.center = ToFloat3(center);
  const Vec3 c = ToVec3(obb.center);
  float* half[3] = {&obb.half_extents.x, &obb.half_extents.y, &obb.half_extents.z};
  for (int k = 0; k < 3; ++k) {
    obb.axes[k] = ToFloat3(sorted[static_cast<size_t>(k)]);
    const Vec3 a = ToVec3(obb.axes[k]);
    // Runtime: fl(dot(a, fl(p - c))); bound its error by 4 float epsilons of sum
    // |a_i|(|p_i|+|c_i|).
    auto error = [&](const Vec3& p) {
      return 4.0 * FLT_EPSILON *
             (std::fabs(a.x) * (std::fabs(p.x) + std::fabs(c.x)) +
              std::fabs(a.y) * (std::fabs(p.y) + std::fabs(c.y)) +
              std::fabs(a.z) * (std::fabs(p.z) + std::fabs(c.z)));
    };
    double h = 0.0;
    for (const Vec3& v : mesh.points) h = std::max(h, std::fabs(Dot(a, v - c)) + error(v));
    const double a_len = Norm(a);
    for (const Vec3& x : inputs) {
      h = std::max(h,
                   std::fabs(Dot(a, x - c)) + delta * a_len + error(x) + 4.0 * FLT_EPSILON * delta);
    }
    *half[k] = std::nextafter(RoundUpToFloat(h), std::numeric_limits<float>::infinity());
  }
  return obb;
}

std::array<Vec3, 3> CovarianceAxes(const Mesh& mesh) {
  Vec3 origin{};
  for (const Vec3& p : mesh.points) origin = origin + p;
  origin = origin * (1.0 / static_cast<double>(mesh.points.size()));
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  Eigen::Vector3d first = Eigen::Vector3d::Zero();
  double total = 0.0;
  for (const auto& tri : mesh.triangles) {
    const Vec3 p = mesh.points[tri[0]] - origin, q = mesh.points[tri[1]] - origin,
               r = mesh.points[tri[2]] - origin;
    const double area = 0.5 * Norm(Cross(q - p, r - p));
    const Eigen::Vector3d ep(p.x, p.y, p.z), eq(q.x, q.y, q.z), er(r.x, r.y, r.z);
    const Eigen::Vector3d m = (ep + eq + er) / 3.0;
    // Gottschalk: second moment of a uniform triangle.
    second +=
        area / 12.0 *
        (9.0 * m * m.transpose() + ep * ep.transpose() + eq * eq.transpose() + er * er.transpose());
    first += area * m;
    total += area;
  }
  std::array<Vec3, 3> axes{Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};
  if (!(total > 0.0)) return axes;
  const Eigen::Vector3d mean = first / total;
  const Eigen::Matrix3d covariance = second / total - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  if (solver.info() != Eigen::Success) return axes;
  const Eigen::Matrix3d vectors = solver.eigenvectors();  // ascending eigenvalues
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d col = vectors.col(2 - k);
    if (!col.allFinite()) return {Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};
    axes[static_cast<size_t>(k)] = {col.x(), col.y(), col.z()};
  }
  return axes;
}

std::array<Vec3, 3> CgalOptimalAxes(const Mesh& mesh, uint32_t seed) {
  std::vector<Point> points;
  points.reserve(mesh.points.size());
  for (const Vec3& p : mesh.points) points.push_back(ToPoint(p));
  Kernel::Aff_transformation_3 rotation;
  CGAL::oriented_bounding_box(points, rotation,
                              CGAL::parameters::random_seed(seed).use_convex_hull(true));
  // rotation maps the box to an axis-aligned one: its rows are the box axes.
  std::array<Vec3, 3> axes;
  for (int r = 0; r < 3; ++r) {
    axes[static_cast<size_t>(r)] = {CGAL::to_double(rotation.m(r, 0)),
                                    CGAL::to_double(rotation.m(r, 1)),
                                    CGAL::to_double(rotation.m(r, 2))};
  }
  return axes;
}

Status Skip(HullStats* stats, std::string reason) {
  if (stats) stats->skip_reason = reason;
  return Status(StatusCode::kInvalidArgument, std::move(reason));
}

}  // namespace

// ---------------------------------------------------------------------------------------------

Status BuildHullGeometry(std::span<const Float3> points, const HullOptions& options,
                         HullColliderData* collider, HullStats* stats_out) {
  const auto start = Clock::now();
  HullStats local_stats;
  HullStats* stats = stats_out ? stats_out : &local_stats;
  *stats = HullStats{};
  if (collider == nullptr) return Skip(stats, "hull: no output collider");
  if (!(options.delta >= 0.f) || !std::isfinite(options.delta)) {
    return Skip(stats,
                "hull: delta must be finite and >= 0 (got " + std::to_string(options.delta) + ")");
  }
  if (options.max_triangles < 4) return Skip(stats, "hull: max_triangles must be >= 4");
  if (!(options.max_growth >= 0.f) || !std::isfinite(options.max_growth)) {
    return Skip(stats, "hull: max_growth must be finite and >= 0");
  }
  if (options.min_points < 1) return Skip(stats, "hull: min_points must be >= 1");

  // 1. Input: finite, distinct (sorted, so the result does not depend on the input order).
  std::vector<Float3> sorted(points.begin(), points.end());
  for (const Float3& p : sorted) {
    if (!IsFinite(p)) return Skip(stats, "hull: non-finite input point");
  }
  auto less = [](const Float3& a, const Float3& b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  };
  std::sort(sorted.begin(), sorted.end(), less);
  std::vector<Vec3> inputs;
  inputs.reserve(sorted.size());
  for (const Float3& p : sorted) {
    const Vec3 v = ToVec3(p);
    if (!inputs.empty() && inputs.back().x == v.x && inputs.back().y == v.y &&
        inputs.back().z == v.z) {
      continue;
    }
    inputs.push_back(v);
  }
  stats->input_points = static_cast<uint32_t>(inputs.size());
  if (inputs.size() < options.min_points) {
    return Skip(stats, "hull: " + std::to_string(inputs.size()) +
                           " distinct points, fewer than min_points " +
                           std::to_string(options.min_points));
  }
  const double delta = options.delta;

  // 2. Inflation.
  Mesh input_hull;
  const bool full_dimensional = ConvexHull(inputs, &input_hull);
  if (delta == 0.0 && !full_dimensional) {
    return Skip(stats, "hull: delta is 0 and the " + std::to_string(inputs.size()) +
                           " points are not full-dimensional (collinear or coplanar)");
  }
  InflationMode inflation = options.inflation;
  if (inflation == InflationMode::kVertexNormalOffset && delta > 0.0 && !full_dimensional) {
    inflation = InflationMode::kMinkowskiIcosahedron;
    stats->note =
        "input not full-dimensional: vertex normals undefined, used the Minkowski inflation";
  }
  const std::vector<Vec3>& base = full_dimensional ? input_hull.points : inputs;
  double max_abs = 0.0;
  for (const Vec3& p : base) max_abs = std::max(max_abs, MaxAbs(p));

  Mesh result;
  std::vector<uint32_t> h0_groups;
  uint32_t h0_group_count = 0;
  bool verified = false;
  // The loop retries with a larger rounding margin if the exact verification ever fails.
  for (int attempt = 0; attempt < 4 && !verified; ++attempt) {
    Mesh h0;
    const auto attempt_inflate = Clock::now();
    if (delta == 0.0) {
      h0 = input_hull;
    } else if (inflation == InflationMode::kVertexNormalOffset) {
      if (!InflateVertexNormals(input_hull, delta, &h0)) {
        return Skip(stats, "hull: vertex-normal inflation produced a degenerate hull");
      }
    } else {
      // Rounding every coordinate to float moves a vertex by <= sqrt(3)/2 ulp: 2 ulps of margin.
      const double margin = 2.0 * FLT_EPSILON * (max_abs + 2.0 * delta) * std::pow(4.0, attempt);
      if (!InflateMinkowski(base, delta, margin, &h0)) continue;
    }
    stats->inflate_ms += MillisecondsSince(attempt_inflate);
    stats->hull_triangles_before = static_cast<uint32_t>(h0.triangles.size());
    h0_groups = GroupCoplanar(h0, &h0_group_count);
    stats->planes_before = h0_group_count;

    // 3. Simplification.
    const auto simplify_start = Clock::now();
    const GrowthReference reference(h0);
    std::vector<Vec3> hint_normals;
    std::vector<double> hint_offsets;
    bool use_hints = false;
    stats->budget_reached = h0.triangles.size() <= options.max_triangles;
    if (options.simplify == SimplifyMode::kNone || stats->budget_reached) {
      result = h0;
    } else if (options.simplify == SimplifyMode::kEdgeCollapse) {
      for (int pass = 0; pass < 2; ++pass) {
        EdgeCollapser collapser(h0, reference, options.max_growth, options.max_triangles,
                                /*global_checks=*/pass == 1);
        collapser.Run(stats);
        result = collapser.Extract();
        uint32_t violations = 0;
        if (MeshIsConvex(result, &violations)) break;
        if (pass == 1) {
          return Status(StatusCode::kInvalidState,
                        "hull: internal error: simplified hull is not convex (" +
                            std::to_string(violations) + " exact violations)");
        }
        stats->note += (stats->note.empty() ? "" : "; ");
        stats->note += "local convexity test insufficient; re-ran with global checks";
      }
      stats->budget_reached = result.triangles.size() <= options.max_triangles;
    } else {
      PlaneRemover remover(h0, h0_groups, h0_group_count, reference, options.max_growth,
                           options.max_triangles);
      PlaneRemovalResult removal;
      if (!remover.Run(&removal)) {
        result = h0;
        stats->note += "plane removal failed; kept the inflated hull";
      } else {
        result = removal.mesh;
        stats->collapses = removal.dropped;
        hint_normals = removal.kept_normals;
        hint_offsets = removal.kept_offsets;
        use_hints = true;
        // Containment of H0 is by construction up to the margin: confirm it exactly.
        for (const Vec3& p : h0.points) {
          if (!PointBallInside(result, p, 0.0)) {
            result = h0;
            use_hints = false;
            stats->note += "plane removal lost containment; kept the inflated hull";
            break;
          }
        }
      }
      stats->budget_reached = result.triangles.size() <= options.max_triangles;
    }
    stats->simplify_ms += MillisecondsSince(simplify_start);

    // 4. Self-verification (exact).
    const auto verify_start = Clock::now();
    uint32_t violations = 0;
    if (!MeshIsConvex(result, &violations)) {
      return Status(StatusCode::kInvalidState,
                    "hull: internal error: collider is not a closed convex mesh");
    }
    stats->uncovered_points = 0;
    double deficit = 0.0;
    for (const Vec3& x : inputs) {
      if (!PointBallInside(result, x, delta)) {
        ++stats->uncovered_points;
        deficit = std::max(deficit, BallDeficit(result, x, delta));
      }
    }
    stats->containment_deficit_mm = static_cast<float>(deficit * 1000.0);
    double growth = 0.0;
    for (const Vec3& v : result.points) growth = std::max(growth, reference.Distance(v));
    stats->growth_mm = static_cast<float>(growth * 1000.0);
    stats->verify_ms += MillisecondsSince(verify_start);
    if (inflation == InflationMode::kMinkowskiIcosahedron && stats->uncovered_points != 0) {
      continue;  // larger margin
    }
    verified = true;

    // 5. Planes.
    const auto planes_start = Clock::now();
    const double hint_tolerance = 32.0 * FLT_EPSILON * (max_abs + 4.0 * delta + options.max_growth);
    const PlaneGroups groups =
        BuildPlaneGroups(result, use_hints ? &hint_normals : nullptr,
                         use_hints ? &hint_offsets : nullptr, hint_tolerance);
    HullColliderData out_geometry;
    for (const Vec3& p : result.points) out_geometry.vertices.push_back(ToFloat3(p));
    for (const auto& tri : result.triangles) {
      out_geometry.triangles.insert(out_geometry.triangles.end(), tri.begin(), tri.end());
    }
    // The paper's vertex-normal offset does not contain every delta-ball (reported above as
    // uncovered points); pushing its planes out over the balls would make the plane set a larger
    // polytope than the stored vertices, triangles, OBB, Kirkpatrick hierarchies and map table
    // describe, and the runtime's OBB rejection would then miss points inside the planes. Its
    // planes support its own vertices; only the guaranteed (Minkowski) hull adds the balls.
    static const std::vector<Vec3> kNoBalls;
    const bool balls_inside = inflation != InflationMode::kVertexNormalOffset;
    FillPlanes(result, groups, balls_inside ? inputs : kNoBalls, delta, &out_geometry);
    stats->planes_ms = MillisecondsSince(planes_start);

    // 6. OBB.
    const auto obb_start = Clock::now();
    const std::array<Vec3, 3> axes = options.obb == ObbMode::kCgalOptimal
                                         ? CgalOptimalAxes(result, options.obb_seed)
                                         : CovarianceAxes(result);
    out_geometry.obb = FitObb(axes, result, inputs, delta);
    stats->obb_ms = MillisecondsSince(obb_start);
    stats->obb_volume = 8.f * out_geometry.obb.half_extents.x * out_geometry.obb.half_extents.y *
                        out_geometry.obb.half_extents.z;

    collider->vertices = std::move(out_geometry.vertices);
    collider->triangles = std::move(out_geometry.triangles);
    collider->triangle_planes = std::move(out_geometry.triangle_planes);
    collider->planes = std::move(out_geometry.planes);
    collider->obb = out_geometry.obb;
    stats->triangles_after = static_cast<uint32_t>(result.triangles.size());
    stats->planes_after = static_cast<uint32_t>(groups.normals.size());
  }
  if (!verified) {
    return Status(StatusCode::kInvalidState,
                  "hull: internal error: could not build a collider containing every input "
                  "delta-ball (" +
                      std::to_string(inputs.size()) + " points)");
  }
  stats->ms = MillisecondsSince(start);
  return Status::Ok();
}

bool HullContainsPoints(const HullColliderData& collider, std::span<const Float3> points,
                        float inflate) {
  if (!(inflate >= 0.f) || collider.triangles.size() < 12) return false;
  const Mesh mesh = MeshFromCollider(collider);
  for (uint32_t index : collider.triangles) {
    if (index >= mesh.points.size()) return false;
  }
  for (const Float3& p : points) {
    if (!IsFinite(p)) return false;
    if (!PointBallInside(mesh, ToVec3(p), inflate)) return false;
  }
  return true;
}

bool HullIsConvex(const HullColliderData& collider) {
  if (collider.triangles.size() % 3 != 0) return false;
  uint32_t violations = 0;
  return MeshIsConvex(MeshFromCollider(collider), &violations);
}

uint32_t CountConvexityViolations(const HullColliderData& collider) {
  const Mesh mesh = MeshFromCollider(collider);
  uint32_t violations = 0;
  for (const auto& tri : mesh.triangles) {
    if (tri[0] >= mesh.points.size() || tri[1] >= mesh.points.size() ||
        tri[2] >= mesh.points.size()) {
      ++violations;
      continue;
    }
    const Point a = ToPoint(mesh.points[tri[0]]), b = ToPoint(mesh.points[tri[1]]),
                c = ToPoint(mesh.points[tri[2]]);
    for (const Vec3& q : mesh.points) {
      if (CGAL::orientation(a, b, c, ToPoint(q)) == CGAL::POSITIVE) ++violations;
    }
  }
  return violations;
}

}  // namespace drape::bake

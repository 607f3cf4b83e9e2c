#include "drape/bake/mesh_reference.h"

// All CGAL code of the reference queries lives in this one translation unit. Kernel: EPICK. Its
// exact predicates make the segment queries watertight: whether a segment meets a triangle (and
// a tree box) is decided exactly on the stored doubles, so a segment through a shared edge or
// vertex hits at least one of the triangles there and never slips between them, as it can with
// Simple_cartesian's rounded predicates. Constructions (closest points, intersection points) are
// double.
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

namespace drape::bake {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Segment = Kernel::Segment_3;
using Triangle = Kernel::Triangle_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using Traits = CGAL::AABB_traits<Kernel, Primitive>;
using Tree = CGAL::AABB_tree<Traits>;
using SegmentIntersection = Tree::Intersection_and_primitive_id<Segment>::Type;

constexpr double kInverseFourPi = 0.25 / M_PI;
// Hits of one segment closer than this in t are the same crossing when their triangles are
// neighbours (a crossing through a shared edge or vertex is found once per triangle there).
constexpr double kSameCrossingT = 1e-12;

inline double Dot(const double* a, const double* b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
inline void Cross(const double* a, const double* b, double* r) {
  r[0] = a[1] * b[2] - a[2] * b[1];
  r[1] = a[2] * b[0] - a[0] * b[2];
  r[2] = a[0] * b[1] - a[1] * b[0];
}
inline bool Finite3(const double* v) {
  return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

// Signed solid angle of the triangle abc seen from q, over 4 pi (Van Oosterom-Strackee); the same
// expression as ExactMesh::WindingNumber, so leaves agree with the brute force to rounding.
inline double TriangleWinding(const double* corners, const double q[3]) {
  double a[3], b[3], c[3];
  for (int k = 0; k < 3; ++k) {
    a[k] = corners[k] - q[k];
    b[k] = corners[3 + k] - q[k];
    c[k] = corners[6 + k] - q[k];
  }
  const double la = std::sqrt(Dot(a, a));
  const double lb = std::sqrt(Dot(b, b));
  const double lc = std::sqrt(Dot(c, c));
  const double det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                     a[2] * (b[0] * c[1] - b[1] * c[0]);
  const double denominator = la * lb * lc + Dot(a, b) * lc + Dot(b, c) * la + Dot(c, a) * lb;
  return 2.0 * std::atan2(det, denominator) * kInverseFourPi;
}

// One BVH node: the Taylor expansion of its triangles' winding number about its area-weighted
// centroid p. With r = p - q, d = |r|, y = x - p for x on a triangle and G' = r / (4 pi d^3):
//   order 0: r . N / (4 pi d^3),                    N = sum a_i n_i          (area vectors)
//   order 1: H(r) : M, H = (I/d^3 - 3 r r^T/d^5)/4pi, M_jk = sum (c_i - p)_j (a_i n_i)_k
//   order 2: 1/2 T(r) : C, C_jkl = sum n_il int_T y_j y_k dA, the triangle second moment being
//            (a/12)(sum_v y_v y_v^T + s s^T), s = sum_v y_v (exact for a triangle).
// Nodes are stored depth first: the left child follows its parent; `right` is the right child.
struct WindingNode {
  double centre[3] = {0, 0, 0};  // area-weighted centroid, metres
  double radius = 0.0;           // max distance from centre to a corner of the node, metres
  double area_vector[3] = {0, 0, 0};
  double first_moment[9] = {};    // M, row-major (j, k)
  double second_moment[18] = {};  // C, symmetric pair (j, k) in xx xy xz yy yz zz order, then l
  uint32_t right = 0;             // right child; 0 for a leaf
  uint32_t first = 0;             // leaf: first triangle (in BVH order)
  uint32_t count = 0;             // leaf: triangle count; 0 for an inner node
};

// Index of the symmetric pair (j, k) in the 6-entry order xx xy xz yy yz zz.
constexpr int kPair[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};

}  // namespace

struct MeshReference::Impl {
  WindingNumberOptions options;
  size_t triangle_count = 0;
  size_t skipped = 0;
  size_t degenerate = 0;

  std::vector<uint32_t> indices;  // the input triples (3 per input triangle), for adjacency

  // Winding-number BVH: corners of its triangles in BVH order (9 doubles each) and their input
  // triangle indices.
  std::vector<double> corners;
  std::vector<uint32_t> bvh_triangle_ids;
  std::vector<WindingNode> nodes;

  // AABB tree over the non-degenerate triangles; tree_triangle_ids maps a position in
  // tree_triangles to the input triangle index. The tree holds iterators into tree_triangles,
  // which Impl owns and never changes after construction (a move moves the Impl pointer only).
  std::vector<Triangle> tree_triangles;
  std::vector<uint32_t> tree_triangle_ids;
  Tree tree;

  void BuildBvh(std::vector<uint32_t>& order, const std::vector<double>& input_corners);
  uint32_t BuildNode(std::vector<uint32_t>& order, uint32_t begin, uint32_t end,
                     const std::vector<double>& centroids);
  void Summarise(WindingNode& node, std::span<const uint32_t> members,
                 const std::vector<double>& input_corners) const;
  double Evaluate(const WindingNode& node, const double q[3]) const;
  double Winding(const double q[3], double beta) const;

  void FaceNormal(uint32_t tree_position, double normal[3]) const;
  bool ShareVertex(uint32_t a, uint32_t b) const {
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        if (indices[3 * size_t{a} + i] == indices[3 * size_t{b} + j]) return true;
      }
    }
    return false;
  }
  struct RawHit {
    double t;
    double point[3];
    uint32_t tree_position;
  };
  void SegmentHits(const double p0[3], const double p1[3], std::vector<RawHit>* hits) const;
};

void MeshReference::Impl::Summarise(WindingNode& node, std::span<const uint32_t> members,
                                    const std::vector<double>& input_corners) const {
  // Area-weighted centroid (the mean of the corners if every triangle is tiny enough to underflow).
  double area_sum = 0.0, weighted[3] = {0, 0, 0}, plain[3] = {0, 0, 0};
  for (uint32_t m : members) {
    const double* v = &input_corners[9 * size_t{m}];
    double e1[3], e2[3], n[3];
    for (int k = 0; k < 3; ++k) e1[k] = v[3 + k] - v[k], e2[k] = v[6 + k] - v[k];
    Cross(e1, e2, n);
    const double area = 0.5 * std::sqrt(Dot(n, n));
    area_sum += area;
    for (int k = 0; k < 3; ++k) {
      const double centroid = (v[k] + v[3 + k] + v[6 + k]) / 3.0;
      weighted[k] += area * centroid;
      plain[k] += centroid;
    }
  }
  for (int k = 0; k < 3; ++k) {
    node.centre[k] =
        area_sum > 0.0 ? weighted[k] / area_sum : plain[k] / static_cast<double>(members.size());
  }
  double radius_squared = 0.0;
  for (uint32_t m : members) {
    const double* v = &input_corners[9 * size_t{m}];
    double y[3][3], s[3] = {0, 0, 0}, e1[3], e2[3], area_vector[3];
    for (int c = 0; c < 3; ++c) {
      for (int k = 0; k < 3; ++k) y[c][k] = v[3 * c + k] - node.centre[k], s[k] += y[c][k];
      radius_squared = std::max(radius_squared, Dot(y[c], y[c]));
    }
    for (int k = 0; k < 3; ++k) e1[k] = v[3 + k] - v[k], e2[k] = v[6 + k] - v[k];
    Cross(e1, e2, area_vector);
    for (int k = 0; k < 3; ++k) area_vector[k] *= 0.5;  // a_i n_i
    for (int k = 0; k < 3; ++k) node.area_vector[k] += area_vector[k];
    // M_jk += (c_i - p)_j (a n)_k, c_i - p = s / 3.
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 3; ++k) node.first_moment[3 * j + k] += s[j] / 3.0 * area_vector[k];
    }
    // C_jkl += (1/12)(sum_v y_vj y_vk + s_j s_k) (a n)_l: the a of the second moment times the
    // unit normal n_l is the area vector.
    for (int j = 0; j < 3; ++j) {
      for (int k = j; k < 3; ++k) {
        const double moment =
            (y[0][j] * y[0][k] + y[1][j] * y[1][k] + y[2][j] * y[2][k] + s[j] * s[k]) / 12.0;
        for (int l = 0; l < 3; ++l)
          node.second_moment[3 * kPair[j][k] + l] += moment * area_vector[l];
      }
    }
  }
  node.radius = std::sqrt(radius_squared);
}

uint32_t MeshReference::Impl::BuildNode(std::vector<uint32_t>& order, uint32_t begin, uint32_t end,
                                        const std::vector<double>& centroids) {
  const uint32_t index = static_cast<uint32_t>(nodes.size());
  nodes.emplace_back();
  if (end - begin <= options.leaf_size) {
    nodes[index].first = begin;
    nodes[index].count = end - begin;
    return index;
  }
  // Median split along the longest axis of the centroids' bounding box.
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (uint32_t i = begin; i < end; ++i) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], centroids[3 * size_t{order[i]} + k]);
      hi[k] = std::max(hi[k], centroids[3 * size_t{order[i]} + k]);
    }
  }
  int axis = 0;
  for (int k = 1; k < 3; ++k) {
    if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
  }
  const uint32_t middle = begin + (end - begin) / 2;
  // Ties are broken by triangle index so the tree does not depend on the library's nth_element.
  std::nth_element(order.begin() + begin, order.begin() + middle, order.begin() + end,
                   [&](uint32_t a, uint32_t b) {
                     const double ca = centroids[3 * size_t{a} + axis];
                     const double cb = centroids[3 * size_t{b} + axis];
                     return ca < cb || (ca == cb && a < b);
                   });
  BuildNode(order, begin, middle, centroids);  // the left child is index + 1
  const uint32_t right = BuildNode(order, middle, end, centroids);
  nodes[index].right = right;
  return index;
}

void MeshReference::Impl::BuildBvh(std::vector<uint32_t>& order,
                                   const std::vector<double>& input_corners) {
  if (order.empty()) return;
  std::vector<double> centroids(input_corners.size() / 3);
  for (size_t t = 0; t < centroids.size() / 3; ++t) {
    for (int k = 0; k < 3; ++k) {
      centroids[3 * t + k] =
          (input_corners[9 * t + k] + input_corners[9 * t + 3 + k] + input_corners[9 * t + 6 + k]) /
          3.0;
    }
  }
  // `order` holds positions into input_corners; BuildNode permutes it into BVH order.
  BuildNode(order, 0, static_cast<uint32_t>(order.size()), centroids);
  // Moments: each node from its own triangles (O(n log n) in all; exact sums, no re-centring).
  // Inner nodes cover a contiguous range of `order`: [first triangle of leftmost leaf, last of
  // rightmost leaf], found by walking the depth-first layout backwards.
  std::vector<std::pair<uint32_t, uint32_t>> range(nodes.size());
  for (size_t n = nodes.size(); n-- > 0;) {
    const WindingNode& node = nodes[n];
    if (node.count > 0) {
      range[n] = {node.first, node.first + node.count};
    } else {
      range[n] = {range[n + 1].first, range[node.right].second};
    }
  }
  for (size_t n = 0; n < nodes.size(); ++n) {
    Summarise(
        nodes[n],
        std::span<const uint32_t>(order).subspan(range[n].first, range[n].second - range[n].first),
        input_corners);
  }
  corners.resize(order.size() * 9);
  for (size_t i = 0; i < order.size(); ++i) {
    std::copy_n(&input_corners[9 * size_t{order[i]}], 9, &corners[9 * i]);
  }
}

double MeshReference::Impl::Evaluate(const WindingNode& node, const double q[3]) const {
  const double r[3] = {node.centre[0] - q[0], node.centre[1] - q[1], node.centre[2] - q[2]};
  const double d2 = Dot(r, r);
  const double inverse_d2 = 1.0 / d2;
  const double inverse_d3 = inverse_d2 / std::sqrt(d2);
  const double inverse_d5 = inverse_d3 * inverse_d2;
  double w = Dot(r, node.area_vector) * inverse_d3;
  if (options.expansion_order >= 1) {
    const double* m = node.first_moment;
    double mr[3];  // M r
    for (int j = 0; j < 3; ++j) mr[j] = m[3 * j] * r[0] + m[3 * j + 1] * r[1] + m[3 * j + 2] * r[2];
    w += (m[0] + m[4] + m[8]) * inverse_d3 - 3.0 * Dot(r, mr) * inverse_d5;
  }
  if (options.expansion_order >= 2) {
    // 1/2 sum_jkl T_jkl C_jkl, T = (-3 (d_jk r_l + d_jl r_k + d_kl r_j)/d^5 + 15 r_j r_k
    // r_l/d^7)/4pi = 1/2 (-3 (r . trace + 2 r . u)/d^5 + 15 sum_l r_l (r^T C_l r)/d^7) with trace_l
    // = C_jjl and u_j = sum_k C_jkk.
    const double* c = node.second_moment;
    auto C = [c](int j, int k, int l) { return c[3 * kPair[j][k] + l]; };
    double trace_dot = 0.0, u_dot = 0.0, cubic = 0.0;
    for (int l = 0; l < 3; ++l) {
      trace_dot += r[l] * (C(0, 0, l) + C(1, 1, l) + C(2, 2, l));
      u_dot += r[l] * (C(l, 0, 0) + C(l, 1, 1) + C(l, 2, 2));
      const double quadratic =
          C(0, 0, l) * r[0] * r[0] + C(1, 1, l) * r[1] * r[1] + C(2, 2, l) * r[2] * r[2] +
          2.0 * (C(0, 1, l) * r[0] * r[1] + C(0, 2, l) * r[0] * r[2] + C(1, 2, l) * r[1] * r[2]);
      cubic += r[l] * quadratic;
    }
    w += 0.5 *
         (-3.0 * (trace_dot + 2.0 * u_dot) * inverse_d5 + 15.0 * cubic * inverse_d5 * inverse_d2);
  }
  return w * kInverseFourPi;
}

double MeshReference::Impl::Winding(const double q[3], double beta) const {
  if (!Finite3(q)) return std::numeric_limits<double>::quiet_NaN();
  if (nodes.empty()) return 0.0;
  // Depth first with an explicit stack; median splits keep the depth near log2(n / leaf_size).
  std::array<uint32_t, 128> stack;
  size_t top = 0;
  stack[top++] = 0;
  double sum = 0.0;
  const double beta_squared = beta * beta;
  while (top > 0) {
    const uint32_t index = stack[--top];
    const WindingNode& node = nodes[index];
    double r[3];
    for (int k = 0; k < 3; ++k) r[k] = q[k] - node.centre[k];
    const double d2 = Dot(r, r);
    if (d2 > beta_squared * node.radius * node.radius) {
      sum += Evaluate(node, q);
    } else if (node.count > 0) {
      double leaf = 0.0;
      for (uint32_t t = node.first; t < node.first + node.count; ++t) {
        leaf += TriangleWinding(&corners[9 * size_t{t}], q);
      }
      sum += leaf;
    } else {
      stack[top++] = node.right;
      stack[top++] = index + 1;
    }
  }
  return sum;
}

void MeshReference::Impl::FaceNormal(uint32_t tree_position, double normal[3]) const {
  const Triangle& triangle = tree_triangles[tree_position];
  double e1[3], e2[3];
  for (int k = 0; k < 3; ++k) {
    e1[k] = triangle[1][k] - triangle[0][k];
    e2[k] = triangle[2][k] - triangle[0][k];
  }
  Cross(e1, e2, normal);
  const double length = std::sqrt(Dot(normal, normal));
  for (int k = 0; k < 3; ++k) normal[k] = length > 0.0 ? normal[k] / length : 0.0;
}

void MeshReference::Impl::SegmentHits(const double p0[3], const double p1[3],
                                      std::vector<RawHit>* hits) const {
  hits->clear();
  if (tree_triangles.empty() || !Finite3(p0) || !Finite3(p1)) return;
  const double d[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
  const double length_squared = Dot(d, d);
  if (!(length_squared > 0.0)) return;
  const Segment segment(Point(p0[0], p0[1], p0[2]), Point(p1[0], p1[1], p1[2]));
  std::vector<SegmentIntersection> found;
  tree.all_intersections(segment, std::back_inserter(found));
  auto parameter = [&](const Point& x) {
    const double v[3] = {x.x() - p0[0], x.y() - p0[1], x.z() - p0[2]};
    return std::clamp(Dot(v, d) / length_squared, 0.0, 1.0);
  };
  for (const SegmentIntersection& intersection : found) {
    RawHit hit;
    hit.tree_position = static_cast<uint32_t>(intersection.second - tree_triangles.begin());
    Point x;
    if (const Point* point = boost::get<Point>(&intersection.first)) {
      x = *point;
    } else if (const Segment* overlap = boost::get<Segment>(&intersection.first)) {
      // The segment lies in the triangle's plane: its end nearest p0.
      x = parameter(overlap->source()) <= parameter(overlap->target()) ? overlap->source()
                                                                       : overlap->target();
    } else {
      continue;
    }
    hit.t = parameter(x);
    hit.point[0] = x.x(), hit.point[1] = x.y(), hit.point[2] = x.z();
    hits->push_back(hit);
  }
  // Sorted by t, ties by input triangle index: the order (and so every result) is deterministic.
  std::sort(hits->begin(), hits->end(), [this](const RawHit& a, const RawHit& b) {
    if (a.t != b.t) return a.t < b.t;
    return tree_triangle_ids[a.tree_position] < tree_triangle_ids[b.tree_position];
  });
}

MeshReference::MeshReference(std::span<const Float3> positions, std::span<const uint32_t> triangles,
                             const WindingNumberOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.options = options;
  m.options.beta =
      std::isfinite(options.beta) ? std::max(options.beta, 1.0001) : WindingNumberOptions{}.beta;
  m.options.expansion_order = std::clamp(options.expansion_order, 0, 2);
  m.options.leaf_size = std::max<uint32_t>(options.leaf_size, 1);

  m.triangle_count = triangles.size() / 3;
  m.indices.assign(triangles.begin(), triangles.begin() + 3 * m.triangle_count);
  std::vector<double> bvh_corners;  // 9 per BVH triangle, input order
  std::vector<uint32_t> bvh_order;  // positions into bvh_corners
  for (size_t t = 0; t < m.triangle_count; ++t) {
    double v[9];
    bool valid = true;
    for (int c = 0; c < 3 && valid; ++c) {
      const uint32_t index = triangles[3 * t + c];
      if (index >= positions.size()) {
        valid = false;
        break;
      }
      const Float3 p = positions[index];
      v[3 * c] = p.x, v[3 * c + 1] = p.y, v[3 * c + 2] = p.z;
      valid = Finite3(&v[3 * c]);
    }
    if (!valid) {
      ++m.skipped;
      continue;
    }
    double e1[3], e2[3], n[3];
    for (int k = 0; k < 3; ++k) e1[k] = v[3 + k] - v[k], e2[k] = v[6 + k] - v[k];
    Cross(e1, e2, n);
    const Triangle triangle(Point(v[0], v[1], v[2]), Point(v[3], v[4], v[5]),
                            Point(v[6], v[7], v[8]));
    if ((n[0] == 0.0 && n[1] == 0.0 && n[2] == 0.0) || triangle.is_degenerate()) {
      ++m.degenerate;
      continue;
    }
    bvh_order.push_back(static_cast<uint32_t>(m.bvh_triangle_ids.size()));
    m.bvh_triangle_ids.push_back(static_cast<uint32_t>(t));
    bvh_corners.insert(bvh_corners.end(), v, v + 9);
    m.tree_triangles.push_back(triangle);
    m.tree_triangle_ids.push_back(static_cast<uint32_t>(t));
  }
  m.BuildBvh(bvh_order, bvh_corners);
  std::vector<uint32_t> ids(bvh_order.size());
  for (size_t i = 0; i < bvh_order.size(); ++i) ids[i] = m.bvh_triangle_ids[bvh_order[i]];
  m.bvh_triangle_ids = std::move(ids);

  if (!m.tree_triangles.empty()) {
    m.tree.insert(m.tree_triangles.cbegin(), m.tree_triangles.cend());
    m.tree.build();
    // Built now, not on the first query: queries are then read-only and safe to run in parallel.
    m.tree.accelerate_distance_queries();
  }
}

MeshReference::~MeshReference() = default;
MeshReference::MeshReference(MeshReference&&) noexcept = default;
MeshReference& MeshReference::operator=(MeshReference&&) noexcept = default;

double MeshReference::WindingNumber(const double q[3]) const {
  return impl_->Winding(q, impl_->options.beta);
}

double MeshReference::ExactWindingNumber(const double q[3]) const {
  return impl_->Winding(q, INFINITY);
}

double MeshReference::Distance(const double q[3]) const {
  if (!Finite3(q)) return std::numeric_limits<double>::quiet_NaN();
  if (impl_->tree_triangles.empty()) return INFINITY;
  return std::sqrt(impl_->tree.squared_distance(Point(q[0], q[1], q[2])));
}

double MeshReference::ClosestPoint(const double q[3], double point[3], uint32_t* triangle,
                                   double normal[3]) const {
  const Impl& m = *impl_;
  if (!Finite3(q) || m.tree_triangles.empty()) {
    if (point != nullptr) std::fill_n(point, 3, std::numeric_limits<double>::quiet_NaN());
    if (triangle != nullptr) *triangle = kNoTriangle;
    if (normal != nullptr) std::fill_n(normal, 3, 0.0);
    return Finite3(q) ? INFINITY : std::numeric_limits<double>::quiet_NaN();
  }
  const Point query(q[0], q[1], q[2]);
  const auto [closest, id] = m.tree.closest_point_and_primitive(query);
  const uint32_t position = static_cast<uint32_t>(id - m.tree_triangles.begin());
  if (point != nullptr) point[0] = closest.x(), point[1] = closest.y(), point[2] = closest.z();
  if (triangle != nullptr) *triangle = m.tree_triangle_ids[position];
  if (normal != nullptr) m.FaceNormal(position, normal);
  return std::sqrt(CGAL::squared_distance(query, closest));
}

SurfaceHit MeshReference::FirstCrossing(const double p0[3], const double p1[3]) const {
  SurfaceHit result;
  result.triangle = kNoTriangle;
  std::vector<Impl::RawHit> hits;
  impl_->SegmentHits(p0, p1, &hits);
  if (hits.empty()) return result;
  const Impl::RawHit& first = hits.front();
  result.hit = true;
  result.t = first.t;
  std::copy_n(first.point, 3, result.point);
  impl_->FaceNormal(first.tree_position, result.normal);
  result.triangle = impl_->tree_triangle_ids[first.tree_position];
  return result;
}

void MeshReference::Crossings(const double p0[3], const double p1[3],
                              std::vector<double>* ts) const {
  ts->clear();
  std::vector<Impl::RawHit> hits;
  impl_->SegmentHits(p0, p1, &hits);
  if (hits.empty()) return;
  const double d[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
  auto direction = [&](const Impl::RawHit& hit) {
    double normal[3];
    impl_->FaceNormal(hit.tree_position, normal);
    const double along = Dot(normal, d);
    return along > 0.0 ? 1 : (along < 0.0 ? -1 : 0);
  };
  std::vector<size_t> kept;  // indices into hits
  for (size_t i = 0; i < hits.size(); ++i) {
    const int sign = direction(hits[i]);
    bool duplicate = false;
    for (size_t j = kept.size(); j-- > 0 && !duplicate;) {
      const Impl::RawHit& other = hits[kept[j]];
      if (hits[i].t - other.t > kSameCrossingT) break;
      duplicate = direction(other) == sign &&
                  impl_->ShareVertex(impl_->tree_triangle_ids[hits[i].tree_position],
                                     impl_->tree_triangle_ids[other.tree_position]);
    }
    if (!duplicate) kept.push_back(i);
  }
  ts->reserve(kept.size());
  for (size_t i : kept) ts->push_back(hits[i].t);
}

size_t MeshReference::triangle_count() const { return impl_->triangle_count; }
size_t MeshReference::skipped_triangle_count() const { return impl_->skipped; }
size_t MeshReference::degenerate_triangle_count() const { return impl_->degenerate; }
size_t MeshReference::bvh_node_count() const { return impl_->nodes.size(); }
const WindingNumberOptions& MeshReference::options() const { return impl_->options; }

size_t MeshReference::memory_bytes() const {
  const Impl& m = *impl_;
  const size_t n = m.tree_triangles.size();
  // AABB tree: one primitive (an iterator) per triangle, n - 1 nodes (a bounding box and two
  // pointers), the KD-tree of one reference point and id per triangle (about twice that with its
  // nodes), plus the triangles it refers to.
  const size_t tree_bytes = n * (sizeof(Primitive) + sizeof(Triangle) + sizeof(uint32_t)) +
                            (n > 0 ? n - 1 : 0) * (sizeof(CGAL::Bbox_3) + 2 * sizeof(void*)) +
                            2 * n * (sizeof(Point) + sizeof(TriangleIterator));
  const size_t bvh_bytes = m.nodes.size() * sizeof(WindingNode) +
                           m.corners.size() * sizeof(double) +
                           m.bvh_triangle_ids.size() * sizeof(uint32_t);
  return tree_bytes + bvh_bytes + m.indices.size() * sizeof(uint32_t);
}

}  // namespace drape::bake

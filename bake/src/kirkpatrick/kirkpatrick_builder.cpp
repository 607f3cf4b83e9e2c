#include "drape/bake/kirkpatrick_builder.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "drape/runtime/hull_collider_set.h"
#include "kirkpatrick/planar_geometry.h"

namespace drape::bake {
namespace {

using detail::EdgeKey;
using detail::Fail;
using detail::Orient;
using detail::Point;

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

// Directions tried when no OBB axis gives valid sides, each OBB axis tilted by this angle
// (radians) towards +-each other axis: 12 directions.
constexpr double kTilt = 0.2;
constexpr int kTiltedDirections = 12;

// The projection frame of direction `index`: 0-2 the OBB axes, 3 + k the k-th tilted direction.
void ProjectionFrame(const Obb& obb, int index, Float3* axis, Float3* u, Float3* v) {
  if (index < 3) {
    *axis = obb.axes[index];
    *u = obb.axes[(index + 1) % 3];
    *v = obb.axes[(index + 2) % 3];
  } else {
    const int tilted = index - 3;                        // 0-11
    const int k = tilted / 4;                            // the axis tilted
    const int towards = (k + 1 + (tilted / 2) % 2) % 3;  // one of the two others
    const float sign = tilted % 2 == 0 ? 1.f : -1.f;     // towards its + or - side
    const Float3 a = obb.axes[k], b = obb.axes[towards] * sign;
    *axis = NormalizeOr(
        a * static_cast<float>(std::cos(kTilt)) + b * static_cast<float>(std::sin(kTilt)), a);
    const Float3 other = obb.axes[3 - k - towards];
    *u = NormalizeOr(other - *axis * Dot(other, *axis), other);
    *v = Cross(*axis, *u);
  }
  if (Dot(Cross(*u, *v), *axis) < 0.f) *v = -*v;
}

AxisResult BuildForAxis(const HullColliderData& hull, int axis_index,
                        const KirkpatrickOptions& options) {
  AxisResult r;
  const Obb& obb = hull.obb;
  ProjectionFrame(obb, axis_index, &r.axis, &r.u, &r.v);
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
  // Triangles a few nanometres wide (a simplified hull keeps some where no collapse was
  // admissible) can wind the wrong way once their corners are rounded to float (u, v), and the
  // shadow folds; another direction rounds them differently.
  AxisResult tilted;
  for (int k = 0; chosen < 0 && k < kTiltedDirections; ++k) {
    tilted = BuildForAxis(*hull, 3 + k, options);
    if (tilted.ok) chosen = 3 + k;
  }
  if (chosen < 0) {
    std::string reasons;
    for (int k = 0; k < 3; ++k) reasons += (k ? "; " : "") + results[k].error;
    return Fail("no OBB axis gives a valid projection, nor " + std::to_string(kTiltedDirections) +
                " tilted directions: " + reasons);
  }
  AxisResult& r = chosen < 3 ? results[chosen] : tilted;
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

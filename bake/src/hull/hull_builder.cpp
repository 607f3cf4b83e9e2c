#include "drape/bake/hull_builder.h"

// The recipe of the hull stage (header, steps 1-6); each stage lives in its own file pair.

#include <algorithm>
#include <array>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "drape/runtime/math.h"
#include "hull/convex_hull.h"
#include "hull/coplanar_faces.h"
#include "hull/edge_collapser.h"
#include "hull/growth_reference.h"
#include "hull/hull_checks.h"
#include "hull/hull_inflation.h"
#include "hull/hull_mesh.h"
#include "hull/hull_planes.h"
#include "hull/obb_fit.h"
#include "hull/plane_remover.h"

namespace drape::bake {
namespace {

using namespace detail;
using Clock = std::chrono::steady_clock;

double MillisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

Status Skip(HullStats* stats, std::string reason) {
  if (stats) stats->skip_reason = reason;
  return Status(StatusCode::kInvalidArgument, std::move(reason));
}

Status CheckOptions(const HullOptions& options, const HullColliderData* collider,
                    HullStats* stats) {
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
  return Status::Ok();
}

// 1. Input: finite, distinct (sorted, so the result does not depend on the input order).
Status DistinctInputs(std::span<const Float3> points, uint32_t min_points, HullStats* stats,
                      std::vector<Vec3>* inputs) {
  std::vector<Float3> sorted(points.begin(), points.end());
  for (const Float3& p : sorted) {
    if (!IsFinite(p)) return Skip(stats, "hull: non-finite input point");
  }
  auto less = [](const Float3& a, const Float3& b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  };
  std::sort(sorted.begin(), sorted.end(), less);
  inputs->reserve(sorted.size());
  for (const Float3& p : sorted) {
    const Vec3 v = ToVec3(p);
    if (!inputs->empty() && inputs->back().x == v.x && inputs->back().y == v.y &&
        inputs->back().z == v.z) {
      continue;
    }
    inputs->push_back(v);
  }
  stats->input_points = static_cast<uint32_t>(inputs->size());
  if (inputs->size() < min_points) {
    return Skip(stats, "hull: " + std::to_string(inputs->size()) +
                           " distinct points, fewer than min_points " + std::to_string(min_points));
  }
  return Status::Ok();
}

// Rounding every coordinate to float moves a vertex by <= sqrt(3)/2 ulp: 2 ulps of margin, four
// times more at each further attempt.
double MinkowskiMargin(double max_abs, double delta, int attempt) {
  return 2.0 * FLT_EPSILON * (max_abs + 2.0 * delta) * std::pow(4.0, attempt);
}

// The simplified hull and, after plane removal, the planes its faces lie on.
struct SimplifiedHull {
  Mesh mesh;
  std::vector<Vec3> hint_normals;
  std::vector<double> hint_offsets;
  bool use_hints = false;
};

// 3. Simplification of H0 within the triangle budget and the growth bound.
Status Simplify(const Mesh& h0, const std::vector<uint32_t>& h0_groups, uint32_t h0_group_count,
                const GrowthReference& reference, const HullOptions& options, HullStats* stats,
                SimplifiedHull* out) {
  Mesh& result = out->mesh;
  stats->budget_reached = h0.triangles.size() <= options.max_triangles;
  if (options.simplify == SimplifyMode::kNone || stats->budget_reached) {
    result = h0;
  } else if (options.simplify == SimplifyMode::kEdgeCollapse) {
    for (int pass = 0; pass < 2; ++pass) {
      result = CollapseEdges(h0, reference, options.max_growth, options.max_triangles,
                             /*global_checks=*/pass == 1, stats);
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
    PlaneRemovalResult removal;
    if (!RemovePlanes(h0, h0_groups, h0_group_count, reference, options.max_growth,
                      options.max_triangles, &removal)) {
      result = h0;
      stats->note += "plane removal failed; kept the inflated hull";
    } else {
      result = removal.mesh;
      stats->collapses = removal.dropped;
      out->hint_normals = removal.kept_normals;
      out->hint_offsets = removal.kept_offsets;
      out->use_hints = true;
      // Containment of H0 is by construction up to the margin: confirm it exactly.
      for (const Vec3& p : h0.points) {
        if (!PointBallInside(result, p, 0.0)) {
          result = h0;
          out->use_hints = false;
          stats->note += "plane removal lost containment; kept the inflated hull";
          break;
        }
      }
    }
    stats->budget_reached = result.triangles.size() <= options.max_triangles;
  }
  return Status::Ok();
}

// 4. Self-verification (exact): a closed convex mesh; counts the delta-balls of `inputs` it does
// not contain and measures its growth beyond H0. A convex collider that contains the balls of the
// input hull's vertices contains every input's ball (each input is a convex combination of those
// vertices, and so is its ball of the vertices' balls), so the caller may pass only those.
Status Verify(const Mesh& result, const std::vector<Vec3>& inputs, double delta,
              const GrowthReference& reference, HullStats* stats) {
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
  return Status::Ok();
}

// 5. Planes: the vertices, triangles and runtime planes of the collider.
HullColliderData StorePlanes(const SimplifiedHull& simplified, const std::vector<Vec3>& inputs,
                             double delta, InflationMode inflation, double hint_tolerance,
                             HullStats* stats) {
  const Mesh& result = simplified.mesh;
  const auto planes_start = Clock::now();
  const PlaneGroups groups =
      BuildPlaneGroups(result, simplified.use_hints ? &simplified.hint_normals : nullptr,
                       simplified.use_hints ? &simplified.hint_offsets : nullptr, hint_tolerance);
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
  stats->planes_after = static_cast<uint32_t>(groups.normals.size());
  return out_geometry;
}

// 6. OBB.
void StoreObb(const Mesh& result, const std::vector<Vec3>& inputs, double delta,
              const HullOptions& options, HullColliderData* geometry, HullStats* stats) {
  const auto obb_start = Clock::now();
  const std::array<Vec3, 3> axes = options.obb == ObbMode::kCgalOptimal
                                       ? CgalOptimalAxes(result, options.obb_seed)
                                       : CovarianceAxes(result);
  geometry->obb = FitObb(axes, result, inputs, delta);
  stats->obb_ms = MillisecondsSince(obb_start);
  stats->obb_volume = 8.f * geometry->obb.half_extents.x * geometry->obb.half_extents.y *
                      geometry->obb.half_extents.z;
}

}  // namespace

Status BuildHullGeometry(std::span<const Float3> points, const HullOptions& options,
                         HullColliderData* collider, HullStats* stats_out) {
  const auto start = Clock::now();
  HullStats local_stats;
  HullStats* stats = stats_out ? stats_out : &local_stats;
  *stats = HullStats{};
  if (Status s = CheckOptions(options, collider, stats); !s.ok()) return s;

  std::vector<Vec3> inputs;
  if (Status s = DistinctInputs(points, options.min_points, stats, &inputs); !s.ok()) return s;
  const double delta = options.delta;

  // 2. Inflation, from the input's hull when it is full-dimensional.
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
  // The points whose delta-balls the verification tests: the input hull's vertices suffice for
  // the Minkowski inflation (see Verify; on a 4 541-point bone of a 75k-triangle character the
  // exact test of every input took 3 of the bake's 10 s). The paper's vertex-normal offset reports
  // how many inputs poke out, so it tests them all.
  const std::vector<Vec3>& containment_points =
      inflation == InflationMode::kMinkowskiIcosahedron ? base : inputs;
  double max_abs = 0.0;
  for (const Vec3& p : base) max_abs = std::max(max_abs, MaxAbs(p));

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
    } else if (!InflateMinkowski(base, delta, MinkowskiMargin(max_abs, delta, attempt), &h0)) {
      continue;
    }
    stats->inflate_ms += MillisecondsSince(attempt_inflate);
    stats->hull_triangles_before = static_cast<uint32_t>(h0.triangles.size());
    uint32_t h0_group_count = 0;
    const std::vector<uint32_t> h0_groups = GroupCoplanar(h0, &h0_group_count);
    stats->planes_before = h0_group_count;

    // 3. Simplification.
    const auto simplify_start = Clock::now();
    const GrowthReference reference(h0);
    SimplifiedHull simplified;
    if (Status s = Simplify(h0, h0_groups, h0_group_count, reference, options, stats, &simplified);
        !s.ok()) {
      return s;
    }
    stats->simplify_ms += MillisecondsSince(simplify_start);

    // 4. Self-verification (exact).
    if (Status s = Verify(simplified.mesh, containment_points, delta, reference, stats); !s.ok()) {
      return s;
    }
    if (inflation == InflationMode::kMinkowskiIcosahedron && stats->uncovered_points != 0) {
      continue;  // larger margin
    }
    verified = true;

    // 5. Planes, 6. OBB.
    const double hint_tolerance = 32.0 * FLT_EPSILON * (max_abs + 4.0 * delta + options.max_growth);
    HullColliderData geometry =
        StorePlanes(simplified, inputs, delta, inflation, hint_tolerance, stats);
    StoreObb(simplified.mesh, inputs, delta, options, &geometry, stats);

    collider->vertices = std::move(geometry.vertices);
    collider->triangles = std::move(geometry.triangles);
    collider->triangle_planes = std::move(geometry.triangle_planes);
    collider->planes = std::move(geometry.planes);
    collider->obb = geometry.obb;
    stats->triangles_after = static_cast<uint32_t>(simplified.mesh.triangles.size());
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
  return CountViolations(MeshFromCollider(collider));
}

}  // namespace drape::bake

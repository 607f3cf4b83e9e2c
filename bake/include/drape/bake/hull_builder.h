#pragma once
// Paper B's convex collider geometry of one bone: from the bone's points (collider frame, metres)
// an inflated convex hull, simplified while it stays convex and contains every input point's
// delta-ball, its triangles merged into runtime planes whose float offsets are rounded outward,
// and an OBB. Fills vertices, triangles, triangle_planes, planes and obb of a HullColliderData;
// the caller fills the rest. Deterministic (byte-identical for any input order or thread count).
// The stages, their guarantees and what reading paper B literally gets wrong:
// docs/ALGORITHMS.md §3.

#include <cstdint>
#include <span>
#include <string>

#include "drape/formats/hull_collider_data.h"
#include "drape/formats/status.h"
#include "drape/formats/types.h"

namespace drape::bake {

enum class InflationMode : uint8_t {
  kMinkowskiIcosahedron,  // hull of {v + delta * u_k}: guarantees every input delta-ball inside
  kVertexNormalOffset,    // paper B: hull vertices offset along their normals, re-hulled
};

enum class SimplifyMode : uint8_t {
  kEdgeCollapse,  // paper B's collapse with constrained (LP) placement, exact acceptance test
  kPlaneRemoval,  // drop supporting planes (dual collapse), re-intersect: ablation
  kNone,          // keep the inflated hull
};

enum class ObbMode : uint8_t {
  kCovariance,   // paper B: covariance of the hull surface (area weighted)
  kCgalOptimal,  // CGAL::oriented_bounding_box, seeded with HullOptions::obb_seed
};

struct HullOptions {
  float delta = 0.005f;  // metres, inflation, >= 0 (0 only if the input is full-dimensional)
  InflationMode inflation = InflationMode::kMinkowskiIcosahedron;
  SimplifyMode simplify = SimplifyMode::kEdgeCollapse;
  uint32_t max_triangles = 100;  // stop simplifying at or below this many triangles, >= 4
  float max_growth = 0.005f;     // metres, >= 0: no vertex may end farther than this beyond H0
  ObbMode obb = ObbMode::kCovariance;
  uint32_t obb_seed = 42;   // random seed of CGAL's OBB optimiser (kCgalOptimal)
  uint32_t min_points = 4;  // >= 1: fewer distinct input points -> skip with a reason
};

struct HullStats {
  uint32_t input_points = 0;           // distinct input points
  uint32_t hull_triangles_before = 0;  // triangles of the inflated hull H0
  uint32_t triangles_after = 0;        // triangles of the stored collider
  uint32_t planes_before = 0;          // distinct planes of H0 (coplanar triangles merged)
  uint32_t planes_after = 0;           // stored planes
  float growth_mm = 0.f;    // mm: max distance of a collider vertex beyond H0 (<= max_growth)
  double ms = 0.0;          // wall time of BuildHullGeometry
  std::string skip_reason;  // why the bone was skipped (empty on success)

  // Refinements.
  bool budget_reached = false;    // triangles_after <= max_triangles; false: growth bound or no
                                  // admissible collapse stopped the simplification first
  uint32_t collapses = 0;         // accepted collapses (edge collapse) or dropped planes
  uint32_t rejected = 0;          // LP candidates refused by the exact acceptance test
  uint32_t evaluations = 0;       // candidate placements computed
  uint32_t uncovered_points = 0;  // input delta-balls not inside the triangles (exact);
                                  // always 0 for kMinkowskiIcosahedron
  float containment_deficit_mm = 0.f;  // mm, how far the worst of those pokes out (approximate)
  float obb_volume = 0.f;              // m^3
  double inflate_ms = 0.0, simplify_ms = 0.0, planes_ms = 0.0, obb_ms = 0.0, verify_ms = 0.0;
  std::string note;  // e.g. an inflation fallback
};

// points: the rigid vertices of one bone in the collider frame (metres). On success fills
// collider->vertices, triangles (counter-clockwise seen from outside), triangle_planes, planes
// and obb. Returns kInvalidArgument with the reason (also in stats->skip_reason) when the bone
// must be skipped or an option is out of range; collider is then left unchanged. stats may be null.
Status BuildHullGeometry(std::span<const Float3> points, const HullOptions& options,
                         HullColliderData* collider, HullStats* stats);

// Exact (CGAL predicates and rational arithmetic) on the stored float vertices: every point's
// closed ball of radius `inflate` (metres, >= 0) is inside every triangle's closed half-space.
// For a convex collider that is containment in the polytope.
bool HullContainsPoints(const HullColliderData& collider, std::span<const Float3> points,
                        float inflate);

// Exact, on the stored float vertices: the triangles form a closed, consistently oriented
// 2-manifold of genus 0 without degenerate triangles, and every vertex lies on or below every
// triangle's plane (orient3d), i.e. the mesh bounds a full-dimensional convex polytope.
bool HullIsConvex(const HullColliderData& collider);

// Number of exact orient3d violations (a vertex strictly above a triangle's plane), for reports.
uint32_t CountConvexityViolations(const HullColliderData& collider);

}  // namespace drape::bake

#pragma once
// Paper B (Sun et al. 2009, section 2.2): the convex collider geometry of one bone. From the
// bone's rigid vertices (collider frame, metres) it builds an inflated convex hull, simplifies it
// while keeping it convex and containing, merges coplanar triangles into runtime planes and fits
// an OBB. It fills these fields of drape::HullColliderData (formats/hull_collider_data.h):
// vertices, triangles, triangle_planes, planes, obb. Everything else (joint, bind_frame, the
// projection frame, the Kirkpatrick hierarchies, the map table) is left untouched for the caller.
//
// Pipeline and guarantees (notes/algorithms.md section 2):
//  1. Input: non-finite points are an error; exact duplicates are merged. Fewer than
//     `min_points` distinct points -> a skip Status (the caller covers the bone otherwise).
//  2. Inflation, H0 = the "inflated hull":
//     - kMinkowskiIcosahedron (default): H0 = hull of {x + r * u_k} over the input hull's
//       vertices x and the 12 vertices u_k of a unit-circumradius icosahedron, with r chosen so
//       that the icosahedron's inradius is delta + m. Every coordinate is rounded to float
//       BEFORE hulling, so H0's vertices are exactly the stored values; the small margin
//       m ~ 2 float ulps of the largest coordinate pays for that rounding. Result: the delta-ball
//       of every input point is inside H0, verified with exact predicates. Always full-dimensional,
//       so collinear, coplanar and 1e-13-thin inputs need no special case.
//     - kVertexNormalOffset (paper): hull of the input, each hull vertex moved by delta along
//       its angle-weighted vertex normal (independent of how flat faces are triangulated),
//       hulled again. No containment guarantee for the triangles: HullStats reports how many
//       input delta-balls poke out of them and by how much. The float planes of step 5 support
//       these vertices too (they are not pushed over the balls: planes beyond the vertices would
//       hold points the OBB, the Kirkpatrick hierarchies and the map table know nothing of, and
//       the runtime's OBB rejection would miss them; measured by drape-speed-vs-error). If the
//       input is not full-dimensional there are no normals; the Minkowski inflation is used
//       instead (noted in HullStats::note).
//     delta = 0 is allowed only for full-dimensional input: H0 is then the hull of the input.
//  3. Simplification until triangles <= max_triangles, never moving the surface more than
//     max_growth beyond H0 (Euclidean distance of every final vertex to H0):
//     - kEdgeCollapse (default): greedy edge collapse, least growth first. The new vertex p is
//       placed by a small 3-variable LP (Seidel; minimum added volume) under the constraints that
//       are linear in p (notes section 2.3): the removed vertices u, v below every new fan
//       triangle, every spoke and link edge convex, each kept a few float ulps inside so that p
//       survives rounding to float. The endpoints themselves are tried as well (half-edge
//       collapse, exact in flat regions). Queue key: a lower bound of the growth (max over H0's
//       planes); entries whose neighbourhood changed are re-evaluated lazily when they surface.
//       A collapse is accepted only if exact CGAL orientation predicates on the float-rounded p
//       confirm containment of u and v and convexity of every edge around p, and p's Euclidean
//       distance to H0 is <= max_growth. Local convexity everywhere plus containment of u and v
//       gives, by induction, a convex result containing H0 (re-checked globally in step 4; if
//       that ever failed, the collapse is re-run with global checks per collapse).
//       Most edges of a Minkowski hull admit no placement (ruled and flat regions: convexity and
//       containment together pin p to a plane), so a flat-sided input (a cube) may stop above
//       the budget; budget_reached tells.
//     - kPlaneRemoval (ablation): drop H0's supporting planes one at a time, the one whose
//       exposed cap has the least growth first (Euclidean distance of the cap's new vertices to
//       H0); containment holds by construction. Adjacency is kept in the dual (points
//       n / (d - n.c)), updated locally per drop. The final vertices are plane-triple
//       intersections pushed out by a few ulps, rounded to float and hulled again.
//     - kNone: H0 as is.
//  4. Self-verification (exact, on the stored floats): the result is a closed convex triangle
//     mesh (every vertex on or below every triangle's plane) and, for the Minkowski inflation,
//     contains every input point's delta-ball. Failure is an internal error Status.
//  5. Planes: edge-adjacent triangles that are exactly coplanar (orientation == COPLANAR) share one
//     plane (kPlaneRemoval also merges triangles lying on one kept plane within 32 float epsilons
//     of the coordinate scale, since rounded plane intersections are not exactly coplanar). The
//     unit normal is stored in float; the offset d is then computed over every collider vertex and
//     every input point x with d >= n.x + delta*|n| plus the worst-case rounding error of a float
//     dot product (3 float ulps of sum |n_i x_i|, and of the delta-ball point), rounded up to float
//     and one more float ulp up. So the runtime test fl(dot(n, p)) <= d in float accepts every
//     float point p within delta of an input point, and every collider vertex.
//     (kVertexNormalOffset: over the collider vertices only, see step 2.)
//  6. OBB of the final collider: kCovariance = paper's statistical method, covariance of the hull
//     surface (area weighted, Gottschalk); kCgalOptimal = CGAL::oriented_bounding_box with a fixed
//     seed. Axes orthonormal, right-handed, axes[0] the longest. Half extents cover every collider
//     vertex and every input delta-ball in the runtime's float arithmetic.
//
// Deterministic: same input and options give byte-identical output, independent of the input
// order (points are sorted first) and of the thread count (one bone per thread is safe). CGAL's
// convex_hull_3 output order and its triangulation of coplanar faces depend on memory addresses
// (measured: repeated calls differ), so every hull is canonicalised: vertices sorted by
// coordinates, coplanar faces re-fanned from their smallest vertex, triangles sorted. The CGAL
// OBB gets a fixed seed; the simplifier's queue breaks ties by edge id.

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
  float max_growth = 0.02f;      // metres, >= 0: no vertex may end farther than this beyond H0
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

#pragma once
// The exact reference a collider is measured against: the original mesh, queried in double. The
// bake measures its proxies' fit with it (fit/collider_fit.h); the benchmarks measure every
// collision method against the posed mesh (DESIGN.md "Speed against error").
//
// - Inside/outside is the generalised winding number (character meshes are open and
//   self-overlapping, so a parity ray test is wrong on them), evaluated hierarchically after
//   Barill et al. 2018, "Fast winding numbers for soups and clouds": a BVH over the triangles,
//   each node summarised by a Taylor expansion about its area-weighted centroid; a node with
//   |q - centre| > beta * radius uses its expansion, nearer nodes recurse, leaves sum the exact
//   Van Oosterom-Strackee solid angles. ExactMesh (mesh_queries.h) is the brute-force check.
// - Distance, closest point and crossings along a segment come from CGAL's AABB tree (EPICK kernel,
//   AABB_triangle_primitive), built with its distance-query KD-tree in the constructor, so every
//   const query is a read-only traversal and thread-safe. EPICK's exact predicates make segment
//   queries watertight: a segment through a shared edge or vertex cannot slip between triangles.
//
// Input handling (the constructor never fails and never crashes):
// - A triangle whose index is out of range or whose corner is not finite is skipped by every
//   query and counted in skipped_triangle_count(); trailing indices that do not make a whole
//   triple are ignored.
// - A zero-area triangle (zero cross product in double, or exactly collinear corners) contributes
//   exactly 0 to the winding number, so the BVH leaves it out; the AABB tree skips it too (CGAL's
//   triangle queries require non-degenerate triangles). Counted in degenerate_triangle_count().
//   Unlike ExactMesh::Distance, an isolated zero-area triangle therefore has no distance.
// Triangle indices in results are those of the input (position of the triple in `triangles`).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "drape/formats/types.h"

namespace drape::bake {

inline constexpr uint32_t kNoTriangle = 0xFFFFFFFFu;  // "no triangle" in query results

struct SurfaceHit {
  bool hit = false;
  double t = 1.0;  // segment parameter of the crossing in [0, 1]
  double point[3] = {0, 0, 0};
  double normal[3] = {0, 0, 0};  // unit face normal of the hit triangle (its winding order)
  uint32_t triangle = 0;         // input triangle index; kNoTriangle when !hit
};

struct WindingNumberOptions {
  // A BVH node is summarised by its expansion when |q - centre| > beta * radius. Larger is more
  // accurate and slower; [Limit: > 1] (values <= 1 are raised to 1.0001; non-finite gives the
  // default). Measured max |fast - brute| at expansion order 2, leaf size 4, on 1000 points in the
  // inflated bounding box and 1000 within 1 cm of the surface
  // (bench/gbench/mesh_reference_bench.cpp, BM_WindingSetting) of an icosphere (5120 triangles),
  // the mannequin (7584) and CesiumMan (4672), and the time per query relative to beta = 2:
  //   beta 2: 4.6e-3 .. 6.4e-3 (1x); beta 3: 0.8e-3 .. 1.1e-3 (1.9x); beta 4: 2.1e-4 .. 3.5e-4 (3x)
  // Default 4: the reference stays 3x under 1e-3. Beta 2 (Barill et al.'s choice) suits speed;
  // neither flips Inside() on any point whose exact winding number is farther than 0.1 from 0.5.
  double beta = 4.0;
  // Taylor terms kept: 0 = dipole (sum a_i n_i), 1 = + second order (sum a_i (c_i - p) n_i^T),
  // 2 = + third order (exact triangle second moments times n_i). [Limit: 0..2] Order 2 is 14-75x
  // more accurate than order 0 at beta 2-4 for 1.2-1.4x the time; order 1 alone gains little.
  int expansion_order = 2;
  uint32_t leaf_size = 4;  // triangles per BVH leaf, [Limit: >= 1]; 4 measured 5-15 % faster than 8
};

class MeshReference {
 public:
  // Positions (metres) and triangle index triples of a posed mesh; see the file comment for how
  // invalid and zero-area triangles are handled. Builds the BVH, the AABB tree and its KD-tree.
  MeshReference(std::span<const Float3> positions, std::span<const uint32_t> triangles,
                const WindingNumberOptions& options = {});
  ~MeshReference();  // pimpl: CGAL types stay in the .cpp
  MeshReference(MeshReference&&) noexcept;
  MeshReference& operator=(MeshReference&&) noexcept;
  MeshReference(const MeshReference&) = delete;
  MeshReference& operator=(const MeshReference&) = delete;

  // Generalised winding number at q: about 1 inside a closed outward-wound surface, 0 outside,
  // 2 where two parts overlap; 0 for an empty mesh; NaN for a non-finite q.
  double WindingNumber(const double q[3]) const;
  bool Inside(const double q[3]) const { return WindingNumber(q) > 0.5; }
  // The same sum with every node expanded down to its leaves (exact; for checks).
  double ExactWindingNumber(const double q[3]) const;

  // Unsigned distance to the surface, metres; +inf for an empty mesh, NaN for a non-finite q.
  double Distance(const double q[3]) const;
  // Closest point on the surface, its input triangle and that triangle's unit face normal; returns
  // the distance. Any output pointer may be null. Empty mesh or non-finite q: returns +inf (NaN for
  // a non-finite q), point NaN, triangle kNoTriangle, normal zero.
  double ClosestPoint(const double q[3], double point[3], uint32_t* triangle,
                      double normal[3]) const;

  // First crossing of the segment p0 -> p1 with the surface (smallest t, ties to the smaller
  // triangle index); hit=false if none, or if p0 == p1, or an endpoint is not finite. Uses CGAL's
  // all_intersections with a Segment_3: a segment lying in a triangle's plane comes back as a
  // segment, whose end nearest p0 is taken. t = (x - p0).(p1 - p0) / |p1 - p0|^2 for the
  // intersection point x.
  SurfaceHit FirstCrossing(const double p0[3], const double p1[3]) const;
  // Every crossing parameter t in [0, 1] of the segment, sorted ascending (for thickness along a
  // ray). Clears *ts first. A crossing through a shared edge or vertex is reported by every
  // triangle there; hits within 1e-12 of each other in t, whose triangles share a vertex index and
  // cross in the same direction (sign of normal . (p1 - p0)), count once. A graze of a fold (same
  // t, opposite directions) therefore gives two equal values, keeping entries and exits paired.
  // Neighbours are found by shared vertex index: across an unwelded seam a crossing counts twice.
  void Crossings(const double p0[3], const double p1[3], std::vector<double>* ts) const;

  size_t triangle_count() const;             // input triangles (whole triples)
  size_t skipped_triangle_count() const;     // out-of-range index or non-finite corner
  size_t degenerate_triangle_count() const;  // zero area: winding 0, not in the AABB tree
  size_t bvh_node_count() const;
  size_t memory_bytes() const;  // approximate bytes of the BVH + AABB tree (+ its KD-tree)
  const WindingNumberOptions& options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace drape::bake

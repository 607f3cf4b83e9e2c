#pragma once
// Paper B §2.3: the point-location hierarchies of a convex hull's upper and lower faces
// (Kirkpatrick 1983), flattened into drape/formats/hull_collider_data.h KirkpatrickHierarchy.
//
// Projection. The faces are projected along an OBB axis a onto (u, v) = ((p - obb.center) .
// projection_u, (p - obb.center) . projection_v), computed in float by
// drape/runtime/hull_collider_set.h ProjectHullUv, so the runtime reproduces a vertex's (u, v) bit for
// bit. (projection_u, projection_v, a) is right-handed. A face is "upper" when its plane normal n
// has n.a > tau and its projected triangle is strictly counter-clockwise (exact predicate on the
// stored floats), "lower" when n.a < -tau and it is strictly clockwise (stored reversed, so
// counter-clockwise); the rest (vertical and nearly vertical faces, tau = vertical_tolerance) are
// in neither set: a point over them projects onto the silhouette, which the runtime's tie rule
// resolves towards the interior. Any axis gives a correct test (notes/algorithms.md §3.1);
// ProjectionAxis::kAuto builds all three OBB axes and keeps the one with the fewest node tests
// per location, measured on points sampled uniformly in the OBB (ties: the shortest axis).
//
// Triangulation. Per side, the shadow's boundary (directed edges whose reverse is missing) must
// be one simple cycle. It is enclosed in a triangle whose circumradius is bounding_scale times
// the shadow's radius, and the annulus is filled (each boundary edge joined to the corner with
// the largest dot product against its outward normal, plus corner wedges where the assignment
// changes; notes §3.2). Fill triangles have leaf plane -1. The whole triangulation is verified
// with exact orientation predicates on the stored float coordinates: every triangle strictly
// counter-clockwise, every directed edge used once, and the unmatched edges exactly the three
// sides of the enclosing triangle, which makes it a proper triangulation of that triangle (each
// point not on an edge is covered once: the winding number of the boundary). If a side fails,
// tau is raised tenfold (up to 1e-3) and the side rebuilt.
//
// Hierarchy. Repeatedly remove a greedy independent set of interior vertices of degree <=
// max_removal_degree (lowest degree first, then lowest index; the limit is raised when the set
// would be empty), re-triangulate each star-shaped hole by ear clipping (strictly convex ears
// with no other link vertex in the closed ear; the best-shaped ear first), and give each new
// triangle as children the old triangles of the hole that overlap it with positive area
// (separating-axis test on exact predicates, touching counts as separated). Surviving triangles
// are shared nodes. Nodes are numbered in creation order, leaves (level 0) first, so every
// child's index is below its parent's and the root (the enclosing triangle) is the last node.
// Children are listed largest area first, so a walk usually accepts the first one.
//
// Deterministic (no unordered iteration, a fixed-seed generator for the auto samples), no CGAL.

#include <cstdint>
#include <span>

#include "drape/formats/hull_collider_data.h"
#include "drape/formats/status.h"

namespace drape::bake {

enum class ProjectionAxis : uint8_t {
  kAuto = 0,      // whichever OBB axis measures fewest node tests per location
  kLongest = 1,   // paper B
  kShortest = 2,  // notes/algorithms.md §3.1 (fewer slivers on limbs)
};

struct KirkpatrickOptions {
  ProjectionAxis axis = ProjectionAxis::kAuto;
  uint32_t max_removal_degree = 8;   // vertices of degree <= this are removed first, in [3, 64]
  float bounding_scale = 20.f;       // enclosing triangle circumradius / shadow radius, [2, 1e4]
  float vertical_tolerance = 1e-6f;  // |n.a| <= this: vertical face, in [0, 1e-3]
  uint32_t auto_samples = 1024;      // points sampled in the OBB to rank axes (kAuto), [16, 1e6]
};

struct KirkpatrickSideStats {
  uint32_t faces = 0;           // hull triangles in this side
  uint32_t fill_triangles = 0;  // leaves outside the shadow
  uint32_t boundary_vertices = 0;
  uint32_t nodes = 0;
  uint32_t levels = 0;  // including the leaf level and the root level
  uint32_t max_children = 0;
  double min_face_area = 0.0;  // smallest projected face, (u, v) units squared
};

struct KirkpatrickStats {
  int32_t axis_index = -1;         // the OBB axis used (0..2)
  bool axis_fallback = false;      // the requested longest/shortest axis failed; another was used
  float vertical_tolerance = 0.f;  // tau actually used
  KirkpatrickSideStats upper, lower;
  double mean_tests = 0.0;  // node tests per location, both sides, on the OBB samples
  double axis_mean_tests[3] = {-1.0, -1.0, -1.0};  // per OBB axis; -1 = not built or failed
};

// Fills hull->projection_axis, projection_u, projection_v, upper and lower. Needs vertices,
// triangles (a closed, consistently oriented mesh: every directed edge once with its reverse),
// triangle_planes, planes and an orthonormal obb. On error the hull's hierarchies are cleared and
// the message names the reason (bad indices, open mesh, no axis giving a valid triangulation).
Status BuildKirkpatrick(HullColliderData* hull, const KirkpatrickOptions& options = {},
                        KirkpatrickStats* stats = nullptr);

// The hierarchy of one planar triangulated region: vertices_uv (2 floats each), triangles (3
// indices each, strictly counter-clockwise), labels (per triangle, the leaf_planes value, >= -1).
// The triangles must form a disk whose boundary is one simple cycle; unused vertices are
// dropped. Used by BuildKirkpatrick for each side, and by tests on hand-made triangulations.
Status BuildPlanarHierarchy(std::span<const float> vertices_uv, std::span<const uint32_t> triangles,
                            std::span<const int32_t> labels, const KirkpatrickOptions& options,
                            KirkpatrickHierarchy* out, KirkpatrickSideStats* stats = nullptr);

}  // namespace drape::bake

#pragma once
// Paper B's point-location hierarchies (Kirkpatrick 1983) of a convex hull's upper and lower
// faces, projected along an OBB axis with the runtime's own ProjectHullUv, triangulated into an
// enclosing triangle and verified with exact predicates on the stored floats, flattened into
// KirkpatrickHierarchy (drape/formats/hull_collider_data.h). Deterministic, no CGAL. Projection,
// triangulation, hierarchy and ties: docs/ALGORITHMS.md §4.

#include <cstdint>
#include <span>

#include "drape/formats/hull_collider_data.h"
#include "drape/formats/status.h"

namespace drape::bake {

enum class ProjectionAxis : uint8_t {
  kAuto = 0,      // whichever OBB axis measures fewest node tests per location
  kLongest = 1,   // paper B
  kShortest = 2,  // docs/ALGORITHMS.md §4.1 (fewer slivers on limbs)
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
  // The OBB axis used (0..2), or 3 + k: the k-th of 12 OBB axes tilted by 0.2 rad, tried when
  // no OBB axis gives valid sides.
  int32_t axis_index = -1;
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

#pragma once
// Paper B §2.4: the map sphere / map cylinder of a convex hull collider, the table that lists per
// direction cell every triangle a response ray in that cell can hit (drape/formats/
// hull_collider_data.h MapTableData; the runtime side is drape/runtime/hull_collider_set.h).
//
// Kind. A hull whose longest OBB half extent is at least cylinder_elongation times the middle one
// gets a map cylinder along its longest OBB axis, the others a map sphere (MapTableChoice forces
// one).
//  - Sphere: source S = the OBB centre when it lies inside the hull by at least 1e-4 of the hull's
//    size (else the mean of the hull vertices); polar axis = the longest OBB axis, reference (phi
//    = 0) = the next OBB axis. Cell (row, col) covers theta in [row, row+1) * pi / rows and phi in
//    [col, col+1) * 2 pi / cols, theta from the axis, phi = atan2(d . (axis x reference),
//    d . reference) in [0, 2 pi).
//  - Cylinder: the axis line through the same inside point, clipped to the hull in double and
//    trimmed by source_inset of its length at each end so the ray source is strictly inside;
//    origin = its first end, length = its length. A particle at axial coordinate z uses the source
//    at clamp(z, 0, length); row = floor(clamp(z) / length * rows).
// Conservative lists. A ray of cell (row, col) hits the hull where the hit point itself has the
// cell's angles (sphere: seen from S; cylinder: phi around the axis and, for interior rows, the
// cell's z range; the first and last rows also take the rays from the end sources, whose hits lie
// beyond the ends). So a triangle is listed iff it meets the cell's region grown by margin_fraction
// of the cell size (plus 1e-4 rad / 1e-6 of the hull size): the triangle is clipped in double by
// the region's azimuth wedge (split into pieces narrower than pi) and, for the cylinder, by the z
// slab; for the sphere the polar-angle range of the clipped polygon is computed exactly (vertices,
// the great-arc extrema of its edges, and whether the polar rays pierce it) and compared with the
// grown theta range. Deterministic; no CGAL.

#include <cstdint>

#include "drape/formats/hull_collider_data.h"
#include "drape/formats/status.h"

namespace drape::bake {

enum class MapTableChoice : uint8_t { kAuto = 0, kSphere = 1, kCylinder = 2 };

struct MapTableOptions {
  MapTableChoice kind = MapTableChoice::kAuto;
  float cylinder_elongation = 2.f;  // auto: longest / middle OBB half extent >= this, [1, 1000]
  uint32_t sphere_rows = 16;        // theta cells over [0, pi], [1, 1024]
  uint32_t sphere_cols = 32;        // phi cells over [0, 2 pi), [1, 1024]
  uint32_t cylinder_rows = 16;      // z cells over [0, length], [1, 1024]
  uint32_t cylinder_cols = 32;      // phi cells, [1, 1024]
  float margin_fraction = 0.05f;    // each cell grown by this fraction of its size, [0, 1]
  float source_inset = 0.02f;       // cylinder: axis part trimmed at each end, fraction, [0, 0.45]
};

struct MapTableStats {
  MapTableKind kind = MapTableKind::kSphere;
  uint32_t rows = 0, cols = 0;
  uint32_t entries = 0;      // total list length
  uint32_t max_list = 0;     // longest cell list
  uint32_t empty_cells = 0;  // cells listing nothing (a conservative table has none)
  double mean_list = 0.0;
  bool source_at_obb_center = false;
};

// Fills hull->map. Needs vertices, triangles, planes (the hull must contain a point strictly
// inside all of them) and an orthonormal obb. On error hull->map is cleared.
Status BuildMapTable(HullColliderData* hull, const MapTableOptions& options = {},
                     MapTableStats* stats = nullptr);

}  // namespace drape::bake

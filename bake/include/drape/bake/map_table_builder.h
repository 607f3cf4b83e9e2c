#pragma once
// Paper B's map sphere / map cylinder of a convex hull collider: per direction cell, every hull
// triangle a response ray of that cell can hit (MapTableData in drape/formats/
// hull_collider_data.h; the runtime's ray is in drape/runtime/hull_collider_set.h). The lists are
// conservative: a triangle is listed iff it meets the cell's region grown by a margin.
// Deterministic, no CGAL. Kind, source and lists: docs/ALGORITHMS.md §5.

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

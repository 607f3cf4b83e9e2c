#pragma once
// Procedural garment meshes for tests, samples and benchmarks: a rectangular sheet, a skirt (a
// cone frustum or cylinder ring), a cape (a trapezoid) and a sleeve (a tube). Each returns
// positions, triangles and a suggested set of particles to pin or attach (the edge that is held).
// Grids are split into triangles along alternating diagonals, so the springs have no preferred
// shear direction. Setup code: allocates.

#include <cstdint>
#include <vector>

#include "drape/formats/status.h"
#include "drape/formats/types.h"
#include "drape/runtime/cloth.h"

namespace drape {

struct GarmentMesh {
  std::vector<Float3> positions;    // metres
  std::vector<uint32_t> triangles;  // 3 per triangle, counter-clockwise seen from `outside`
  std::vector<uint32_t> held;       // suggested pinned / attached particles, ascending
};

// A width x height rectangle of (columns + 1) x (rows + 1) particles centred on `center`,
// spanning axis_u (columns, width) and axis_v (rows, height). held: the row at +axis_v / 2
// (the top edge when axis_v points up).
struct SheetShape {
  Float3 center;
  Float3 axis_u{1.f, 0.f, 0.f};      // unit
  Float3 axis_v{0.f, 0.f, 1.f};      // unit, perpendicular to axis_u
  float width = 1.f, height = 1.f;   // metres, > 0
  uint32_t columns = 30, rows = 30;  // cells, >= 1
};

// A ring around the vertical (+y) axis through `top_center`: `segments` particles around,
// `rings` + 1 rings from radius top_radius at the top down to bottom_radius at `length` below
// (a cylinder when the radii are equal, a flared skirt when bottom > top). The seam is closed
// (the last column connects to the first). held: the top ring (the waistband).
struct SkirtShape {
  Float3 top_center;
  float top_radius = 0.15f;    // metres, > 0
  float bottom_radius = 0.3f;  // metres, > 0
  float length = 0.5f;         // metres, > 0
  uint32_t segments = 48;      // around, >= 3
  uint32_t rings = 20;         // cells down, >= 1
};

// A trapezoid hanging from a horizontal top edge centred on `top_center`, in the plane z =
// top_center.z spanned by +x and -y: top_width at the top, bottom_width at `length` below. Its
// outside faces -z (the back of a character facing +z). held: the top row (the shoulders).
struct CapeShape {
  Float3 top_center;
  float top_width = 0.4f;            // metres, > 0
  float bottom_width = 0.8f;         // metres, > 0
  float length = 1.f;                // metres, > 0
  uint32_t columns = 20, rows = 30;  // cells, >= 1
};

// A tube of `radius` from `start` along unit `axis` for `length`: `segments` around, `rings` + 1
// rings (closed seam, open ends). held: the ring at `start` (the shoulder seam).
struct SleeveShape {
  Float3 start;
  Float3 axis{1.f, 0.f, 0.f};  // unit
  float radius = 0.06f;        // metres, > 0
  float length = 0.5f;         // metres, > 0
  uint32_t segments = 16;      // >= 3
  uint32_t rings = 20;         // >= 1
};

// Each validates its shape (kInvalidArgument naming the field: non-finite or non-positive
// sizes, counts out of range, more than 2^24 particles, non-unit or parallel axes) and fills
// `mesh` (cleared on error).
Status MakeSheet(const SheetShape& shape, GarmentMesh* mesh);
Status MakeSkirt(const SkirtShape& shape, GarmentMesh* mesh);
Status MakeCape(const CapeShape& shape, GarmentMesh* mesh);
Status MakeSleeve(const SleeveShape& shape, GarmentMesh* mesh);

// The garment as a cloth: its positions and triangles, and its held particles attached to
// `joint` at their current positions, read as the bind-pose asset frame (place the garment in
// the bind pose first). Masses, materials and pins keep the description's defaults.
ClothDescription DescribeAttachedGarment(const GarmentMesh& mesh, int32_t joint);

}  // namespace drape

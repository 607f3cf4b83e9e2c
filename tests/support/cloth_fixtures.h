#pragma once
// Cloths the cloth and solver tests share.

#include <gtest/gtest.h>

#include <cstdint>

#include "drape/runtime/cloth.h"
#include "drape/runtime/garments.h"

namespace drape::test {

// A square sheet of cells x cells quads, `size` metres wide, centred on `center` (held row not
// attached: the caller pins or attaches what it needs).
inline ClothDescription SheetDescription(uint32_t cells, float size, Float3 center) {
  SheetShape shape;
  shape.center = center;
  shape.width = shape.height = size;
  shape.columns = shape.rows = cells;
  GarmentMesh mesh;
  EXPECT_TRUE(MakeSheet(shape, &mesh).ok());
  ClothDescription d;
  d.positions = mesh.positions;
  d.triangles = mesh.triangles;
  return d;
}

}  // namespace drape::test

#pragma once
// A bone's region split into convex pieces that fit the body. One convex hull per bone bridges
// whatever the bone's skin wraps around: the arms and the torso of a body without a skeleton, a
// creature's head and jaw, the air in an armpit. Each piece gets its own hull (with its OBB,
// Kirkpatrick hierarchies and map table), all moving with the bone.

#include <cstdint>
#include <span>
#include <vector>

#include "drape/formats/types.h"

namespace drape::bake {

class MeshReference;

struct ConvexPieceOptions {
  double max_bloat = 0.015;  // metres: a piece whose hull bulges farther out of the body splits
  uint32_t max_pieces = 32;  // per bone, >= 1
};

struct ConvexPiece {
  // Rest-pose points: the piece's region vertices and where the cuts crossed its triangles.
  std::vector<Float3> points;
  double bloat = 0.0;  // metres: how far the convex hull of the points reaches out of the body
};

// `vertices`: the bone's region (indices into rest_positions); `triangles`: the rest-pose mesh's
// triangles (those with all three corners in the region are clipped by the cuts, so the pieces'
// hulls together hold every such triangle). `interior`: rest-pose points inside the body the
// pieces' hulls hold too (along the bone), each going with the side of every cut it lies on.
// `body`: the rest-pose body. When the region's hull bloats beyond max_bloat: its connected parts
// of the mesh (an eye, a fang, a plate: shells no plane cuts out of the part they sit on) are the
// first pieces, those whose joint hull fits joining (and the nearest beyond the budget); then the
// worst piece is cut in two by a plane while it bloats beyond max_bloat and the budget allows,
// and once the budget is spent, a cut is still made when two other pieces can join for it with
// less bloat. Deterministic.
std::vector<ConvexPiece> SplitIntoConvexPieces(std::span<const Float3> rest_positions,
                                               std::span<const uint32_t> triangles,
                                               std::span<const uint32_t> vertices,
                                               std::span<const Float3> interior,
                                               const MeshReference& body,
                                               const ConvexPieceOptions& options);

}  // namespace drape::bake

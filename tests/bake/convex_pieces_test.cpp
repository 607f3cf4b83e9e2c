// A bone's region split into convex pieces (regions/convex_pieces.h) on bodies made of separate
// shells: an eye on a head, a part the head's hull holds, more parts than the budget.
#include "regions/convex_pieces.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <vector>

#include "drape/bake/mesh_reference.h"
#include "hull_fixtures.h"

namespace drape {
namespace {

struct Ball {
  Float3 centre;
  float radius;  // metres
};

struct ConvexPieceResult {
  bake::ConvexPiece piece;
  std::set<size_t> balls;  // the shells its points lie on
};

// Closed icospheres, one shell each (no shared vertex), wound outward.
struct Shells {
  std::vector<Float3> positions;
  std::vector<uint32_t> triangles;
  std::vector<Ball> balls;

  void Add(Ball ball, int levels = 2) {
    const Float3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const HullColliderData sphere =
        test::MakeEllipsoid({ball.radius, ball.radius, ball.radius}, levels, ball.centre, axes);
    const uint32_t base = static_cast<uint32_t>(positions.size());
    positions.insert(positions.end(), sphere.vertices.begin(), sphere.vertices.end());
    for (uint32_t index : sphere.triangles) triangles.push_back(base + index);
    balls.push_back(ball);
  }

  std::vector<ConvexPieceResult> Split(uint32_t max_pieces = 8) const {
    std::vector<uint32_t> region(positions.size());
    for (uint32_t v = 0; v < region.size(); ++v) region[v] = v;
    const bake::MeshReference body(positions, triangles);
    bake::ConvexPieceOptions options;
    options.max_pieces = max_pieces;
    std::vector<ConvexPieceResult> out;
    for (bake::ConvexPiece& piece :
         bake::SplitIntoConvexPieces(positions, triangles, region, {}, body, options)) {
      std::set<size_t> on;
      for (const Float3& p : piece.points) on.insert(BallOf(p));
      out.push_back({std::move(piece), std::move(on)});
    }
    return out;
  }

  // The shell a point of a piece lies on (a vertex of it: the pieces here are whole shells).
  size_t BallOf(Float3 p) const {
    for (size_t k = 0; k < balls.size(); ++k) {
      if (std::fabs(Length(p - balls[k].centre) - balls[k].radius) < 1e-4f) return k;
    }
    return balls.size();
  }
};

constexpr double kMaxBloat = bake::ConvexPieceOptions{}.max_bloat;

bool EveryVertexIsInAPiece(const Shells& body, const std::vector<ConvexPieceResult>& pieces) {
  for (const Float3& v : body.positions) {
    bool found = false;
    for (const ConvexPieceResult& p : pieces) {
      for (const Float3& q : p.piece.points)
        found = found || (q.x == v.x && q.y == v.y && q.z == v.z);
    }
    if (!found) return false;
  }
  return true;
}

TEST(ConvexPieces, AnEyeOnAHeadIsAPieceOfItsOwn) {
  // Two eyes half out of a head: the head's hull with them bridges the air around and between
  // them, and no plane cuts an eye out of the head without cutting the head.
  Shells body;
  body.Add({{0, 0, 0}, 0.10f});
  body.Add({{0.12f, 0, 0}, 0.03f});
  body.Add({{0, 0.12f, 0}, 0.03f});
  const std::vector<ConvexPieceResult> pieces = body.Split();
  ASSERT_EQ(pieces.size(), 3u);
  std::set<size_t> seen;
  for (const ConvexPieceResult& p : pieces) {
    ASSERT_EQ(p.balls.size(), 1u) << "a piece holds points of one shell only";
    seen.insert(*p.balls.begin());
    EXPECT_LE(p.piece.bloat, kMaxBloat);
  }
  EXPECT_EQ(seen, (std::set<size_t>{0, 1, 2}));
}

TEST(ConvexPieces, APartTheHullOfItsNeighbourHoldsJoinsIt) {
  // A small ball almost inside the head (a tooth in its gum) joins it; the eye does not.
  Shells body;
  body.Add({{0, 0, 0}, 0.10f});
  body.Add({{0.12f, 0, 0}, 0.03f});
  body.Add({{0, -0.09f, 0}, 0.02f});
  const std::vector<ConvexPieceResult> pieces = body.Split();
  ASSERT_EQ(pieces.size(), 2u);
  const std::set<size_t> head_and_tooth{0, 2}, eye{1};
  EXPECT_TRUE((pieces[0].balls == head_and_tooth && pieces[1].balls == eye) ||
              (pieces[0].balls == eye && pieces[1].balls == head_and_tooth));
  for (const ConvexPieceResult& p : pieces) EXPECT_LE(p.piece.bloat, kMaxBloat);
}

TEST(ConvexPieces, BeyondTheBudgetTheNearestPartsJoin) {
  // Four balls in two pairs 1 cm apart, the pairs 28 cm apart; a budget of two pieces.
  Shells body;
  for (float x : {0.f, 0.11f, 0.50f, 0.61f}) body.Add({{x, 0, 0}, 0.05f});
  const std::vector<ConvexPieceResult> pieces = body.Split(2);
  ASSERT_EQ(pieces.size(), 2u);
  const std::set<size_t> left{0, 1}, right{2, 3};
  EXPECT_TRUE((pieces[0].balls == left && pieces[1].balls == right) ||
              (pieces[0].balls == right && pieces[1].balls == left));
}

TEST(ConvexPieces, ManySmallShellsStayWithinTheBudget) {
  // 400 small shells over a metre (chain mail, scales): grouped along the longest side, then
  // joined within the budget (pair by pair, 400 parts would weigh 80 000 joins).
  Shells body;
  for (int i = 0; i < 400; ++i) {
    const float x = static_cast<float>(i % 20) * 0.05f, y = static_cast<float>(i / 20) * 0.03f;
    body.Add({{x, y, 0.f}, 0.01f}, 0);
  }
  const std::vector<ConvexPieceResult> pieces = body.Split(8);
  EXPECT_LE(pieces.size(), 8u);
  EXPECT_TRUE(EveryVertexIsInAPiece(body, pieces));
}

TEST(ConvexPieces, AFlatPartJoinsASolidOrIsCutAwayAsOne) {
  // A ball and a lone triangle 2-4 cm beside it (a card of hair): three points make no hull, so
  // the triangle first goes with the ball rather than become a piece no collider can be built
  // from; their joint hull bridges the gap, so a cut then takes the triangle away with a point
  // under it, a solid of its own.
  Shells body;
  body.Add({{0, 0, 0}, 0.10f});
  body.Add({{0.25f, 0, 0}, 0.05f});
  const uint32_t base = static_cast<uint32_t>(body.positions.size());
  body.positions.insert(body.positions.end(),
                        {{0.12f, 0.f, 0.f}, {0.14f, 0.f, 0.f}, {0.13f, 0.f, 0.02f}});
  body.triangles.insert(body.triangles.end(), {base, base + 1, base + 2});
  const std::vector<ConvexPieceResult> pieces = body.Split();
  for (const ConvexPieceResult& p : pieces) {
    EXPECT_GE(p.piece.points.size(), 4u);
    EXPECT_LE(p.piece.bloat, kMaxBloat);
  }
  // Each ball whole and the card alone (a cut could not take the card while a side needed four
  // points: the large ball went into six pieces around it, one 14 mm out of the body).
  ASSERT_EQ(pieces.size(), 3u);
  size_t cards = 0;
  for (const ConvexPieceResult& p : pieces) cards += p.balls == std::set<size_t>{2};
  EXPECT_EQ(cards, 1u);
  EXPECT_TRUE(EveryVertexIsInAPiece(body, pieces));
}

}  // namespace
}  // namespace drape

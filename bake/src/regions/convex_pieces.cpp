#include "regions/convex_pieces.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "drape/bake/mesh_reference.h"
#include "hull/convex_hull.h"
#include "hull/hull_mesh.h"

namespace drape::bake {

namespace {

using detail::Mesh;
using detail::Vec3;

// A piece while splitting: the parts of the region's triangles it holds (whole triangles, or
// the polygons a cut left of one) and loose points (region vertices in none of its triangles).
struct WorkPiece {
  std::vector<std::vector<Vec3>> polygons;
  std::vector<Vec3> loose;
  double bloat = 0.0;
  bool splittable = true;
};

struct Context {
  const MeshReference& body;
};

Vec3 ToVec3(Float3 p) { return {p.x, p.y, p.z}; }

std::vector<Vec3> PiecePoints(const WorkPiece& piece) {
  std::vector<Vec3> out = piece.loose;
  for (const std::vector<Vec3>& polygon : piece.polygons) {
    out.insert(out.end(), polygon.begin(), polygon.end());
  }
  detail::SortUnique(&out);
  return out;
}

bool HullOf(const std::vector<Vec3>& points, Mesh* hull) {
  return points.size() >= 4 && detail::ConvexHull(points, hull);
}

double Volume(const Mesh& hull) {
  double six = 0.0;
  for (const auto& t : hull.triangles) {
    six += Dot(hull.points[t[0]], Cross(hull.points[t[1]], hull.points[t[2]]));
  }
  return six / 6.0;
}

double HullVolume(const std::vector<Vec3>& points) {
  Mesh hull;
  return HullOf(points, &hull) ? Volume(hull) : 0.0;
}

// How far the hull's faces reach out of the body: at each face's centroid and three points
// towards its corners (the corners are body vertices). Stops once beyond `stop_above` (the
// caller has a better choice already).
double Bloat(const Context& c, const std::vector<Vec3>& points, double stop_above = INFINITY) {
  Mesh hull;
  if (!HullOf(points, &hull)) return 0.0;
  constexpr double kWeights[4][3] = {
      {1.0 / 3, 1.0 / 3, 1.0 / 3}, {0.6, 0.2, 0.2}, {0.2, 0.6, 0.2}, {0.2, 0.2, 0.6}};
  double worst = 0.0;
  for (const auto& w : kWeights) {
    for (const auto& t : hull.triangles) {
      const Vec3 p = hull.points[t[0]] * w[0] + hull.points[t[1]] * w[1] + hull.points[t[2]] * w[2];
      const double q[3] = {p.x, p.y, p.z};
      // The distance first: only a sample farther than the worst so far needs the winding number.
      const double distance = c.body.Distance(q);
      if (distance > worst && !c.body.Inside(q)) worst = distance;
      if (worst > stop_above) return worst;
    }
  }
  return worst;
}

// The principal axes of the points (covariance eigenvectors by Jacobi rotations), largest first.
std::array<Vec3, 3> PrincipalAxes(const std::vector<Vec3>& points) {
  Vec3 mean;
  for (const Vec3& p : points) mean = mean + p;
  mean = mean * (1.0 / static_cast<double>(std::max<size_t>(points.size(), 1)));
  double a[3][3] = {};
  for (const Vec3& p : points) {
    const double d[3] = {p.x - mean.x, p.y - mean.y, p.z - mean.z};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) a[i][j] += d[i] * d[j];
  }
  double v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int sweep = 0; sweep < 32; ++sweep) {
    for (int p = 0; p < 2; ++p) {
      for (int q = p + 1; q < 3; ++q) {
        if (std::fabs(a[p][q]) < 1e-30) continue;
        const double theta = 0.5 * std::atan2(2 * a[p][q], a[q][q] - a[p][p]);
        const double cs = std::cos(theta), sn = std::sin(theta);
        for (int k = 0; k < 3; ++k) {  // A <- A J, V <- V J
          const double akp = a[k][p], akq = a[k][q];
          a[k][p] = cs * akp - sn * akq;
          a[k][q] = sn * akp + cs * akq;
          const double vkp = v[k][p], vkq = v[k][q];
          v[k][p] = cs * vkp - sn * vkq;
          v[k][q] = sn * vkp + cs * vkq;
        }
        for (int k = 0; k < 3; ++k) {  // A <- J^T A
          const double apk = a[p][k], aqk = a[q][k];
          a[p][k] = cs * apk - sn * aqk;
          a[q][k] = sn * apk + cs * aqk;
        }
      }
    }
  }
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](int i, int j) { return a[i][i] > a[j][j]; });
  std::array<Vec3, 3> axes;
  for (int i = 0; i < 3; ++i) axes[i] = {v[0][order[i]], v[1][order[i]], v[2][order[i]]};
  return axes;
}

// Candidate cuts per axis: at q / kQuantiles of the piece's extent along it, 0 < q < kQuantiles.
constexpr uint32_t kQuantiles = 8;

// The parts of `polygon` below and above the plane dot(x, axis) = cut (Sutherland-Hodgman); a
// part with fewer than three corners is left empty.
void ClipPolygon(const std::vector<Vec3>& polygon, Vec3 axis, double cut, std::vector<Vec3>* below,
                 std::vector<Vec3>* above) {
  const size_t n = polygon.size();
  for (size_t i = 0; i < n; ++i) {
    const Vec3& p = polygon[i];
    const Vec3& q = polygon[(i + 1) % n];
    const double dp = Dot(p, axis) - cut, dq = Dot(q, axis) - cut;
    (dp < 0.0 ? below : above)->push_back(p);
    if ((dp < 0.0) != (dq < 0.0)) {
      const Vec3 x = p + (q - p) * (dp / (dp - dq));
      below->push_back(x);
      above->push_back(x);
    }
  }
  if (below->size() < 3) below->clear();
  if (above->size() < 3) above->clear();
}

// The two sides of the plane dot(x, axis) = cut: polygons across it are clipped, so the two
// hulls together still hold every triangle of the piece (a low-poly body's triangles can span a
// whole limb; kept whole, they would make each side's hull bridge the cut).
void Cut(const WorkPiece& piece, Vec3 axis, double cut, WorkPiece* below, WorkPiece* above) {
  for (const std::vector<Vec3>& polygon : piece.polygons) {
    std::vector<Vec3> a, b;
    ClipPolygon(polygon, axis, cut, &a, &b);
    if (!a.empty()) below->polygons.push_back(std::move(a));
    if (!b.empty()) above->polygons.push_back(std::move(b));
  }
  for (const Vec3& p : piece.loose) (Dot(p, axis) < cut ? below : above)->loose.push_back(p);
}

// How many of the candidate cuts that leave the least hull volume have their bloat measured.
constexpr size_t kBloatCandidates = 3;

// Cuts the piece in two: of the candidate planes (three principal and three frame axes, seven
// evenly spaced positions each), the few that leave the least hull volume are measured, and the one
// whose worse side bloats least wins (ties: less volume). A cut between two parts removes the air a
// hull bridging them holds; the volume alone can prefer a cut that leaves the deep bridge on
// one side. False when no candidate puts a solid on both sides. Sets both sides' bloat.
bool Split(const Context& c, const WorkPiece& piece, WorkPiece* left, WorkPiece* right) {
  const std::vector<Vec3> points = PiecePoints(piece);
  const std::array<Vec3, 3> principal = PrincipalAxes(points);
  const std::array<Vec3, 6> axes = {principal[0],  principal[1],  principal[2],
                                    Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};
  struct Candidate {
    double volume;
    WorkPiece below, above;
  };
  std::vector<Candidate> candidates;
  for (const Vec3& axis : axes) {
    // Evenly spaced over the piece's extent: quantiles of its elements would crowd where
    // earlier cuts left many small fragments and slice slivers off there.
    double lo = INFINITY, hi = -INFINITY;
    for (const Vec3& p : points) {
      lo = std::min(lo, Dot(p, axis));
      hi = std::max(hi, Dot(p, axis));
    }
    for (uint32_t q = 1; q < kQuantiles; ++q) {
      const double cut = lo + (hi - lo) * q / kQuantiles;
      Candidate candidate;
      Cut(piece, axis, cut, &candidate.below, &candidate.above);
      // Each side must stay a solid (a hull needs four points).
      const std::vector<Vec3> pa = PiecePoints(candidate.below);
      const std::vector<Vec3> pb = PiecePoints(candidate.above);
      if (pa.size() < 4 || pb.size() < 4) continue;
      candidate.volume = HullVolume(pa) + HullVolume(pb);
      candidates.push_back(std::move(candidate));
    }
  }
  if (candidates.empty()) return false;
  // Stable: equal volumes keep the axis and position order (deterministic).
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.volume < b.volume; });
  double best_bloat = INFINITY;
  for (size_t i = 0; i < std::min(kBloatCandidates, candidates.size()); ++i) {
    Candidate& candidate = candidates[i];
    candidate.below.bloat = Bloat(c, PiecePoints(candidate.below), best_bloat);
    if (candidate.below.bloat >= best_bloat) continue;
    candidate.above.bloat = Bloat(c, PiecePoints(candidate.above), best_bloat);
    const double bloat = std::max(candidate.below.bloat, candidate.above.bloat);
    if (bloat < best_bloat) {
      best_bloat = bloat;
      *left = std::move(candidate.below);
      *right = std::move(candidate.above);
    }
  }
  return true;
}

}  // namespace

std::vector<ConvexPiece> SplitIntoConvexPieces(std::span<const Float3> rest_positions,
                                               std::span<const uint32_t> triangles,
                                               std::span<const uint32_t> vertices,
                                               std::span<const Float3> interior,
                                               const MeshReference& body,
                                               const ConvexPieceOptions& options) {
  const Context c{body};
  // The region's whole triangles, and its vertices in none of them.
  std::vector<uint8_t> in_region(rest_positions.size(), 0), in_triangle(rest_positions.size(), 0);
  for (uint32_t v : vertices) in_region[v] = 1;
  WorkPiece whole;
  for (uint32_t t = 0; t + 2 < triangles.size(); t += 3) {
    if (in_region[triangles[t]] && in_region[triangles[t + 1]] && in_region[triangles[t + 2]]) {
      whole.polygons.push_back({ToVec3(rest_positions[triangles[t]]),
                                ToVec3(rest_positions[triangles[t + 1]]),
                                ToVec3(rest_positions[triangles[t + 2]])});
      for (uint32_t k = 0; k < 3; ++k) in_triangle[triangles[t + k]] = 1;
    }
  }
  for (uint32_t v : vertices) {
    if (!in_triangle[v]) whole.loose.push_back(ToVec3(rest_positions[v]));
  }
  for (const Float3& p : interior) whole.loose.push_back(ToVec3(p));
  detail::SortUnique(&whole.loose);
  whole.bloat = Bloat(c, PiecePoints(whole));
  std::vector<WorkPiece> pieces{std::move(whole)};
  while (pieces.size() < std::max<uint32_t>(options.max_pieces, 1)) {
    size_t worst = pieces.size();
    for (size_t i = 0; i < pieces.size(); ++i) {
      if (pieces[i].splittable && pieces[i].bloat > options.max_bloat &&
          (worst == pieces.size() || pieces[i].bloat > pieces[worst].bloat)) {
        worst = i;
      }
    }
    if (worst == pieces.size()) break;
    WorkPiece left, right;
    if (!Split(c, pieces[worst], &left, &right)) {
      pieces[worst].splittable = false;
      continue;
    }
    pieces[worst] = std::move(left);
    pieces.push_back(std::move(right));
  }
  std::vector<ConvexPiece> out;
  for (const WorkPiece& p : pieces) {
    ConvexPiece piece{{}, p.bloat};
    for (const Vec3& x : PiecePoints(p)) {
      piece.points.push_back(
          {static_cast<float>(x.x), static_cast<float>(x.y), static_cast<float>(x.z)});
    }
    out.push_back(std::move(piece));
  }
  return out;
}

}  // namespace drape::bake

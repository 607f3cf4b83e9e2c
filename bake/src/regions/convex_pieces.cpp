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

// A piece while splitting: whole triangles (indices of their first corner in `triangles`) and
// loose vertices (in the region, in none of its triangles).
struct WorkPiece {
  std::vector<uint32_t> triangles;
  std::vector<uint32_t> loose;
  double bloat = 0.0;
  bool splittable = true;
};

struct Context {
  std::span<const Float3> positions;
  std::span<const uint32_t> triangles;
  const MeshReference& body;
};

Vec3 ToVec3(Float3 p) { return {p.x, p.y, p.z}; }

std::vector<uint32_t> PieceVertices(const Context& c, const WorkPiece& piece) {
  std::vector<uint32_t> out = piece.loose;
  for (uint32_t t : piece.triangles) {
    for (uint32_t k = 0; k < 3; ++k) out.push_back(c.triangles[t + k]);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

bool HullOf(const Context& c, const std::vector<uint32_t>& vertices, Mesh* hull) {
  std::vector<Vec3> points;
  points.reserve(vertices.size());
  for (uint32_t v : vertices) points.push_back(ToVec3(c.positions[v]));
  detail::SortUnique(&points);
  return points.size() >= 4 && detail::ConvexHull(points, hull);
}

double Volume(const Mesh& hull) {
  double six = 0.0;
  for (const auto& t : hull.triangles) {
    six += Dot(hull.points[t[0]], Cross(hull.points[t[1]], hull.points[t[2]]));
  }
  return six / 6.0;
}

double HullVolume(const Context& c, const std::vector<uint32_t>& vertices) {
  Mesh hull;
  return HullOf(c, vertices, &hull) ? Volume(hull) : 0.0;
}

// How far the hull's faces reach out of the body: at each face's centroid and three points
// towards its corners (the corners are body vertices).
double Bloat(const Context& c, const std::vector<uint32_t>& vertices) {
  Mesh hull;
  if (!HullOf(c, vertices, &hull)) return 0.0;
  constexpr double kWeights[4][3] = {
      {1.0 / 3, 1.0 / 3, 1.0 / 3}, {0.6, 0.2, 0.2}, {0.2, 0.6, 0.2}, {0.2, 0.2, 0.6}};
  double worst = 0.0;
  for (const auto& t : hull.triangles) {
    for (const auto& w : kWeights) {
      const Vec3 p = hull.points[t[0]] * w[0] + hull.points[t[1]] * w[1] + hull.points[t[2]] * w[2];
      const double q[3] = {p.x, p.y, p.z};
      if (!c.body.Inside(q)) worst = std::max(worst, c.body.Distance(q));
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

// Candidate cuts per principal axis: at q / kQuantiles of the elements' order, 0 < q < kQuantiles.
constexpr uint32_t kQuantiles = 8;

// Cuts the piece in two by the candidate plane that leaves the least hull volume. False when
// no candidate puts something on both sides.
bool Split(const Context& c, const WorkPiece& piece, WorkPiece* left, WorkPiece* right) {
  std::vector<Vec3> points;
  for (uint32_t v : PieceVertices(c, piece)) points.push_back(ToVec3(c.positions[v]));
  const std::array<Vec3, 3> axes = PrincipalAxes(points);
  // Where each element sits: a triangle by its centroid, a loose vertex by itself.
  const auto centroid = [&](uint32_t t) {
    return (ToVec3(c.positions[c.triangles[t]]) + ToVec3(c.positions[c.triangles[t + 1]]) +
            ToVec3(c.positions[c.triangles[t + 2]])) *
           (1.0 / 3.0);
  };
  double best_volume = INFINITY;
  bool found = false;
  for (const Vec3& axis : axes) {
    std::vector<double> keys;
    for (uint32_t t : piece.triangles) keys.push_back(Dot(centroid(t), axis));
    for (uint32_t v : piece.loose) keys.push_back(Dot(ToVec3(c.positions[v]), axis));
    std::vector<double> sorted = keys;
    std::sort(sorted.begin(), sorted.end());
    for (uint32_t q = 1; q < kQuantiles; ++q) {
      const double cut = sorted[sorted.size() * q / kQuantiles];
      WorkPiece a, b;
      size_t k = 0;
      for (uint32_t t : piece.triangles) (keys[k++] < cut ? a : b).triangles.push_back(t);
      for (uint32_t v : piece.loose) (keys[k++] < cut ? a : b).loose.push_back(v);
      // Each side must stay a solid (a hull needs four points).
      const std::vector<uint32_t> va = PieceVertices(c, a), vb = PieceVertices(c, b);
      if (va.size() < 4 || vb.size() < 4) continue;
      const double volume = HullVolume(c, va) + HullVolume(c, vb);
      if (volume < best_volume) {
        best_volume = volume;
        *left = std::move(a);
        *right = std::move(b);
        found = true;
      }
    }
  }
  return found;
}

}  // namespace

std::vector<ConvexPiece> SplitIntoConvexPieces(std::span<const Float3> rest_positions,
                                               std::span<const uint32_t> triangles,
                                               std::span<const uint32_t> vertices,
                                               const MeshReference& body,
                                               const ConvexPieceOptions& options) {
  const Context c{rest_positions, triangles, body};
  // The region's whole triangles, and its vertices in none of them.
  std::vector<uint8_t> in_region(rest_positions.size(), 0), in_triangle(rest_positions.size(), 0);
  for (uint32_t v : vertices) in_region[v] = 1;
  WorkPiece whole;
  for (uint32_t t = 0; t + 2 < triangles.size(); t += 3) {
    if (in_region[triangles[t]] && in_region[triangles[t + 1]] && in_region[triangles[t + 2]]) {
      whole.triangles.push_back(t);
      for (uint32_t k = 0; k < 3; ++k) in_triangle[triangles[t + k]] = 1;
    }
  }
  for (uint32_t v : vertices) {
    if (!in_triangle[v]) whole.loose.push_back(v);
  }
  std::sort(whole.loose.begin(), whole.loose.end());
  whole.loose.erase(std::unique(whole.loose.begin(), whole.loose.end()), whole.loose.end());
  whole.bloat = Bloat(c, PieceVertices(c, whole));
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
    left.bloat = Bloat(c, PieceVertices(c, left));
    right.bloat = Bloat(c, PieceVertices(c, right));
    pieces[worst] = std::move(left);
    pieces.push_back(std::move(right));
  }
  std::vector<ConvexPiece> out;
  for (const WorkPiece& p : pieces) out.push_back({PieceVertices(c, p), p.bloat});
  return out;
}

}  // namespace drape::bake

#include "regions/convex_pieces.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <utility>

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
  Vec3 worst;  // where its hull bulges farthest out of the body (with bloat > 0)
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
// towards its corners (the corners are body vertices); *worst_at (may be null) gets the farthest
// sample. Stops once beyond `stop_above` (the caller has a better choice already).
double Bloat(const Context& c, const std::vector<Vec3>& points, double stop_above = INFINITY,
             Vec3* worst_at = nullptr) {
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
      if (distance > worst && !c.body.Inside(q)) {
        worst = distance;
        if (worst_at != nullptr) *worst_at = p;
      }
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

// Metres a cut may leave a polygon reaching across it (what the hull of the side holding it may
// gain beyond the plane).
constexpr double kCutSnap = 1e-3;

// The two sides of the plane dot(x, axis) = cut: polygons across it are clipped, so the two
// hulls together still hold every triangle of the piece (a low-poly body's triangles can span a
// whole limb; kept whole, they would make each side's hull bridge the cut).
void Cut(const WorkPiece& piece, Vec3 axis, double cut, WorkPiece* below, WorkPiece* above) {
  for (const std::vector<Vec3>& polygon : piece.polygons) {
    double lo = INFINITY, hi = -INFINITY;
    for (const Vec3& p : polygon) {
      lo = std::min(lo, Dot(p, axis) - cut);
      hi = std::max(hi, Dot(p, axis) - cut);
    }
    // A polygon reaching across by less than kCutSnap goes whole to the side that holds the
    // rest of it: clipped, its corner would be a sliver of a triangle that no later cut can
    // separate from the far parts of its piece (a side needs four points), so the piece's hull
    // would keep bridging them.
    if (lo < 0.0 && hi >= 0.0 && std::min(hi, -lo) <= kCutSnap) {
      (hi <= -lo ? below : above)->polygons.push_back(polygon);
      continue;
    }
    std::vector<Vec3> a, b;
    ClipPolygon(polygon, axis, cut, &a, &b);
    if (!a.empty()) below->polygons.push_back(std::move(a));
    if (!b.empty()) above->polygons.push_back(std::move(b));
  }
  for (const Vec3& p : piece.loose) (Dot(p, axis) < cut ? below : above)->loose.push_back(p);
}

// Metres under a lone polygon the point that makes it a solid lies.
constexpr double kSolidDepth = 1e-3;

// A piece of fewer than four points (a cut's sliver of one triangle, which no later cut could
// separate from the far parts of a piece) gets a point kSolidDepth under its largest polygon,
// inside the body (polygons wind counter-clockwise seen from outside), so that it can be a piece
// of its own. False when it has no polygon with an area.
bool MakeSolid(WorkPiece* piece) {
  if (PiecePoints(*piece).size() >= 4) return true;
  Vec3 normal{0, 0, 0}, centre{0, 0, 0};
  double largest = 0.0;
  for (const std::vector<Vec3>& polygon : piece->polygons) {
    Vec3 area{0, 0, 0}, sum{0, 0, 0};
    for (size_t i = 0; i < polygon.size(); ++i) {
      area = area + Cross(polygon[i], polygon[(i + 1) % polygon.size()]);
      sum = sum + polygon[i];
    }
    const double length = std::sqrt(Dot(area, area));
    if (length > largest) {
      largest = length;
      normal = area * (1.0 / length);
      centre = sum * (1.0 / static_cast<double>(polygon.size()));
    }
  }
  if (!(largest > 0.0)) return false;
  // Off the plane of three points that span an area: a fourth.
  piece->loose.push_back(centre - normal * kSolidDepth);
  return true;
}

// How many of the cuts through the middle that leave the least hull volume have their bloat
// measured.
constexpr size_t kBloatCandidates = 3;

// Cuts the piece in two. Candidate planes: across its three principal axes and the frame's three
// axes, through the middle of its extent and through the point where its hull bulges farthest.
// The three through the middle that leave the least hull volume and every one through the bulge
// are measured, and the one whose worse side bloats least wins (ties: less volume). A cut between
// two parts removes the air a hull bridging them holds; a plane through the bulge reaches a bridge
// that planes at fixed positions miss (seven evenly spaced per axis, ranked by volume alone, left
// the deep bridge on one side: measured in docs/ALGORITHMS.md §2.3). False when no candidate puts
// a solid on both sides. Sets both sides' bloat.
bool Split(const Context& c, const WorkPiece& piece, WorkPiece* left, WorkPiece* right) {
  const std::vector<Vec3> points = PiecePoints(piece);
  const std::array<Vec3, 3> principal = PrincipalAxes(points);
  const std::array<Vec3, 6> axes = {principal[0],  principal[1],  principal[2],
                                    Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};
  struct Candidate {
    double volume;
    WorkPiece below, above;
    bool through_bulge;  // always measured
  };
  std::vector<Candidate> candidates;
  const auto add = [&](Vec3 axis, double cut, bool through_bulge) {
    Candidate candidate{0.0, {}, {}, through_bulge};
    Cut(piece, axis, cut, &candidate.below, &candidate.above);
    // Each side must stay a solid (a hull needs four points): a side that is one sliver of a
    // triangle gets a point under it.
    if (!MakeSolid(&candidate.below) || !MakeSolid(&candidate.above)) return;
    const std::vector<Vec3> pa = PiecePoints(candidate.below);
    const std::vector<Vec3> pb = PiecePoints(candidate.above);
    candidate.volume = HullVolume(pa) + HullVolume(pb);
    candidates.push_back(std::move(candidate));
  };
  for (const Vec3& axis : axes) {
    double lo = INFINITY, hi = -INFINITY;
    for (const Vec3& p : points) {
      lo = std::min(lo, Dot(p, axis));
      hi = std::max(hi, Dot(p, axis));
    }
    add(axis, 0.5 * (lo + hi), false);
    if (const double cut = Dot(piece.worst, axis); cut > lo && cut < hi) add(axis, cut, true);
  }
  if (candidates.empty()) return false;
  // Stable: equal volumes keep the axis and position order (deterministic).
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.volume < b.volume; });
  double best_bloat = INFINITY;
  size_t through_middle = 0;
  for (Candidate& candidate : candidates) {
    if (!candidate.through_bulge && through_middle++ >= kBloatCandidates) continue;
    candidate.below.bloat =
        Bloat(c, PiecePoints(candidate.below), best_bloat, &candidate.below.worst);
    if (candidate.below.bloat >= best_bloat) continue;
    candidate.above.bloat =
        Bloat(c, PiecePoints(candidate.above), best_bloat, &candidate.above.worst);
    const double bloat = std::max(candidate.below.bloat, candidate.above.bloat);
    if (bloat < best_bloat) {
      best_bloat = bloat;
      *left = std::move(candidate.below);
      *right = std::move(candidate.above);
    }
  }
  return true;
}

// ---- Connected parts ---------------------------------------------------------------------------

struct Box {
  Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  void Add(Vec3 p) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  void Add(const Box& b) {
    Add(b.lo);
    Add(b.hi);
  }
  double Volume() const {
    return std::max(hi.x - lo.x, 0.0) * std::max(hi.y - lo.y, 0.0) * std::max(hi.z - lo.z, 0.0);
  }
  double Distance(Vec3 p) const {  // 0 inside
    const Vec3 d{std::max({lo.x - p.x, 0.0, p.x - hi.x}), std::max({lo.y - p.y, 0.0, p.y - hi.y}),
                 std::max({lo.z - p.z, 0.0, p.z - hi.z})};
    return Norm(d);
  }
  double Gap(const Box& b) const {  // 0 when they overlap
    const Vec3 d{std::max({lo.x - b.hi.x, 0.0, b.lo.x - hi.x}),
                 std::max({lo.y - b.hi.y, 0.0, b.lo.y - hi.y}),
                 std::max({lo.z - b.hi.z, 0.0, b.lo.z - hi.z})};
    return Norm(d);
  }
};

Box BoxOf(const WorkPiece& piece) {
  Box box;
  for (const Vec3& p : piece.loose) box.Add(p);
  for (const std::vector<Vec3>& polygon : piece.polygons)
    for (const Vec3& p : polygon) box.Add(p);
  return box;
}

void Absorb(WorkPiece* into, WorkPiece&& from) {
  for (std::vector<Vec3>& polygon : from.polygons) into->polygons.push_back(std::move(polygon));
  into->loose.insert(into->loose.end(), from.loose.begin(), from.loose.end());
}

size_t NearestBox(const std::vector<Box>& boxes, Vec3 p, size_t skip) {
  size_t best = boxes.size();
  for (size_t i = 0; i < boxes.size(); ++i) {
    if (i != skip && (best == boxes.size() || boxes[i].Distance(p) < boxes[best].Distance(p))) {
      best = i;
    }
  }
  return best;
}

// The region's whole triangles grouped into the connected parts of the mesh they belong to
// (triangles sharing a vertex; the mesh is welded by position): an eye, a fang, a plate of armour
// modelled as a shell of its own is a piece before any cut, which no plane could cut out of the
// part it sits in. Loose points (region vertices in no whole triangle, points inside the body) go
// with the part of the body triangle nearest them, else the part whose box is nearest. A part too
// small for a hull joins the part whose box is nearest. Parts in order of their first triangle.
std::vector<WorkPiece> ConnectedParts(std::span<const Float3> rest_positions,
                                      std::span<const uint32_t> triangles,
                                      std::span<const uint32_t> vertices,
                                      std::span<const Float3> interior, const MeshReference& body) {
  std::vector<uint8_t> in_region(rest_positions.size(), 0), in_triangle(rest_positions.size(), 0);
  for (uint32_t v : vertices) in_region[v] = 1;
  std::vector<uint32_t> root(rest_positions.size());
  for (uint32_t v = 0; v < root.size(); ++v) root[v] = v;
  const auto find = [&](uint32_t v) {
    while (root[v] != v) v = root[v] = root[root[v]];
    return v;
  };
  std::vector<uint32_t> whole;  // first index of each region triangle
  for (uint32_t t = 0; t + 2 < triangles.size(); t += 3) {
    if (!in_region[triangles[t]] || !in_region[triangles[t + 1]] || !in_region[triangles[t + 2]])
      continue;
    whole.push_back(t);
    for (uint32_t k = 0; k < 3; ++k) in_triangle[triangles[t + k]] = 1;
    const uint32_t a = find(triangles[t]), b = find(triangles[t + 1]), d = find(triangles[t + 2]);
    root[b] = a;
    root[find(d)] = a;
  }
  std::vector<int32_t> part_of_root(rest_positions.size(), -1);
  std::vector<int32_t> triangle_part(triangles.size() / 3, -1);
  std::vector<WorkPiece> parts;
  for (uint32_t t : whole) {
    int32_t& part = part_of_root[find(triangles[t])];
    if (part < 0) {
      part = static_cast<int32_t>(parts.size());
      parts.emplace_back();
    }
    triangle_part[t / 3] = part;
    parts[static_cast<size_t>(part)].polygons.push_back({ToVec3(rest_positions[triangles[t]]),
                                                         ToVec3(rest_positions[triangles[t + 1]]),
                                                         ToVec3(rest_positions[triangles[t + 2]])});
  }
  std::vector<Vec3> loose;
  for (uint32_t v : vertices) {
    if (!in_triangle[v]) loose.push_back(ToVec3(rest_positions[v]));
  }
  for (const Float3& p : interior) loose.push_back(ToVec3(p));
  detail::SortUnique(&loose);
  if (parts.empty()) parts.emplace_back();
  std::vector<Box> boxes;
  for (const WorkPiece& part : parts) boxes.push_back(BoxOf(part));
  for (const Vec3& p : loose) {
    const double q[3] = {p.x, p.y, p.z};
    uint32_t triangle = kNoTriangle;
    body.ClosestPoint(q, nullptr, &triangle, nullptr);
    const int32_t part = triangle < triangle_part.size() ? triangle_part[triangle] : -1;
    const size_t to = part >= 0 ? static_cast<size_t>(part) : NearestBox(boxes, p, boxes.size());
    parts[to].loose.push_back(p);
  }
  // A part too flat or small for a hull (a card of hair, a lone triangle) joins the solid part
  // whose box is nearest; with no solid part, the region is one piece.
  std::vector<WorkPiece> solids, flats;
  std::vector<Box> solid_boxes, flat_boxes;
  for (size_t i = 0; i < parts.size(); ++i) {
    const std::vector<Vec3> points = PiecePoints(parts[i]);
    const bool solid = points.size() >= 4 && HullVolume(points) > 0.0;
    (solid ? solids : flats).push_back(std::move(parts[i]));
    (solid ? solid_boxes : flat_boxes).push_back(boxes[i]);
  }
  if (solids.empty()) {
    WorkPiece one;
    for (WorkPiece& flat : flats) Absorb(&one, std::move(flat));
    return {std::move(one)};
  }
  for (size_t i = 0; i < flats.size(); ++i) {
    const Vec3 centre = (flat_boxes[i].lo + flat_boxes[i].hi) * 0.5;
    Absorb(&solids[NearestBox(solid_boxes, centre, solid_boxes.size())], std::move(flats[i]));
  }
  return solids;
}

// More parts than the joining below can weigh pair by pair (a mesh of many small shells: chain
// mail, scales) become kMaxParts groups of parts consecutive along the longest side of their
// boxes, a cost linear in the parts.
constexpr size_t kMaxParts = 64;

void GroupAlongTheLongestSide(std::vector<WorkPiece>* parts) {
  if (parts->size() <= kMaxParts) return;
  Box all;
  std::vector<Box> boxes;
  for (const WorkPiece& part : *parts) {
    boxes.push_back(BoxOf(part));
    all.Add(boxes.back());
  }
  const Vec3 size = all.hi - all.lo;
  const int axis = size.x >= size.y && size.x >= size.z ? 0 : (size.y >= size.z ? 1 : 2);
  const auto centre = [&](size_t i) {
    const Vec3 c = (boxes[i].lo + boxes[i].hi) * 0.5;
    return axis == 0 ? c.x : (axis == 1 ? c.y : c.z);
  };
  std::vector<size_t> order(parts->size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return centre(a) < centre(b); });
  std::vector<WorkPiece> groups(kMaxParts);
  for (size_t k = 0; k < order.size(); ++k)
    Absorb(&groups[k * kMaxParts / order.size()], std::move((*parts)[order[k]]));
  *parts = std::move(groups);
}

// The pieces of one region while they are joined and cut to fit the body within the budget.
// Joining costs are cached by the pieces' ids (a piece that changes gets a new id).
class PieceSet {
 public:
  // `parts`: with their bloat measured.
  PieceSet(const Context& c, const ConvexPieceOptions& options, std::vector<WorkPiece> parts)
      : c_(c), max_bloat_(options.max_bloat), budget_(std::max<uint32_t>(options.max_pieces, 1)) {
    for (WorkPiece& part : parts) Add(std::move(part));
  }

  // The two pieces whose joint hull bloats least join (of those whose boxes lie within max_bloat
  // of each other) while that hull fits the body (a tooth in its gum, an eye the head's hull
  // holds) or the pieces are more than the budget; beyond the budget with no such pair, the two
  // whose joint box grows least.
  void JoinWhileTheyFit() {
    for (;;) {
      const bool over = pieces_.size() > budget_;
      size_t a = 0, b = 0;
      const double fits = std::nextafter(max_bloat_, INFINITY);
      if (CheapestJoin(over ? INFINITY : fits, pieces_.size(), &a, &b) == INFINITY) {
        if (!over) return;
        LeastBoxGrowth(&a, &b);
      }
      Join(a, b);
    }
  }

  // The piece that bloats most beyond max_bloat is cut in two (Split) while the budget allows;
  // once it is spent, a cut is still made when two other pieces can join for it and both the
  // join and the cut's sides bloat less than that piece (the worst piece only gets better).
  void CutWhileTheyBloat() {
    for (size_t round = 0; round < 4 * budget_; ++round) {
      const size_t worst = Worst();
      if (worst == pieces_.size()) return;
      const double bloat = pieces_[worst].bloat;
      size_t a = 0, b = 0;
      const bool full = pieces_.size() >= budget_;
      if (full && CheapestJoin(bloat, worst, &a, &b) >= bloat) return;
      WorkPiece left, right;
      if (!Split(c_, pieces_[worst], &left, &right) ||
          (full && std::max(left.bloat, right.bloat) >= bloat)) {
        pieces_[worst].splittable = false;
        continue;
      }
      Replace(worst, std::move(left));
      Add(std::move(right));
      if (full) Join(a, b);
    }
  }

  std::vector<WorkPiece> Take() { return std::move(pieces_); }

 private:
  void Add(WorkPiece piece) {
    ids_.push_back(next_id_++);
    boxes_.push_back(BoxOf(piece));
    pieces_.push_back(std::move(piece));
  }
  void Replace(size_t i, WorkPiece piece) {
    ids_[i] = next_id_++;
    boxes_[i] = BoxOf(piece);
    pieces_[i] = std::move(piece);
  }
  void Join(size_t a, size_t b) {
    if (a > b) std::swap(a, b);
    WorkPiece joined = pieces_[a];
    Absorb(&joined, std::move(pieces_[b]));
    joined.bloat = Bloat(c_, PiecePoints(joined), INFINITY, &joined.worst);
    pieces_.erase(pieces_.begin() + static_cast<std::ptrdiff_t>(b));
    ids_.erase(ids_.begin() + static_cast<std::ptrdiff_t>(b));
    boxes_.erase(boxes_.begin() + static_cast<std::ptrdiff_t>(b));
    Replace(a, std::move(joined));
  }

  // The splittable piece that bloats most beyond max_bloat, or pieces_.size().
  size_t Worst() const {
    size_t worst = pieces_.size();
    for (size_t i = 0; i < pieces_.size(); ++i) {
      const WorkPiece& piece = pieces_[i];
      if (piece.splittable && piece.bloat > max_bloat_ &&
          (worst == pieces_.size() || piece.bloat > pieces_[worst].bloat)) {
        worst = i;
      }
    }
    return worst;
  }

  // The least bloat of the joint hull of two pieces other than `skip` whose boxes lie within
  // max_bloat of each other, if below `below` (else `below` or more); sets *a < *b.
  double CheapestJoin(double below, size_t skip, size_t* a, size_t* b) {
    double best = INFINITY;
    for (size_t i = 0; i < pieces_.size(); ++i) {
      for (size_t j = i + 1; j < pieces_.size(); ++j) {
        if (i == skip || j == skip || boxes_[i].Gap(boxes_[j]) > max_bloat_) continue;
        const double cost = JoinCost(i, j, std::min(best, below));
        if (cost < best && cost < below) best = cost, *a = i, *b = j;
      }
    }
    return best;
  }

  // The bloat of the joint hull of pieces i and j, or a bound beyond `above` when it is farther.
  // Cached: a bound is reused while it is beyond what the caller asks about.
  double JoinCost(size_t i, size_t j, double above) {
    const std::pair<uint32_t, uint32_t> key{ids_[i], ids_[j]};
    const auto found = join_cost_.find(key);
    if (found != join_cost_.end() && (found->second.exact || found->second.bloat > above))
      return found->second.bloat;
    WorkPiece joined = pieces_[i];
    Absorb(&joined, WorkPiece(pieces_[j]));
    const double bloat = Bloat(c_, PiecePoints(joined), above);
    join_cost_[key] = {bloat, bloat <= above};
    return bloat;
  }

  void LeastBoxGrowth(size_t* a, size_t* b) const {
    double best = INFINITY;
    for (size_t i = 0; i < pieces_.size(); ++i) {
      for (size_t j = i + 1; j < pieces_.size(); ++j) {
        Box joint = boxes_[i];
        joint.Add(boxes_[j]);
        const double growth = joint.Volume() - boxes_[i].Volume() - boxes_[j].Volume();
        if (growth < best) best = growth, *a = i, *b = j;
      }
    }
  }

  const Context& c_;
  const double max_bloat_;
  const size_t budget_;
  std::vector<WorkPiece> pieces_;
  std::vector<uint32_t> ids_;
  std::vector<Box> boxes_;
  uint32_t next_id_ = 0;
  struct Cost {
    double bloat;
    bool exact;  // else a bound: the joint hull bloats at least this much
  };
  std::map<std::pair<uint32_t, uint32_t>, Cost> join_cost_;
};

}  // namespace

std::vector<ConvexPiece> SplitIntoConvexPieces(std::span<const Float3> rest_positions,
                                               std::span<const uint32_t> triangles,
                                               std::span<const uint32_t> vertices,
                                               std::span<const Float3> interior,
                                               const MeshReference& body,
                                               const ConvexPieceOptions& options) {
  const Context c{body};
  std::vector<WorkPiece> pieces =
      ConnectedParts(rest_positions, triangles, vertices, interior, body);
  // The region as one piece first: parts whose one hull fits stay one.
  WorkPiece whole;
  for (const WorkPiece& part : pieces) Absorb(&whole, WorkPiece(part));
  whole.bloat = Bloat(c, PiecePoints(whole), INFINITY, &whole.worst);
  const bool fits = whole.bloat <= options.max_bloat || options.max_pieces <= 1;
  if (fits || pieces.size() == 1) {
    pieces = {std::move(whole)};
  } else {
    GroupAlongTheLongestSide(&pieces);
    for (WorkPiece& part : pieces) part.bloat = Bloat(c, PiecePoints(part), INFINITY, &part.worst);
  }
  if (!fits) {
    PieceSet set(c, options, std::move(pieces));
    set.JoinWhileTheyFit();
    set.CutWhileTheyBloat();
    pieces = set.Take();
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

#include "drape/bake/map_table_builder.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "drape/runtime/math.h"

namespace drape::bake {
namespace {

constexpr double kPi = 3.14159265358979323846;

Status Fail(const std::string& what) {
  return Status(StatusCode::kInvalidArgument, "map table: " + what);
}

struct V {
  double x = 0, y = 0, z = 0;
};
V operator+(const V& a, const V& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V operator-(const V& a, const V& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V operator*(const V& a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double Dot(const V& a, const V& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V Cross(const V& a, const V& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double Norm(const V& a) { return std::sqrt(Dot(a, a)); }
V ToV(Float3 a) { return {a.x, a.y, a.z}; }

// A convex polygon with at most 3 + (clipping planes) vertices.
struct Polygon {
  std::array<V, 12> p;
  int n = 0;
};
// Keeps the part with a.X + b >= 0 (Sutherland-Hodgman on a convex polygon).
template <typename F>
void Clip(Polygon* poly, F value) {
  Polygon out;
  for (int i = 0; i < poly->n; ++i) {
    const V& a = poly->p[i];
    const V& b = poly->p[(i + 1) % poly->n];
    const double fa = value(a), fb = value(b);
    if (fa >= 0.0) out.p[out.n++] = a;
    if ((fa >= 0.0) != (fb >= 0.0)) out.p[out.n++] = a + (b - a) * (fa / (fa - fb));
  }
  *poly = out;
}

// Smallest distance from the origin to the 2D triangle (X, Y) of a, b, c (0 when inside).
double OriginDistance2d(const V& a, const V& b, const V& c) {
  const V pts[3] = {a, b, c};
  auto cross2 = [](const V& u, const V& v) { return u.x * v.y - u.y * v.x; };
  const double s0 = cross2(b - a, V{} - a), s1 = cross2(c - b, V{} - b),
               s2 = cross2(a - c, V{} - c);
  if ((s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0)) return 0.0;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    const V& p = pts[i];
    const V& q = pts[(i + 1) % 3];
    const double dx = q.x - p.x, dy = q.y - p.y;
    const double len2 = dx * dx + dy * dy;
    double t = len2 > 0.0 ? -(p.x * dx + p.y * dy) / len2 : 0.0;
    t = std::min(1.0, std::max(0.0, t));
    best = std::min(best, std::hypot(p.x + t * dx, p.y + t * dy));
  }
  return best;
}

// Range of polar angle cos(theta) = Z / |x| over a convex polygon seen from the origin, exact up
// to rounding: vertices, the extrema of the great arcs of its edges, and the poles (conservative
// when the polygon passes within `axis_tolerance` of the axis line).
void PolarCosRange(const Polygon& poly, const V& ta, const V& tb, const V& tc,
                   double axis_tolerance, double* cos_min, double* cos_max) {
  double lo = 2.0, hi = -2.0;
  for (int i = 0; i < poly.n; ++i) {
    const double len = Norm(poly.p[i]);
    if (len > 0.0) {
      const double c = poly.p[i].z / len;
      lo = std::min(lo, c);
      hi = std::max(hi, c);
    }
  }
  for (int i = 0; i < poly.n; ++i) {
    const V& p = poly.p[i];
    const V& q = poly.p[(i + 1) % poly.n];
    const V m = Cross(p, q);
    const double mlen = Norm(m);
    if (!(mlen > 1e-300)) continue;
    const V mh = m * (1.0 / mlen);
    const double along = std::sqrt(std::max(0.0, 1.0 - mh.z * mh.z));  // |a_p|
    if (!(along > 1e-15)) continue;
    const V ap = V{-mh.z * mh.x, -mh.z * mh.y, 1.0 - mh.z * mh.z};
    if (Dot(Cross(p, ap), m) >= 0.0 && Dot(Cross(ap, q), m) >= 0.0) hi = std::max(hi, along);
    const V an = ap * -1.0;
    if (Dot(Cross(p, an), m) >= 0.0 && Dot(Cross(an, q), m) >= 0.0) lo = std::min(lo, -along);
  }
  // Poles: if the axis line passes through (or within tolerance of) the original triangle, the
  // polygon (its part in a wedge, which always contains the axis) may reach theta = 0 or pi.
  if (OriginDistance2d(ta, tb, tc) <= axis_tolerance) {
    if (ta.z > 0 || tb.z > 0 || tc.z > 0) hi = 1.0;
    if (ta.z < 0 || tb.z < 0 || tc.z < 0) lo = -1.0;
  }
  *cos_min = lo;
  *cos_max = hi;
}

// Columns (azimuth cells, possibly wrapping) a triangle can reach: all, or [first, first+count).
void AzimuthColumns(const V& a, const V& b, const V& c, uint32_t cols, double margin,
                    double axis_tolerance, uint32_t* first, uint32_t* count) {
  *first = 0;
  *count = cols;
  if (cols == 1 || OriginDistance2d(a, b, c) <= axis_tolerance) return;
  double angle[3] = {std::atan2(a.y, a.x), std::atan2(b.y, b.x), std::atan2(c.y, c.x)};
  for (double& x : angle)
    if (x < 0.0) x += 2.0 * kPi;
  std::sort(angle, angle + 3);
  // The covering arc is the complement of the largest circular gap.
  double gaps[3] = {angle[1] - angle[0], angle[2] - angle[1], angle[0] + 2.0 * kPi - angle[2]};
  int largest = 0;
  for (int i = 1; i < 3; ++i)
    if (gaps[i] > gaps[largest]) largest = i;
  if (gaps[largest] < kPi) return;  // the arc would exceed pi: numerically near the axis
  const double start = angle[(largest + 1) % 3] - margin;
  const double span = 2.0 * kPi - gaps[largest] + 2.0 * margin;
  const double cell = 2.0 * kPi / cols;
  const double first_cell = std::floor(start / cell);
  const double last_cell = std::floor((start + span) / cell);
  const double n = last_cell - first_cell + 1.0;
  if (n >= cols) return;
  const int64_t f = static_cast<int64_t>(first_cell);
  *first = static_cast<uint32_t>(((f % cols) + cols) % cols);
  *count = static_cast<uint32_t>(n);
}

// Clips `poly` to the azimuth range [alpha, beta] (width < pi) around the Z axis.
void ClipWedge(Polygon* poly, double alpha, double beta) {
  const double sa = std::sin(alpha), ca = std::cos(alpha), sb = std::sin(beta), cb = std::cos(beta);
  Clip(poly, [&](const V& p) { return -sa * p.x + ca * p.y; });
  if (poly->n == 0) return;
  Clip(poly, [&](const V& p) { return sb * p.x - cb * p.y; });
}

double MaxPlaneDistance(const HullColliderData& hull, const V& p) {
  double m = -std::numeric_limits<double>::infinity();
  for (const Plane& pl : hull.planes) m = std::max(m, Dot(ToV(pl.normal), p) - pl.offset);
  return m;
}

Status ValidateMapTableInput(const HullColliderData& hull, const MapTableOptions& options) {
  if (!(options.cylinder_elongation >= 1.f && options.cylinder_elongation <= 1000.f))
    return Fail("cylinder_elongation is not in [1, 1000]");
  for (uint32_t n :
       {options.sphere_rows, options.sphere_cols, options.cylinder_rows, options.cylinder_cols})
    if (n < 1 || n > 1024) return Fail("rows and cols must be in [1, 1024]");
  if (!(options.margin_fraction >= 0.f && options.margin_fraction <= 1.f))
    return Fail("margin_fraction is not in [0, 1]");
  if (!(options.source_inset >= 0.f && options.source_inset <= 0.45f))
    return Fail("source_inset is not in [0, 0.45]");
  if (hull.vertices.empty() || hull.triangles.empty() || hull.triangles.size() % 3 != 0 ||
      hull.planes.empty())
    return Fail("the hull has no vertices, triangles or planes");
  for (uint32_t i : hull.triangles)
    if (i >= hull.vertices.size()) return Fail("a triangle index is out of range");
  for (const Float3& v : hull.vertices)
    if (!IsFinite(v)) return Fail("a vertex is not finite");
  for (const Plane& p : hull.planes)
    if (!IsFinite(p.normal) || !std::isfinite(p.offset)) return Fail("a plane is not finite");
  const Obb& obb = hull.obb;
  for (int a = 0; a < 3; ++a)
    if (!IsFinite(obb.axes[a]) || std::fabs(Length(obb.axes[a]) - 1.f) > 1e-3f)
      return Fail("an OBB axis is not unit length");
  if (!IsFinite(obb.center) || !IsFinite(obb.half_extents)) return Fail("the OBB is not finite");
  return Status::Ok();
}

// The hull's proportions: which OBB axis is longest, the larger of the two other half extents,
// and the hull's size (the largest distance of a vertex from the OBB centre, metres).
struct HullShape {
  int longest = 0, second = 1;
  float longest_half = 0.f, middle_half = 0.f;
  double size = 0.0;
};

Status MeasureHull(const HullColliderData& hull, HullShape* shape) {
  const Obb& obb = hull.obb;
  const float h[3] = {obb.half_extents.x, obb.half_extents.y, obb.half_extents.z};
  int longest = 0;
  for (int k = 1; k < 3; ++k)
    if (h[k] > h[longest]) longest = k;
  const int second = (longest + 1) % 3, third = (longest + 2) % 3;
  const float middle = std::max(h[second], h[third]);
  double size = 0.0;
  for (const Float3& v : hull.vertices) size = std::max(size, Norm(ToV(v) - ToV(obb.center)));
  if (!(size > 0.0)) return Fail("the hull has zero size");
  shape->longest = longest;
  shape->second = second;
  shape->longest_half = h[longest];
  shape->middle_half = middle;
  shape->size = size;
  return Status::Ok();
}

// A point strictly inside the hull (by inside_margin): the OBB centre, else the vertex mean.
Status FindInsidePoint(const HullColliderData& hull, double inside_margin, V* inside_point,
                       MapTableStats* stats) {
  V inside = ToV(hull.obb.center);
  stats->source_at_obb_center = true;
  if (!(MaxPlaneDistance(hull, inside) < -inside_margin)) {
    stats->source_at_obb_center = false;
    inside = V{};
    for (const Float3& v : hull.vertices) inside = inside + ToV(v);
    inside = inside * (1.0 / static_cast<double>(hull.vertices.size()));
    if (!(MaxPlaneDistance(hull, inside) < -inside_margin))
      return Fail("neither the OBB centre nor the vertex mean is inside the hull (flat hull?)");
  }
  *inside_point = inside;
  return Status::Ok();
}

// The table's frame: Z along the OBB's longest axis, X its second axis made orthogonal to Z.
struct TableFrame {
  V axis, reference, binormal;
};

TableFrame FrameAlongLongestAxis(const Obb& obb, const HullShape& shape) {
  TableFrame f;
  const V axis = ToV(obb.axes[shape.longest]) * (1.0 / Norm(ToV(obb.axes[shape.longest])));
  V reference = ToV(obb.axes[shape.second]);
  reference = reference - axis * Dot(reference, axis);
  reference = reference * (1.0 / Norm(reference));
  f.axis = axis;
  f.reference = reference;
  f.binormal = Cross(axis, reference);
  return f;
}

// A cylinder's source segment: the axis line through `inside`, clipped to the hull and trimmed by
// source_inset at both ends, with ends that stay strictly inside once stored as floats. Clears
// *cylinder (and puts the origin back at `inside`) when nothing of the segment is left.
Status PlaceCylinderSource(const HullColliderData& hull, const MapTableOptions& options,
                           const V& inside, const V& axis, double inside_margin, bool* cylinder,
                           V* origin_out, double* length_out) {
  double t_lo = -std::numeric_limits<double>::infinity(),
         t_hi = std::numeric_limits<double>::infinity();
  for (const Plane& pl : hull.planes) {
    const V n = ToV(pl.normal);
    const double rate = Dot(n, axis), room = pl.offset - Dot(n, inside);
    if (rate > 0.0) t_hi = std::min(t_hi, room / rate);
    if (rate < 0.0) t_lo = std::max(t_lo, room / rate);
  }
  if (!(std::isfinite(t_lo) && std::isfinite(t_hi) && t_hi > t_lo))
    return Fail("the hull is unbounded along its axis");
  const double span = t_hi - t_lo;
  const double a0 = t_lo + options.source_inset * span, a1 = t_hi - options.source_inset * span;
  V origin = inside + axis * a0;
  double length = std::max(0.0, a1 - a0);
  // The stored (float) ends must be strictly inside; trim further if rounding says otherwise.
  for (int attempt = 0; attempt < 8; ++attempt) {
    const Float3 o{static_cast<float>(origin.x), static_cast<float>(origin.y),
                   static_cast<float>(origin.z)};
    const V end = ToV(o) + axis * static_cast<float>(length);
    if (MaxPlaneDistance(hull, ToV(o)) < -inside_margin &&
        MaxPlaneDistance(hull, end) < -inside_margin)
      break;
    origin = origin + axis * (0.05 * length);
    length *= 0.9;
  }
  if (!(length > 0.0)) *cylinder = false;
  if (!*cylinder) origin = inside;
  *origin_out = origin;
  *length_out = length;
  return Status::Ok();
}

// The cells of the table and how far a triangle may miss one and still be listed in it.
struct CellGrid {
  bool cylinder = false;
  uint32_t rows = 0, cols = 0;
  double col_width = 0.0, phi_margin = 0.0;   // radians
  double row_height = 0.0, row_margin = 0.0;  // metres (cylinder) or radians (sphere)
  double axis_tolerance = 0.0;                // metres
};

CellGrid GridOf(const MapTableData& t, const MapTableOptions& options, bool cylinder, double size) {
  CellGrid g;
  g.cylinder = cylinder;
  const uint32_t rows = t.rows, cols = t.cols;
  g.rows = rows;
  g.cols = cols;
  g.col_width = 2.0 * kPi / cols;
  g.phi_margin = options.margin_fraction * g.col_width + 1e-4;
  g.row_height = cylinder ? t.length / static_cast<double>(rows) : kPi / rows;
  g.row_margin = cylinder ? options.margin_fraction * g.row_height + 1e-6 * size
                          : options.margin_fraction * g.row_height + 1e-4;
  g.axis_tolerance = 1e-7 * size;
  return g;
}

// Triangles in the table frame (X = reference, Y = binormal, Z = axis), relative to the stored
// (float) origin.
std::vector<std::array<V, 3>> TrianglesInTableFrame(const HullColliderData& hull,
                                                    const MapTableData& t,
                                                    const TableFrame& frame) {
  const V o = ToV(t.origin);
  const size_t tri_count = hull.triangles.size() / 3;
  std::vector<std::array<V, 3>> local(tri_count);
  for (size_t i = 0; i < tri_count; ++i)
    for (int c = 0; c < 3; ++c) {
      const V p = ToV(hull.vertices[hull.triangles[3 * i + c]]) - o;
      local[i][c] = {Dot(p, frame.reference), Dot(p, frame.binormal), Dot(p, frame.axis)};
    }
  return local;
}

// Whether triangle (a, b, c) reaches cell (row, col) grown by the margins: its azimuth range
// [alpha, beta] is cut into `pieces` wedges narrower than pi (one piece for a full turn).
bool ReachesCell(const CellGrid& g, const V& a, const V& b, const V& c, uint32_t row, double alpha,
                 double beta, bool full_turn, int pieces) {
  bool hit = false;
  for (int piece = 0; piece < pieces && !hit; ++piece) {
    Polygon poly;
    poly.p[0] = a;
    poly.p[1] = b;
    poly.p[2] = c;
    poly.n = 3;
    if (!full_turn) {
      const double w = (beta - alpha) / pieces;
      ClipWedge(&poly, alpha + piece * w, alpha + (piece + 1) * w);
      if (poly.n == 0) continue;
    }
    if (g.cylinder) {
      // Interior rows: the z slab; the first/last rows extend to the ends' sources.
      if (row > 0) {
        const double lo = row * g.row_height - g.row_margin;
        Clip(&poly, [&](const V& p) { return p.z - lo; });
        if (poly.n == 0) continue;
      }
      if (row + 1 < g.rows) {
        const double hi = (row + 1) * g.row_height + g.row_margin;
        Clip(&poly, [&](const V& p) { return hi - p.z; });
        if (poly.n == 0) continue;
      }
      hit = true;
    } else {
      double cos_min, cos_max;
      PolarCosRange(poly, a, b, c, g.axis_tolerance, &cos_min, &cos_max);
      const double theta_min = std::acos(std::clamp(cos_max, -1.0, 1.0));
      const double theta_max = std::acos(std::clamp(cos_min, -1.0, 1.0));
      hit = theta_max >= row * g.row_height - g.row_margin &&
            theta_min <= (row + 1) * g.row_height + g.row_margin;
    }
  }
  return hit;
}

// Appends triangle i (a, b, c) to the list of every cell it reaches.
void ListTriangle(const CellGrid& g, const V& a, const V& b, const V& c, uint32_t i,
                  std::vector<std::vector<uint32_t>>* lists) {
  const uint32_t rows = g.rows, cols = g.cols;
  uint32_t col_first, col_count;
  AzimuthColumns(a, b, c, cols, g.phi_margin, g.axis_tolerance, &col_first, &col_count);
  // Rows the triangle can reach (a coarse filter before the exact per-cell test).
  uint32_t row_lo = 0, row_hi = rows - 1;
  if (g.cylinder) {
    const double zmin = std::min({a.z, b.z, c.z}) - g.row_margin,
                 zmax = std::max({a.z, b.z, c.z}) + g.row_margin;
    row_lo =
        static_cast<uint32_t>(std::clamp(std::floor(zmin / g.row_height), 0.0, double(rows - 1)));
    row_hi =
        static_cast<uint32_t>(std::clamp(std::floor(zmax / g.row_height), 0.0, double(rows - 1)));
  }
  for (uint32_t k = 0; k < col_count; ++k) {
    const uint32_t col = (col_first + k) % cols;
    // The cell's grown azimuth range, in pieces narrower than pi.
    const double alpha = col * g.col_width - g.phi_margin,
                 beta = (col + 1) * g.col_width + g.phi_margin;
    const bool full_turn = beta - alpha >= 2.0 * kPi;
    const int pieces = full_turn ? 1 : static_cast<int>(std::ceil((beta - alpha) / (0.5 * kPi)));
    for (uint32_t row = row_lo; row <= row_hi; ++row) {
      if (ReachesCell(g, a, b, c, row, alpha, beta, full_turn, pieces))
        (*lists)[static_cast<size_t>(row) * cols + col].push_back(i);
    }
  }
}

// The cell lists into the table's flat arrays, and their statistics.
void FlattenCellLists(const std::vector<std::vector<uint32_t>>& lists, MapTableData* t,
                      MapTableStats* stats) {
  t->cell_offsets.reserve(lists.size() + 1);
  t->cell_offsets.push_back(0);
  for (const auto& list : lists) {
    t->cell_triangles.insert(t->cell_triangles.end(), list.begin(), list.end());
    t->cell_offsets.push_back(static_cast<uint32_t>(t->cell_triangles.size()));
    stats->max_list = std::max(stats->max_list, static_cast<uint32_t>(list.size()));
    if (list.empty()) ++stats->empty_cells;
  }
  stats->kind = t->kind;
  stats->rows = t->rows;
  stats->cols = t->cols;
  stats->entries = static_cast<uint32_t>(t->cell_triangles.size());
  stats->mean_list = static_cast<double>(stats->entries) / static_cast<double>(lists.size());
}

}  // namespace

Status BuildMapTable(HullColliderData* hull, const MapTableOptions& options, MapTableStats* stats) {
  MapTableStats local_stats;
  if (stats == nullptr) stats = &local_stats;
  *stats = MapTableStats{};
  hull->map = MapTableData{};
  if (Status s = ValidateMapTableInput(*hull, options); !s.ok()) return s;

  HullShape shape;
  if (Status s = MeasureHull(*hull, &shape); !s.ok()) return s;
  const double inside_margin = 1e-4 * shape.size;
  V inside;
  if (Status s = FindInsidePoint(*hull, inside_margin, &inside, stats); !s.ok()) return s;

  // The table's shape and source: a cylinder along an elongated hull's axis, else a sphere
  // around the inside point.
  MapTableData& t = hull->map;
  bool cylinder = options.kind == MapTableChoice::kCylinder ||
                  (options.kind == MapTableChoice::kAuto &&
                   shape.longest_half >= options.cylinder_elongation * shape.middle_half);
  const TableFrame frame = FrameAlongLongestAxis(hull->obb, shape);
  V origin = inside;
  double length = 0.0;
  if (cylinder) {
    if (Status s = PlaceCylinderSource(*hull, options, inside, frame.axis, inside_margin, &cylinder,
                                       &origin, &length);
        !s.ok()) {
      return s;
    }
  }
  t.kind = cylinder ? MapTableKind::kCylinder : MapTableKind::kSphere;
  t.rows = cylinder ? options.cylinder_rows : options.sphere_rows;
  t.cols = cylinder ? options.cylinder_cols : options.sphere_cols;
  t.origin = {static_cast<float>(origin.x), static_cast<float>(origin.y),
              static_cast<float>(origin.z)};
  t.axis = {static_cast<float>(frame.axis.x), static_cast<float>(frame.axis.y),
            static_cast<float>(frame.axis.z)};
  t.reference = {static_cast<float>(frame.reference.x), static_cast<float>(frame.reference.y),
                 static_cast<float>(frame.reference.z)};
  t.length = cylinder ? static_cast<float>(length) : 0.f;

  // Each cell lists the triangles it can reach.
  const std::vector<std::array<V, 3>> local = TrianglesInTableFrame(*hull, t, frame);
  const CellGrid grid = GridOf(t, options, cylinder, shape.size);
  std::vector<std::vector<uint32_t>> lists(static_cast<size_t>(grid.rows) * grid.cols);
  for (size_t i = 0; i < local.size(); ++i)
    ListTriangle(grid, local[i][0], local[i][1], local[i][2], static_cast<uint32_t>(i), &lists);
  FlattenCellLists(lists, &t, stats);
  return Status::Ok();
}

}  // namespace drape::bake

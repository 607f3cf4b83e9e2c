#include "body_map/cpu_rasterizer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

namespace drape::bake {
namespace {

constexpr uint32_t kNoFace = std::numeric_limits<uint32_t>::max();
// Triangles whose bounding box is narrower than this many texels are tested texel by texel.
constexpr int64_t kNarrowTriangleTexels = 12;

// One edge of a triangle, evaluated canonically: always from the lower to the higher vertex
// index, so the two triangles sharing an edge compute bit-identical values, and the sign is
// applied afterwards (exact). `top_left` marks the edges that own texel centres lying exactly on
// them (interior to the right of a downward edge, or below a horizontal edge).
struct Edge {
  double ax, ay;      // canonical start vertex, texel units
  double dx, dy;      // canonical end minus start
  double inverse_dy;  // 1 / dy (0 when dy == 0); only for estimating span boundaries
  double sign;        // +1 or -1: makes the value positive inside the triangle
  bool top_left;
  // (dx*(py-ay)) is constant along a row; keep the expression's evaluation order identical for
  // every triangle so that shared edges give exactly negated values.
  double RowTerm(double py) const { return dx * (py - ay); }
  double Value(double row_term, double px) const { return sign * (row_term - dy * (px - ax)); }
  bool Inside(double value) const { return value > 0.0 || (value == 0.0 && top_left); }
};

struct TriangleSetup {
  Edge edge[3];   // edge k is opposite vertex k
  double area2;   // twice the signed area in texel units, != 0
  double x0, y0;  // vertex 0, texel units
  // Barycentrics of vertices 1 and 2 as linear functions of the texel centre (normals pass):
  // lambda_k = lk_x * (px - x0) + lk_y * (py - y0).
  double l1_x, l1_y, l2_x, l2_y;
};

// The three edges of a triangle; false for zero area in the window (it covers no texel).
bool SetUpEdges(const MapRasterInput& in, const uint32_t v[3], TriangleSetup* setup) {
  const double x0 = in.window_x[v[0]], y0 = in.window_y[v[0]];
  const double x1 = in.window_x[v[1]], y1 = in.window_y[v[1]];
  const double x2 = in.window_x[v[2]], y2 = in.window_y[v[2]];
  const double area2 = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0);
  if (!(area2 != 0.0)) return false;
  const double orientation = area2 > 0.0 ? 1.0 : -1.0;
  for (int k = 0; k < 3; ++k) {
    // Oriented edge v[k+1] -> v[k+2]: for a counter-clockwise triangle the interior is on its left.
    uint32_t from = v[(k + 1) % 3], to = v[(k + 2) % 3];
    double sign = orientation;
    if (from > to) {
      std::swap(from, to);
      sign = -sign;
    }
    Edge& e = setup->edge[k];
    e.ax = in.window_x[from];
    e.ay = in.window_y[from];
    e.dx = in.window_x[to] - e.ax;
    e.dy = in.window_y[to] - e.ay;
    e.inverse_dy = 0.0;  // filled by PrepareSpans() when the triangle uses spans
    e.sign = sign;
    // Direction of the edge with the interior on its left.
    const double dir_x = sign * e.dx, dir_y = sign * e.dy;
    e.top_left = dir_y < 0.0 || (dir_y == 0.0 && dir_x < 0.0);
  }
  setup->area2 = area2;
  setup->x0 = x0;
  setup->y0 = y0;
  return true;
}

void PrepareSpans(TriangleSetup* setup) {
  for (Edge& e : setup->edge) e.inverse_dy = e.dy != 0.0 ? 1.0 / e.dy : 0.0;
}

// floor() and ceil() of a window coordinate (|x| < 2^52) without a libm call.
int64_t FloorToInt(double x) {
  const int64_t i = static_cast<int64_t>(x);  // truncates toward zero
  return i - (static_cast<double>(i) > x ? 1 : 0);
}
int64_t CeilToInt(double x) {
  const int64_t i = static_cast<int64_t>(x);
  return i + (static_cast<double>(i) < x ? 1 : 0);
}

void NormalizeOr(double n[3], double fx, double fy, double fz) {
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (len > 1e-300 && std::isfinite(len)) {
    const double inverse = 1.0 / len;
    n[0] *= inverse;
    n[1] *= inverse;
    n[2] *= inverse;
  } else {
    n[0] = fx;
    n[1] = fy;
    n[2] = fz;
  }
}

// Only the barycentric planes of a triangle (for the normals pass); false for zero area.
bool SetUpBarycentrics(const MapRasterInput& in, const uint32_t v[3], TriangleSetup* setup) {
  const double x0 = in.window_x[v[0]], y0 = in.window_y[v[0]];
  const double x1 = in.window_x[v[1]], y1 = in.window_y[v[1]];
  const double x2 = in.window_x[v[2]], y2 = in.window_y[v[2]];
  const double area2 = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0);
  if (!(area2 != 0.0)) return false;
  const double inverse_area2 = 1.0 / area2;
  setup->x0 = x0;
  setup->y0 = y0;
  setup->l1_x = (y2 - y0) * inverse_area2;
  setup->l1_y = -(x2 - x0) * inverse_area2;
  setup->l2_x = -(y1 - y0) * inverse_area2;
  setup->l2_y = (x1 - x0) * inverse_area2;
  return true;
}

// Narrows the texel span [*lo, *hi] of one row to the texels whose centres are inside edge `e`.
// Along a row the edge value is a monotone function of px (every rounded operation in Value()
// is monotone), so the inside texels form a prefix or a suffix of the row: estimate the boundary
// analytically, then settle it with the exact predicate, so the span is exactly the set the
// per-texel test would accept. Returns false when the span becomes empty.
bool ClipSpan(const Edge& e, double row_term, int64_t* lo, int64_t* hi) {
  auto inside = [&](int64_t i) {
    return e.Inside(e.Value(row_term, static_cast<double>(i) + 0.5));
  };
  if (e.dy == 0.0) return inside(*lo);  // the value does not depend on px
  // row_term - dy * (px - ax) = 0 at px = ax + row_term / dy; texel i is sampled at i + 1/2.
  double boundary = e.ax + row_term * e.inverse_dy - 0.5;
  const double lo_d = static_cast<double>(*lo) - 1.0, hi_d = static_cast<double>(*hi) + 1.0;
  if (!(boundary >= lo_d)) boundary = lo_d;  // also catches NaN
  if (!(boundary <= hi_d)) boundary = hi_d;
  if (-e.sign * e.dy > 0.0) {  // the value grows with px: inside for i >= boundary
    int64_t i = std::clamp(CeilToInt(boundary), *lo, *hi + 1);
    while (i > *lo && inside(i - 1)) --i;
    while (i <= *hi && !inside(i)) ++i;
    *lo = i;
  } else {  // inside for i <= boundary
    int64_t i = std::clamp(FloorToInt(boundary), *lo - 1, *hi);
    while (i < *hi && inside(i + 1)) ++i;
    while (i >= *lo && !inside(i)) --i;
    *hi = i;
  }
  return *lo <= *hi;
}

// The working depth and triangle of each texel live in the texel's 12 bytes of the output
// normal image (a double and a uint32), so a view needs no memory beyond its image: no extra
// multi-megabyte buffer to fault in and fill per call. The normals pass reads a texel's slot
// before it writes that texel's normal over it. memcpy: the floats' storage is reused as bytes.
class TexelSlots {
 public:
  static_assert(sizeof(double) + sizeof(uint32_t) == 3 * sizeof(float));
  TexelSlots() = default;
  explicit TexelSlots(std::vector<float>* normal)
      : bytes_(reinterpret_cast<unsigned char*>(normal->data())) {}
  double Depth(size_t index) const {
    double depth;
    std::memcpy(&depth, bytes_ + kBytes * index, sizeof(double));
    return depth;
  }
  uint32_t Face(size_t index) const {
    uint32_t face;
    std::memcpy(&face, bytes_ + kBytes * index + sizeof(double), sizeof(uint32_t));
    return face;
  }
  void SetDepth(size_t index, double depth) {
    std::memcpy(bytes_ + kBytes * index, &depth, sizeof(double));
  }
  void Set(size_t index, double depth, uint32_t face) {
    SetDepth(index, depth);
    std::memcpy(bytes_ + kBytes * index + sizeof(double), &face, sizeof(uint32_t));
  }

 private:
  static constexpr size_t kBytes = 3 * sizeof(float);
  unsigned char* bytes_ = nullptr;
};

// The barycentric depth of one triangle in one view as a plane over the texel centres, clamped
// to the vertex depths (a sliver's huge gradient cannot extrapolate, and a NaN from it becomes
// the minimum). The rasterizer and FragmentDepth() evaluate it with this one code path, so their
// values are bit-identical.
struct DepthPlane {
  double d0 = 0.0, grad_x = 0.0, grad_y = 0.0, d_min = 0.0, d_max = 0.0;
  double x0 = 0.0, y0 = 0.0;  // vertex 0, texel units

  // `area2` as SetUpEdges() computes it (twice the signed window area, != 0).
  void SetUp(const MapRasterInput& in, const double* vertex_depth, const uint32_t v[3],
             double area2) {
    x0 = in.window_x[v[0]];
    y0 = in.window_y[v[0]];
    const double x1 = in.window_x[v[1]], x2 = in.window_x[v[2]];
    const double y1 = in.window_y[v[1]], y2 = in.window_y[v[2]];
    const double inverse_area2 = 1.0 / area2;
    const double a = vertex_depth[v[0]], b = vertex_depth[v[1]], c = vertex_depth[v[2]];
    d0 = a;
    grad_x = ((b - a) * (y2 - y0) - (c - a) * (y1 - y0)) * inverse_area2;
    grad_y = ((c - a) * (x1 - x0) - (b - a) * (x2 - x0)) * inverse_area2;
    d_min = std::min({a, b, c});
    d_max = std::max({a, b, c});
  }
  double Row(double py) const { return d0 + grad_y * (py - y0); }
  // max(d_min, min(d, d_max)) also maps a NaN to d_min (the operand order matters).
  double At(double row, double px) const {
    return std::max(d_min, std::min(row + grad_x * (px - x0), d_max));
  }
};

double TwiceWindowArea(const MapRasterInput& in, const uint32_t v[3]) {
  const double x0 = in.window_x[v[0]], y0 = in.window_y[v[0]];
  const double x1 = in.window_x[v[1]], y1 = in.window_y[v[1]];
  const double x2 = in.window_x[v[2]], y2 = in.window_y[v[2]];
  return (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0);
}

// Calls visit(texel index, triangle, depths, area2) for every triangle and texel centre it
// covers, triangles in index order and, within one, texels row by row: the coverage rule of
// RasterizeViewCpu() (its only implementation). depths[k] is the barycentric depth in view
// views[k] (kViews may be 0: coverage only); area2 is the triangle's twice signed window area.
template <int kViews, class Visit>
void ForEachFragment(const MapRasterInput& in, const std::array<int, kViews>& views,
                     Visit&& visit) {
  const double* vertex_depth[kViews > 0 ? kViews : 1] = {};
  for (int k = 0; k < kViews; ++k) vertex_depth[k] = in.view_depth[views[k]].data();
  const size_t triangle_count = in.triangles.size() / 3;
  const int64_t max_i = static_cast<int64_t>(in.width) - 1;
  const int64_t max_j = static_cast<int64_t>(in.height) - 1;

  for (size_t t = 0; t < triangle_count; ++t) {
    const uint32_t v[3] = {in.triangles[3 * t], in.triangles[3 * t + 1], in.triangles[3 * t + 2]};
    const double x0 = in.window_x[v[0]], x1 = in.window_x[v[1]], x2 = in.window_x[v[2]];
    const double y0 = in.window_y[v[0]], y1 = in.window_y[v[1]], y2 = in.window_y[v[2]];
    // Texel centres i + 1/2 inside the bounding box; most small triangles stop here.
    const int64_t i0 = std::max<int64_t>(0, CeilToInt(std::min({x0, x1, x2}) - 0.5));
    const int64_t i1 = std::min(max_i, FloorToInt(std::max({x0, x1, x2}) - 0.5));
    if (i0 > i1) continue;
    const int64_t j0 = std::max<int64_t>(0, CeilToInt(std::min({y0, y1, y2}) - 0.5));
    const int64_t j1 = std::min(max_j, FloorToInt(std::max({y0, y1, y2}) - 0.5));
    if (j0 > j1) continue;
    TriangleSetup s;
    if (!SetUpEdges(in, v, &s)) continue;
    DepthPlane plane[kViews > 0 ? kViews : 1];
    for (int k = 0; k < kViews; ++k) plane[k].SetUp(in, vertex_depth[k], v, s.area2);
    const uint32_t face_id = static_cast<uint32_t>(t);
    // Narrow triangles test every texel of the bounding box; wider ones find each row's span
    // (the same predicate, so both give the same coverage; a span costs 3 boundary estimates
    // and 3-6 exact edge tests a row, which only pays off for wide rows).
    const bool narrow = i1 - i0 < kNarrowTriangleTexels;
    if (!narrow) PrepareSpans(&s);
    for (int64_t j = j0; j <= j1; ++j) {
      const double py = static_cast<double>(j) + 0.5;
      const double row0 = s.edge[0].RowTerm(py);
      const double row1 = s.edge[1].RowTerm(py);
      const double row2 = s.edge[2].RowTerm(py);
      double row_depth[kViews > 0 ? kViews : 1];
      for (int k = 0; k < kViews; ++k) row_depth[k] = plane[k].Row(py);
      const size_t row_start = static_cast<size_t>(j) * in.width;
      int64_t lo = i0, hi = i1;
      if (!narrow &&
          (!ClipSpan(s.edge[0], row0, &lo, &hi) || !ClipSpan(s.edge[1], row1, &lo, &hi) ||
           !ClipSpan(s.edge[2], row2, &lo, &hi))) {
        continue;
      }
      for (int64_t i = lo; i <= hi; ++i) {
        const double px = static_cast<double>(i) + 0.5;
        if (narrow && !(s.edge[0].Inside(s.edge[0].Value(row0, px)) &&
                        s.edge[1].Inside(s.edge[1].Value(row1, px)) &&
                        s.edge[2].Inside(s.edge[2].Value(row2, px)))) {
          continue;
        }
        std::array<double, kViews> depth;
        for (int k = 0; k < kViews; ++k) depth[k] = plane[k].At(row_depth[k], px);
        visit(row_start + static_cast<size_t>(i), face_id, depth, s.area2);
      }
    }
  }
}

// The normal rule of body_map_baker.h step 7 for triangle v at texel centre (px, py), given its
// barycentric setup `s` (`ok`: SetUpBarycentrics() succeeded): the vertex normals interpolated
// with the clamped barycentrics; if that sum vanishes, the offset triangle's face normal; if that
// vanishes too, (0, 0, fallback_z). Normalised. Always inlined: as a call, the normals pass of
// RasterizeViewsCpu was 7 % slower (sphere of 80k triangles at N = 1024).
[[gnu::always_inline]] inline void InterpolatedNormal(const MapRasterInput& in, const uint32_t v[3],
                                                      const TriangleSetup& s, bool ok, double px,
                                                      double py, double fallback_z, double n[3]) {
  const double* n0 = &in.normals[3 * v[0]];
  const double* n1 = &in.normals[3 * v[1]];
  const double* n2 = &in.normals[3 * v[2]];
  double lambda1 = 1.0 / 3.0, lambda2 = 1.0 / 3.0;
  if (ok) {
    const double dx = px - s.x0, dy = py - s.y0;
    lambda1 = std::clamp(s.l1_x * dx + s.l1_y * dy, 0.0, 1.0);
    lambda2 = std::clamp(s.l2_x * dx + s.l2_y * dy, 0.0, 1.0 - lambda1);
  }
  const double lambda0 = 1.0 - lambda1 - lambda2;
  for (int c = 0; c < 3; ++c) n[c] = lambda0 * n0[c] + lambda1 * n1[c] + lambda2 * n2[c];
  const double len2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  if (!(len2 > 1e-24)) {
    // Face normal of the offset triangle, then the fallback axis.
    const double* p0 = &in.positions[3 * v[0]];
    const double* p1 = &in.positions[3 * v[1]];
    const double* p2 = &in.positions[3 * v[2]];
    const double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    const double e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
  }
  NormalizeOr(n, 0.0, 0.0, fallback_z);
}

// The rasterizer for `kViews` views (1 or 2) of the same triangles: the coverage of a texel
// centre depends only on the window coordinates, so the edge tests, which are most of the work,
// run once per triangle and texel for all views; each view keeps its own depth test, with exactly
// the arithmetic of a single-view pass (so a view does not depend on which others share the pass).
template <int kViews>
void RasterizeViews(const MapRasterInput& in, const std::array<int, kViews>& views,
                    MapViewImage* const (&images)[kViews],
                    std::vector<uint32_t>* const (&faces)[kViews]) {
  const size_t texels = static_cast<size_t>(in.width) * in.height;
  // A texel's triangle is written exactly when its depth drops below +infinity (a depth of
  // +infinity or NaN never wins), so only the depths need a start value; the triangles are read
  // only where the depth is finite. Every texel of the images is written below, so resize()
  // suffices and an image reused from an earlier call keeps no stale texel.
  constexpr double kEmpty = std::numeric_limits<double>::infinity();
  TexelSlots slots[kViews];
  for (int k = 0; k < kViews; ++k) {
    images[k]->valid.resize(texels);
    images[k]->depth.resize(texels);
    images[k]->normal.resize(3 * texels);
    slots[k] = TexelSlots(&images[k]->normal);
    for (size_t index = 0; index < texels; ++index) slots[k].SetDepth(index, kEmpty);
  }
  ForEachFragment<kViews>(
      in, views,
      [&slots](size_t index, uint32_t face_id, const std::array<double, kViews>& depth, double) {
        for (int k = 0; k < kViews; ++k) {
          if (depth[k] < slots[k].Depth(index)) slots[k].Set(index, depth[k], face_id);
        }
      });

  for (int k = 0; k < kViews; ++k) {
    MapViewImage* image = images[k];
    const TexelSlots& slot = slots[k];
    uint32_t* out_face = nullptr;
    if (faces[k] != nullptr) {
      faces[k]->resize(texels);
      out_face = faces[k]->data();
    }
    uint8_t* out_valid = image->valid.data();
    float* out_depth = image->depth.data();
    float* out_normal = image->normal.data();
    const double view_axis_z = views[k] == 0 ? 1.0 : -1.0;
    uint32_t cached_face = kNoFace;
    bool cached_ok = false;
    TriangleSetup s{};
    for (uint32_t j = 0; j < in.height; ++j) {
      const double py = j + 0.5;
      for (uint32_t i = 0; i < in.width; ++i) {
        const size_t index = static_cast<size_t>(j) * in.width + i;
        const double texel_depth = slot.Depth(index);
        if (!(texel_depth < kEmpty)) {
          if (out_face != nullptr) out_face[index] = kNoFace;
          out_valid[index] = 0;
          out_depth[index] = 0.f;
          out_normal[3 * index] = 0.f;
          out_normal[3 * index + 1] = 0.f;
          out_normal[3 * index + 2] = 0.f;
          continue;
        }
        const uint32_t t = slot.Face(index);
        if (out_face != nullptr) out_face[index] = t;
        const uint32_t v[3] = {in.triangles[3 * t], in.triangles[3 * t + 1],
                               in.triangles[3 * t + 2]};
        if (t != cached_face) {
          cached_face = t;
          cached_ok = SetUpBarycentrics(in, v, &s);
        }
        double n[3];
        InterpolatedNormal(in, v, s, cached_ok, i + 0.5, py, view_axis_z, n);
        out_valid[index] = 1;
        out_depth[index] = static_cast<float>(texel_depth);
        for (int c = 0; c < 3; ++c) out_normal[3 * index + c] = static_cast<float>(n[c]);
      }
    }
  }
}

}  // namespace

void RasterizeViewCpu(const MapRasterInput& input, int view, MapViewImage* image,
                      std::vector<uint32_t>* face) {
  MapViewImage* const outputs[1] = {image};
  std::vector<uint32_t>* const faces[1] = {face};
  RasterizeViews<1>(input, {view}, outputs, faces);
}

void RasterizeViewsCpu(const MapRasterInput& input, MapViewImage images[2]) {
  MapViewImage* const outputs[2] = {&images[0], &images[1]};
  std::vector<uint32_t>* const faces[2] = {nullptr, nullptr};
  RasterizeViews<2>(input, {0, 1}, outputs, faces);
}

bool CollectFragmentsCpu(const MapRasterInput& input, uint32_t min_fragments,
                         MapFragments* fragments) {
  const size_t texels = static_cast<size_t>(input.width) * input.height;
  // Pass 1: fragments per texel, counted into offsets[n + 1] (at most one per triangle: no
  // overflow, the triangle count is < 2^32 / 3).
  std::vector<uint32_t>& offsets = fragments->offsets;
  offsets.assign(texels + 1, 0);
  ForEachFragment<0>(input, {},
                     [&offsets](size_t index, uint32_t, const std::array<double, 0>&, double) {
                       ++offsets[index + 1];
                     });
  // Texels with too few fragments keep none (the gap layers' texels need 4; most of a body's
  // texels have 2, so this saves most of the storage and its page faults). `keep` marks the
  // others for the fill pass. Prefix sum: offsets[n] is where texel n's fragments start.
  std::vector<uint8_t> keep(texels);
  uint64_t total = 0;
  for (size_t n = 0; n < texels; ++n) {
    const uint32_t count = offsets[n + 1];
    keep[n] = count >= min_fragments && count > 0;
    if (keep[n]) total += count;
    if (total > std::numeric_limits<uint32_t>::max()) return false;
    offsets[n + 1] = static_cast<uint32_t>(total);
  }
  fragments->depth.resize(total);
  fragments->triangle.resize(total);
  fragments->facing.resize(total);
  // Pass 2: fill, with offsets[n] as texel n's write cursor (then it holds the start of texel
  // n + 1; shifting restores the starts). Triangles in index order: each texel's fragments are
  // sorted by triangle.
  double* depth = fragments->depth.data();
  uint32_t* triangle = fragments->triangle.data();
  int8_t* facing = fragments->facing.data();
  const uint8_t* kept = keep.data();
  ForEachFragment<1>(
      input, {0},
      [&](size_t index, uint32_t face_id, const std::array<double, 1>& d, double area2) {
        if (!kept[index]) return;
        const uint32_t slot = offsets[index]++;
        depth[slot] = d[0];
        triangle[slot] = face_id;
        facing[slot] = area2 > 0.0 ? int8_t{1} : int8_t{-1};
      });
  for (size_t n = texels; n > 0; --n) offsets[n] = offsets[n - 1];
  offsets[0] = 0;
  return true;
}

double FragmentDepth(const MapRasterInput& input, int view, uint32_t triangle, uint32_t i,
                     uint32_t j) {
  const uint32_t v[3] = {input.triangles[3 * size_t{triangle}],
                         input.triangles[3 * size_t{triangle} + 1],
                         input.triangles[3 * size_t{triangle} + 2]};
  DepthPlane plane;
  plane.SetUp(input, input.view_depth[view].data(), v, TwiceWindowArea(input, v));
  return plane.At(plane.Row(static_cast<double>(j) + 0.5), static_cast<double>(i) + 0.5);
}

void FragmentNormal(const MapRasterInput& input, uint32_t triangle, uint32_t i, uint32_t j,
                    double fallback_z, float normal[3]) {
  const uint32_t v[3] = {input.triangles[3 * size_t{triangle}],
                         input.triangles[3 * size_t{triangle} + 1],
                         input.triangles[3 * size_t{triangle} + 2]};
  TriangleSetup s{};
  const bool ok = SetUpBarycentrics(input, v, &s);
  double n[3];
  InterpolatedNormal(input, v, s, ok, i + 0.5, j + 0.5, fallback_z, n);
  for (int c = 0; c < 3; ++c) normal[c] = static_cast<float>(n[c]);
}

}  // namespace drape::bake

#pragma once
// The body-map renderer's rasterizer pieces (body_map_renderer.cpp and its gap pass): one
// triangle set up in window coordinates, and the normal rule at a texel centre. Internal.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "drape/runtime/math.h"
#include "drape/runtime/task_system.h"
#include "tasks/parallel_for.h"

namespace drape::detail {

inline constexpr uint32_t kNoFace = std::numeric_limits<uint32_t>::max();
// Triangle indices stay below this: the gap search packs two flags above them.
inline constexpr uint32_t kMaxRasterTriangles = 1u << 30;

// One triangle set up for the rasterizer in window coordinates (texel units; texel (i, j) is
// sampled at its centre (i + 1/2, j + 1/2)). Each edge is evaluated canonically, from its lower
// to its higher vertex index, so the two triangles sharing an edge compute exactly negated values
// and a texel centre on it is covered by both (the tests are inclusive): no crack, and a texel
// covered twice keeps the same extreme depth whichever triangle draws it first.
struct RasterTriangle {
  struct Edge {
    double ax, ay, dx, dy;  // canonical start vertex and its difference to the end vertex
    double sign;            // +1 or -1: makes the value >= 0 inside the triangle
    double inverse_dy;      // 1 / dy, or 0 where dy is 0: Narrow's bound without a division
    double RowTerm(double py) const { return dx * (py - ay); }
    // >= 0: the texel centre is inside the edge (inclusive).
    double Value(double row_term, double px) const { return sign * (row_term - dy * (px - ax)); }
    bool Inside(double row_term, double px) const { return Value(row_term, px) >= 0.0; }
    // The tie rule: a texel centre on an edge belongs to exactly one of the two triangles
    // sharing it (their values are exactly negated, and so are their signs). For counting the
    // surfaces along a texel's ray, where Inside would count a shared edge twice.
    bool CountsOnce(double value) const { return value > 0.0 || (value == 0.0 && sign > 0.0); }
    // Narrows [*lo, *hi] to about the texels inside the edge on this row, a texel or two
    // generous on the side it cuts (the caller still tests each texel exactly), and
    // [*inner_lo, *inner_hi] to texels whose centre lies inside it by more than a texel, whose
    // value is then positive whatever the rounding (the caller need not test them). False: none
    // inside.
    bool Narrow(double row_term, int64_t* lo, int64_t* hi, int64_t* inner_lo,
                int64_t* inner_hi) const {
      if (dy == 0.0) return Inside(row_term, 0.0);  // the same value all along the row
      // The texel index where the value is 0, to within rounding: the slack below covers it.
      const double boundary = ax + row_term * inverse_dy - 0.5;
      if (!(std::fabs(boundary) < kMaxInner && std::fabs(ax) < kMaxInner)) {
        // Nearly along the row, or from a vertex far off: no texel is certain.
        *inner_hi = std::min(*inner_hi, *inner_lo - 1);
        if (!(std::fabs(boundary) < 1e15)) return true;
      }
      // Truncation and one texel more than floor / ceil needs: the library calls cost more
      // than the texel (no SSE4.1 rounding in the baseline build).
      const int64_t truncated = static_cast<int64_t>(boundary);
      if (-sign * dy > 0.0) {
        *lo = std::max(*lo, truncated - 2);
        *inner_lo = std::max(*inner_lo, truncated + 2);
      } else {
        *hi = std::min(*hi, truncated + 2);
        *inner_hi = std::min(*inner_hi, truncated - 2);
      }
      return *lo <= *hi;
    }
    // Texels: with the boundary and the edge's start within this, both terms of Value are at
    // most about this many times |dy|, so its rounding (and the boundary's) stays far below the
    // |dy| a texel inside the edge adds.
    static constexpr double kMaxInner = 1e7;
  };
  Edge edge[3];
  double x0, y0;          // vertex 0
  double grad_x, grad_y;  // dz per texel along x and y
  double z0, z_min, z_max;
  // Counter-clockwise in the window: the drawn (offset) triangle's normal points to +z, so going
  // along -z the ray enters the body through it (false: leaves it).
  bool entering;

  // Window coordinates (texel units) and depths of a triangle's corners.
  struct Corners {
    double x[3], y[3], z[3];
    double Area2() const { return (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]); }
  };
  static Corners CornersOf(const Float3* vertices, const uint32_t v[3], double origin_x,
                           double origin_y, double inverse_texel) {
    Corners c;
    for (int k = 0; k < 3; ++k) {
      c.x[k] = (static_cast<double>(vertices[v[k]].x) - origin_x) * inverse_texel;
      c.y[k] = (static_cast<double>(vertices[v[k]].y) - origin_y) * inverse_texel;
      c.z[k] = vertices[v[k]].z;
    }
    return c;
  }

  // The edges and the depth plane of a triangle with area (corners.Area2() != 0).
  void SetUp(const Corners& c, const uint32_t v[3]) {
    const double area2 = c.Area2();
    const double orientation = area2 > 0.0 ? 1.0 : -1.0;
    entering = area2 > 0.0;
    for (int k = 0; k < 3; ++k) {
      int from = (k + 1) % 3, to = (k + 2) % 3;  // counter-clockwise: the inside is on the left
      double sign = orientation;
      if (v[from] > v[to]) {
        std::swap(from, to);
        sign = -sign;
      }
      const double dy = c.y[to] - c.y[from];
      edge[k] = {c.x[from], c.y[from], c.x[to] - c.x[from], dy, sign, dy != 0.0 ? 1.0 / dy : 0.0};
    }
    x0 = c.x[0];
    y0 = c.y[0];
    const double inverse_area2 = 1.0 / area2;
    const double* x = c.x;
    const double* y = c.y;
    const double* z = c.z;
    grad_x = ((z[1] - z[0]) * (y[2] - y[0]) - (z[2] - z[0]) * (y[1] - y[0])) * inverse_area2;
    grad_y = ((z[2] - z[0]) * (x[1] - x[0]) - (z[1] - z[0]) * (x[2] - x[0])) * inverse_area2;
    z0 = z[0];
    z_min = std::min({z[0], z[1], z[2]});
    z_max = std::max({z[0], z[1], z[2]});
  }
  // The plane's z at a texel centre, clamped to the vertices' range (a sliver's steep gradient
  // cannot extrapolate past its corners).
  float Depth(double px, double py) const {
    const double z = z0 + grad_x * (px - x0) + grad_y * (py - y0);
    return static_cast<float>(std::clamp(z, z_min, z_max));
  }
};

// The normal rule of one triangle at a texel centre: its vertex normals interpolated with the
// clamped barycentrics; its face normal where they cancel; the caller's fallback where it has
// none. Set up once per drawn triangle and render (texels of a row mostly share their
// triangle, and the next row meets the same ones). 72 bytes.
struct TriangleShading {
  float x0, y0;                  // vertex 0, texels
  float b1_x, b1_y, b2_x, b2_y;  // barycentric gradients, per texel
  Float3 n0, n1, n2;             // vertex normals
  Float3 face;                   // unit face normal, or zero

  void SetUp(const Float3* offset, const Float3* normals, const uint32_t* v, Float3 face_normal,
             double origin_x, double origin_y, double inverse_texel) {
    double x[3], y[3];
    for (int k = 0; k < 3; ++k) {
      x[k] = (static_cast<double>(offset[v[k]].x) - origin_x) * inverse_texel;
      y[k] = (static_cast<double>(offset[v[k]].y) - origin_y) * inverse_texel;
    }
    const double area2 = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
    const double inverse_area2 = area2 != 0.0 ? 1.0 / area2 : 0.0;  // a sliver: vertex 0's normal
    x0 = static_cast<float>(x[0]);
    y0 = static_cast<float>(y[0]);
    b1_x = static_cast<float>((y[2] - y[0]) * inverse_area2);
    b1_y = static_cast<float>(-(x[2] - x[0]) * inverse_area2);
    b2_x = static_cast<float>(-(y[1] - y[0]) * inverse_area2);
    b2_y = static_cast<float>((x[1] - x[0]) * inverse_area2);
    n0 = normals[v[0]];
    n1 = normals[v[1]];
    n2 = normals[v[2]];
    face = NormalizeOr(face_normal, Float3{0.f, 0.f, 0.f});
  }
  // Unnormalised: the octahedral code divides by the L1 norm anyway.
  Float3 At(float px, float py, Float3 fallback) const {
    const float dx = px - x0, dy = py - y0;
    const float b1 = std::clamp(b1_x * dx + b1_y * dy, 0.f, 1.f);
    const float b2 = std::clamp(b2_x * dx + b2_y * dy, 0.f, 1.f - b1);
    const Float3 n = n0 * (1.f - b1 - b2) + n1 * b1 + n2 * b2;
    if (std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z) > 1e-6f) return n;
    return face.x != 0.f || face.y != 0.f || face.z != 0.f ? face : fallback;
  }
};

// The texel grid one render draws into: texel (i, j) is entry j * width + i.
struct RasterWindow {
  double origin_x = 0.0, origin_y = 0.0;  // metres, view frame
  int64_t width = 0, height = 0;          // texels
  double inverse_texel = 0.0;             // 1 / metres
};

// Walks the texel centres of rows [j_begin, j_end) and columns [i_begin, i_end) of r's box.
template <class Fragment>
void DrawTriangleRows(uint32_t t, const RasterTriangle& r, int64_t j_begin, int64_t j_end,
                      int64_t i_begin, int64_t i_end, int64_t width, Fragment& fragment) {
  constexpr int64_t kNarrowFrom = 5;  // texels: a narrower box is tested texel by texel
  const RasterTriangle::Edge* e = r.edge;
  for (int64_t j = j_begin; j < j_end; ++j) {
    const double py = static_cast<double>(j) + 0.5;
    const double row[3] = {e[0].RowTerm(py), e[1].RowTerm(py), e[2].RowTerm(py)};
    int64_t lo = i_begin, hi = i_end - 1;
    int64_t inner_lo = lo, inner_hi = -1;  // none certain inside unless narrowed
    if (i_end - i_begin >= kNarrowFrom) {
      inner_hi = hi;
      if (!(e[0].Narrow(row[0], &lo, &hi, &inner_lo, &inner_hi) &&
            e[1].Narrow(row[1], &lo, &hi, &inner_lo, &inner_hi) &&
            e[2].Narrow(row[2], &lo, &hi, &inner_lo, &inner_hi))) {
        continue;
      }
    }
    const auto tested = [&](int64_t i) {
      const double px = static_cast<double>(i) + 0.5;
      const double v0 = e[0].Value(row[0], px), v1 = e[1].Value(row[1], px);
      const double v2 = e[2].Value(row[2], px);
      if (!(v0 >= 0.0 && v1 >= 0.0 && v2 >= 0.0)) return;
      const bool once = e[0].CountsOnce(v0) && e[1].CountsOnce(v1) && e[2].CountsOnce(v2);
      fragment(t, r, static_cast<size_t>(j * width + i), px, py, once);
    };
    // Texels inside every edge by more than a texel: covered, and counted once (every value > 0).
    inner_lo = std::max(inner_lo, lo);
    inner_hi = std::min(inner_hi, hi);
    if (inner_lo > inner_hi) {
      for (int64_t i = lo; i <= hi; ++i) tested(i);
      continue;
    }
    for (int64_t i = lo; i < inner_lo; ++i) tested(i);
    for (int64_t i = inner_lo; i <= inner_hi; ++i) {
      fragment(t, r, static_cast<size_t>(j * width + i), static_cast<double>(i) + 0.5, py, true);
    }
    for (int64_t i = inner_hi + 1; i <= hi; ++i) tested(i);
  }
}

// Which 8 x 8-texel tiles of the window hold texels a pass needs: the gap pass skips the
// triangles whose box meets none (most of a body has no second surface to find).
struct TileMask {
  static constexpr int kShift = 3;  // 8 texels
  int64_t tiles_x = 0;
  std::span<uint8_t> flags;  // tiles_x * tiles_y entries
  static size_t TileCount(int64_t width, int64_t height) {
    return static_cast<size_t>(((width + 7) >> kShift) * ((height + 7) >> kShift));
  }
  void Mark(int64_t i, int64_t j) {
    flags[static_cast<size_t>((j >> kShift) * tiles_x + (i >> kShift))] = 1;
  }
  // Any tile of texels [i_begin, i_end) x [j_begin, j_end) (non-empty, within the window) marked.
  bool Any(int64_t i_begin, int64_t i_end, int64_t j_begin, int64_t j_end) const {
    for (int64_t tj = j_begin >> kShift; tj <= (j_end - 1) >> kShift; ++tj) {
      for (int64_t ti = i_begin >> kShift; ti <= (i_end - 1) >> kShift; ++ti) {
        if (flags[static_cast<size_t>(tj * tiles_x + ti)] != 0) return true;
      }
    }
    return false;
  }
};

// The texel box a triangle holds, kept apart from its set-up: each row band scans every
// triangle's box, and a 208-byte set-up per triangle would stream through the cache.
struct RasterBox {
  int32_t first, last;  // texel rows, within [-1, height]; first > last: none
  int32_t left, right;  // texel columns, within [-1, width]

  // The texel centres c = i + 1/2 within the corners' box: i in [ceil(min - 1/2),
  // floor(max - 1/2)], clamped to the window before the conversion (a vertex far outside a
  // region); empty (first > last) when it holds no centre of the window or the triangle has no
  // area. Ceil and floor by truncation and a compare: the baseline build has no SSE4.1 rounding.
  static RasterBox Of(const RasterTriangle::Corners& c, int64_t width, int64_t height) {
    const auto clamped = [](double x, int64_t size) {
      return std::clamp(x, -1.0, static_cast<double>(size));
    };
    const auto ceil = [&](double x, int64_t size) {
      const double y = clamped(x, size);
      const int32_t t = static_cast<int32_t>(y);
      return t + (static_cast<double>(t) < y ? 1 : 0);
    };
    const auto floor = [&](double x, int64_t size) {
      const double y = clamped(x, size);
      const int32_t t = static_cast<int32_t>(y);
      return t - (static_cast<double>(t) > y ? 1 : 0);
    };
    RasterBox b;
    b.left = ceil(std::min({c.x[0], c.x[1], c.x[2]}) - 0.5, width);
    b.right = floor(std::max({c.x[0], c.x[1], c.x[2]}) - 0.5, width);
    b.first = ceil(std::min({c.y[0], c.y[1], c.y[2]}) - 0.5, height);
    b.last = floor(std::max({c.y[0], c.y[1], c.y[2]}) - 0.5, height);
    const bool holds = std::max(b.left, 0) < std::min<int64_t>(int64_t{b.right} + 1, width) &&
                       std::max(b.first, 0) < std::min<int64_t>(int64_t{b.last} + 1, height);
    if (!holds || !(c.Area2() != 0.0)) b = {0, -1, 0, -1};
    return b;
  }
};

// The positions (in the set-up triangles) of those whose box meets a marked tile, ascending: what
// a pass over a few tiles draws (the others are not scanned by every row band).
inline void TrianglesOnTiles(std::span<const RasterBox> boxes, const TileMask& tiles,
                             std::vector<uint32_t>* positions) {
  positions->clear();
  for (size_t c = 0; c < boxes.size(); ++c) {
    const RasterBox& b = boxes[c];  // within the window, not empty
    if (tiles.Any(b.left, int64_t{b.right} + 1, b.first, int64_t{b.last} + 1))
      positions->push_back(static_cast<uint32_t>(c));
  }
}

// Calls fragment(t, r, k, px, py, once) for every texel centre the set-up triangles at
// `positions` cover (edges inclusive; null positions: all of them): t the triangle (faces[c]), r
// its set-up (set_up[c], boxes[c] its box within the window), k the texel's index, (px, py) its
// centre, and once whether the centre counts for this triangle when the surfaces along the ray
// are counted (a centre on an edge two triangles share counts for exactly one of them);
// r.Depth(px, py) is its depth. Row bands run in parallel, each drawing every triangle that
// crosses its rows, so a texel is handled by one band only, its triangles in order, whatever the
// banding: a fragment may write texel k's entries without a lock and the result does not depend
// on the thread count.
template <class Fragment>
void RasterizeInBands(std::span<const uint32_t> faces, std::span<const RasterTriangle> set_up,
                      std::span<const RasterBox> boxes, const RasterWindow& w,
                      const std::vector<uint32_t>* positions, Fragment&& fragment) {
  const int64_t bands = 4 * int64_t{GetTaskSystem().WorkerCount()};  // balance, not results
  const int64_t rows_per_band = std::max<int64_t>(8, (w.height + bands - 1) / bands);
  const int64_t band_count = (w.height + rows_per_band - 1) / rows_per_band;
  const size_t count = positions != nullptr ? positions->size() : faces.size();
  ParallelFor(band_count, 1, [&](int64_t band) {
    const int64_t row_begin = band * rows_per_band;
    const int64_t row_end = std::min(w.height, row_begin + rows_per_band);
    for (size_t n = 0; n < count; ++n) {
      const size_t c = positions != nullptr ? (*positions)[n] : n;
      const RasterBox& b = boxes[c];
      const int64_t j_begin = std::max<int64_t>(b.first, row_begin);
      const int64_t j_end = std::min<int64_t>(int64_t{b.last} + 1, row_end);
      if (j_begin >= j_end) continue;
      DrawTriangleRows(faces[c], set_up[c], j_begin, j_end, b.left, int64_t{b.right} + 1, w.width,
                       fragment);
    }
  });
}

// The triangles that cover a texel centre of the window, set up in `drawn` order: faces[c] the
// triangle, boxes[c] its box (clipped to the window), set_up[c] its edges and depth plane.
// Boxes first (most triangles of a finely meshed body at a coarse texel cover no centre), then
// the set-up of the covering ones only. `all_boxes`: scratch, one per drawn triangle. Returns
// how many cover a centre.
inline size_t SetUpTriangles(const Float3* vertices, const uint32_t* triangles,
                             std::span<const uint32_t> drawn, const RasterWindow& w,
                             std::span<RasterBox> all_boxes, std::span<uint32_t> faces,
                             std::span<RasterBox> boxes, std::span<RasterTriangle> set_up) {
  const auto corners = [&](uint32_t t) {
    return RasterTriangle::CornersOf(vertices, triangles + 3 * size_t{t}, w.origin_x, w.origin_y,
                                     w.inverse_texel);
  };
  ParallelFor(static_cast<int64_t>(drawn.size()), 2048, [&](int64_t d) {
    const size_t n = static_cast<size_t>(d);
    all_boxes[n] = RasterBox::Of(corners(drawn[n]), w.width, w.height);
  });
  size_t count = 0;
  for (size_t d = 0; d < drawn.size(); ++d) {
    const RasterBox& b = all_boxes[d];
    if (b.first > b.last) continue;
    faces[count] = drawn[d];
    boxes[count] = {
        std::max(b.first, 0), static_cast<int32_t>(std::min<int64_t>(b.last, w.height - 1)),
        std::max(b.left, 0), static_cast<int32_t>(std::min<int64_t>(b.right, w.width - 1))};
    ++count;
  }
  ParallelFor(static_cast<int64_t>(count), 2048, [&](int64_t c) {
    const size_t n = static_cast<size_t>(c);
    set_up[n].SetUp(corners(faces[n]), triangles + 3 * size_t{faces[n]});
  });
  return count;
}

}  // namespace drape::detail

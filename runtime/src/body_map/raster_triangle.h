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

// The texel grid one render draws into: texel (i, j) is entry j * width + i. Triangles are drawn
// in fixed point: corners snapped to 1 / 2^sub_bits texel, texel centres on the same grid, so
// every edge value is an exact 64-bit integer and a row is stepped by adding a constant. A render
// takes the finest grid (at most 1/65536 texel) on which its drawn corners stay below 2^29 units
// from the window's origin: every coordinate and edge difference then fits 32 bits, every edge
// value 62 bits. Only a triangle reaching 2^13 texels away coarsens the grid; corners beyond
// 2^29 texels (a hostile pose) are clamped there.
struct RasterWindow {
  double origin_x = 0.0, origin_y = 0.0;  // metres, view frame
  int64_t width = 0, height = 0;          // texels
  double inverse_texel = 0.0;             // 1 / metres
  int sub_bits = kMaxSubBits;             // [0, kMaxSubBits]: grid units per texel = 2^sub_bits

  static constexpr int kMaxSubBits = 16;
  static constexpr double kUnitLimit = 536870912.0;  // 2^29 grid units
  int64_t unit() const { return int64_t{1} << sub_bits; }
  // The finest grid on which |coordinate| (texels) stays below kUnitLimit units.
  static int SubBitsFor(double max_abs_texels) {
    int bits = kMaxSubBits;
    while (bits > 0 && !(max_abs_texels * static_cast<double>(int64_t{1} << bits) < kUnitLimit))
      --bits;
    return bits;
  }
  // Texels to grid units: rounded to nearest (halves away from zero), within +-(2^29 - 1).
  int32_t Snap(double texels) const {
    constexpr double kMax = kUnitLimit - 1.0;
    const double units = std::clamp(texels * static_cast<double>(unit()), -kMax, kMax);
    return static_cast<int32_t>(units + (units >= 0.0 ? 0.5 : -0.5));
  }
};

// One vertex in the window: texels, and snapped to the grid. Placed once per vertex (a vertex
// is shared by about six triangles). 24 bytes.
struct RasterVertex {
  double x, y;
  int32_t gx, gy;  // grid units
  static RasterVertex Of(const Float3& p, const RasterWindow& w) {
    RasterVertex v;
    v.x = (static_cast<double>(p.x) - w.origin_x) * w.inverse_texel;
    v.y = (static_cast<double>(p.y) - w.origin_y) * w.inverse_texel;
    v.gx = w.Snap(v.x);
    v.gy = w.Snap(v.y);
    return v;
  }
};

// One triangle set up for the rasterizer (RasterWindow's grid). Each edge is evaluated
// canonically, from its lower to its higher vertex index, so the two triangles sharing an edge
// compute exactly negated values and a texel centre on it is covered by both (the tests are
// inclusive): no crack, and a texel covered twice keeps the same extreme depth whichever triangle
// draws it first. 112 bytes: written and read once per render, so kept small.
struct RasterTriangle {
  // value(x, y) = dx (y - ay) - dy (x - ax), grid units, exact in 64 bits.
  struct Edge {
    int32_t ax, ay;  // canonical start vertex
    int32_t dx, dy;  // sign * (end - start): the value is >= 0 inside the triangle
    int32_t tie;     // 1 where the sign is -1, else 0: value - tie >= 0 counts the texel once
    int64_t Value(int64_t x, int64_t y) const {
      return int64_t{dx} * (y - ay) - int64_t{dy} * (x - ax);
    }
  };
  Edge edge[3];
  // Counter-clockwise in the window: the drawn (offset) triangle's normal points to +z, so going
  // along -z the ray enters the body through it (false: leaves it).
  bool entering;
  double x0, y0;          // vertex 0, texels
  double grad_x, grad_y;  // dz per texel along x and y
  float z0, z_min, z_max;

  // Window coordinates (texels, and snapped to the grid) and depths of a triangle's corners.
  struct Corners {
    double x[3], y[3];
    float z[3];
    int32_t gx[3], gy[3];  // grid units
    double Area2() const { return (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]); }
    int64_t GridArea2() const {
      return (int64_t{gx[1]} - gx[0]) * (int64_t{gy[2]} - gy[0]) -
             (int64_t{gy[1]} - gy[0]) * (int64_t{gx[2]} - gx[0]);
    }
  };
  static Corners CornersOf(const Float3* vertices, const RasterVertex* placed,
                           const uint32_t v[3]) {
    Corners c;
    for (int k = 0; k < 3; ++k) {
      const RasterVertex& p = placed[v[k]];
      c.x[k] = p.x;
      c.y[k] = p.y;
      c.z[k] = vertices[v[k]].z;
      c.gx[k] = p.gx;
      c.gy[k] = p.gy;
    }
    return c;
  }

  // The edges and the depth plane of a triangle with area on the grid (GridArea2() != 0).
  void SetUp(const Corners& c, const uint32_t v[3]) {
    entering = c.GridArea2() > 0;
    for (int k = 0; k < 3; ++k) {
      int from = (k + 1) % 3, to = (k + 2) % 3;  // counter-clockwise: the inside is on the left
      bool flipped = !entering;
      if (v[from] > v[to]) {
        std::swap(from, to);
        flipped = !flipped;
      }
      const int32_t sign = flipped ? -1 : 1;
      edge[k] = {c.gx[from], c.gy[from], sign * (c.gx[to] - c.gx[from]),
                 sign * (c.gy[to] - c.gy[from]), flipped ? 1 : 0};
    }
    x0 = c.x[0];
    y0 = c.y[0];
    // A sliver with area on the grid but none in double has a flat depth.
    const double area2 = c.Area2();
    const double inverse_area2 = area2 != 0.0 ? 1.0 / area2 : 0.0;
    const double* x = c.x;
    const double* y = c.y;
    const double z[3] = {c.z[0], c.z[1], c.z[2]};
    grad_x = ((z[1] - z[0]) * (y[2] - y[0]) - (z[2] - z[0]) * (y[1] - y[0])) * inverse_area2;
    grad_y = ((z[2] - z[0]) * (x[1] - x[0]) - (z[1] - z[0]) * (x[2] - x[0])) * inverse_area2;
    z0 = c.z[0];
    z_min = std::min({c.z[0], c.z[1], c.z[2]});
    z_max = std::max({c.z[0], c.z[1], c.z[2]});
  }
  // The plane's z at a texel centre, clamped to the vertices' range (a sliver's steep gradient
  // cannot extrapolate past its corners).
  float Depth(double px, double py) const {
    const double z = z0 + grad_x * (px - x0) + grad_y * (py - y0);
    return static_cast<float>(std::clamp(z, double{z_min}, double{z_max}));
  }
};
static_assert(sizeof(RasterTriangle) == 112);

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

// Walks the texel centres of rows [j_begin, j_end) and columns [i_begin, i_end) of r's box: each
// row's edge values at its first texel, then a constant step per texel. On a wide row the texels
// outside an edge are skipped by an exact division instead of visited.
template <class Fragment>
void DrawTriangleRows(uint32_t t, const RasterTriangle& r, const RasterWindow& w, int64_t j_begin,
                      int64_t j_end, int64_t i_begin, int64_t i_end, Fragment& fragment) {
  constexpr int64_t kSkipFrom = 12;  // texels: a narrower row is tested texel by texel
  const RasterTriangle::Edge* e = r.edge;
  const int64_t unit = w.unit(), half = unit / 2;
  const int64_t x_begin = i_begin * unit + half;
  const int64_t step[3] = {-int64_t{e[0].dy} * unit, -int64_t{e[1].dy} * unit,
                           -int64_t{e[2].dy} * unit};
  for (int64_t j = j_begin; j < j_end; ++j) {
    const int64_t y = j * unit + half;
    int64_t v[3] = {e[0].Value(x_begin, y), e[1].Value(x_begin, y), e[2].Value(x_begin, y)};
    int64_t begin = i_begin, end = i_end;
    if (i_end - i_begin >= kSkipFrom) {
      // Where each edge's value changes sign along the row, exactly.
      for (int k = 0; k < 3; ++k) {
        if (step[k] > 0 && v[k] < 0) {
          begin = std::max(begin, i_begin + (step[k] - 1 - v[k]) / step[k]);
        } else if (step[k] < 0 && v[k] >= 0) {
          end = std::min(end, i_begin + v[k] / -step[k] + 1);
        } else if (v[k] < 0) {
          end = i_begin;  // outside the edge along the whole row
        }
      }
      if (begin >= end) continue;
      for (int k = 0; k < 3; ++k) v[k] += (begin - i_begin) * step[k];
    }
    const double py = static_cast<double>(j) + 0.5;
    for (int64_t i = begin; i < end; ++i) {
      if ((v[0] | v[1] | v[2]) >= 0) {
        const bool once = ((v[0] - e[0].tie) | (v[1] - e[1].tie) | (v[2] - e[2].tie)) >= 0;
        fragment(t, r, static_cast<size_t>(j * w.width + i), static_cast<double>(i) + 0.5, py,
                 once);
      }
      v[0] += step[0];
      v[1] += step[1];
      v[2] += step[2];
    }
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
// triangle's box, and the set-ups would stream through the cache.
struct RasterBox {
  int32_t first, last;  // texel rows, within [-1, height]; first > last: none
  int32_t left, right;  // texel columns, within [-1, width]

  // The texel centres within the snapped corners' box, clamped to [-1, size]; empty (first >
  // last) when it holds no centre of the window or the triangle has no area on the grid.
  static RasterBox Of(const RasterTriangle::Corners& c, const RasterWindow& w) {
    // Floor division by the unit, a power of two: an arithmetic shift (C++20), not a divide.
    const int bits = w.sub_bits;
    const int64_t half = w.unit() / 2;
    const auto first_centre = [&](int64_t lo, int64_t size) {  // the least i: centre >= lo
      return static_cast<int32_t>(std::clamp<int64_t>(-((half - lo) >> bits), -1, size));
    };
    const auto last_centre = [&](int64_t hi, int64_t size) {  // the greatest i: centre <= hi
      return static_cast<int32_t>(std::clamp<int64_t>((hi - half) >> bits, -1, size));
    };
    RasterBox b;
    b.left = first_centre(std::min({c.gx[0], c.gx[1], c.gx[2]}), w.width);
    b.right = last_centre(std::max({c.gx[0], c.gx[1], c.gx[2]}), w.width);
    b.first = first_centre(std::min({c.gy[0], c.gy[1], c.gy[2]}), w.height);
    b.last = last_centre(std::max({c.gy[0], c.gy[1], c.gy[2]}), w.height);
    const bool holds = std::max(b.left, 0) < std::min<int64_t>(int64_t{b.right} + 1, w.width) &&
                       std::max(b.first, 0) < std::min<int64_t>(int64_t{b.last} + 1, w.height);
    if (!holds || c.GridArea2() == 0) b = {0, -1, 0, -1};
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
// on the thread count. row_spans (optional, 2 per row of the window): each row's columns
// [first, second) that the drawn triangles' boxes reach (empty: [width, 0)); no fragment lies
// outside them.
template <class Fragment>
void RasterizeInBands(std::span<const uint32_t> faces, std::span<const RasterTriangle> set_up,
                      std::span<const RasterBox> boxes, const RasterWindow& w,
                      const std::vector<uint32_t>* positions, Fragment&& fragment,
                      uint32_t* row_spans = nullptr) {
  // Balance, not results: four bands per worker, one without a second worker (each band scans
  // every triangle's box).
  const int64_t workers = GetTaskSystem().WorkerCount();
  const int64_t bands = workers > 1 ? 4 * workers : 1;
  const int64_t rows_per_band = std::max<int64_t>(8, (w.height + bands - 1) / bands);
  const int64_t band_count = (w.height + rows_per_band - 1) / rows_per_band;
  const size_t count = positions != nullptr ? positions->size() : faces.size();
  ParallelFor(band_count, 1, [&](int64_t band) {
    const int64_t row_begin = band * rows_per_band;
    const int64_t row_end = std::min(w.height, row_begin + rows_per_band);
    for (int64_t j = row_begin; row_spans != nullptr && j < row_end; ++j) {
      row_spans[2 * j] = static_cast<uint32_t>(w.width);
      row_spans[2 * j + 1] = 0;
    }
    for (size_t n = 0; n < count; ++n) {
      const size_t c = positions != nullptr ? (*positions)[n] : n;
      const RasterBox& b = boxes[c];
      const int64_t j_begin = std::max<int64_t>(b.first, row_begin);
      const int64_t j_end = std::min<int64_t>(int64_t{b.last} + 1, row_end);
      if (j_begin >= j_end) continue;
      DrawTriangleRows(faces[c], set_up[c], w, j_begin, j_end, b.left, int64_t{b.right} + 1,
                       fragment);
      for (int64_t j = j_begin; row_spans != nullptr && j < j_end; ++j) {
        row_spans[2 * j] = std::min(row_spans[2 * j], static_cast<uint32_t>(b.left));
        row_spans[2 * j + 1] = std::max(row_spans[2 * j + 1], static_cast<uint32_t>(b.right) + 1);
      }
    }
  });
}

// The triangles that cover a texel centre of the window, set up in `drawn` order: faces[c] the
// triangle, boxes[c] its box (clipped to the window), set_up[c] its edges and depth plane.
// Every vertex placed in the window first, then the boxes (most triangles of a finely meshed body
// at a coarse texel cover no centre), then the set-up of the covering ones only. `placed`: one
// per vertex, `all_boxes`: one per drawn triangle, both scratch. Returns how many cover a centre.
inline size_t SetUpTriangles(std::span<const Float3> vertices, const uint32_t* triangles,
                             std::span<const uint32_t> drawn, const RasterWindow& w,
                             std::span<RasterVertex> placed, std::span<RasterBox> all_boxes,
                             std::span<uint32_t> faces, std::span<RasterBox> boxes,
                             std::span<RasterTriangle> set_up) {
  ParallelFor(static_cast<int64_t>(vertices.size()), 4096, [&](int64_t v) {
    const size_t n = static_cast<size_t>(v);
    placed[n] = RasterVertex::Of(vertices[n], w);
  });
  const auto corners = [&](uint32_t t) {
    return RasterTriangle::CornersOf(vertices.data(), placed.data(), triangles + 3 * size_t{t});
  };
  ParallelFor(static_cast<int64_t>(drawn.size()), 2048, [&](int64_t d) {
    const size_t n = static_cast<size_t>(d);
    all_boxes[n] = RasterBox::Of(corners(drawn[n]), w);
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

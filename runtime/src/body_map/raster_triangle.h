#pragma once
// The body-map renderer's rasterizer pieces (body_map_renderer.cpp and its gap pass): one
// triangle set up in window coordinates, and the normal rule at a texel centre. Internal.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>

#include "drape/runtime/math.h"
#include "drape/runtime/task_system.h"
#include "tasks/parallel_for.h"

namespace drape::detail {

inline constexpr uint32_t kNoFace = std::numeric_limits<uint32_t>::max();

// One triangle set up for the rasterizer in window coordinates (texel units; texel (i, j) is
// sampled at its centre (i + 1/2, j + 1/2)). Each edge is evaluated canonically, from its lower
// to its higher vertex index, so the two triangles sharing an edge compute exactly negated values
// and a texel centre on it is covered by both (the tests are inclusive): no crack, and a texel
// covered twice keeps the same extreme depth whichever triangle draws it first.
struct RasterTriangle {
  struct Edge {
    double ax, ay, dx, dy;  // canonical start vertex and its difference to the end vertex
    double sign;            // +1 or -1: makes the value >= 0 inside the triangle
    double RowTerm(double py) const { return dx * (py - ay); }
    bool Inside(double row_term, double px) const {
      return sign * (row_term - dy * (px - ax)) >= 0.0;
    }
    // The same with a tie rule: a texel centre on an edge belongs to exactly one of the two
    // triangles sharing it (their values are exactly negated, and so are their signs). For
    // counting the surfaces along a texel's ray, where Inside would count a shared edge twice.
    bool InsideOnce(double row_term, double px) const {
      const double value = sign * (row_term - dy * (px - ax));
      return value > 0.0 || (value == 0.0 && sign > 0.0);
    }
    // Narrows [*lo, *hi] to about the texels inside the edge on this row, one texel generous on
    // the side it cuts (the caller still tests each texel exactly). False: none inside.
    bool Narrow(double row_term, int64_t* lo, int64_t* hi) const {
      if (dy == 0.0) return Inside(row_term, 0.0);       // the same value all along the row
      const double boundary = ax + row_term / dy - 0.5;  // texel index where the value is 0
      if (!(std::fabs(boundary) < 1e15)) return true;
      if (-sign * dy > 0.0) {
        *lo = std::max(*lo, static_cast<int64_t>(std::floor(boundary)) - 1);
      } else {
        *hi = std::min(*hi, static_cast<int64_t>(std::ceil(boundary)) + 1);
      }
      return *lo <= *hi;
    }
  };
  Edge edge[3];
  double x0, y0;          // vertex 0
  double grad_x, grad_y;  // dz per texel along x and y
  double z0, z_min, z_max;
  // Counter-clockwise in the window: the drawn (offset) triangle's normal points to +z, so going
  // along -z the ray enters the body through it (false: leaves it).
  bool entering;
  int64_t i_lo, i_hi, j_lo, j_hi;  // texel centres the triangle's box holds (may be empty)

  // False when the triangle has no area in the window (it covers no texel centre).
  bool SetUp(const Float3* vertices, const uint32_t v[3], double origin_x, double origin_y,
             double inverse_texel, double width, double height) {
    double x[3], y[3], z[3];
    for (int k = 0; k < 3; ++k) {
      x[k] = (static_cast<double>(vertices[v[k]].x) - origin_x) * inverse_texel;
      y[k] = (static_cast<double>(vertices[v[k]].y) - origin_y) * inverse_texel;
      z[k] = vertices[v[k]].z;
    }
    const double area2 = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
    if (!(area2 != 0.0)) return false;
    const double orientation = area2 > 0.0 ? 1.0 : -1.0;
    entering = area2 > 0.0;
    for (int k = 0; k < 3; ++k) {
      int from = (k + 1) % 3, to = (k + 2) % 3;  // counter-clockwise: the inside is on the left
      double sign = orientation;
      if (v[from] > v[to]) {
        std::swap(from, to);
        sign = -sign;
      }
      edge[k] = {x[from], y[from], x[to] - x[from], y[to] - y[from], sign};
    }
    x0 = x[0];
    y0 = y[0];
    const double inverse_area2 = 1.0 / area2;
    grad_x = ((z[1] - z[0]) * (y[2] - y[0]) - (z[2] - z[0]) * (y[1] - y[0])) * inverse_area2;
    grad_y = ((z[2] - z[0]) * (x[1] - x[0]) - (z[1] - z[0]) * (x[2] - x[0])) * inverse_area2;
    z0 = z[0];
    z_min = std::min({z[0], z[1], z[2]});
    z_max = std::max({z[0], z[1], z[2]});
    // Centres c = i + 1/2 within [min, max]: i in [ceil(min - 1/2), floor(max - 1/2)], kept
    // within the window before the conversion (a vertex far outside a region).
    const auto index = [](double c, double size) {
      return static_cast<int64_t>(std::clamp(c, -1.0, size));
    };
    i_lo = index(std::ceil(std::min({x[0], x[1], x[2]}) - 0.5), width);
    i_hi = index(std::floor(std::max({x[0], x[1], x[2]}) - 0.5), width);
    j_lo = index(std::ceil(std::min({y[0], y[1], y[2]}) - 0.5), height);
    j_hi = index(std::floor(std::max({y[0], y[1], y[2]}) - 0.5), height);
    return true;
  }
  // The plane's z at a texel centre, clamped to the vertices' range (a sliver's steep gradient
  // cannot extrapolate past its corners).
  float Depth(double px, double py) const {
    const double z = z0 + grad_x * (px - x0) + grad_y * (py - y0);
    return static_cast<float>(std::clamp(z, z_min, z_max));
  }
};

// The normal rule at a texel centre: the triangle's vertex normals interpolated with the clamped
// barycentrics; its face normal where they cancel; `fallback` where it has none. Set up once per
// triangle and reused along a row, where neighbouring texels mostly share their triangle.
class NormalInterpolator {
 public:
  void SetUp(const Float3* offset, const Float3* normals, const uint32_t* triangles,
             uint32_t triangle, Float3 face_normal, double origin_x, double origin_y,
             double inverse_texel, Float3 fallback) {
    const uint32_t* v = triangles + 3 * size_t{triangle};
    double x[3], y[3];
    for (int k = 0; k < 3; ++k) {
      x[k] = (static_cast<double>(offset[v[k]].x) - origin_x) * inverse_texel;
      y[k] = (static_cast<double>(offset[v[k]].y) - origin_y) * inverse_texel;
      n_[k] = normals[v[k]];
    }
    const double inverse_area2 =
        1.0 / ((x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]));
    x0_ = x[0];
    y0_ = y[0];
    b1_x_ = (y[2] - y[0]) * inverse_area2;
    b1_y_ = -(x[2] - x[0]) * inverse_area2;
    b2_x_ = -(y[1] - y[0]) * inverse_area2;
    b2_y_ = (x[1] - x[0]) * inverse_area2;
    fallback_ = NormalizeOr(face_normal, fallback);
    triangle_ = triangle;
  }
  uint32_t triangle() const { return triangle_; }
  Float3 At(double px, double py) const {
    const double dx = px - x0_, dy = py - y0_;
    const double b1 = std::clamp(b1_x_ * dx + b1_y_ * dy, 0.0, 1.0);
    const double b2 = std::clamp(b2_x_ * dx + b2_y_ * dy, 0.0, 1.0 - b1);
    const float w1 = static_cast<float>(b1), w2 = static_cast<float>(b2);
    // Unnormalised: the octahedral code divides by the L1 norm anyway.
    const Float3 n = n_[0] * (1.f - w1 - w2) + n_[1] * w1 + n_[2] * w2;
    return std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z) > 1e-6f ? n : fallback_;
  }

 private:
  uint32_t triangle_ = kNoFace;
  double x0_ = 0.0, y0_ = 0.0;
  double b1_x_ = 0.0, b1_y_ = 0.0, b2_x_ = 0.0, b2_y_ = 0.0;  // barycentric gradients
  Float3 n_[3];
  Float3 fallback_;
};

// The texel grid one render draws into: texel (i, j) is entry j * width + i.
struct RasterWindow {
  double origin_x = 0.0, origin_y = 0.0;  // metres, view frame
  int64_t width = 0, height = 0;          // texels
  double inverse_texel = 0.0;             // 1 / metres
};

// Calls fragment(t, r, k, px, row) for every texel centre the `drawn` triangles cover (edges
// inclusive): t the triangle, r its set-up, k the texel's index, px its centre's x and row the
// edge terms of its row (for RasterTriangle::Edge::InsideOnce); r.Depth(px, py) is its depth.
// Row bands run in parallel, each drawing every triangle that crosses its rows, so a texel is
// handled by one band only, its triangles in `drawn` order, whatever the banding: a fragment may
// write texel k's entries without a lock and the result does not depend on the thread count.
template <class Fragment>
void RasterizeInBands(const Float3* vertices, const uint32_t* triangles,
                      std::span<const uint32_t> drawn, const RasterWindow& w, Fragment&& fragment) {
  const int64_t bands = 4 * int64_t{GetTaskSystem().WorkerCount()};  // balance, not results
  const int64_t rows_per_band = std::max<int64_t>(8, (w.height + bands - 1) / bands);
  const int64_t band_count = (w.height + rows_per_band - 1) / rows_per_band;
  ParallelFor(band_count, 1, [&](int64_t band) {
    const int64_t row_begin = band * rows_per_band;
    const int64_t row_end = std::min(w.height, row_begin + rows_per_band);
    for (uint32_t t : drawn) {
      const uint32_t* v = triangles + 3 * size_t{t};
      // Rows first, from the vertices alone: most triangles miss the band.
      const double y_lo = std::min({vertices[v[0]].y, vertices[v[1]].y, vertices[v[2]].y});
      const double y_hi = std::max({vertices[v[0]].y, vertices[v[1]].y, vertices[v[2]].y});
      if ((y_hi - w.origin_y) * w.inverse_texel < static_cast<double>(row_begin) ||
          (y_lo - w.origin_y) * w.inverse_texel > static_cast<double>(row_end) + 1.0) {
        continue;
      }
      RasterTriangle r;
      if (!r.SetUp(vertices, v, w.origin_x, w.origin_y, w.inverse_texel,
                   static_cast<double>(w.width), static_cast<double>(w.height))) {
        continue;
      }
      const int64_t j_begin = std::max(r.j_lo, row_begin), j_end = std::min(r.j_hi + 1, row_end);
      const int64_t i_begin = std::max<int64_t>(r.i_lo, 0), i_end = std::min(r.i_hi + 1, w.width);
      for (int64_t j = j_begin; j < j_end; ++j) {
        const double py = static_cast<double>(j) + 0.5;
        const double row[3] = {r.edge[0].RowTerm(py), r.edge[1].RowTerm(py), r.edge[2].RowTerm(py)};
        int64_t lo = i_begin, hi = i_end - 1;
        if (!(r.edge[0].Narrow(row[0], &lo, &hi) && r.edge[1].Narrow(row[1], &lo, &hi) &&
              r.edge[2].Narrow(row[2], &lo, &hi))) {
          continue;
        }
        for (int64_t i = lo; i <= hi; ++i) {
          const double px = static_cast<double>(i) + 0.5;
          if (!(r.edge[0].Inside(row[0], px) && r.edge[1].Inside(row[1], px) &&
                r.edge[2].Inside(row[2], px))) {
            continue;
          }
          fragment(t, r, static_cast<size_t>(j * w.width + i), px, py, row);
        }
      }
    }
  });
}

}  // namespace drape::detail

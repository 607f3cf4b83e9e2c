#include "renderer.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "drape/runtime/math.h"

namespace drape::sim {
namespace {

constexpr float kFovY = 30.f * std::numbers::pi_v<float> / 180.f;  // vertical field of view

struct Projected {
  float x, y;           // canvas pixels
  float inverse_depth;  // 1 / camera z
};

bool Project(const Camera& c, Float3 p, Projected* out) {
  const Float3 v = p - c.eye;
  const float z = Dot(v, c.forward);
  if (!(z > c.near_z)) return false;
  const float inv = 1.f / z;
  out->x = c.center_x + c.focal * Dot(v, c.right) * inv;
  out->y = c.center_y - c.focal * Dot(v, c.up) * inv;
  out->inverse_depth = inv;
  return true;
}

Rgb Scale(Rgb c, float s) { return {c.r * s, c.g * s, c.b * s}; }

}  // namespace

Camera FitCamera(Float3 lo, Float3 hi, float yaw_deg, float pitch_deg, float zoom, int width,
                 int height) {
  const float yaw = yaw_deg * std::numbers::pi_v<float> / 180.f;
  const float pitch = pitch_deg * std::numbers::pi_v<float> / 180.f;
  // From the target towards the eye.
  const Float3 back{std::sin(yaw) * std::cos(pitch), std::sin(pitch),
                    std::cos(yaw) * std::cos(pitch)};
  Camera c;
  c.forward = -back;
  c.right = NormalizeOr(Cross(c.forward, Float3{0.f, 1.f, 0.f}), Float3{1.f, 0.f, 0.f});
  c.up = Cross(c.right, c.forward);
  const Float3 center = (lo + hi) * 0.5f;
  const float aspect = static_cast<float>(width) / static_cast<float>(height);
  const float tan_half = std::tan(kFovY * 0.5f);
  // The nearest eye distance (from the centre, along `back`) at which every corner of the box
  // projects inside the picture, with 6 % of air: a corner at camera offsets (x, y) and depth
  // offset z from the centre needs d + z >= |y| / tan_half and |x| / (aspect tan_half).
  float fit = 0.f;
  for (int k = 0; k < 8; ++k) {
    const Float3 corner{(k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z};
    const Float3 d = corner - center;
    const float need =
        std::max(std::fabs(Dot(d, c.up)), std::fabs(Dot(d, c.right)) / aspect) * 1.06f / tan_half;
    fit = std::max(fit, need - Dot(d, c.forward));
  }
  c.eye = center + back * (fit / std::max(zoom, 1e-3f));
  c.focal = static_cast<float>(height) * 0.5f / tan_half;
  c.center_x = static_cast<float>(width) * 0.5f;
  c.center_y = static_cast<float>(height) * 0.5f;
  return c;
}

Canvas::Canvas(int width, int height, int supersample)
    : width_(width), height_(height), supersample_(std::max(supersample, 1)) {
  const size_t n = static_cast<size_t>(canvas_width()) * static_cast<size_t>(canvas_height());
  color_.assign(n, Rgb{});
  inverse_depth_.assign(n, 0.f);
}

void Canvas::Clear(Rgb top, Rgb bottom) {
  const int w = canvas_width(), h = canvas_height();
  for (int y = 0; y < h; ++y) {
    const float t = static_cast<float>(y) / static_cast<float>(std::max(h - 1, 1));
    const Rgb c{top.r + (bottom.r - top.r) * t, top.g + (bottom.g - top.g) * t,
                top.b + (bottom.b - top.b) * t};
    std::fill(color_.begin() + static_cast<ptrdiff_t>(y) * w,
              color_.begin() + static_cast<ptrdiff_t>(y + 1) * w, c);
  }
  std::fill(inverse_depth_.begin(), inverse_depth_.end(), 0.f);
}

void Canvas::DrawTriangle(const Camera& camera, const Float3 p[3], const Rgb color[3]) {
  Projected q[3];
  for (int k = 0; k < 3; ++k)
    if (!Project(camera, p[k], &q[k])) return;  // crosses the near plane: skipped
  const float area = (q[1].x - q[0].x) * (q[2].y - q[0].y) - (q[2].x - q[0].x) * (q[1].y - q[0].y);
  if (!(std::fabs(area) > 1e-12f)) return;
  const int w = canvas_width(), h = canvas_height();
  const int x0 = std::max(0, static_cast<int>(std::floor(std::min({q[0].x, q[1].x, q[2].x}))));
  const int x1 = std::min(w - 1, static_cast<int>(std::ceil(std::max({q[0].x, q[1].x, q[2].x}))));
  const int y0 = std::max(0, static_cast<int>(std::floor(std::min({q[0].y, q[1].y, q[2].y}))));
  const int y1 = std::min(h - 1, static_cast<int>(std::ceil(std::max({q[0].y, q[1].y, q[2].y}))));
  const float inv_area = 1.f / area;
  for (int y = y0; y <= y1; ++y) {
    const float py = static_cast<float>(y) + 0.5f;
    for (int x = x0; x <= x1; ++x) {
      const float px = static_cast<float>(x) + 0.5f;
      // Barycentrics by edge functions (the sign of `area` makes both windings work).
      const float b0 = ((q[1].x - px) * (q[2].y - py) - (q[2].x - px) * (q[1].y - py)) * inv_area;
      const float b1 = ((q[2].x - px) * (q[0].y - py) - (q[0].x - px) * (q[2].y - py)) * inv_area;
      const float b2 = 1.f - b0 - b1;
      if (b0 < 0.f || b1 < 0.f || b2 < 0.f) continue;
      const float inv_depth =
          b0 * q[0].inverse_depth + b1 * q[1].inverse_depth + b2 * q[2].inverse_depth;
      const size_t i = static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x);
      if (inv_depth <= inverse_depth_[i]) continue;  // larger 1/z is nearer
      // Perspective-correct colour.
      const float w0 = b0 * q[0].inverse_depth / inv_depth;
      const float w1 = b1 * q[1].inverse_depth / inv_depth;
      const float w2 = 1.f - w0 - w1;
      inverse_depth_[i] = inv_depth;
      color_[i] = {w0 * color[0].r + w1 * color[1].r + w2 * color[2].r,
                   w0 * color[0].g + w1 * color[1].g + w2 * color[2].g,
                   w0 * color[0].b + w1 * color[1].b + w2 * color[2].b};
    }
  }
}

void Canvas::Plot(int x, int y, float inverse_depth, Rgb color, float hidden_alpha) {
  if (x < 0 || y < 0 || x >= canvas_width() || y >= canvas_height()) return;
  const size_t i =
      static_cast<size_t>(y) * static_cast<size_t>(canvas_width()) + static_cast<size_t>(x);
  // A line on a surface is visible; 1 % depth bias against z-fighting with its own surface.
  const bool visible = inverse_depth * 1.01f >= inverse_depth_[i];
  const float alpha = visible ? 1.f : hidden_alpha;
  Rgb& c = color_[i];
  c = {c.r + (color.r - c.r) * alpha, c.g + (color.g - c.g) * alpha, c.b + (color.b - c.b) * alpha};
}

void Canvas::DrawLine(const Camera& camera, Float3 a, Float3 b, Rgb color, float hidden_alpha,
                      int thickness) {
  Projected qa, qb;
  if (!Project(camera, a, &qa) || !Project(camera, b, &qb)) return;
  const float dx = qb.x - qa.x, dy = qb.y - qa.y;
  const int steps =
      std::max(1, static_cast<int>(std::ceil(std::max(std::fabs(dx), std::fabs(dy)))));
  const int half = thickness / 2;
  for (int s = 0; s <= steps; ++s) {
    const float t = static_cast<float>(s) / static_cast<float>(steps);
    const int x = static_cast<int>(std::floor(qa.x + dx * t));
    const int y = static_cast<int>(std::floor(qa.y + dy * t));
    const float inv = qa.inverse_depth + (qb.inverse_depth - qa.inverse_depth) * t;
    for (int oy = -half; oy <= half; ++oy)
      for (int ox = -half; ox <= half; ++ox) Plot(x + ox, y + oy, inv, color, hidden_alpha);
  }
}

std::vector<uint8_t> Canvas::Resolve() const {
  std::vector<uint8_t> out(static_cast<size_t>(width_) * static_cast<size_t>(height_) * 3);
  const float norm = 1.f / static_cast<float>(supersample_ * supersample_);
  for (int y = 0; y < height_; ++y) {
    for (int x = 0; x < width_; ++x) {
      Rgb sum;
      for (int sy = 0; sy < supersample_; ++sy) {
        for (int sx = 0; sx < supersample_; ++sx) {
          const Rgb& c = color_[static_cast<size_t>(y * supersample_ + sy) *
                                    static_cast<size_t>(canvas_width()) +
                                static_cast<size_t>(x * supersample_ + sx)];
          sum.r += c.r;
          sum.g += c.g;
          sum.b += c.b;
        }
      }
      const size_t o = (static_cast<size_t>(y) * static_cast<size_t>(width_) + x) * 3;
      // A display gamma of 2.2 over the linear shading.
      const auto encode = [&](float v) {
        const float g = std::pow(std::clamp(v * norm, 0.f, 1.f), 1.f / 2.2f);
        return static_cast<uint8_t>(std::lround(g * 255.f));
      };
      out[o] = encode(sum.r);
      out[o + 1] = encode(sum.g);
      out[o + 2] = encode(sum.b);
    }
  }
  return out;
}

void DrawMesh(Canvas* canvas, const Camera& camera, const Light& light,
              std::span<const Float3> positions, std::span<const uint32_t> triangles, Rgb albedo,
              bool two_sided, Rgb back_albedo) {
  // Area-weighted vertex normals.
  std::vector<Float3> normals(positions.size());
  for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
    const Float3 a = positions[triangles[t]], b = positions[triangles[t + 1]],
                 c = positions[triangles[t + 2]];
    const Float3 n = Cross(b - a, c - a);
    for (int k = 0; k < 3; ++k) normals[triangles[t + k]] += n;
  }
  for (Float3& n : normals) n = NormalizeOr(n, Float3{0.f, 1.f, 0.f});
  for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
    const Float3 p[3] = {positions[triangles[t]], positions[triangles[t + 1]],
                         positions[triangles[t + 2]]};
    const Float3 face = Cross(p[1] - p[0], p[2] - p[0]);
    const Float3 centroid = (p[0] + p[1] + p[2]) * (1.f / 3.f);
    const bool front = Dot(face, camera.eye - centroid) >= 0.f;
    if (!front && !two_sided) continue;
    const float side = front ? 1.f : -1.f;
    const Rgb base = front ? albedo : back_albedo;
    Rgb colors[3];
    for (int k = 0; k < 3; ++k) {
      const float lambert = std::max(0.f, side * Dot(normals[triangles[t + k]], light.direction));
      colors[k] = Scale(base, light.ambient + light.diffuse * lambert);
    }
    canvas->DrawTriangle(camera, p, colors);
  }
}

void DrawFloor(Canvas* canvas, const Camera& camera, const Light& light, float x, float y, float z,
               float tile, int tiles) {
  const Rgb light_tile{0.62f, 0.62f, 0.60f}, dark_tile{0.50f, 0.50f, 0.48f};
  const float shade = light.ambient + light.diffuse * std::max(0.f, light.direction.y);
  const float origin_x = x - tile * static_cast<float>(tiles) * 0.5f;
  const float origin_z = z - tile * static_cast<float>(tiles) * 0.5f;
  for (int j = 0; j < tiles; ++j) {
    for (int i = 0; i < tiles; ++i) {
      const float x0 = origin_x + tile * static_cast<float>(i), x1 = x0 + tile;
      const float z0 = origin_z + tile * static_cast<float>(j), z1 = z0 + tile;
      const Rgb c = Scale((i + j) % 2 == 0 ? light_tile : dark_tile, shade);
      const Rgb colors[3] = {c, c, c};
      const Float3 a[3] = {{x0, y, z0}, {x1, y, z0}, {x1, y, z1}};
      const Float3 b[3] = {{x0, y, z0}, {x1, y, z1}, {x0, y, z1}};
      canvas->DrawTriangle(camera, a, colors);
      canvas->DrawTriangle(camera, b, colors);
    }
  }
}

std::vector<uint8_t> Downscale(std::span<const uint8_t> rgb, int width, int height,
                               int target_width, int* out_width, int* out_height) {
  const int factor = std::max(1, (width + target_width - 1) / std::max(target_width, 1));
  const int w = std::max(1, width / factor), h = std::max(1, height / factor);
  std::vector<uint8_t> out(static_cast<size_t>(w) * static_cast<size_t>(h) * 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int ch = 0; ch < 3; ++ch) {
        int sum = 0;
        for (int sy = 0; sy < factor; ++sy)
          for (int sx = 0; sx < factor; ++sx)
            sum += rgb[(static_cast<size_t>(y * factor + sy) * static_cast<size_t>(width) +
                        static_cast<size_t>(x * factor + sx)) *
                           3 +
                       static_cast<size_t>(ch)];
        out[(static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x)) * 3 +
            static_cast<size_t>(ch)] = static_cast<uint8_t>(sum / (factor * factor));
      }
    }
  }
  *out_width = w;
  *out_height = h;
  return out;
}

}  // namespace drape::sim

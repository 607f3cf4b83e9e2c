#pragma once
// drape-sim's small software renderer: a perspective camera, a z-buffered triangle and line
// rasterizer with supersampling, and Lambert-shaded meshes (Gouraud: lighting per vertex from
// area-weighted vertex normals, colours interpolated perspective-correctly). Enough to see cloth
// hang on a body; nothing here is used by the library.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "drape/formats/status.h"
#include "drape/formats/types.h"

namespace drape::sim {

struct Rgb {
  float r = 0.f, g = 0.f, b = 0.f;  // linear-ish, [0, 1]
};

// A pinhole camera looking at a target. Camera space: x right, y up, z forward (into the scene).
struct Camera {
  Float3 eye;
  Float3 right, up, forward;  // orthonormal
  float focal = 1.f;          // pixels of the supersampled canvas per unit of x/z
  float center_x = 0.f, center_y = 0.f;
  float near_z = 0.05f;  // metres; triangles reaching closer are skipped
};

// The camera that frames the box [lo, hi] (asset frame, +Y up) from `yaw_deg` about +Y
// (0 = from the front, +Z; positive turns towards +X) and `pitch_deg` above the horizon, for a
// width x height picture (pixels of the supersampled canvas). zoom > 1 moves closer.
Camera FitCamera(Float3 lo, Float3 hi, float yaw_deg, float pitch_deg, float zoom, int width,
                 int height);

// A colour picture with a depth buffer, rendered at `supersample` x the output size and
// box-filtered down by Resolve.
class Canvas {
 public:
  Canvas(int width, int height, int supersample);

  int width() const { return width_; }    // output pixels
  int height() const { return height_; }  // output pixels
  int canvas_width() const { return width_ * supersample_; }
  int canvas_height() const { return height_ * supersample_; }

  // A vertical gradient from `top` to `bottom`; depth to infinity.
  void Clear(Rgb top, Rgb bottom);
  // One triangle with per-vertex colours (already lit).
  void DrawTriangle(const Camera& camera, const Float3 p[3], const Rgb color[3]);
  // A 3D segment, `thickness` canvas pixels wide: where it is in front of the depth buffer
  // (within a small bias) it is drawn in `color`, behind it blended with `hidden_alpha`.
  void DrawLine(const Camera& camera, Float3 a, Float3 b, Rgb color, float hidden_alpha,
                int thickness);

  // Output-size RGB8 pixels, row-major from the top row.
  std::vector<uint8_t> Resolve() const;

 private:
  void Plot(int x, int y, float inverse_depth, Rgb color, float hidden_alpha);

  int width_, height_, supersample_;
  std::vector<Rgb> color_;
  std::vector<float> inverse_depth_;  // 1 / camera z; 0 = background
};

struct Light {
  Float3 direction{0.f, 1.f, 0.f};  // unit, towards the light
  float ambient = 0.22f;
  float diffuse = 0.85f;
};

// Draws a triangle mesh with Lambert shading. two_sided: faces seen from behind are lit with
// the flipped normal and drawn in `back_albedo` (cloth); otherwise back faces are culled.
void DrawMesh(Canvas* canvas, const Camera& camera, const Light& light,
              std::span<const Float3> positions, std::span<const uint32_t> triangles, Rgb albedo,
              bool two_sided, Rgb back_albedo);

// A checkered floor of `tiles` x `tiles` squares of `tile` metres centred on (x, z) at height y.
void DrawFloor(Canvas* canvas, const Camera& camera, const Light& light, float x, float y, float z,
               float tile, int tiles);

// Writes RGB8 pixels as a PNG (stb_image_write).
Status WritePng(const std::string& path, int width, int height, std::span<const uint8_t> rgb);

// Box-filters RGB8 pixels down to (or near) the given width, keeping the aspect ratio.
std::vector<uint8_t> Downscale(std::span<const uint8_t> rgb, int width, int height,
                               int target_width, int* out_width, int* out_height);

}  // namespace drape::sim

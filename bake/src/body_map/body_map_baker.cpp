#include "drape/bake/body_map_baker.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "body_map/cpu_rasterizer.h"
#include "body_map/gap_layers.h"
#include "body_map/osmesa_renderer.h"
#include "body_map/pose_entries.h"
#include "drape/runtime/normal_encoding.h"

namespace drape::bake {
namespace {

constexpr uint32_t kMinResolution = 16;
constexpr uint32_t kMaxResolution = 8192;
// The fitted window of a very elongated body can exceed N on its long side; cap it so a bake
// never allocates more than the square window at the maximum resolution allows per row.
constexpr double kMaxWindowSide = 16384.0;
constexpr uint16_t kUnorm16MaxValid = 65534;

Status Invalid(std::string message) {
  return Status(StatusCode::kInvalidArgument, "BakeBodyMapPose: " + std::move(message));
}

// Smallest float >= x (x finite and within float range).
float RoundUpToFloat(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

Status ValidateOptions(const BodyMapOptions& o) {
  if (o.resolution < kMinResolution || o.resolution > kMaxResolution) {
    return Invalid("resolution " + std::to_string(o.resolution) + " is outside [16, 8192]");
  }
  if (!std::isfinite(o.epsilon) || o.epsilon < 0.f) {
    return Invalid("epsilon " + std::to_string(o.epsilon) + " must be finite and >= 0 (metres)");
  }
  if (!std::isfinite(o.margin) || o.margin < 0.f) {
    return Invalid("margin " + std::to_string(o.margin) + " must be finite and >= 0 (metres)");
  }
  if (o.depth_encoding != DepthEncoding::kFloat32 && o.depth_encoding != DepthEncoding::kUnorm16) {
    return Invalid("unknown depth encoding " + std::to_string(static_cast<int>(o.depth_encoding)));
  }
  if (static_cast<uint8_t>(o.view_axis) > 2) {
    return Invalid("unknown view axis " + std::to_string(static_cast<int>(o.view_axis)));
  }
  if (o.normal_encoding != NormalEncoding::kFloat32 &&
      o.normal_encoding != NormalEncoding::kOct16 && o.normal_encoding != NormalEncoding::kRgb8) {
    return Invalid("unknown normal encoding " +
                   std::to_string(static_cast<int>(o.normal_encoding)));
  }
  if (o.layout != BodyMapLayout::kDense && o.layout != BodyMapLayout::kRowSpans) {
    return Invalid("unknown layout " + std::to_string(static_cast<int>(o.layout)));
  }
  if (o.renderer != MapRenderer::kCpu && o.renderer != MapRenderer::kOsMesa) {
    return Invalid("unknown renderer " + std::to_string(static_cast<int>(o.renderer)));
  }
  if (o.layers < 1 || o.layers > kMaxBodyMapLayers) {
    return Invalid("layers " + std::to_string(o.layers) + " is outside [1, " +
                   std::to_string(kMaxBodyMapLayers) + "]");
  }
  return Status::Ok();
}

Status ValidateMesh(std::span<const Float3> positions, std::span<const uint32_t> triangles) {
  if (triangles.empty()) return Invalid("the mesh has no triangles");
  if (triangles.size() % 3 != 0) {
    return Invalid("triangle index count " + std::to_string(triangles.size()) +
                   " is not a multiple of 3");
  }
  for (size_t k = 0; k < triangles.size(); ++k) {
    if (triangles[k] >= positions.size()) {
      return Invalid("triangle " + std::to_string(k / 3) + " uses vertex " +
                     std::to_string(triangles[k]) + " but the mesh has " +
                     std::to_string(positions.size()) + " vertices");
    }
  }
  for (size_t v = 0; v < positions.size(); ++v) {
    const Float3 p = positions[v];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      return Invalid("vertex " + std::to_string(v) + " has a non-finite position");
    }
  }
  return Status::Ok();
}

// Area-weighted vertex normals (sum of the unnormalised face normals), normalised; zero where
// the sum vanishes. Double precision, triangle order: deterministic.
std::vector<double> AreaWeightedNormals(std::span<const Float3> positions,
                                        std::span<const uint32_t> triangles) {
  std::vector<double> normals(3 * positions.size(), 0.0);
  for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
    const Float3 a = positions[triangles[t]], b = positions[triangles[t + 1]],
                 c = positions[triangles[t + 2]];
    const double e1[3] = {double(b.x) - a.x, double(b.y) - a.y, double(b.z) - a.z};
    const double e2[3] = {double(c.x) - a.x, double(c.y) - a.y, double(c.z) - a.z};
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                         e1[0] * e2[1] - e1[1] * e2[0]};
    for (int k = 0; k < 3; ++k) {
      double* out = &normals[3 * triangles[t + k]];
      out[0] += n[0];
      out[1] += n[1];
      out[2] += n[2];
    }
  }
  for (size_t v = 0; v < positions.size(); ++v) {
    double* n = &normals[3 * v];
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (len > 0.0 && std::isfinite(len)) {
      n[0] /= len;
      n[1] /= len;
      n[2] /= len;
    } else {
      n[0] = n[1] = n[2] = 0.0;
    }
  }
  return normals;
}

double MillisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

double Sign(double x) { return x < 0.0 ? -1.0 : 1.0; }  // sign(0) = +1, as the decoder

// The documented oct16 decode without the final normalisation.
void DecodeOct16Unnormalised(uint32_t u, uint32_t v, double n[3]) {
  const double px = u / 65535.0 * 2.0 - 1.0, py = v / 65535.0 * 2.0 - 1.0;
  n[0] = px;
  n[1] = py;
  n[2] = 1.0 - std::fabs(px) - std::fabs(py);
  if (n[2] < 0.0) {
    n[0] = (1.0 - std::fabs(py)) * Sign(px);
    n[1] = (1.0 - std::fabs(px)) * Sign(py);
  }
}

// The request checks: a pose to fill, options in range, a well-formed mesh, the renderer built in.
Status ValidateRequest(std::span<const Float3> positions, std::span<const uint32_t> triangles,
                       const BodyMapOptions& options, const BodyMapPose* pose) {
  if (pose == nullptr) return Invalid("pose output is null");
  Status status = ValidateOptions(options);
  if (!status.ok()) return status;
  status = ValidateMesh(positions, triangles);
  if (!status.ok()) return status;
  if (options.renderer == MapRenderer::kOsMesa && !OsMesaCompiledIn()) {
    return Status(StatusCode::kInvalidState, "OSMesa renderer not available in this build");
  }
  return Status::Ok();
}

// Steps 1-2: vertex normals and the surface offset by epsilon along them, in double.
struct OffsetSurface {
  std::vector<double> normals;  // 3 per vertex, unit length or zero
  std::vector<double> offset;   // 3 per vertex, metres
};

OffsetSurface OffsetAlongNormals(std::span<const Float3> positions,
                                 std::span<const uint32_t> triangles,
                                 const BodyMapOptions& options) {
  OffsetSurface surface;
  const size_t vertex_count = positions.size();
  surface.normals = AreaWeightedNormals(positions, triangles);
  const std::vector<double>& normals = surface.normals;
  const double epsilon = options.epsilon;
  std::vector<double>& offset = surface.offset;
  offset.resize(3 * vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) {
    offset[3 * v] = positions[v].x + epsilon * normals[3 * v];
    offset[3 * v + 1] = positions[v].y + epsilon * normals[3 * v + 1];
    offset[3 * v + 2] = positions[v].z + epsilon * normals[3 * v + 2];
  }
  return surface;
}

// Step 3: the camera box and the two view planes, metres.
struct CameraBox {
  double lo[3], hi[3];              // AABB of the offset vertices the triangles use
  double box_lo[3], box_hi[3];      // the AABB enlarged by the margin
  double box_l = 0.0, box_h = 0.0;  // the box's extent in x and y
  float front_z = 0.f;              // the front view's plane: box_hi z rounded up to float
  float depth_range = 0.f;          // from the front plane to the back one, rounded up to float
  double back_z = 0.0;              // front_z - depth_range <= box_lo[2]
};

Status FitCameraBox(const OffsetSurface& surface, std::span<const uint32_t> triangles,
                    const BodyMapOptions& options, CameraBox* box) {
  const std::vector<double>& offset = surface.offset;
  double* lo = box->lo;
  double* hi = box->hi;
  for (int c = 0; c < 3; ++c) {
    lo[c] = std::numeric_limits<double>::infinity();
    hi[c] = -lo[c];
  }
  for (uint32_t v : triangles) {
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::min(lo[c], offset[3 * v + c]);
      hi[c] = std::max(hi[c], offset[3 * v + c]);
    }
  }
  const double margin = options.margin;
  double* box_lo = box->box_lo;
  double* box_hi = box->box_hi;
  for (int c = 0; c < 3; ++c) {
    box_lo[c] = lo[c] - margin;
    box_hi[c] = hi[c] + margin;
  }
  const double box_l = box_hi[0] - box_lo[0], box_h = box_hi[1] - box_lo[1];
  box->box_l = box_l;
  box->box_h = box_h;
  if (!(box_hi[2] - box_lo[2] > 0.0)) {
    return Invalid("the offset mesh is flat in z and margin is 0: depth_range would be 0");
  }
  if (!(box_l > 0.0) || !(box_h > 0.0)) {
    return Invalid("the offset mesh has no extent in x or y: it covers no texel");
  }
  const float front_z = RoundUpToFloat(box_hi[2]);
  const float depth_range = RoundUpToFloat(double(front_z) - box_lo[2]);
  if (!std::isfinite(front_z) || !std::isfinite(depth_range) || !std::isfinite(box_l) ||
      !std::isfinite(box_h) || !(std::max(box_l, box_h) < 1e30)) {
    return Invalid("the mesh extent does not fit in float (box " + std::to_string(box_l) + " x " +
                   std::to_string(box_h) + " m)");
  }
  box->front_z = front_z;
  box->depth_range = depth_range;
  box->back_z = double(front_z) - double(depth_range);
  return Status::Ok();
}

// Step 4: the window, its texel size, and the raster rectangle: the window texels that the offset
// surface can touch plus one texel of border on each side (so the crop of step 6 can keep a
// background border).
struct MapWindow {
  float texel_size = 0.f;                   // metres
  double t = 0.0;                           // texel_size in double
  double window_w = 0.0, window_h = 0.0;    // texels
  uint32_t raster_w = 0, raster_h = 0;      // texels of the raster rectangle
  double raster_x0 = 0.0, raster_y0 = 0.0;  // asset x and y of its corner, metres
};

Status PlaceWindow(const BodyMapOptions& options, const CameraBox& box, MapWindow* window) {
  const double box_l = box.box_l, box_h = box.box_h;
  const double n = options.resolution;
  const double texel_exact =
      options.fitted_window ? std::sqrt(box_l * box_h) / n : std::max(box_l, box_h) / n;
  const float texel_size = static_cast<float>(texel_exact);
  if (!(texel_size > 0.f) || !std::isfinite(texel_size)) {
    return Invalid("the texel size is not representable (mesh extent " + std::to_string(box_l) +
                   " x " + std::to_string(box_h) + " m)");
  }
  const double t = texel_size;
  double window_w = n, window_h = n;
  if (options.fitted_window) {
    window_w = std::max(1.0, std::ceil(box_l / t));
    window_h = std::max(1.0, std::ceil(box_h / t));
    if (window_w > kMaxWindowSide || window_h > kMaxWindowSide) {
      return Invalid("the fitted window would be " + std::to_string(window_w) + " x " +
                     std::to_string(window_h) + " texels (max 16384 per side); lower resolution");
    }
  }
  const double centre_x = 0.5 * (box.box_lo[0] + box.box_hi[0]);
  const double centre_y = 0.5 * (box.box_lo[1] + box.box_hi[1]);
  const double window_x0 = centre_x - 0.5 * window_w * t;
  const double window_y0 = centre_y - 0.5 * window_h * t;

  const double raster_i0 = std::floor((box.lo[0] - window_x0) / t) - 1.0;
  const double raster_i1 = std::floor((box.hi[0] - window_x0) / t) + 1.0;
  const double raster_j0 = std::floor((box.lo[1] - window_y0) / t) - 1.0;
  const double raster_j1 = std::floor((box.hi[1] - window_y0) / t) + 1.0;
  window->texel_size = texel_size;
  window->t = t;
  window->window_w = window_w;
  window->window_h = window_h;
  window->raster_w = static_cast<uint32_t>(raster_i1 - raster_i0 + 1.0);
  window->raster_h = static_cast<uint32_t>(raster_j1 - raster_j0 + 1.0);
  window->raster_x0 = window_x0 + raster_i0 * t;
  window->raster_y0 = window_y0 + raster_j0 * t;
  return Status::Ok();
}

// Step 5: per-vertex window coordinates and view depths. The returned request refers to
// `vertices` and `surface`, which must outlive it.
struct RasterVertices {
  std::vector<double> window_x, window_y;       // texel units of the raster rectangle
  std::vector<double> depth_front, depth_back;  // metres from each view's plane
};

MapRasterInput RasterRequest(const OffsetSurface& surface, std::span<const uint32_t> triangles,
                             const CameraBox& box, const MapWindow& window,
                             RasterVertices* vertices) {
  const std::vector<double>& offset = surface.offset;
  const size_t vertex_count = offset.size() / 3;
  const double t = window.t;
  std::vector<double>& window_x = vertices->window_x;
  std::vector<double>& window_y = vertices->window_y;
  std::vector<double>& depth_front = vertices->depth_front;
  std::vector<double>& depth_back = vertices->depth_back;
  window_x.resize(vertex_count);
  window_y.resize(vertex_count);
  depth_front.resize(vertex_count);
  depth_back.resize(vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) {
    window_x[v] = (offset[3 * v] - window.raster_x0) / t;
    window_y[v] = (offset[3 * v + 1] - window.raster_y0) / t;
    depth_front[v] = double(box.front_z) - offset[3 * v + 2];
    depth_back[v] = offset[3 * v + 2] - box.back_z;
  }
  MapRasterInput input;
  input.width = window.raster_w;
  input.height = window.raster_h;
  input.depth_range = box.depth_range;
  input.window_x = window_x;
  input.window_y = window_y;
  input.view_depth[0] = depth_front;
  input.view_depth[1] = depth_back;
  input.normals = surface.normals;
  input.positions = offset;
  input.triangles = triangles;
  return input;
}

// Both views of the raster rectangle, with the renderer's name and each view's wall time.
struct RenderedViews {
  MapViewImage images[2];
  double view_ms[2] = {0.0, 0.0};
  const char* renderer_name = "cpu";
};

Status RenderViews(const BodyMapOptions& options, const MapRasterInput& input,
                   RenderedViews* views) {
  if (options.renderer == MapRenderer::kCpu) {
    // Both views in one pass (the edge tests are shared); each view is charged half the time.
    const auto start = std::chrono::steady_clock::now();
    RasterizeViewsCpu(input, views->images);
    views->view_ms[0] = views->view_ms[1] = 0.5 * MillisecondsSince(start);
    return Status::Ok();
  }
  return RenderViewsOsMesa(input, views->images, views->view_ms, &views->renderer_name);
}

// Step 6: the texels both views cover, and the rectangle that keeps them with one texel of
// background border.
struct CoveredRectangle {
  uint32_t conflicts = 0;             // texels covered in exactly one view, made background in both
  size_t valid_count = 0;             // texels covered in both views
  uint32_t crop_i0 = 0, crop_j0 = 0;  // the rectangle's first texel in the raster
  uint32_t width = 0, height = 0;     // texels
};

Status ReconcileViews(const BodyMapOptions& options, const MapWindow& window,
                      MapViewImage images[2], CoveredRectangle* cover) {
  const uint32_t raster_w = window.raster_w, raster_h = window.raster_h;
  uint32_t conflicts = 0;
  size_t valid_count = 0;
  uint32_t cover_i0 = raster_w, cover_i1 = 0, cover_j0 = raster_h, cover_j1 = 0;
  for (uint32_t j = 0; j < raster_h; ++j) {
    for (uint32_t i = 0; i < raster_w; ++i) {
      const size_t index = static_cast<size_t>(j) * raster_w + i;
      const bool front = images[0].valid[index] != 0, back = images[1].valid[index] != 0;
      if (front != back) {
        images[0].valid[index] = 0;
        images[1].valid[index] = 0;
        ++conflicts;
        continue;
      }
      if (!front) continue;
      ++valid_count;
      cover_i0 = std::min(cover_i0, i);
      cover_i1 = std::max(cover_i1, i);
      cover_j0 = std::min(cover_j0, j);
      cover_j1 = std::max(cover_j1, j);
    }
  }
  if (valid_count == 0) {
    return Invalid("the mesh covers no texel centre at resolution " +
                   std::to_string(options.resolution) + " (texel " +
                   std::to_string(window.texel_size * 1000.f) + " mm)");
  }
  // One texel of background border where the raster rectangle has it (it always does: covered
  // centres lie inside the offset AABB, which is one texel inside the rectangle).
  const uint32_t crop_i0 = cover_i0 > 0 ? cover_i0 - 1 : 0;
  const uint32_t crop_j0 = cover_j0 > 0 ? cover_j0 - 1 : 0;
  const uint32_t crop_i1 = std::min(cover_i1 + 1, raster_w - 1);
  const uint32_t crop_j1 = std::min(cover_j1 + 1, raster_h - 1);
  cover->conflicts = conflicts;
  cover->valid_count = valid_count;
  cover->crop_i0 = crop_i0;
  cover->crop_j0 = crop_j0;
  cover->width = crop_i1 - crop_i0 + 1;
  cover->height = crop_j1 - crop_j0 + 1;
  return Status::Ok();
}

// Step 7: layer 0 of both views over the covered rectangle, dense, in the options' encodings.
// clip and time are the caller's.
BodyMapPose EncodeViews(const BodyMapPose& caller, const BodyMapOptions& options,
                        const CameraBox& box, const MapWindow& window,
                        const CoveredRectangle& cover, const MapViewImage images[2]) {
  const uint32_t width = cover.width, height = cover.height;
  const uint32_t crop_i0 = cover.crop_i0, crop_j0 = cover.crop_j0;
  const uint32_t raster_w = window.raster_w;
  const float depth_range = box.depth_range;
  BodyMapPose result;
  result.clip = caller.clip;
  result.time = caller.time;
  result.width = width;
  result.height = height;
  result.origin_x = static_cast<float>(window.raster_x0 + crop_i0 * window.t);
  result.origin_y = static_cast<float>(window.raster_y0 + crop_j0 * window.t);
  result.texel_size = window.texel_size;
  result.front_z = box.front_z;
  result.depth_range = depth_range;
  result.depth_encoding = options.depth_encoding;
  result.normal_encoding = options.normal_encoding;
  result.layers = options.layers;
  const size_t texels = static_cast<size_t>(width) * height;
  const float max_valid_depth = std::nextafter(depth_range, 0.f);
  for (int view = 0; view < 2; ++view) {
    switch (options.depth_encoding) {
      case DepthEncoding::kFloat32:
        result.depth_f32[view].assign(texels, depth_range);
        break;
      case DepthEncoding::kUnorm16:
        result.depth_u16[view].assign(texels, kUnorm16Background);
        break;
    }
    switch (options.normal_encoding) {
      case NormalEncoding::kFloat32:
        result.normal_f32[view].assign(3 * texels, 0.f);
        break;
      case NormalEncoding::kOct16:
        result.normal_oct16[view].assign(2 * texels, 0);
        break;
      case NormalEncoding::kRgb8:
        result.normal_rgb8[view].assign(3 * texels, 0);
        break;
    }
    const MapViewImage& image = images[view];
    // Rows are independent and every texel writes only its own slots: the result does not
    // depend on the thread count.
#pragma omp parallel for schedule(static)
    for (uint32_t j = 0; j < height; ++j) {
      for (uint32_t i = 0; i < width; ++i) {
        const size_t src = static_cast<size_t>(j + crop_j0) * raster_w + (i + crop_i0);
        if (!image.valid[src]) continue;
        const size_t dst = static_cast<size_t>(j) * width + i;
        WriteDepth(&result, view, dst, std::clamp(image.depth[src], 0.f, max_valid_depth));
        WriteNormal(&result, view, dst,
                    {image.normal[3 * src], image.normal[3 * src + 1], image.normal[3 * src + 2]});
      }
    }
  }
  return result;
}

// The report's numbers for one baked pose.
BodyMapPoseStats PoseStats(const BodyMapOptions& options, const MapWindow& window,
                           const CoveredRectangle& cover, const RenderedViews& views,
                           const GapCounts& gap_counts, double gap_ms, const BodyMapPose& result) {
  BodyMapPoseStats s;
  s.width = cover.width;
  s.height = cover.height;
  s.window_width = static_cast<uint32_t>(window.window_w);
  s.window_height = static_cast<uint32_t>(window.window_h);
  s.texel_size_mm = window.texel_size * 1000.f;
  s.coverage = static_cast<float>(static_cast<double>(cover.valid_count) /
                                  (window.window_w * window.window_h));
  s.valid_texels = cover.valid_count;
  for (int view = 0; view < 2; ++view) {
    s.bytes += result.depth_f32[view].size() * sizeof(float) +
               result.depth_u16[view].size() * sizeof(uint16_t) +
               result.normal_f32[view].size() * sizeof(float) +
               result.normal_oct16[view].size() * sizeof(uint16_t) +
               result.normal_rgb8[view].size() * sizeof(uint8_t);
  }
  s.stored_texels = BodyMapStoredTexels(result);
  s.bytes += result.row_span_offsets.size() * sizeof(uint32_t) +
             result.span_begin.size() * sizeof(uint16_t) +
             result.span_texel_offsets.size() * sizeof(uint32_t) +
             result.gap_texels.size() * sizeof(uint32_t);
  s.render_ms_front = views.view_ms[0] + 0.5 * gap_ms;
  s.render_ms_back = views.view_ms[1] + 0.5 * gap_ms;
  s.renderer = views.renderer_name;
  s.silhouette_conflicts = cover.conflicts;
  s.layers = options.layers;
  s.gap_texels = gap_counts.gap_texels;
  s.dropped_gaps = gap_counts.dropped_gaps;
  s.gap_ms = gap_ms;
  return s;
}

}  // namespace

bool OsMesaRendererAvailable() { return OsMesaCompiledIn(); }

OctNormal16 EncodeNormalOct16(Float3 unit_normal) {
  double n[3] = {unit_normal.x, unit_normal.y, unit_normal.z};
  const double l1 = std::fabs(n[0]) + std::fabs(n[1]) + std::fabs(n[2]);
  if (!(l1 > 0.0) || !std::isfinite(l1)) return {};
  const double inverse_l1 = 1.0 / l1;
  for (double& c : n) c *= inverse_l1;
  double px = n[0], py = n[1];
  if (n[2] < 0.0) {
    px = (1.0 - std::fabs(n[1])) * Sign(n[0]);
    py = (1.0 - std::fabs(n[0])) * Sign(n[1]);
  }
  // Round to the nearest code (angle error <= 0.004 degrees: the decoder's grid spacing is
  // 2/65535 on the octahedron).
  const double fu = std::clamp((px * 0.5 + 0.5) * 65535.0, 0.0, 65535.0);
  const double fv = std::clamp((py * 0.5 + 0.5) * 65535.0, 0.0, 65535.0);
  return {static_cast<uint16_t>(fu + 0.5), static_cast<uint16_t>(fv + 0.5)};  // fu, fv >= 0
}

Float3 DecodeNormalOct16(OctNormal16 code) {
  double n[3];
  DecodeOct16Unnormalised(code.u, code.v, n);
  const double inverse = 1.0 / std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  return {static_cast<float>(n[0] * inverse), static_cast<float>(n[1] * inverse),
          static_cast<float>(n[2] * inverse)};
}

void EncodeNormalRgb8(Float3 unit_normal, uint8_t rgb[3]) {
  const float n[3] = {unit_normal.x, unit_normal.y, unit_normal.z};
  for (int c = 0; c < 3; ++c) {
    const double value = std::clamp((double(n[c]) * 0.5 + 0.5) * 255.0, 0.0, 255.0);
    rgb[c] = static_cast<uint8_t>(value + 0.5);  // round half up; value >= 0
  }
}

Float3 DecodeNormalRgb8(const uint8_t rgb[3]) {
  double n[3];
  for (int c = 0; c < 3; ++c) n[c] = rgb[c] / 255.0 * 2.0 - 1.0;
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(len > 0.0)) return {0.f, 0.f, 0.f};
  const double inverse = 1.0 / len;
  return {static_cast<float>(n[0] * inverse), static_cast<float>(n[1] * inverse),
          static_cast<float>(n[2] * inverse)};
}

uint16_t EncodeDepthUnorm16(float depth, float depth_range) {
  const double scaled = std::clamp(double(depth) / depth_range * 65535.0, 0.0, 65535.0);
  return static_cast<uint16_t>(std::min(scaled + 0.5, double(kUnorm16MaxValid)));
}

float DecodeDepthUnorm16(uint16_t code, float depth_range) {
  return static_cast<float>(code * (double(depth_range) / 65535.0));
}

BodyMapTexel ReadBodyMapTexel(const BodyMapPose& pose, int view, uint32_t i, uint32_t j,
                              uint32_t layer) {
  BodyMapTexel texel;
  texel.depth = pose.depth_range;
  if (view < 0 || view > 1 || i >= pose.width || j >= pose.height) return texel;
  if (layer > 0 && layer >= pose.layers) return texel;
  const int64_t stored = BodyMapTexelIndex(pose, i, j);
  if (stored < 0) return texel;  // outside the spans: background
  size_t index = static_cast<size_t>(stored);
  if (layer > 0) {  // the texel's place in the gap list, if it has a gap
    const auto found = std::lower_bound(pose.gap_texels.begin(), pose.gap_texels.end(),
                                        static_cast<uint32_t>(index));
    if (found == pose.gap_texels.end() || *found != index) return texel;
    index = BodyMapStoredTexels(pose) + (layer - 1) * pose.gap_texels.size() +
            static_cast<size_t>(found - pose.gap_texels.begin());
  }
  if (pose.depth_encoding == DepthEncoding::kFloat32) {
    if (index >= pose.depth_f32[view].size()) return texel;
    texel.depth = pose.depth_f32[view][index];
    texel.valid = texel.depth < pose.depth_range;
  } else {
    if (index >= pose.depth_u16[view].size()) return texel;
    const uint16_t code = pose.depth_u16[view][index];
    texel.valid = code != kUnorm16Background;
    texel.depth = texel.valid ? DecodeDepthUnorm16(code, pose.depth_range) : pose.depth_range;
  }
  if (!texel.valid) return texel;
  switch (pose.normal_encoding) {
    case NormalEncoding::kFloat32:
      if (3 * index + 2 < pose.normal_f32[view].size()) {
        const float* n = &pose.normal_f32[view][3 * index];
        texel.normal = {n[0], n[1], n[2]};
      }
      break;
    case NormalEncoding::kOct16:
      if (2 * index + 1 < pose.normal_oct16[view].size()) {
        texel.normal = DecodeNormalOct16(
            {pose.normal_oct16[view][2 * index], pose.normal_oct16[view][2 * index + 1]});
      }
      break;
    case NormalEncoding::kRgb8:
      if (3 * index + 2 < pose.normal_rgb8[view].size()) {
        texel.normal = DecodeNormalRgb8(&pose.normal_rgb8[view][3 * index]);
      }
      break;
  }
  return texel;
}

Status BakeBodyMapPose(std::span<const Float3> positions, std::span<const uint32_t> triangles,
                       const BodyMapOptions& options, BodyMapPose* pose, BodyMapPoseStats* stats) {
  Status status = ValidateRequest(positions, triangles, options, pose);
  if (!status.ok()) return status;
  // Everything below works in the view frame, whose z' is the view axis (an exact permutation).
  std::vector<Float3> view_positions;
  if (options.view_axis != BodyMapViewAxis::kZ) {
    view_positions.reserve(positions.size());
    for (const Float3& p : positions) view_positions.push_back(ToBodyMapView(options.view_axis, p));
    positions = view_positions;
  }

  // Steps 1-7: the offset surface, its camera box and window, both views rendered, reconciled
  // and encoded as layer 0 (docs/ALGORITHMS.md §6.1-6.4, 6.6).
  const OffsetSurface surface = OffsetAlongNormals(positions, triangles, options);
  CameraBox box;
  status = FitCameraBox(surface, triangles, options, &box);
  if (!status.ok()) return status;
  MapWindow window;
  status = PlaceWindow(options, box, &window);
  if (!status.ok()) return status;
  RasterVertices vertices;
  const MapRasterInput input = RasterRequest(surface, triangles, box, window, &vertices);
  RenderedViews views;
  status = RenderViews(options, input, &views);
  if (!status.ok()) return status;
  CoveredRectangle cover;
  status = ReconcileViews(options, window, views.images, &cover);
  if (!status.ok()) return status;
  BodyMapPose result = EncodeViews(*pose, options, box, window, cover, views.images);
  result.view_axis = options.view_axis;

  // 8. Gap layers, from the CPU fragment pass whichever renderer drew layer 0.
  GapCounts gap_counts;
  double gap_ms = 0.0;
  if (options.layers > 1) {
    const auto start = std::chrono::steady_clock::now();
    status = BakeGapLayers(input, views.images[0].valid, cover.crop_i0, cover.crop_j0, &result,
                           &gap_counts);
    if (!status.ok()) return status;
    gap_ms = MillisecondsSince(start);
  }

  // The dense maps are complete; the row-span layout keeps exactly their non-background texels.
  if (options.layout == BodyMapLayout::kRowSpans) {
    BodyMapPose packed;
    status = ConvertBodyMapLayout(result, BodyMapLayout::kRowSpans, &packed);
    if (!status.ok()) return status;
    result = std::move(packed);
  }

  if (stats != nullptr)
    *stats = PoseStats(options, window, cover, views, gap_counts, gap_ms, result);
  *pose = std::move(result);
  return Status::Ok();
}

}  // namespace drape::bake

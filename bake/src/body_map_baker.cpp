#include "drape/bake/body_map_baker.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "cpu_rasterizer.h"
#include "osmesa_renderer.h"

namespace drape::bake {
namespace {

constexpr uint32_t kMinResolution = 16;
constexpr uint32_t kMaxResolution = 8192;
// The fitted window of a very elongated body can exceed N on its long side; cap it so a bake
// never allocates more than the square window at the maximum resolution allows per row.
constexpr double kMaxWindowSide = 16384.0;
constexpr uint16_t kUnorm16Background = 65535;
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

BodyMapTexel ReadBodyMapTexel(const BodyMapPose& pose, int view, uint32_t i, uint32_t j) {
  BodyMapTexel texel;
  texel.depth = pose.depth_range;
  if (view < 0 || view > 1 || i >= pose.width || j >= pose.height) return texel;
  const int64_t stored = BodyMapTexelIndex(pose, i, j);
  if (stored < 0) return texel;  // outside the spans: background
  const size_t index = static_cast<size_t>(stored);
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
  if (pose == nullptr) return Invalid("pose output is null");
  Status status = ValidateOptions(options);
  if (!status.ok()) return status;
  status = ValidateMesh(positions, triangles);
  if (!status.ok()) return status;
  if (options.renderer == MapRenderer::kOsMesa && !OsMesaCompiledIn()) {
    return Status(StatusCode::kInvalidState, "OSMesa renderer not available in this build");
  }

  // 1-2. Vertex normals and the offset surface, in double.
  const size_t vertex_count = positions.size();
  const std::vector<double> normals = AreaWeightedNormals(positions, triangles);
  const double epsilon = options.epsilon;
  std::vector<double> offset(3 * vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) {
    offset[3 * v] = positions[v].x + epsilon * normals[3 * v];
    offset[3 * v + 1] = positions[v].y + epsilon * normals[3 * v + 1];
    offset[3 * v + 2] = positions[v].z + epsilon * normals[3 * v + 2];
  }

  // 3. The box: AABB of the offset vertices the triangles use, enlarged by the margin.
  double lo[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity()};
  double hi[3] = {-lo[0], -lo[1], -lo[2]};
  for (uint32_t v : triangles) {
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::min(lo[c], offset[3 * v + c]);
      hi[c] = std::max(hi[c], offset[3 * v + c]);
    }
  }
  const double margin = options.margin;
  const double box_lo[3] = {lo[0] - margin, lo[1] - margin, lo[2] - margin};
  const double box_hi[3] = {hi[0] + margin, hi[1] + margin, hi[2] + margin};
  const double box_l = box_hi[0] - box_lo[0], box_h = box_hi[1] - box_lo[1];
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
  const double back_z = double(front_z) - double(depth_range);  // <= box_lo[2]

  // 4. Window and texel size.
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
  const double centre_x = 0.5 * (box_lo[0] + box_hi[0]);
  const double centre_y = 0.5 * (box_lo[1] + box_hi[1]);
  const double window_x0 = centre_x - 0.5 * window_w * t;
  const double window_y0 = centre_y - 0.5 * window_h * t;

  // The raster rectangle: the window texels that the offset surface can touch plus one texel
  // of border on each side (so the crop below can keep a background border).
  const double raster_i0 = std::floor((lo[0] - window_x0) / t) - 1.0;
  const double raster_i1 = std::floor((hi[0] - window_x0) / t) + 1.0;
  const double raster_j0 = std::floor((lo[1] - window_y0) / t) - 1.0;
  const double raster_j1 = std::floor((hi[1] - window_y0) / t) + 1.0;
  const uint32_t raster_w = static_cast<uint32_t>(raster_i1 - raster_i0 + 1.0);
  const uint32_t raster_h = static_cast<uint32_t>(raster_j1 - raster_j0 + 1.0);
  const double raster_x0 = window_x0 + raster_i0 * t;
  const double raster_y0 = window_y0 + raster_j0 * t;

  // 5. Per-vertex window coordinates and view depths.
  std::vector<double> window_x(vertex_count), window_y(vertex_count);
  std::vector<double> depth_front(vertex_count), depth_back(vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) {
    window_x[v] = (offset[3 * v] - raster_x0) / t;
    window_y[v] = (offset[3 * v + 1] - raster_y0) / t;
    depth_front[v] = double(front_z) - offset[3 * v + 2];
    depth_back[v] = offset[3 * v + 2] - back_z;
  }
  MapRasterInput input;
  input.width = raster_w;
  input.height = raster_h;
  input.depth_range = depth_range;
  input.window_x = window_x;
  input.window_y = window_y;
  input.view_depth[0] = depth_front;
  input.view_depth[1] = depth_back;
  input.normals = normals;
  input.positions = offset;
  input.triangles = triangles;

  MapViewImage images[2];
  double view_ms[2] = {0.0, 0.0};
  const char* renderer_name = "cpu";
  if (options.renderer == MapRenderer::kCpu) {
    // Both views in one pass (the edge tests are shared); each view is charged half the time.
    const auto start = std::chrono::steady_clock::now();
    RasterizeViewsCpu(input, images);
    view_ms[0] = view_ms[1] = 0.5 * MillisecondsSince(start);
  } else {
    status = RenderViewsOsMesa(input, images, view_ms, &renderer_name);
    if (!status.ok()) return status;
  }

  // 6. Consistency between the views, and the covered rectangle.
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
                   std::to_string(texel_size * 1000.f) + " mm)");
  }
  // One texel of background border where the raster rectangle has it (it always does: covered
  // centres lie inside the offset AABB, which is one texel inside the rectangle).
  const uint32_t crop_i0 = cover_i0 > 0 ? cover_i0 - 1 : 0;
  const uint32_t crop_j0 = cover_j0 > 0 ? cover_j0 - 1 : 0;
  const uint32_t crop_i1 = std::min(cover_i1 + 1, raster_w - 1);
  const uint32_t crop_j1 = std::min(cover_j1 + 1, raster_h - 1);
  const uint32_t width = crop_i1 - crop_i0 + 1, height = crop_j1 - crop_j0 + 1;

  // 7. Encode.
  BodyMapPose result;
  result.clip = pose->clip;
  result.time = pose->time;
  result.width = width;
  result.height = height;
  result.origin_x = static_cast<float>(raster_x0 + crop_i0 * t);
  result.origin_y = static_cast<float>(raster_y0 + crop_j0 * t);
  result.texel_size = texel_size;
  result.front_z = front_z;
  result.depth_range = depth_range;
  result.depth_encoding = options.depth_encoding;
  result.normal_encoding = options.normal_encoding;
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
        const float depth = std::clamp(image.depth[src], 0.f, max_valid_depth);
        if (options.depth_encoding == DepthEncoding::kFloat32) {
          result.depth_f32[view][dst] = depth;
        } else {
          result.depth_u16[view][dst] = EncodeDepthUnorm16(depth, depth_range);
        }
        const Float3 normal = {image.normal[3 * src], image.normal[3 * src + 1],
                               image.normal[3 * src + 2]};
        switch (options.normal_encoding) {
          case NormalEncoding::kFloat32:
            result.normal_f32[view][3 * dst] = normal.x;
            result.normal_f32[view][3 * dst + 1] = normal.y;
            result.normal_f32[view][3 * dst + 2] = normal.z;
            break;
          case NormalEncoding::kOct16: {
            const OctNormal16 code = EncodeNormalOct16(normal);
            result.normal_oct16[view][2 * dst] = code.u;
            result.normal_oct16[view][2 * dst + 1] = code.v;
            break;
          }
          case NormalEncoding::kRgb8:
            EncodeNormalRgb8(normal, &result.normal_rgb8[view][3 * dst]);
            break;
        }
      }
    }
  }

  // The dense maps are complete; the row-span layout keeps exactly their non-background texels.
  if (options.layout == BodyMapLayout::kRowSpans) {
    BodyMapPose packed;
    status = ConvertBodyMapLayout(result, BodyMapLayout::kRowSpans, &packed);
    if (!status.ok()) return status;
    result = std::move(packed);
  }

  if (stats != nullptr) {
    BodyMapPoseStats s;
    s.width = width;
    s.height = height;
    s.window_width = static_cast<uint32_t>(window_w);
    s.window_height = static_cast<uint32_t>(window_h);
    s.texel_size_mm = texel_size * 1000.f;
    s.coverage = static_cast<float>(static_cast<double>(valid_count) / (window_w * window_h));
    s.valid_texels = valid_count;
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
               result.span_texel_offsets.size() * sizeof(uint32_t);
    s.render_ms_front = view_ms[0];
    s.render_ms_back = view_ms[1];
    s.renderer = renderer_name;
    s.silhouette_conflicts = conflicts;
    *stats = s;
  }
  *pose = std::move(result);
  return Status::Ok();
}

}  // namespace drape::bake

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
#include "body_map/osmesa_renderer.h"
#include "drape/runtime/normal_encoding.h"

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

// Writes a valid depth (metres from the view's plane, in [0, depth_range)) at array entry
// `entry` of `view` in the pose's depth encoding.
void WriteDepth(BodyMapPose* pose, int view, size_t entry, float depth) {
  if (pose->depth_encoding == DepthEncoding::kFloat32) {
    pose->depth_f32[view][entry] = depth;
  } else {
    pose->depth_u16[view][entry] = EncodeDepthUnorm16(depth, pose->depth_range);
  }
}

void WriteBackgroundDepth(BodyMapPose* pose, int view, size_t entry) {
  if (pose->depth_encoding == DepthEncoding::kFloat32) {
    pose->depth_f32[view][entry] = pose->depth_range;
  } else {
    pose->depth_u16[view][entry] = kUnorm16Background;
  }
}

// Writes a unit normal at array entry `entry` of `view` in the pose's normal encoding.
void WriteNormal(BodyMapPose* pose, int view, size_t entry, Float3 normal) {
  switch (pose->normal_encoding) {
    case NormalEncoding::kFloat32:
      pose->normal_f32[view][3 * entry] = normal.x;
      pose->normal_f32[view][3 * entry + 1] = normal.y;
      pose->normal_f32[view][3 * entry + 2] = normal.z;
      break;
    case NormalEncoding::kOct16: {
      const OctNormal16 code = EncodeNormalOct16(normal);
      pose->normal_oct16[view][2 * entry] = code.u;
      pose->normal_oct16[view][2 * entry + 1] = code.v;
      break;
    }
    case NormalEncoding::kRgb8:
      EncodeNormalRgb8(normal, &pose->normal_rgb8[view][3 * entry]);
      break;
  }
}

// --- Step 8: gap layers ---

struct Fragment {
  double depth;  // metres from the front plane
  uint32_t triangle;
  int8_t facing;  // +1 the ray along -z enters the body, -1 it leaves
};

// Front to back; at equal depth entering first (touching parts and zero-thickness slivers then
// make neither a negative count nor an empty gap), then by triangle: a total order, since a
// triangle covers a texel centre at most once.
bool FrontToBack(const Fragment& a, const Fragment& b) {
  if (a.depth != b.depth) return a.depth < b.depth;
  if (a.facing != b.facing) return a.facing > b.facing;
  return a.triangle < b.triangle;
}

struct GapCandidate {
  uint32_t upper;    // index in the sorted fragments of the leaving fragment; upper + 1 enters
  double thickness;  // metres
};

// The winding sweep of one texel's sorted fragments: appends its gaps thicker than
// kMinBodyMapGap to *gaps, front to back. Returns false, appending nothing, when the count goes
// negative or does not end at 0 (the texel keeps paper A's slab).
bool SweepWinding(std::span<const Fragment> sorted, std::vector<GapCandidate>* gaps) {
  const size_t first = gaps->size();
  int count = 0;
  for (size_t k = 0; k < sorted.size(); ++k) {
    count += sorted[k].facing;
    if (count < 0) break;
    // count == 0 before the last fragment: air up to the next fragment, which must enter (a
    // leaving one would make the count negative).
    if (count == 0 && k + 1 < sorted.size()) {
      const double thickness = sorted[k + 1].depth - sorted[k].depth;
      if (thickness > kMinBodyMapGap) {
        gaps->push_back({static_cast<uint32_t>(k), thickness});
      }
    }
  }
  if (count != 0) {
    gaps->resize(first);
    return false;
  }
  return true;
}

// Keeps the `keep` thickest of *gaps (equal thickness: the nearer), still front to back.
void KeepThickest(std::vector<GapCandidate>* gaps, size_t keep) {
  if (gaps->size() <= keep) return;
  std::sort(gaps->begin(), gaps->end(), [](const GapCandidate& a, const GapCandidate& b) {
    if (a.thickness != b.thickness) return a.thickness > b.thickness;
    return a.upper < b.upper;
  });
  gaps->resize(keep);
  std::sort(gaps->begin(), gaps->end(),
            [](const GapCandidate& a, const GapCandidate& b) { return a.upper < b.upper; });
}

// The decoded depth (metres from the view's plane) of array entry `entry` of `view`; for unorm16
// either the documented decoder (in double, DecodeDepthUnorm16) or the same formula in float
// (code / 65535 * depth_range), which a reader may use instead: the nesting check must hold for
// both.
float DecodedDepth(const BodyMapPose& pose, int view, size_t entry, bool float_decoder) {
  if (pose.depth_encoding == DepthEncoding::kFloat32) return pose.depth_f32[view][entry];
  const uint16_t code = pose.depth_u16[view][entry];
  return float_decoder ? static_cast<float>(code) / 65535.f * pose.depth_range
                       : DecodeDepthUnorm16(code, pose.depth_range);
}

// Decoded depths of one texel, metres from each view's plane: the slab (top from the front,
// bottom from the back), a gap (upper from the front, lower from the back) and the floor above
// the gap (the previous kept gap's lower, from the back; has_floor false for the first gap).
struct NestingDepths {
  float top = 0.f, bottom = 0.f, upper = 0.f, lower = 0.f, floor = 0.f;
  bool has_floor = false;
};

// top > upper > lower > bottom and floor (if any) > upper in asset z, computed exactly (double) and
// as a float reader would (front_z - d, and (front_z - depth_range) + d, each rounded to float).
bool StrictlyNested(const NestingDepths& d, float front_z, float depth_range) {
  const double back_z = double(front_z) - double(depth_range);
  const double top = double(front_z) - d.top, upper = double(front_z) - d.upper;
  const double lower = back_z + d.lower, bottom = back_z + d.bottom;
  const double ceiling = d.has_floor ? back_z + d.floor : top;
  if (!(ceiling > upper && upper > lower && lower > bottom)) return false;
  const float back_zf = front_z - depth_range;
  const float top_f = front_z - d.top, upper_f = front_z - d.upper;
  const float lower_f = back_zf + d.lower, bottom_f = back_zf + d.bottom;
  const float ceiling_f = d.has_floor ? back_zf + d.floor : top_f;
  return ceiling_f > upper_f && upper_f > lower_f && lower_f > bottom_f;
}

struct GapCounts {
  size_t gap_texels = 0;
  size_t dropped_gaps = 0;
};

// Appends one background entry (depth: depth_range or 65535; normal: zeros) to every array of
// the pose's encodings.
void AppendBackground(BodyMapPose* pose) {
  for (int view = 0; view < 2; ++view) {
    if (pose->depth_encoding == DepthEncoding::kFloat32) {
      pose->depth_f32[view].push_back(pose->depth_range);
    } else {
      pose->depth_u16[view].push_back(kUnorm16Background);
    }
    switch (pose->normal_encoding) {
      case NormalEncoding::kFloat32:
        pose->normal_f32[view].insert(pose->normal_f32[view].end(), 3, 0.f);
        break;
      case NormalEncoding::kOct16:
        pose->normal_oct16[view].insert(pose->normal_oct16[view].end(), 2, uint16_t{0});
        break;
      case NormalEncoding::kRgb8:
        pose->normal_rgb8[view].insert(pose->normal_rgb8[view].end(), 3, uint8_t{0});
        break;
    }
  }
}

// Removes the last entry AppendBackground() added.
void PopEntry(BodyMapPose* pose) {
  for (int view = 0; view < 2; ++view) {
    if (!pose->depth_f32[view].empty()) pose->depth_f32[view].pop_back();
    if (!pose->depth_u16[view].empty()) pose->depth_u16[view].pop_back();
    if (!pose->normal_f32[view].empty())
      pose->normal_f32[view].resize(pose->normal_f32[view].size() - 3);
    if (!pose->normal_oct16[view].empty())
      pose->normal_oct16[view].resize(pose->normal_oct16[view].size() - 2);
    if (!pose->normal_rgb8[view].empty())
      pose->normal_rgb8[view].resize(pose->normal_rgb8[view].size() - 3);
  }
}

// Appends the arrays of `from` to those of `to`.
void AppendArrays(const BodyMapPose& from, BodyMapPose* to) {
  const auto append = [](const auto& src, auto& dst) {
    dst.insert(dst.end(), src.begin(), src.end());
  };
  for (int view = 0; view < 2; ++view) {
    append(from.depth_f32[view], to->depth_f32[view]);
    append(from.depth_u16[view], to->depth_u16[view]);
    append(from.normal_f32[view], to->normal_f32[view]);
    append(from.normal_oct16[view], to->normal_oct16[view]);
    append(from.normal_rgb8[view], to->normal_rgb8[view]);
  }
}

// Step 8 over the cropped rectangle of a dense pose whose layer 0 is encoded (its arrays hold
// exactly its width * height texels): fills pose->gap_texels and appends the gap layers' entries
// to every array. `valid` is layer 0's validity per raster texel (after step 6); crop_i0/crop_j0
// place the pose's texel (0, 0) in the raster.
Status BakeGapLayers(const MapRasterInput& input, std::span<const uint8_t> valid, uint32_t crop_i0,
                     uint32_t crop_j0, BodyMapPose* pose, GapCounts* out) {
  // A gap needs 4 fragments: enter, leave, enter, leave.
  constexpr uint32_t kMinGapFragments = 4;
  GapCounts counts;
  MapFragments fragments;
  if (!CollectFragmentsCpu(input, kMinGapFragments, &fragments)) {
    return Invalid(
        "the gap layers would need more than 2^32 - 1 fragments (triangles covering "
        "a texel centre); lower the resolution or set layers to 1");
  }
  const size_t max_gaps = pose->layers - 1u;
  const float max_valid_depth = std::nextafter(pose->depth_range, 0.f);
  // The gap layers k = 1 .. layers - 1, one entry per texel of pose->gap_texels, each held as a
  // pose with only those arrays (so the encoders and decoders above apply).
  BodyMapPose gap_layers[kMaxBodyMapLayers - 1];
  for (size_t k = 0; k < max_gaps; ++k) {
    gap_layers[k].depth_range = pose->depth_range;
    gap_layers[k].depth_encoding = pose->depth_encoding;
    gap_layers[k].normal_encoding = pose->normal_encoding;
  }
  pose->gap_texels.clear();
  std::vector<Fragment> sorted;
  std::vector<GapCandidate> gaps;
  for (uint32_t j = 0; j < pose->height; ++j) {
    for (uint32_t i = 0; i < pose->width; ++i) {
      const uint32_t raster_i = i + crop_i0, raster_j = j + crop_j0;
      const size_t src = static_cast<size_t>(raster_j) * input.width + raster_i;
      const uint32_t begin = fragments.offsets[src], end = fragments.offsets[src + 1];
      if (end - begin < kMinGapFragments) continue;
      sorted.clear();
      for (uint32_t f = begin; f < end; ++f) {
        sorted.push_back({fragments.depth[f], fragments.triangle[f], fragments.facing[f]});
      }
      std::sort(sorted.begin(), sorted.end(), FrontToBack);
      gaps.clear();
      if (!SweepWinding(sorted, &gaps) || gaps.empty()) continue;
      if (!valid[src]) {  // background in layer 0 (OSMesa's coverage differs from the CPU's)
        counts.dropped_gaps += gaps.size();
        continue;
      }
      counts.dropped_gaps += gaps.size() > max_gaps ? gaps.size() - max_gaps : 0;
      KeepThickest(&gaps, max_gaps);
      const size_t dst = static_cast<size_t>(j) * pose->width + i;  // dense: also layer 0's entry
      NestingDepths depths[2];  // [0] documented decoder, [1] float decoder
      for (int decoder = 0; decoder < 2; ++decoder) {
        depths[decoder].top = DecodedDepth(*pose, 0, dst, decoder == 1);
        depths[decoder].bottom = DecodedDepth(*pose, 1, dst, decoder == 1);
      }
      const size_t entry = pose->gap_texels.size();  // this texel's entry in every gap layer
      for (size_t k = 0; k < max_gaps; ++k) AppendBackground(&gap_layers[k]);
      size_t stored = 0;  // gaps stored at this texel: the next one goes to gap_layers[stored]
      for (const GapCandidate& gap : gaps) {
        BodyMapPose* layer = &gap_layers[stored];
        const Fragment& upper = sorted[gap.upper];
        const Fragment& lower = sorted[gap.upper + 1];
        const double lower_depth = FragmentDepth(input, 1, lower.triangle, raster_i, raster_j);
        WriteDepth(layer, 0, entry,
                   std::clamp(static_cast<float>(upper.depth), 0.f, max_valid_depth));
        WriteDepth(layer, 1, entry,
                   std::clamp(static_cast<float>(lower_depth), 0.f, max_valid_depth));
        bool nested = true;
        for (int decoder = 0; decoder < 2; ++decoder) {
          depths[decoder].upper = DecodedDepth(*layer, 0, entry, decoder == 1);
          depths[decoder].lower = DecodedDepth(*layer, 1, entry, decoder == 1);
          nested = nested && StrictlyNested(depths[decoder], pose->front_z, pose->depth_range);
        }
        if (!nested) {  // restore the background; a later gap may take this layer
          WriteBackgroundDepth(layer, 0, entry);
          WriteBackgroundDepth(layer, 1, entry);
          ++counts.dropped_gaps;
          continue;
        }
        float normal[3];
        FragmentNormal(input, upper.triangle, raster_i, raster_j, -1.0, normal);
        WriteNormal(layer, 0, entry, {normal[0], normal[1], normal[2]});
        FragmentNormal(input, lower.triangle, raster_i, raster_j, 1.0, normal);
        WriteNormal(layer, 1, entry, {normal[0], normal[1], normal[2]});
        for (NestingDepths& d : depths) {
          d.floor = d.lower;
          d.has_floor = true;
        }
        ++stored;
      }
      if (stored == 0) {  // every gap was dropped: the texel is not listed
        for (size_t k = 0; k < max_gaps; ++k) PopEntry(&gap_layers[k]);
        continue;
      }
      pose->gap_texels.push_back(static_cast<uint32_t>(dst));
      ++counts.gap_texels;
    }
  }
  for (size_t k = 0; k < max_gaps; ++k) AppendArrays(gap_layers[k], pose);
  *out = counts;
  return Status::Ok();
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

  // 8. Gap layers, from the CPU fragment pass whichever renderer drew layer 0.
  GapCounts gap_counts;
  double gap_ms = 0.0;
  if (options.layers > 1) {
    const auto start = std::chrono::steady_clock::now();
    status = BakeGapLayers(input, images[0].valid, crop_i0, crop_j0, &result, &gap_counts);
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
               result.span_texel_offsets.size() * sizeof(uint32_t) +
               result.gap_texels.size() * sizeof(uint32_t);
    s.render_ms_front = view_ms[0] + 0.5 * gap_ms;
    s.render_ms_back = view_ms[1] + 0.5 * gap_ms;
    s.renderer = renderer_name;
    s.silhouette_conflicts = conflicts;
    s.layers = options.layers;
    s.gap_texels = gap_counts.gap_texels;
    s.dropped_gaps = gap_counts.dropped_gaps;
    s.gap_ms = gap_ms;
    *stats = s;
  }
  *pose = std::move(result);
  return Status::Ok();
}

}  // namespace drape::bake

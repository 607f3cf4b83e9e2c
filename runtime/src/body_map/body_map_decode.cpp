// BodyMapCollider::Build: the checks of an untrusted pose and its decoding into the collider's
// layout (slabs, oct16 normals, the gaps of the texels that have them).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <new>
#include <string>
#include <vector>

#include "drape/runtime/body_map_collider.h"
#include "drape/runtime/normal_encoding.h"

namespace drape {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr uint32_t kMaxMapSide = 1u << 16;  // texels per side accepted by Build

std::string DescribePose(const BodyMapPose& pose) {
  return "body map pose (clip " + std::to_string(pose.clip) + ", t=" + std::to_string(pose.time) +
         ", " + std::to_string(pose.width) + "x" + std::to_string(pose.height) + ")";
}

// Why the pose's sizes, floats, sampling or layer count cannot be built ("" when they can).
std::string CheckPoseHeader(const BodyMapPose& pose, DepthSampling sampling) {
  if (pose.width == 0 || pose.height == 0 || pose.width > kMaxMapSide ||
      pose.height > kMaxMapSide) {
    return "width and height must be in [1, " + std::to_string(kMaxMapSide) + "]";
  }
  if (!(std::isfinite(pose.texel_size) && pose.texel_size > 0.f)) {
    return "texel_size must be finite and > 0";
  }
  if (!(std::isfinite(pose.depth_range) && pose.depth_range > 0.f)) {
    return "depth_range must be finite and > 0";
  }
  if (!std::isfinite(pose.origin_x) || !std::isfinite(pose.origin_y) ||
      !std::isfinite(pose.front_z)) {
    return "origin and front_z must be finite";
  }
  if (sampling != DepthSampling::kNearest && sampling != DepthSampling::kBilinear) {
    return "unknown depth sampling";
  }
  if (pose.layers < 1 || pose.layers > kMaxBodyMapLayers) {
    return "layers = " + std::to_string(pose.layers) + " is outside [1, " +
           std::to_string(kMaxBodyMapLayers) + "]";
  }
  if (static_cast<uint8_t>(pose.view_axis) > 2) {
    return "view_axis = " + std::to_string(static_cast<int>(pose.view_axis)) +
           " is not 0 (z), 1 (x) or 2 (y)";
  }
  return CheckBodyMapLayout(pose);
}

// Why the arrays of a dense pose do not hold exactly what its encodings and layers need ("" when
// they do): exactly the arrays of the chosen encodings are filled (body_map_data.h).
std::string CheckArraySizes(const BodyMapPose& pose) {
  const size_t n = static_cast<size_t>(pose.width) * pose.height;
  const size_t layers = pose.layers;
  const size_t gap_texels = pose.gap_texels.size();
  // Per array: layer 0 of every texel, then the gap layers of the listed texels.
  const size_t values = n + (layers - 1) * gap_texels;
  const char* view_name[2] = {"front", "back"};
  for (int view = 0; view < 2; ++view) {
    const std::string name = view_name[view];
    size_t depth_f32 = 0, depth_u16 = 0;
    switch (pose.depth_encoding) {
      case DepthEncoding::kFloat32:
        depth_f32 = values;
        break;
      case DepthEncoding::kUnorm16:
        depth_u16 = values;
        break;
      default:
        return "unknown depth encoding";
    }
    if (pose.depth_f32[view].size() != depth_f32 || pose.depth_u16[view].size() != depth_u16) {
      return name + " depth arrays hold " + std::to_string(pose.depth_f32[view].size()) +
             " float32 / " + std::to_string(pose.depth_u16[view].size()) +
             " unorm16 values, expected " + std::to_string(depth_f32) + " / " +
             std::to_string(depth_u16) + " for width*height=" + std::to_string(n) + ", " +
             std::to_string(layers) + " layer(s) and " + std::to_string(gap_texels) + " gap texels";
    }
    size_t normal_f32 = 0, normal_oct16 = 0, normal_rgb8 = 0;
    switch (pose.normal_encoding) {
      case NormalEncoding::kFloat32:
        normal_f32 = 3 * values;
        break;
      case NormalEncoding::kOct16:
        normal_oct16 = 2 * values;
        break;
      case NormalEncoding::kRgb8:
        normal_rgb8 = 3 * values;
        break;
      default:
        return "unknown normal encoding";
    }
    if (pose.normal_f32[view].size() != normal_f32 ||
        pose.normal_oct16[view].size() != normal_oct16 ||
        pose.normal_rgb8[view].size() != normal_rgb8) {
      return name + " normal arrays hold " + std::to_string(pose.normal_f32[view].size()) +
             " float32 / " + std::to_string(pose.normal_oct16[view].size()) + " oct16 / " +
             std::to_string(pose.normal_rgb8[view].size()) + " rgb8 values, expected " +
             std::to_string(normal_f32) + " / " + std::to_string(normal_oct16) + " / " +
             std::to_string(normal_rgb8);
    }
  }
  return "";
}

}  // namespace

// Reads the values of a dense pose whose array sizes passed CheckArraySizes. A corrupt value
// (a NaN or negative depth, a non-finite float normal, a misplaced gap) stops the decoding with
// `problem` saying where and why.
struct BodyMapCollider::Decoder {
  explicit Decoder(const BodyMapPose& p)
      : pose(p), n(static_cast<size_t>(p.width) * p.height), gap_list(p.gap_texels) {}

  const BodyMapPose& pose;
  const size_t n;                         // texels of the rectangle
  const std::vector<uint32_t>& gap_list;  // dense texel indices of the texels with gaps
  std::string problem;

  // Array entry `index` of one view: layer 0 of every texel, then the gap layers of the listed
  // texels.
  std::string Where(int view, size_t index) const {
    const char* view_name[2] = {"front", "back"};
    if (index < n) return std::string(view_name[view]) + " at texel " + std::to_string(index);
    const size_t layer = (index - n) / gap_list.size() + 1, t = (index - n) % gap_list.size();
    return std::string(view_name[view]) + " gap layer " + std::to_string(layer) + " at texel " +
           std::to_string(gap_list[t]);
  }

  bool ReadDepth(int view, size_t index, float* depth, bool* valid) {
    if (pose.depth_encoding == DepthEncoding::kFloat32) {
      const float d = pose.depth_f32[view][index];
      if (std::isnan(d) || d < 0.f) {
        problem = Where(view, index) + ": depth is NaN or negative";
        return false;
      }
      *valid = d < pose.depth_range;  // +inf and >= depth_range are background
      *depth = d;
    } else {
      const uint16_t q = pose.depth_u16[view][index];
      *valid = q != 65535;
      *depth = static_cast<float>(q) / 65535.f * pose.depth_range;
    }
    return true;
  }

  // Normals are kept as oct16 whatever the input encoding.
  bool ReadNormal(int view, size_t index, uint16_t oct[2]) {
    const Float3 view_fallback{0.f, 0.f, view == 0 ? 1.f : -1.f};
    if (pose.normal_encoding == NormalEncoding::kOct16) {
      oct[0] = pose.normal_oct16[view][2 * index];
      oct[1] = pose.normal_oct16[view][2 * index + 1];
      return true;
    }
    Float3 normal;
    if (pose.normal_encoding == NormalEncoding::kFloat32) {
      const float* f = &pose.normal_f32[view][3 * index];
      normal = {f[0], f[1], f[2]};
      if (!IsFinite(normal)) {
        problem = Where(view, index) + ": normal is not finite";
        return false;
      }
      normal = NormalizeOr(normal, view_fallback);
    } else {
      const uint8_t* c = &pose.normal_rgb8[view][3 * index];
      const Float3 raw{static_cast<float>(c[0]) / 255.f * 2.f - 1.f,
                       static_cast<float>(c[1]) / 255.f * 2.f - 1.f,
                       static_cast<float>(c[2]) / 255.f * 2.f - 1.f};
      normal = NormalizeOr(raw, view_fallback);
    }
    const std::array<uint16_t, 2> q = EncodeOct16(normal);
    oct[0] = q[0];
    oct[1] = q[1];
    return true;
  }

  // Every texel's slab (top and bottom z; background where a map is invalid or the surfaces are
  // inverted, counted in the stats) and normals into c.
  bool DecodeSlabs(BodyMapCollider* c) {
    c->slabs_.resize(n);
    c->normals_.resize(n);
    const float back_plane_z = pose.front_z - pose.depth_range;
    for (size_t k = 0; k < n; ++k) {
      float depth[2];
      bool valid[2];
      for (int view = 0; view < 2; ++view) {
        if (!ReadDepth(view, k, &depth[view], &valid[view])) return false;
      }
      Slab slab{-kInf, kInf};
      if (valid[0] && valid[1]) {
        const float top = pose.front_z - depth[0];
        const float bottom = back_plane_z + depth[1];
        if (top >= bottom) {
          slab = {top, bottom};
        } else {
          ++c->stats_.inverted_texels;
        }
      } else if (valid[0] != valid[1]) {
        ++c->stats_.one_sided_texels;  // a silhouette disagreement: background
      }
      c->slabs_[k] = slab;
      if (!ReadNormal(0, k, c->normals_[k].front) || !ReadNormal(1, k, c->normals_[k].back)) {
        return false;
      }
    }
    return true;
  }

  // The gaps of the listed texels into *texels. Each gap must sit strictly inside the interval
  // above it, so that a texel's inside set is a sorted list of disjoint intervals (the walk relies
  // on it). Needs c's slabs and gap_layers_.
  bool DecodeGaps(const BodyMapCollider& c, std::vector<GapTexel>* texels) {
    const uint32_t layers = c.gap_layers_;
    if (layers == 0 && !gap_list.empty()) {
      problem = "gap_texels lists " + std::to_string(gap_list.size()) +
                " texels but layers = 1 (no gap layers)";
      return false;
    }
    const float back_plane_z = pose.front_z - pose.depth_range;
    texels->reserve(gap_list.size());
    for (size_t t = 0; t < gap_list.size(); ++t) {
      const size_t k = gap_list[t];
      if (k >= n || (t > 0 && k <= gap_list[t - 1])) {
        problem = "gap_texels[" + std::to_string(t) + "] = " + std::to_string(k) +
                  (k >= n ? " is not a texel of the rectangle" : " does not increase");
        return false;
      }
      GapTexel& texel = texels->emplace_back();
      texel.i = static_cast<uint32_t>(k % pose.width);
      texel.j = static_cast<uint32_t>(k / pose.width);
      for (size_t g = 0; g < layers; ++g) {
        texel.gaps[g] = Slab{-kInf, kInf};
        texel.normals[g] = TexelNormals{};
      }
      float floor_z = c.slabs_[k].top;  // the gap must lie below this (the previous interval's top)
      bool absent_before = false;
      for (size_t g = 0; g < layers; ++g) {
        const size_t index = n + g * gap_list.size() + t;
        float depth[2];
        bool valid[2];
        for (int view = 0; view < 2; ++view) {
          if (!ReadDepth(view, index, &depth[view], &valid[view])) return false;
        }
        if (!valid[0] && !valid[1]) {
          if (g == 0) {
            problem = Where(0, index) + ": a listed texel has no gap 1";
            return false;
          }
          absent_before = true;
          continue;
        }
        const float upper = pose.front_z - depth[0];
        const float lower = back_plane_z + depth[1];
        const Slab& slab = c.slabs_[k];
        const char* reason = nullptr;
        if (valid[0] != valid[1]) {
          reason = "has only one of its two boundaries";
        } else if (!(slab.top >= slab.bottom)) {
          reason = "lies on a background texel";
        } else if (absent_before) {
          reason = "follows an absent gap (gaps are filled in order)";
        } else if (!(floor_z > upper && upper > lower && lower > slab.bottom)) {
          reason = "is not strictly inside the slab below the previous gap";
        }
        if (reason != nullptr) {
          problem = Where(0, index) + ": the gap " + reason;
          return false;
        }
        texel.gaps[g] = {upper, lower};
        floor_z = lower;
        TexelNormals& normals = texel.normals[g];
        if (!ReadNormal(0, index, normals.front) || !ReadNormal(1, index, normals.back)) {
          return false;
        }
      }
    }
    return true;
  }
};

Status BodyMapCollider::Build(const BodyMapPose& pose, DepthSampling sampling) {
  Clear();
  const auto fail = [&](const std::string& reason) {
    Clear();
    return Status(StatusCode::kInvalidArgument, DescribePose(pose) + ": " + reason);
  };
  if (const std::string problem = CheckPoseHeader(pose, sampling); !problem.empty()) {
    return fail(problem);
  }
  if (pose.layout != BodyMapLayout::kDense) {
    // Row spans: expand into the dense rectangle (background outside the spans) and build from
    // that, so both layouts of one bake give the same grid bit for bit. Setup-time memory only.
    try {
      BodyMapPose dense;
      if (Status expanded = ConvertBodyMapLayout(pose, BodyMapLayout::kDense, &dense);
          !expanded.ok()) {
        return fail(expanded.message());
      }
      return Build(dense, sampling);
    } catch (const std::bad_alloc&) {
      return fail("the expanded rectangle does not fit in memory");
    }
  }
  if (const std::string problem = CheckArraySizes(pose); !problem.empty()) return fail(problem);

  Decoder decoder(pose);
  if (!decoder.DecodeSlabs(this)) return fail(decoder.problem);
  gap_layers_ = static_cast<uint32_t>(pose.layers - 1);
  std::vector<GapTexel> gap_texels;
  if (!decoder.DecodeGaps(*this, &gap_texels)) return fail(decoder.problem);

  width_ = pose.width;
  height_ = pose.height;
  width_f_ = static_cast<float>(width_);
  height_f_ = static_cast<float>(height_);
  origin_x_ = pose.origin_x;
  origin_y_ = pose.origin_y;
  texel_size_ = pose.texel_size;
  inv_texel_size_ = 1.f / pose.texel_size;
  sampling_ = sampling;
  view_axis_ = pose.view_axis;
  clip_ = pose.clip;
  time_ = pose.time;
  PackGaps(&gap_texels);
  Finish();
  return Status::Ok();
}

}  // namespace drape

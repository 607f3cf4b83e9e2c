// Every count, index and value range the runtime relies on, checked once at load so the runtime
// can index without checks. Messages name the field path and the offending value. Also the
// body-map layout helpers of body_map_data.h (at the end).

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <utility>

#include "drape/formats/asset_file.h"

namespace drape {
namespace {

bool IsFinite(const Float3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
// Rotations are applied without renormalising, so they must be unit length.
bool IsUnit(const Quat& q) {
  const double n = double(q.x) * q.x + double(q.y) * q.y + double(q.z) * q.z + double(q.w) * q.w;
  return std::isfinite(n) && std::fabs(n - 1.0) <= 2e-3;
}
bool IsUnit(const Float3& v) {
  const double n = double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z;
  return std::isfinite(n) && std::fabs(n - 1.0) <= 2e-3;
}
float Dot3(const Float3& a, const Float3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
// Beyond this magnitude products of two coordinates overflow float (1e19^2 > 3.4e38).
constexpr float kMaxCoordinate = 1e18f;
bool IsSane(const Float3& v) {
  return IsFinite(v) && std::fabs(v.x) <= kMaxCoordinate && std::fabs(v.y) <= kMaxCoordinate &&
         std::fabs(v.z) <= kMaxCoordinate;
}

constexpr uint16_t kUnorm16Background = 65535;

// Entry `entry` of a view's depth array holds a surface, not background (a float32 NaN counts
// as a surface, so that the validator, which refuses NaN, sees it).
bool HasDepth(const BodyMapPose& p, int view, size_t entry) {
  if (p.depth_encoding == DepthEncoding::kFloat32)
    return !(p.depth_f32[view][entry] >= p.depth_range);
  return p.depth_u16[view][entry] != kUnorm16Background;
}

class Checker {
 public:
  bool failed() const { return !message_.empty(); }
  const std::string& message() const { return message_; }

  // Records the first failure only; returns `condition` so callers can stop early.
  bool Require(bool condition, const std::string& field, const std::string& reason) {
    if (!condition && message_.empty()) message_ = field + " " + reason;
    return condition;
  }
  // A message already in the "field reason" form.
  bool Fail(const std::string& message) {
    if (message_.empty()) message_ = message;
    return false;
  }
  bool Finite(float v, const std::string& field) {
    return Require(std::isfinite(v), field, "is not finite");
  }
  bool Finite(const Float3& v, const std::string& field) {
    return Finite(v.x, field + ".x") && Finite(v.y, field + ".y") && Finite(v.z, field + ".z");
  }
  bool Finite(const Mat34& m, const std::string& field) {
    for (int i = 0; i < 12; ++i)
      if (!Finite(m.m[i], field + ".m[" + std::to_string(i) + "]")) return false;
    return true;
  }
  bool Index(int64_t value, int64_t count, const std::string& field) {
    return Require(
        value >= 0 && value < count, field,
        "= " + std::to_string(value) + " is out of range [0, " + std::to_string(count) + ")");
  }
  bool Size(size_t actual, size_t expected, const std::string& field) {
    return Require(
        actual == expected, field,
        "has " + std::to_string(actual) + " elements, expected " + std::to_string(expected));
  }
  // Compressed-row offsets: count + 1 entries, from 0, non-decreasing, ending at `total`.
  bool Offsets(const std::vector<uint32_t>& offsets, size_t count, size_t total,
               const std::string& field) {
    if (!Size(offsets.size(), count + 1, field)) return false;
    if (!Require(offsets.front() == 0, field, "does not start at 0")) return false;
    for (size_t i = 1; i < offsets.size(); ++i)
      if (!Require(offsets[i] >= offsets[i - 1], field + "[" + std::to_string(i) + "]",
                   "decreases"))
        return false;
    return Require(
        offsets.back() == total, field,
        "ends at " + std::to_string(offsets.back()) + ", expected " + std::to_string(total));
  }

 private:
  std::string message_;
};

void CheckSkeleton(const SkeletonData& s, Checker& c) {
  const size_t n = s.parents.size();
  if (!c.Size(s.joint_names.size(), n, "skeleton.joint_names") ||
      !c.Size(s.rest_local.size(), n, "skeleton.rest_local") ||
      !c.Size(s.inverse_bind.size(), n, "skeleton.inverse_bind") ||
      !c.Require(n <= 65535, "skeleton", "has more than 65535 joints"))
    return;
  std::set<std::string> names;
  for (size_t j = 0; j < n; ++j) {
    const std::string at = "[" + std::to_string(j) + "]";
    if (!c.Require(!s.joint_names[j].empty(), "skeleton.joint_names" + at, "is empty") ||
        !c.Require(names.insert(s.joint_names[j]).second, "skeleton.joint_names" + at,
                   "'" + s.joint_names[j] + "' is a duplicate") ||
        !c.Require(s.parents[j] >= -1 && s.parents[j] < static_cast<int32_t>(j),
                   "skeleton.parents" + at,
                   "= " + std::to_string(s.parents[j]) + " is not -1 or smaller than " +
                       std::to_string(j)) ||
        !c.Finite(s.rest_local[j].translation, "skeleton.rest_local" + at + ".translation") ||
        !c.Finite(s.rest_local[j].scale, "skeleton.rest_local" + at + ".scale") ||
        !c.Finite(s.inverse_bind[j], "skeleton.inverse_bind" + at))
      return;
    if (!c.Require(IsUnit(s.rest_local[j].rotation), "skeleton.rest_local" + at + ".rotation",
                   "is not a finite unit quaternion") ||
        !c.Require(IsSane(s.rest_local[j].translation) && IsSane(s.rest_local[j].scale),
                   "skeleton.rest_local" + at, "has a translation or scale beyond 1e18"))
      return;
  }
}

void CheckClip(const ClipData& clip, size_t index, size_t joints, Checker& c) {
  const std::string at = "clips[" + std::to_string(index) + "]";
  if (!c.Require(!clip.name.empty(), at + ".name", "is empty")) return;
  if (!c.Require(clip.duration >= 0.f && std::isfinite(clip.duration), at + ".duration",
                 "is negative or not finite") ||
      !c.Require(
          clip.sample_rate > 0.f && clip.sample_rate <= 10000.f && std::isfinite(clip.sample_rate),
          at + ".sample_rate", "is not in (0, 10000]") ||
      !c.Require(clip.frame_count >= 1, at + ".frame_count", "is 0"))
    return;
  // Frame k sits at min(k / rate, duration): the last frame must reach the duration.
  const double needed =
      std::ceil(static_cast<double>(clip.duration) * clip.sample_rate - 1e-3) + 1.0;
  if (!c.Require(
          static_cast<double>(clip.frame_count) >= needed && clip.frame_count <= needed + 1.0,
          at + ".frame_count",
          "= " + std::to_string(clip.frame_count) + " does not cover the duration"))
    return;
  if (!c.Size(clip.keys.size(), static_cast<size_t>(clip.frame_count) * joints, at + ".keys"))
    return;
  for (size_t k = 0; k < clip.keys.size(); ++k) {
    const Transform& t = clip.keys[k];
    if (IsSane(t.translation) && IsSane(t.scale) && IsUnit(t.rotation)) continue;
    const std::string key = at + ".keys[" + std::to_string(k) + "]";
    c.Require(false, key, "is not finite, beyond 1e18, or its rotation is not a unit quaternion");
    return;
  }
}

// `name`: the field's name in messages ("mesh", "render_mesh").
void CheckMesh(const MeshData& m, size_t joints, const std::string& name, Checker& c) {
  const size_t v = m.positions.size();
  if (!c.Require(m.triangles.size() % 3 == 0, name + ".triangles", "size is not a multiple of 3"))
    return;
  for (size_t i = 0; i < v; ++i)
    if (!IsFinite(m.positions[i]) &&
        !c.Finite(m.positions[i], name + ".positions[" + std::to_string(i) + "]"))
      return;
  for (size_t i = 0; i < m.triangles.size(); ++i)
    if (m.triangles[i] >= v && !c.Index(m.triangles[i], static_cast<int64_t>(v),
                                        name + ".triangles[" + std::to_string(i) + "]"))
      return;
  if (m.influence_offsets.empty() && m.influence_joints.empty() && m.influence_weights.empty())
    return;
  if (!c.Offsets(m.influence_offsets, v, m.influence_joints.size(), name + ".influence_offsets") ||
      !c.Size(m.influence_weights.size(), m.influence_joints.size(), name + ".influence_weights"))
    return;
  for (size_t i = 0; i < m.influence_joints.size(); ++i) {
    const float w = m.influence_weights[i];
    if (m.influence_joints[i] < joints && std::isfinite(w) && w >= 0.f && w <= 1.f + 1e-4f)
      continue;
    const std::string at = "[" + std::to_string(i) + "]";
    if (!c.Index(m.influence_joints[i], static_cast<int64_t>(joints),
                 name + ".influence_joints" + at) ||
        !c.Require(std::isfinite(m.influence_weights[i]) && m.influence_weights[i] >= 0.f &&
                       m.influence_weights[i] <= 1.f + 1e-4f,
                   name + ".influence_weights" + at, "is not in [0, 1]"))
      return;
  }
}

// The gap list and the gap layers (body_map_data.h): gap_texels strictly increasing stored
// texels whose slab (layer 0) is valid in either view, each with gap 1 present; a gap has both
// boundaries or neither, and gap k exists only where gap k - 1 does. So the row-span layout,
// whose spans follow the slab alone, keeps every gap. The depth order of the boundaries within a
// texel is left to the runtime's Build, which reads them decoded. `texels`: stored texels of
// layer 0 (array sizes already checked); `prefix` starts the field names.
bool CheckGapLayers(const BodyMapPose& p, size_t texels, const std::string& prefix, Checker& c) {
  const std::vector<uint32_t>& list = p.gap_texels;
  if (p.layers == 1 && !list.empty()) {
    return c.Fail(prefix + "gap_texels has " + std::to_string(list.size()) +
                  " entries but layers = 1 (no gap layers)");
  }
  const std::string depth =
      prefix + (p.depth_encoding == DepthEncoding::kFloat32 ? "depth_f32_" : "depth_u16_");
  for (size_t t = 0; t < list.size(); ++t) {
    const std::string entry_name =
        "gap_texels[" + std::to_string(t) + "] = " + std::to_string(list[t]);
    const std::string at = prefix + entry_name;
    if (list[t] >= texels) {
      return c.Fail(at + " is not a stored texel (" + std::to_string(texels) + " stored)");
    }
    if (t > 0 && list[t] <= list[t - 1]) return c.Fail(at + " does not increase");
    if (!HasDepth(p, 0, list[t]) && !HasDepth(p, 1, list[t])) {
      return c.Fail(at + " holds a gap where the slab (layer 0) is background");
    }
    for (size_t k = 1; k < p.layers; ++k) {
      const size_t entry = texels + (k - 1) * list.size() + t;
      const bool upper = HasDepth(p, 0, entry);
      const bool lower = HasDepth(p, 1, entry);
      const std::string where = "layer " + std::to_string(k) + " of " + entry_name;
      if (upper != lower) {
        return c.Fail(depth + (upper ? "back[" : "front[") + std::to_string(entry) +
                      "] is background where the other view is not (" + where +
                      ": a gap has both boundaries or neither)");
      }
      if (k == 1 && !upper) {
        return c.Fail(depth + "front[" + std::to_string(entry) + "] is background (" + where +
                      ": a listed texel holds gap 1)");
      }
      if (k > 1 && upper && !HasDepth(p, 0, entry - list.size())) {
        return c.Fail(depth + "front[" + std::to_string(entry) + "] holds a gap (" + where +
                      ") where layer " + std::to_string(k - 1) +
                      " holds none (gaps are filled in order)");
      }
    }
  }
  return true;
}

// One pose (of the poses or of a bone map) named `at`; false when it fails.
bool CheckBodyMapPose(const BodyMapPose& pose, const std::string& at, size_t clips, Checker& c) {
  {
    if (!c.Require(pose.clip >= -1 && pose.clip < static_cast<int64_t>(clips), at + ".clip",
                   "is not -1 or a clip index") ||
        !c.Require(
            pose.width >= 1 && pose.height >= 1 && pose.width <= 16384 && pose.height <= 16384, at,
            "size is not in [1, 16384] texels") ||
        !c.Require(
            std::isfinite(pose.texel_size) && pose.texel_size >= 1e-6f && pose.texel_size <= 1e3f,
            at + ".texel_size", "is not in [1e-6, 1e3] m") ||
        !c.Require(std::isfinite(pose.depth_range) && pose.depth_range > 0.f, at + ".depth_range",
                   "is not > 0") ||
        !c.Finite(pose.origin_x, at + ".origin_x") || !c.Finite(pose.origin_y, at + ".origin_y") ||
        !c.Finite(pose.front_z, at + ".front_z") || !c.Finite(pose.time, at + ".time") ||
        !c.Require(static_cast<uint8_t>(pose.depth_encoding) <= 1, at + ".depth_encoding",
                   "is unknown") ||
        !c.Require(static_cast<uint8_t>(pose.normal_encoding) <= 2, at + ".normal_encoding",
                   "is unknown") ||
        !c.Require(pose.layers >= 1 && pose.layers <= kMaxBodyMapLayers, at + ".layers",
                   "= " + std::to_string(pose.layers) + " is not in [1, " +
                       std::to_string(kMaxBodyMapLayers) + "]") ||
        !c.Require(static_cast<uint8_t>(pose.view_axis) <= 2, at + ".view_axis",
                   "= " + std::to_string(static_cast<int>(pose.view_axis)) +
                       " is not 0 (z), 1 (x) or 2 (y)"))
      return false;
    // The span table before any array size that depends on it (row spans: the spans' total).
    if (const std::string problem = CheckBodyMapLayout(pose); !problem.empty()) {
      c.Fail(at + "." + problem);
      return false;
    }
    const size_t texels = BodyMapStoredTexels(pose);   // of layer 0
    const size_t entries = BodyMapArrayEntries(pose);  // values of one component, all layers
    const bool f32 = pose.depth_encoding == DepthEncoding::kFloat32;
    for (int view = 0; view < 2; ++view) {
      const std::string v = view == 0 ? "front" : "back";
      if (!c.Size(pose.depth_f32[view].size(), f32 ? entries : 0, at + ".depth_f32_" + v) ||
          !c.Size(pose.depth_u16[view].size(), f32 ? 0 : entries, at + ".depth_u16_" + v) ||
          !c.Size(pose.normal_f32[view].size(),
                  pose.normal_encoding == NormalEncoding::kFloat32 ? 3 * entries : 0,
                  at + ".normal_f32_" + v) ||
          !c.Size(pose.normal_oct16[view].size(),
                  pose.normal_encoding == NormalEncoding::kOct16 ? 2 * entries : 0,
                  at + ".normal_oct16_" + v) ||
          !c.Size(pose.normal_rgb8[view].size(),
                  pose.normal_encoding == NormalEncoding::kRgb8 ? 3 * entries : 0,
                  at + ".normal_rgb8_" + v))
        return false;
      for (size_t i = 0; i < pose.depth_f32[view].size(); ++i)
        if (!(pose.depth_f32[view][i] >= 0.f) &&
            !c.Require(false, at + ".depth_f32_" + v + "[" + std::to_string(i) + "]",
                       "is NaN or negative"))
          return false;
      for (size_t i = 0; i < pose.normal_f32[view].size(); ++i)
        if (!std::isfinite(pose.normal_f32[view][i]) &&
            !c.Finite(pose.normal_f32[view][i],
                      at + ".normal_f32_" + v + "[" + std::to_string(i) + "]"))
          return false;
    }
    return CheckGapLayers(pose, texels, at + ".", c);
  }
}

// A rigid transform: finite, its 3x3 part a rotation within 1e-3.
bool IsRigid(const Mat34& m) {
  for (float v : m.m)
    if (!std::isfinite(v)) return false;
  for (int r = 0; r < 3; ++r) {
    for (int q = 0; q < 3; ++q) {
      const double dot = double(m.m[4 * r]) * m.m[4 * q] + double(m.m[4 * r + 1]) * m.m[4 * q + 1] +
                         double(m.m[4 * r + 2]) * m.m[4 * q + 2];
      if (std::fabs(dot - (r == q ? 1.0 : 0.0)) > 1e-3) return false;
    }
  }
  const double det = double(m.m[0]) * (double(m.m[5]) * m.m[10] - double(m.m[6]) * m.m[9]) -
                     double(m.m[1]) * (double(m.m[4]) * m.m[10] - double(m.m[6]) * m.m[8]) +
                     double(m.m[2]) * (double(m.m[4]) * m.m[9] - double(m.m[5]) * m.m[8]);
  return det > 0.0;
}

void CheckBodyMaps(const BodyMapSet& set, size_t clips, Checker& c) {
  if (!c.Require(std::isfinite(set.epsilon) && set.epsilon >= 0.f, "body_maps.epsilon",
                 "is negative or not finite"))
    return;
  for (size_t p = 0; p < set.poses.size(); ++p) {
    const std::string at = "body_maps.poses[" + std::to_string(p) + "]";
    if (!CheckBodyMapPose(set.poses[p], at, clips, c)) return;
    // One view frame for the set: a clip's poses blend texel by texel.
    if (!c.Require(set.poses[p].view_axis == set.poses[0].view_axis, at + ".view_axis",
                   std::string("is ") + BodyMapViewAxisName(set.poses[p].view_axis) +
                       ", pose 0's is " + BodyMapViewAxisName(set.poses[0].view_axis)))
      return;
  }
}

void CheckBoneMaps(const BoneMapSet& set, size_t clips, size_t joints, Checker& c) {
  if (!c.Require(std::isfinite(set.epsilon) && set.epsilon >= 0.f, "bone_maps.epsilon",
                 "is negative or not finite"))
    return;
  for (size_t b = 0; b < set.maps.size(); ++b) {
    const BoneMapData& bone = set.maps[b];
    const std::string at = "bone_maps.maps[" + std::to_string(b) + "]";
    if (!c.Index(bone.joint, static_cast<int64_t>(joints), at + ".joint") ||
        !c.Require(IsRigid(bone.view_from_bind), at + ".view_from_bind",
                   "is not a finite rigid transform") ||
        !c.Require(bone.pose.clip == -1, at + ".pose.clip", "is not -1") ||
        !CheckBodyMapPose(bone.pose, at + ".pose", clips, c))
      return;
  }
}

void CheckHierarchy(const KirkpatrickHierarchy& k, size_t planes, const std::string& at,
                    Checker& c) {
  if (k.node_triangles.empty() && k.vertices_uv.empty() && k.child_offsets.empty())
    return;  // not baked
  const size_t vertices = k.vertices_uv.size() / 2;
  const size_t nodes = k.node_triangles.size() / 3;
  if (!c.Require(k.vertices_uv.size() % 2 == 0, at + ".vertices_uv", "size is odd") ||
      !c.Require(k.node_triangles.size() % 3 == 0, at + ".node_triangles",
                 "size is not a multiple of 3") ||
      !c.Offsets(k.child_offsets, nodes, k.children.size(), at + ".child_offsets") ||
      !c.Size(k.leaf_planes.size(), nodes, at + ".leaf_planes") ||
      !c.Require(k.root_begin <= k.root_end && k.root_end <= nodes && k.root_begin < k.root_end, at,
                 "root range is empty or out of range"))
    return;
  for (size_t i = 0; i < k.vertices_uv.size(); ++i)
    if (!std::isfinite(k.vertices_uv[i]) &&
        !c.Finite(k.vertices_uv[i], at + ".vertices_uv[" + std::to_string(i) + "]"))
      return;
  for (size_t i = 0; i < k.node_triangles.size(); ++i)
    if (k.node_triangles[i] >= vertices &&
        !c.Index(k.node_triangles[i], static_cast<int64_t>(vertices),
                 at + ".node_triangles[" + std::to_string(i) + "]"))
      return;
  for (size_t node = 0; node < nodes; ++node) {
    for (uint32_t e = k.child_offsets[node]; e < k.child_offsets[node + 1]; ++e) {
      // Children come before their parent, so every walk from a root terminates.
      if (k.children[e] >= node && !c.Index(k.children[e], static_cast<int64_t>(node),
                                            at + ".children[" + std::to_string(e) + "]"))
        return;
    }
    if (!c.Require(k.leaf_planes[node] >= -1 && k.leaf_planes[node] < static_cast<int64_t>(planes),
                   at + ".leaf_planes[" + std::to_string(node) + "]", "is not -1 or a plane index"))
      return;
  }
}

void CheckHull(const HullColliderData& h, size_t index, size_t joints, Checker& c) {
  const std::string at = "hulls[" + std::to_string(index) + "]";
  if (!c.Index(h.joint, static_cast<int64_t>(joints), at + ".joint") ||
      !c.Finite(h.bind_frame, at + ".bind_frame") ||
      !c.Require(!h.planes.empty() && h.planes.size() <= 4096, at + ".planes",
                 "count is not in [1, 4096]") ||
      !c.Require(h.triangles.size() % 3 == 0, at + ".triangles", "size is not a multiple of 3") ||
      !c.Size(h.triangle_planes.size(), h.triangles.size() / 3, at + ".triangle_planes") ||
      !c.Require(h.plane_internal.empty() || h.plane_internal.size() == h.planes.size(),
                 at + ".plane_internal", "is neither empty nor one flag per plane"))
    return;
  for (size_t i = 0; i < h.plane_internal.size(); ++i)
    if (!c.Require(h.plane_internal[i] <= 1, at + ".plane_internal[" + std::to_string(i) + "]",
                   "is not 0 or 1"))
      return;
  for (size_t i = 0; i < h.vertices.size(); ++i)
    if (!c.Finite(h.vertices[i], at + ".vertices[" + std::to_string(i) + "]")) return;
  for (size_t i = 0; i < h.triangles.size(); ++i)
    if (!c.Index(h.triangles[i], static_cast<int64_t>(h.vertices.size()),
                 at + ".triangles[" + std::to_string(i) + "]"))
      return;
  for (size_t i = 0; i < h.triangle_planes.size(); ++i)
    if (!c.Index(h.triangle_planes[i], static_cast<int64_t>(h.planes.size()),
                 at + ".triangle_planes[" + std::to_string(i) + "]"))
      return;
  for (size_t i = 0; i < h.planes.size(); ++i) {
    const std::string p = at + ".planes[" + std::to_string(i) + "]";
    if (!c.Require(IsUnit(h.planes[i].normal), p + ".normal", "is not a finite unit vector") ||
        !c.Finite(h.planes[i].offset, p + ".offset"))
      return;
  }
  if (!c.Finite(h.obb.center, at + ".obb.center") ||
      !c.Finite(h.obb.half_extents, at + ".obb.half_extents") ||
      !c.Finite(h.obb.axes[0], at + ".obb.axes[0]") ||
      !c.Finite(h.obb.axes[1], at + ".obb.axes[1]") ||
      !c.Finite(h.obb.axes[2], at + ".obb.axes[2]") ||
      !c.Require(IsUnit(h.obb.axes[0]) && IsUnit(h.obb.axes[1]) && IsUnit(h.obb.axes[2]) &&
                     std::fabs(Dot3(h.obb.axes[0], h.obb.axes[1])) <= 2e-3f &&
                     std::fabs(Dot3(h.obb.axes[1], h.obb.axes[2])) <= 2e-3f &&
                     std::fabs(Dot3(h.obb.axes[0], h.obb.axes[2])) <= 2e-3f,
                 at + ".obb.axes", "are not orthonormal") ||
      !c.Require(
          h.obb.half_extents.x >= 0.f && h.obb.half_extents.y >= 0.f && h.obb.half_extents.z >= 0.f,
          at + ".obb.half_extents", "are negative"))
    return;
  CheckHierarchy(h.upper, h.planes.size(), at + ".upper", c);
  CheckHierarchy(h.lower, h.planes.size(), at + ".lower", c);
  const MapTableData& t = h.map;
  if (t.rows == 0 && t.cols == 0 && t.cell_offsets.empty()) return;  // no table baked
  if (!c.Require(static_cast<uint8_t>(t.kind) <= 1, at + ".map.kind", "is unknown") ||
      !c.Require(t.rows >= 1 && t.cols >= 1 && static_cast<uint64_t>(t.rows) * t.cols <= (1u << 20),
                 at + ".map", "rows x cols is not in [1, 2^20]") ||
      !c.Offsets(t.cell_offsets, static_cast<size_t>(t.rows) * t.cols, t.cell_triangles.size(),
                 at + ".map.cell_offsets") ||
      !c.Finite(t.origin, at + ".map.origin") || !c.Finite(t.axis, at + ".map.axis") ||
      !c.Finite(t.reference, at + ".map.reference") || !c.Finite(t.length, at + ".map.length"))
    return;
  for (size_t i = 0; i < t.cell_triangles.size(); ++i)
    if (t.cell_triangles[i] >= h.triangles.size() / 3 &&
        !c.Index(t.cell_triangles[i], static_cast<int64_t>(h.triangles.size() / 3),
                 at + ".map.cell_triangles[" + std::to_string(i) + "]"))
      return;
}

}  // namespace

Status ValidateAsset(const CharacterAsset& asset) {
  Checker c;
  CheckSkeleton(asset.skeleton, c);
  const size_t joints = asset.skeleton.parents.size();
  for (size_t i = 0; i < asset.clips.size() && !c.failed(); ++i)
    CheckClip(asset.clips[i], i, joints, c);
  if (!c.failed()) CheckMesh(asset.mesh, joints, "mesh", c);
  // The render mesh's vertices are the bind mesh's (a subset), skinned the same way.
  if (!c.failed() && !asset.render_mesh.positions.empty()) {
    CheckMesh(asset.render_mesh, joints, "render_mesh", c);
    c.Require(asset.render_mesh.influence_offsets.empty() == asset.mesh.influence_offsets.empty(),
              "render_mesh.influence_offsets", "is empty where mesh's is not, or the reverse");
  }
  if (!c.failed()) CheckBodyMaps(asset.body_maps, asset.clips.size(), c);
  if (!c.failed()) CheckBoneMaps(asset.bone_maps, asset.clips.size(), joints, c);
  for (size_t i = 0; i < asset.hulls.size() && !c.failed(); ++i)
    CheckHull(asset.hulls[i], i, joints, c);
  for (size_t i = 0; i < asset.joint_spheres.size() && !c.failed(); ++i) {
    const JointSphereData& s = asset.joint_spheres[i];
    const std::string at = "joint_spheres[" + std::to_string(i) + "]";
    if (c.Index(s.joint, static_cast<int64_t>(joints), at + ".joint") &&
        c.Require(s.parent_joint >= -1 && s.parent_joint < static_cast<int64_t>(joints),
                  at + ".parent_joint", "is not -1 or a joint index") &&
        c.Finite(s.center, at + ".center"))
      c.Require(std::isfinite(s.radius) && s.radius > 0.f, at + ".radius", "is not > 0");
  }
  for (size_t i = 0; i < asset.capsules.size() && !c.failed(); ++i) {
    const CapsuleColliderData& k = asset.capsules[i];
    const std::string at = "capsules[" + std::to_string(i) + "]";
    if (c.Index(k.joint, static_cast<int64_t>(joints), at + ".joint") &&
        c.Finite(k.from, at + ".from") && c.Finite(k.to, at + ".to") &&
        c.Require(std::isfinite(k.radius_from) && k.radius_from > 0.f, at + ".radius_from",
                  "is not > 0"))
      c.Require(std::isfinite(k.radius_to) && k.radius_to > 0.f, at + ".radius_to", "is not > 0");
  }
  if (c.failed()) return Status(StatusCode::kCorrupt, c.message());
  return Status::Ok();
}

}  // namespace drape

// ---------------------------------------------------------------------------------------------
// The row-span layout of a body-map pose (body_map_data.h): checking the span table, finding a
// texel, converting between the dense and the row-span layouts. Shared by the validator above,
// the bake (which bakes dense and converts) and the runtime (which expands spans into its own
// grid). Here rather than in a file of its own so that every build of the validator (the fuzz
// targets list their sources) has it.

namespace drape {
namespace {

std::string Count(size_t actual, size_t expected, const std::string& field,
                  const std::string& what) {
  return field + " has " + std::to_string(actual) + " elements, expected " + what + " = " +
         std::to_string(expected);
}

// "" or a message when the arrays of the chosen encodings do not hold BodyMapArrayEntries().
std::string CheckArraySizes(const BodyMapPose& p) {
  const size_t texels = BodyMapArrayEntries(p);
  const bool f32 = p.depth_encoding == DepthEncoding::kFloat32;
  for (int view = 0; view < 2; ++view) {
    const std::string v = view == 0 ? "front" : "back";
    const size_t sizes[5] = {p.depth_f32[view].size(), p.depth_u16[view].size(),
                             p.normal_f32[view].size(), p.normal_oct16[view].size(),
                             p.normal_rgb8[view].size()};
    const size_t expected[5] = {f32 ? texels : 0, f32 ? 0 : texels,
                                p.normal_encoding == NormalEncoding::kFloat32 ? 3 * texels : 0,
                                p.normal_encoding == NormalEncoding::kOct16 ? 2 * texels : 0,
                                p.normal_encoding == NormalEncoding::kRgb8 ? 3 * texels : 0};
    const char* names[5] = {"depth_f32_", "depth_u16_", "normal_f32_", "normal_oct16_",
                            "normal_rgb8_"};
    for (int k = 0; k < 5; ++k) {
      if (sizes[k] != expected[k]) {
        return names[k] + v + " has " + std::to_string(sizes[k]) + " elements, expected " +
               std::to_string(expected[k]);
      }
    }
  }
  return {};
}

// Every field except the per-texel arrays, the span table and the gap list.
BodyMapPose CopyHeader(const BodyMapPose& in, BodyMapLayout layout) {
  BodyMapPose out;
  out.clip = in.clip;
  out.time = in.time;
  out.width = in.width;
  out.height = in.height;
  out.origin_x = in.origin_x;
  out.origin_y = in.origin_y;
  out.texel_size = in.texel_size;
  out.front_z = in.front_z;
  out.depth_range = in.depth_range;
  out.depth_encoding = in.depth_encoding;
  out.normal_encoding = in.normal_encoding;
  out.layout = layout;
  out.layers = in.layers;
  out.view_axis = in.view_axis;
  return out;
}

// Sizes the arrays of the pose's encodings for its stored texels and gap list, all background.
void AssignBackground(BodyMapPose& p) {
  const size_t texels = BodyMapArrayEntries(p);
  for (int view = 0; view < 2; ++view) {
    if (p.depth_encoding == DepthEncoding::kFloat32) {
      p.depth_f32[view].assign(texels, p.depth_range);
    } else {
      p.depth_u16[view].assign(texels, kUnorm16Background);
    }
    switch (p.normal_encoding) {
      case NormalEncoding::kFloat32:
        p.normal_f32[view].assign(3 * texels, 0.f);
        break;
      case NormalEncoding::kOct16:
        p.normal_oct16[view].assign(2 * texels, 0);
        break;
      case NormalEncoding::kRgb8:
        p.normal_rgb8[view].assign(3 * texels, 0);
        break;
    }
  }
}

// Copies entry `from` of every array of `src` (one texel of one layer) to entry `to` of `dst`.
void CopyEntry(const BodyMapPose& src, size_t from, BodyMapPose& dst, size_t to) {
  for (int view = 0; view < 2; ++view) {
    if (src.depth_encoding == DepthEncoding::kFloat32) {
      dst.depth_f32[view][to] = src.depth_f32[view][from];
    } else {
      dst.depth_u16[view][to] = src.depth_u16[view][from];
    }
    switch (src.normal_encoding) {
      case NormalEncoding::kFloat32:
        for (size_t c = 0; c < 3; ++c)
          dst.normal_f32[view][3 * to + c] = src.normal_f32[view][3 * from + c];
        break;
      case NormalEncoding::kOct16:
        for (size_t c = 0; c < 2; ++c)
          dst.normal_oct16[view][2 * to + c] = src.normal_oct16[view][2 * from + c];
        break;
      case NormalEncoding::kRgb8:
        for (size_t c = 0; c < 3; ++c)
          dst.normal_rgb8[view][3 * to + c] = src.normal_rgb8[view][3 * from + c];
        break;
    }
  }
}

// Copies the gap entries (everything after layer 0) of `src` to `dst`, in the same order, and
// renumbers the gap list with `stored_index` (the destination's position of a source texel).
template <class StoredIndex>
void CopyGaps(const BodyMapPose& src, BodyMapPose& dst, StoredIndex stored_index) {
  const size_t from = BodyMapStoredTexels(src), to = BodyMapStoredTexels(dst);
  const size_t entries = BodyMapArrayEntries(src) - from;
  for (size_t e = 0; e < entries; ++e) CopyEntry(src, from + e, dst, to + e);
  for (size_t t = 0; t < src.gap_texels.size(); ++t)
    dst.gap_texels[t] = stored_index(src.gap_texels[t]);
}

// The slab (layer 0, the first `texels` entries) is not background in either view. Gaps lie
// inside the slab (the validator checks it), so this decides for every layer.
bool ValidInEitherView(const BodyMapPose& p, size_t index) {
  return HasDepth(p, 0, index) || HasDepth(p, 1, index);
}

BodyMapPose ExpandToDense(const BodyMapPose& in) {
  BodyMapPose out = CopyHeader(in, BodyMapLayout::kDense);
  out.gap_texels.resize(in.gap_texels.size());
  AssignBackground(out);
  std::vector<uint32_t> dense_index(BodyMapStoredTexels(in));  // stored texel -> j * width + i
  for (uint32_t j = 0; j < in.height; ++j) {
    for (uint32_t s = in.row_span_offsets[j]; s < in.row_span_offsets[j + 1]; ++s) {
      const uint32_t length = in.span_texel_offsets[s + 1] - in.span_texel_offsets[s];
      const size_t to = static_cast<size_t>(j) * in.width + in.span_begin[s];
      for (uint32_t t = 0; t < length; ++t) {
        CopyEntry(in, in.span_texel_offsets[s] + t, out, to + t);
        dense_index[in.span_texel_offsets[s] + t] = static_cast<uint32_t>(to + t);
      }
    }
  }
  CopyGaps(in, out, [&](uint32_t n) { return dense_index[n]; });
  return out;
}

BodyMapPose PackRowSpans(const BodyMapPose& dense) {
  BodyMapPose out = CopyHeader(dense, BodyMapLayout::kRowSpans);
  const size_t width = dense.width;
  out.row_span_offsets.reserve(dense.height + 1u);
  out.row_span_offsets.push_back(0);
  out.span_texel_offsets.push_back(0);
  uint32_t stored = 0;
  for (size_t j = 0; j < dense.height; ++j) {
    size_t i = 0;
    while (i < width) {
      if (!ValidInEitherView(dense, j * width + i)) {
        ++i;
        continue;
      }
      const size_t begin = i;
      while (i < width && ValidInEitherView(dense, j * width + i)) ++i;
      out.span_begin.push_back(static_cast<uint16_t>(begin));  // width <= 16384 (validated)
      stored += static_cast<uint32_t>(i - begin);
      out.span_texel_offsets.push_back(stored);
    }
    out.row_span_offsets.push_back(static_cast<uint32_t>(out.span_begin.size()));
  }
  out.gap_texels.resize(dense.gap_texels.size());
  AssignBackground(out);
  for (size_t j = 0; j < dense.height; ++j) {
    for (uint32_t s = out.row_span_offsets[j]; s < out.row_span_offsets[j + 1]; ++s) {
      const uint32_t length = out.span_texel_offsets[s + 1] - out.span_texel_offsets[s];
      const size_t from = j * width + out.span_begin[s];
      for (uint32_t t = 0; t < length; ++t)
        CopyEntry(dense, from + t, out, out.span_texel_offsets[s] + t);
    }
  }
  // A gap texel's slab is valid (checked before), so it lies in a span.
  CopyGaps(dense, out, [&](uint32_t n) {
    return static_cast<uint32_t>(
        BodyMapTexelIndex(out, static_cast<uint32_t>(n % width), static_cast<uint32_t>(n / width)));
  });
  return out;
}

}  // namespace

const char* BodyMapViewAxisName(BodyMapViewAxis axis) {
  switch (axis) {
    case BodyMapViewAxis::kZ:
      return "z";
    case BodyMapViewAxis::kX:
      return "x";
    case BodyMapViewAxis::kY:
      return "y";
  }
  return "unknown";
}

size_t BodyMapStoredTexels(const BodyMapPose& pose) {
  if (pose.layout == BodyMapLayout::kDense) return static_cast<size_t>(pose.width) * pose.height;
  return pose.span_texel_offsets.empty() ? 0 : pose.span_texel_offsets.back();
}

size_t BodyMapArrayEntries(const BodyMapPose& pose) {
  const size_t gap_layers = pose.layers > 1 ? pose.layers - 1u : 0u;
  return BodyMapStoredTexels(pose) + gap_layers * pose.gap_texels.size();
}

std::string CheckBodyMapLayout(const BodyMapPose& p) {
  if (p.layout == BodyMapLayout::kDense) {
    if (!p.row_span_offsets.empty() || !p.span_begin.empty() || !p.span_texel_offsets.empty())
      return "row_span_offsets, span_begin, span_texel_offsets are not empty in the dense layout";
    return {};
  }
  if (p.layout != BodyMapLayout::kRowSpans)
    return "layout = " + std::to_string(static_cast<int>(p.layout)) + " is unknown";
  const std::vector<uint32_t>& rows = p.row_span_offsets;
  const std::vector<uint32_t>& texels = p.span_texel_offsets;
  const size_t spans = p.span_begin.size();
  if (rows.size() != static_cast<size_t>(p.height) + 1)
    return Count(rows.size(), static_cast<size_t>(p.height) + 1, "row_span_offsets", "height + 1");
  if (rows.front() != 0) return "row_span_offsets does not start at 0";
  for (size_t j = 1; j < rows.size(); ++j)
    if (rows[j] < rows[j - 1]) return "row_span_offsets[" + std::to_string(j) + "] decreases";
  if (rows.back() != spans)
    return "row_span_offsets ends at " + std::to_string(rows.back()) + ", expected the " +
           std::to_string(spans) + " spans of span_begin";
  if (texels.size() != spans + 1)
    return Count(texels.size(), spans + 1, "span_texel_offsets", "span count + 1");
  if (texels.front() != 0) return "span_texel_offsets does not start at 0";
  for (size_t j = 0; j < p.height; ++j) {
    uint64_t previous_end = 0;  // texel column where the previous span of this row ended
    for (uint32_t s = rows[j]; s < rows[j + 1]; ++s) {
      const std::string at = "[" + std::to_string(s) + "]";
      if (texels[s + 1] <= texels[s])
        return "span_texel_offsets[" + std::to_string(s + 1) +
               "] does not increase (an empty span)";
      const uint64_t begin = p.span_begin[s];
      const uint64_t end = begin + (texels[s + 1] - texels[s]);
      if (begin < previous_end)
        return "span_begin" + at + " = " + std::to_string(begin) +
               " is before the end of the previous span of row " + std::to_string(j) + " (" +
               std::to_string(previous_end) + ")";
      if (end > p.width)
        return "span_begin" + at + " = " + std::to_string(begin) + ": the span of row " +
               std::to_string(j) + " ends at " + std::to_string(end) + ", beyond width " +
               std::to_string(p.width);
      previous_end = end;
    }
  }
  // The runtime expands a row-span pose into its dense rectangle. A dense pose is bounded by its
  // own arrays (hence by the file's size); keep a span pose's expansion proportional to what it
  // stores, so a small file cannot declare a huge empty rectangle. The bake crops the rectangle
  // to the covered texels (the mannequin's rectangle is 4.5x its stored texels).
  constexpr uint64_t kMaxExpansion = 256;
  const uint64_t area = static_cast<uint64_t>(p.width) * p.height;
  const uint64_t stored = texels.back();
  if (area > kMaxExpansion * std::max<uint64_t>(stored, 4096))
    return "width x height = " + std::to_string(area) + " texels for " + std::to_string(stored) +
           " stored: more than " + std::to_string(kMaxExpansion) +
           "x (a sparse pose must be cropped to its covered texels)";
  return {};
}

int64_t BodyMapTexelIndex(const BodyMapPose& pose, uint32_t i, uint32_t j) {
  if (i >= pose.width || j >= pose.height) return -1;
  if (pose.layout == BodyMapLayout::kDense) return static_cast<int64_t>(j) * pose.width + i;
  if (static_cast<size_t>(j) + 1 >= pose.row_span_offsets.size()) return -1;
  const auto first = pose.span_begin.begin() + pose.row_span_offsets[j];
  const auto last = pose.span_begin.begin() + pose.row_span_offsets[j + 1];
  const auto after = std::upper_bound(
      first, last, i, [](uint32_t column, uint16_t begin) { return column < begin; });
  if (after == first) return -1;
  const size_t s = static_cast<size_t>(after - pose.span_begin.begin()) - 1;
  const uint32_t offset = i - pose.span_begin[s];
  if (offset >= pose.span_texel_offsets[s + 1] - pose.span_texel_offsets[s]) return -1;
  return static_cast<int64_t>(pose.span_texel_offsets[s]) + offset;
}

Status ConvertBodyMapLayout(const BodyMapPose& in, BodyMapLayout layout, BodyMapPose* out) {
  const auto invalid = [](const std::string& reason) {
    return Status(StatusCode::kInvalidArgument, "ConvertBodyMapLayout: " + reason);
  };
  if (layout != BodyMapLayout::kDense && layout != BodyMapLayout::kRowSpans)
    return invalid("unknown target layout");
  if (in.depth_encoding != DepthEncoding::kFloat32 && in.depth_encoding != DepthEncoding::kUnorm16)
    return invalid("unknown depth encoding");
  if (in.normal_encoding != NormalEncoding::kFloat32 &&
      in.normal_encoding != NormalEncoding::kOct16 && in.normal_encoding != NormalEncoding::kRgb8)
    return invalid("unknown normal encoding");
  if (layout == BodyMapLayout::kRowSpans && in.width > 65536)
    return invalid("width " + std::to_string(in.width) + " exceeds the 65536 of span_begin");
  if (in.layers < 1 || in.layers > kMaxBodyMapLayers)
    return invalid("layers = " + std::to_string(in.layers) + " is not in [1, " +
                   std::to_string(kMaxBodyMapLayers) + "]");
  if (std::string problem = CheckBodyMapLayout(in); !problem.empty()) return invalid(problem);
  if (std::string problem = CheckArraySizes(in); !problem.empty()) return invalid(problem);
  // Spans follow the slab alone: a gap outside it would be dropped without a word.
  if (Checker gaps; !CheckGapLayers(in, BodyMapStoredTexels(in), "", gaps))
    return invalid(gaps.message());
  if (layout == in.layout) {
    *out = in;
  } else if (layout == BodyMapLayout::kDense) {
    *out = ExpandToDense(in);
  } else {
    *out = PackRowSpans(in);
  }
  return Status::Ok();
}

}  // namespace drape

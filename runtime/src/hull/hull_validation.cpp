#include "hull/hull_validation.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "drape/runtime/exact_orientation.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"

namespace drape::detail {
namespace {

Status ValidateHierarchy(const KirkpatrickHierarchy& k, size_t plane_count, const std::string& at) {
  const size_t vertices = k.vertices_uv.size() / 2;
  const size_t nodes = k.node_triangles.size() / 3;
  if (k.vertices_uv.size() % 2 != 0) return HullError(at + ".vertices_uv", "size is odd");
  if (k.node_triangles.size() % 3 != 0 || nodes == 0)
    return HullError(at + ".node_triangles", "size is 0 or not a multiple of 3");
  if (nodes > (1u << 24)) return HullError(at + ".node_triangles", "has more than 2^24 nodes");
  if (k.child_offsets.size() != nodes + 1 || k.child_offsets[0] != 0 ||
      k.child_offsets[nodes] != k.children.size())
    return HullError(at + ".child_offsets",
                     "do not have node_count + 1 entries from 0 to the child count");
  if (k.leaf_planes.size() != nodes)
    return HullError(at + ".leaf_planes", "size is not node_count");
  if (!(k.root_begin < k.root_end && k.root_end <= nodes))
    return HullError(at + ".root_begin/root_end", "range is empty or out of range");
  for (size_t i = 0; i < k.vertices_uv.size(); ++i)
    if (!std::isfinite(k.vertices_uv[i]))
      return HullError(at + ".vertices_uv[" + std::to_string(i) + "]", "is not finite");
  for (size_t i = 0; i < k.node_triangles.size(); ++i)
    if (k.node_triangles[i] >= vertices)
      return HullError(at + ".node_triangles[" + std::to_string(i) + "]", "is out of range");
  bool has_face = false;
  for (size_t n = 0; n < nodes; ++n) {
    if (k.child_offsets[n] > k.child_offsets[n + 1])
      return HullError(at + ".child_offsets[" + std::to_string(n) + "]", "decreases");
    for (uint32_t e = k.child_offsets[n]; e < k.child_offsets[n + 1]; ++e)
      if (k.children[e] >= n)
        return HullError(at + ".children[" + std::to_string(e) + "]",
                         "is not below its parent node");
    if (k.leaf_planes[n] < -1 || k.leaf_planes[n] >= static_cast<int64_t>(plane_count))
      return HullError(at + ".leaf_planes[" + std::to_string(n) + "]",
                       "is not -1 or a plane index");
    if (k.leaf_planes[n] >= 0 && k.child_offsets[n] == k.child_offsets[n + 1]) has_face = true;
    const uint32_t* t = &k.node_triangles[3 * n];
    const float* uv = k.vertices_uv.data();
    if (Orient2dExact(uv[2 * t[0]], uv[2 * t[0] + 1], uv[2 * t[1]], uv[2 * t[1] + 1], uv[2 * t[2]],
                      uv[2 * t[2] + 1]) <= 0)
      return HullError(at + ".node_triangles[" + std::to_string(n) + "]",
                       "is not strictly counter-clockwise");
  }
  if (!has_face) return HullError(at, "has no leaf on a hull plane");
  return Status::Ok();
}

}  // namespace

Status ValidateHullData(const HullColliderData& h, size_t index, uint32_t joint_count) {
  if (h.joint < 0 || static_cast<uint32_t>(h.joint) >= joint_count)
    return HullError(HullField("hulls", index, "joint"), "is out of range");
  if (!IsFinite(h.bind_frame))
    return HullError(HullField("hulls", index, "bind_frame"), "is not finite");
  if (h.planes.empty() || h.planes.size() > kMaxHullPlanes)
    return HullError(HullField("hulls", index, "planes"), "count is not in [1, 4096]");
  for (size_t i = 0; i < h.planes.size(); ++i) {
    const Plane& p = h.planes[i];
    if (!IsFinite(p.normal) || !std::isfinite(p.offset))
      return HullError(HullField("hulls", index, "planes[" + std::to_string(i) + "]"),
                       "is not finite");
    if (std::fabs(Length(p.normal) - 1.f) > kHullUnitTolerance)
      return HullError(HullField("hulls", index, "planes[" + std::to_string(i) + "].normal"),
                       "is not unit length");
  }
  for (size_t i = 0; i < h.vertices.size(); ++i)
    if (!IsFinite(h.vertices[i]))
      return HullError(HullField("hulls", index, "vertices[" + std::to_string(i) + "]"),
                       "is not finite");
  if (h.triangles.size() % 3 != 0)
    return HullError(HullField("hulls", index, "triangles"), "size is not a multiple of 3");
  for (size_t i = 0; i < h.triangles.size(); ++i)
    if (h.triangles[i] >= h.vertices.size())
      return HullError(HullField("hulls", index, "triangles[" + std::to_string(i) + "]"),
                       "is out of range");
  if (h.triangle_planes.size() != h.triangles.size() / 3)
    return HullError(HullField("hulls", index, "triangle_planes"),
                     "size is not the triangle count");
  for (size_t i = 0; i < h.triangle_planes.size(); ++i)
    if (h.triangle_planes[i] >= h.planes.size())
      return HullError(HullField("hulls", index, "triangle_planes[" + std::to_string(i) + "]"),
                       "is out of range");
  const Obb& o = h.obb;
  if (!IsFinite(o.center) || !IsFinite(o.half_extents) || !IsFinite(o.axes[0]) ||
      !IsFinite(o.axes[1]) || !IsFinite(o.axes[2]))
    return HullError(HullField("hulls", index, "obb"), "is not finite");
  if (o.half_extents.x < 0.f || o.half_extents.y < 0.f || o.half_extents.z < 0.f)
    return HullError(HullField("hulls", index, "obb.half_extents"), "are negative");
  for (int a = 0; a < 3; ++a) {
    if (std::fabs(Length(o.axes[a]) - 1.f) > kHullUnitTolerance)
      return HullError(HullField("hulls", index, "obb.axes"), "are not unit length");
    for (int b = a + 1; b < 3; ++b)
      if (std::fabs(Dot(o.axes[a], o.axes[b])) > kHullUnitTolerance)
        return HullError(HullField("hulls", index, "obb.axes"), "are not orthogonal");
  }
  const bool upper = !h.upper.node_triangles.empty(), lower = !h.lower.node_triangles.empty();
  if (upper != lower)
    return HullError(HullField("hulls", index, "upper/lower"), "only one hierarchy is present");
  if (upper) {
    if (!IsFinite(h.projection_axis) || !IsFinite(h.projection_u) || !IsFinite(h.projection_v))
      return HullError(HullField("hulls", index, "projection axes"), "are not finite");
    Status s = ValidateHierarchy(h.upper, h.planes.size(), HullField("hulls", index, "upper"));
    if (!s.ok()) return s;
    s = ValidateHierarchy(h.lower, h.planes.size(), HullField("hulls", index, "lower"));
    if (!s.ok()) return s;
    // Every hierarchy vertex but the enclosing triangle's corners (the root's vertices) is the
    // projection of a hull vertex, bit for bit: the exact ties and the fill leaves' guard planes
    // rely on it, and a hull whose OBB or axes changed after the bake fails here.
    std::vector<uint64_t> projected;
    for (const Float3& v : h.vertices) {
      const HullUv q = ProjectHullUv(v, h.obb.center, h.projection_u, h.projection_v);
      uint32_t bits[2];
      std::memcpy(&bits[0], &q.u, sizeof(float));
      std::memcpy(&bits[1], &q.v, sizeof(float));
      projected.push_back((uint64_t(bits[0]) << 32) | bits[1]);
    }
    std::sort(projected.begin(), projected.end());
    for (const KirkpatrickHierarchy* k : {&h.upper, &h.lower}) {
      const uint32_t* root = &k->node_triangles[3 * k->root_begin];
      for (uint32_t v : k->node_triangles) {
        if (v == root[0] || v == root[1] || v == root[2]) continue;
        uint32_t bits[2];
        std::memcpy(bits, &k->vertices_uv[2 * v], sizeof(bits));
        if (!std::binary_search(projected.begin(), projected.end(),
                                (uint64_t(bits[0]) << 32) | bits[1]))
          return HullError(
              HullField("hulls", index, k == &h.upper ? "upper" : "lower"),
              "has a vertex that is not the projection of a hull vertex (stale bake?)");
      }
    }
  }
  const MapTableData& t = h.map;
  const bool has_map = !(t.rows == 0 && t.cols == 0 && t.cell_offsets.empty());
  if (has_map) {
    const std::string at = HullField("hulls", index, "map");
    if (static_cast<uint8_t>(t.kind) > 1) return HullError(at + ".kind", "is unknown");
    if (t.rows < 1 || t.cols < 1 || static_cast<uint64_t>(t.rows) * t.cols > (1u << 20))
      return HullError(at, "rows x cols is not in [1, 2^20]");
    const size_t cells = static_cast<size_t>(t.rows) * t.cols;
    if (t.cell_offsets.size() != cells + 1 || t.cell_offsets[0] != 0 ||
        t.cell_offsets[cells] != t.cell_triangles.size())
      return HullError(at + ".cell_offsets",
                       "do not have rows*cols + 1 entries from 0 to the list size");
    for (size_t c = 0; c < cells; ++c)
      if (t.cell_offsets[c] > t.cell_offsets[c + 1])
        return HullError(at + ".cell_offsets[" + std::to_string(c) + "]", "decreases");
    for (size_t i = 0; i < t.cell_triangles.size(); ++i)
      if (t.cell_triangles[i] >= h.triangles.size() / 3)
        return HullError(at + ".cell_triangles[" + std::to_string(i) + "]", "is out of range");
    if (!IsFinite(t.origin) || !IsFinite(t.axis) || !IsFinite(t.reference) ||
        !std::isfinite(t.length))
      return HullError(at, "origin, axis, reference or length is not finite");
    if (std::fabs(Length(t.axis) - 1.f) > kHullUnitTolerance ||
        std::fabs(Length(t.reference) - 1.f) > kHullUnitTolerance ||
        std::fabs(Dot(t.axis, t.reference)) > kHullUnitTolerance)
      return HullError(at, "axis and reference are not orthonormal");
    if (t.length < 0.f) return HullError(at + ".length", "is negative");
  }
  return Status::Ok();
}

Status ValidateJointSphereData(const JointSphereData& s, size_t i, uint32_t joint_count) {
  if (s.joint < 0 || static_cast<uint32_t>(s.joint) >= joint_count)
    return HullError(HullField("spheres", i, "joint"), "is out of range");
  if (!IsFinite(s.center)) return HullError(HullField("spheres", i, "center"), "is not finite");
  if (!(std::isfinite(s.radius) && s.radius > 0.f))
    return HullError(HullField("spheres", i, "radius"), "is not finite and > 0");
  return Status::Ok();
}

}  // namespace drape::detail

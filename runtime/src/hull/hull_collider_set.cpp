#include "drape/runtime/hull_collider_set.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "hull/hull_validation.h"
#include "hull/plane_kernels.h"

namespace drape {
namespace {

constexpr float kPi = 3.14159265358979323846f;

}  // namespace

using detail::HullError;
using detail::HullField;
using detail::kPadCenter;
using detail::kPadOffset;
using detail::kPlanePad;

// Build's stages, each appending one part of a hull to the flat arrays.
struct HullColliderSet::BuildStages {
  // The planes, SoA and padded to a multiple of kPlanePad.
  static void AppendPlanes(const HullColliderData& h, HullRecord* r, HullColliderSet* set) {
    r->plane_begin = static_cast<uint32_t>(set->plane_nx_.size());
    r->plane_count = static_cast<uint32_t>(h.planes.size());
    r->plane_padded = (r->plane_count + kPlanePad - 1) / kPlanePad * kPlanePad;
    for (uint32_t p = 0; p < r->plane_padded; ++p) {
      const bool real = p < r->plane_count;
      const Plane plane = real ? h.planes[p] : Plane{Float3{}, kPadOffset};
      set->plane_nx_.push_back(plane.normal.x);
      set->plane_ny_.push_back(plane.normal.y);
      set->plane_nz_.push_back(plane.normal.z);
      set->plane_d_.push_back(plane.offset);
      set->planes_.push_back(plane);
      const uint8_t internal = real && !h.plane_internal.empty() ? h.plane_internal[p] : 0;
      set->plane_internal_.push_back(internal);
      set->outer_plane_d_.push_back(internal ? kPadOffset : plane.offset);
    }
  }
  // The OBB, grown so that float rounding of the transforms and of the planes never rejects a
  // point the plane test accepts: the half extents cover every vertex too, plus 1e-5 relative
  // and 1e-6 m absolute.
  static void GrowObb(const HullColliderData& h, HullRecord* r) {
    r->obb_center = h.obb.center;
    for (int a = 0; a < 3; ++a) r->obb_axes[a] = h.obb.axes[a];
    float half[3] = {h.obb.half_extents.x, h.obb.half_extents.y, h.obb.half_extents.z};
    float scale = Length(h.obb.center);
    for (const Float3& v : h.vertices) {
      scale = std::max(scale, Length(v));
      for (int a = 0; a < 3; ++a)
        half[a] = std::max(half[a], std::fabs(Dot(v - h.obb.center, h.obb.axes[a])));
    }
    const float grow = 1e-6f + 2e-6f * scale;
    for (float& x : half) x = x * (1.f + 1e-5f) + grow;
    r->obb_half = {half[0], half[1], half[2]};
    r->bound_radius = Length(r->obb_half) * (1.f + 1e-5f) + grow;
  }
  // The triangles the map-table ray tests, 9 floats each, and their planes.
  static void AppendRayTriangles(const HullColliderData& h, HullRecord* r, HullColliderSet* set) {
    r->triangle_begin = static_cast<uint32_t>(set->ray_triangle_planes_.size());
    r->triangle_count = static_cast<uint32_t>(h.triangles.size() / 3);
    for (uint32_t t = 0; t < r->triangle_count; ++t) {
      for (int c = 0; c < 3; ++c) {
        const Float3 v = h.vertices[h.triangles[3 * t + c]];
        set->ray_triangles_.push_back(v.x);
        set->ray_triangles_.push_back(v.y);
        set->ray_triangles_.push_back(v.z);
      }
      set->ray_triangle_planes_.push_back(h.triangle_planes[t]);
    }
  }
  // The Kirkpatrick hierarchies: canonical edge functions, children, leaf planes and the fill
  // leaves' guard planes.
  static void AppendHierarchies(const HullColliderData& h, HullRecord* r, HullColliderSet* set) {
    r->has_hierarchy = !h.upper.node_triangles.empty();
    r->uv_origin = h.obb.center;
    r->uv_u = h.projection_u;
    r->uv_v = h.projection_v;
    if (r->has_hierarchy) {
      if (set->node_child_begin_.empty()) set->node_child_begin_.push_back(0);
      if (set->node_guard_begin_.empty()) set->node_guard_begin_.push_back(0);
      // Hull vertices by their projection (float bits, as the bake stored them), and the planes
      // of the faces around each vertex (CSR), for the fill leaves' guard planes.
      std::vector<std::array<uint32_t, 3>> uv_keys;
      for (uint32_t v = 0; v < h.vertices.size(); ++v) {
        const HullUv q = ProjectHullUv(h.vertices[v], r->uv_origin, r->uv_u, r->uv_v);
        uint32_t bits[2];
        std::memcpy(&bits[0], &q.u, sizeof(float));
        std::memcpy(&bits[1], &q.v, sizeof(float));
        uv_keys.push_back({bits[0], bits[1], v});
      }
      std::sort(uv_keys.begin(), uv_keys.end());
      std::vector<std::pair<uint32_t, uint32_t>> vertex_plane;
      for (size_t t = 0; t < h.triangles.size() / 3; ++t)
        for (int c = 0; c < 3; ++c)
          vertex_plane.push_back({h.triangles[3 * t + c], h.triangle_planes[t]});
      std::sort(vertex_plane.begin(), vertex_plane.end());
      vertex_plane.erase(std::unique(vertex_plane.begin(), vertex_plane.end()), vertex_plane.end());
      std::vector<uint32_t> incident_begin(h.vertices.size() + 1, 0), incident_planes;
      for (const auto& [v, plane] : vertex_plane) {
        ++incident_begin[v + 1];
        incident_planes.push_back(plane);
      }
      for (size_t v = 0; v < h.vertices.size(); ++v) incident_begin[v + 1] += incident_begin[v];
      for (int side = 0; side < 2; ++side) {
        const KirkpatrickHierarchy& k = side == 0 ? h.upper : h.lower;
        Hierarchy& out = side == 0 ? r->upper : r->lower;
        const uint32_t base = static_cast<uint32_t>(set->node_leaf_plane_.size());
        out.node_begin = base;
        out.node_count = k.node_count();
        out.root_begin = base + k.root_begin;
        out.root_end = base + k.root_end;
        double sum_u = 0.0, sum_v = 0.0;
        uint32_t faces = 0;
        for (uint32_t n = 0; n < out.node_count; ++n) {
          const uint32_t* tri = &k.node_triangles[3 * n];
          for (int e = 0; e < 3; ++e) {
            const uint32_t from = tri[e], to = tri[(e + 1) % 3];
            const uint32_t a = std::min(from, to), b = std::max(from, to);
            EdgeFunction f;
            f.au = k.vertices_uv[2 * a];
            f.av = k.vertices_uv[2 * a + 1];
            f.du = double(k.vertices_uv[2 * b]) - f.au;
            f.dv = double(k.vertices_uv[2 * b + 1]) - f.av;
            if (from != a) {  // the node uses the edge as B -> A: the interior is on the other side
              f.du = -f.du;
              f.dv = -f.dv;
            }
            set->node_edges_.push_back(f);
          }
          set->node_leaf_plane_.push_back(k.leaf_planes[n]);
          for (uint32_t e = k.child_offsets[n]; e < k.child_offsets[n + 1]; ++e)
            set->node_children_.push_back(base + k.children[e]);
          set->node_child_begin_.push_back(static_cast<uint32_t>(set->node_children_.size()));
          // Guard planes of a fill leaf: every plane of a hull face incident to a hull vertex that
          // projects onto one of the leaf's vertices other than the enclosing triangle's corners
          // (the root's vertices). Each fill triangle lies beyond one silhouette edge or vertex;
          // a point projecting there is inside the hull only if it is inside the faces meeting at
          // that rim (see the header), which is what the guards test.
          if (k.leaf_planes[n] < 0 && k.child_offsets[n] == k.child_offsets[n + 1] &&
              k.root_end - k.root_begin == 1) {
            const uint32_t* root = &k.node_triangles[3 * k.root_begin];
            const size_t first = set->node_guard_planes_.size();
            for (int c = 0; c < 3; ++c) {
              const uint32_t v = tri[c];
              if (v == root[0] || v == root[1] || v == root[2]) continue;
              uint32_t bits[2];
              std::memcpy(bits, &k.vertices_uv[2 * v], sizeof(bits));
              auto it = std::lower_bound(uv_keys.begin(), uv_keys.end(),
                                         std::array<uint32_t, 3>{bits[0], bits[1], 0});
              for (; it != uv_keys.end() && (*it)[0] == bits[0] && (*it)[1] == bits[1]; ++it)
                for (uint32_t e = incident_begin[(*it)[2]]; e < incident_begin[(*it)[2] + 1]; ++e)
                  set->node_guard_planes_.push_back(incident_planes[e]);
            }
            std::sort(set->node_guard_planes_.begin() + static_cast<std::ptrdiff_t>(first),
                      set->node_guard_planes_.end());
            set->node_guard_planes_.erase(
                std::unique(set->node_guard_planes_.begin() + static_cast<std::ptrdiff_t>(first),
                            set->node_guard_planes_.end()),
                set->node_guard_planes_.end());
          }
          set->node_guard_begin_.push_back(static_cast<uint32_t>(set->node_guard_planes_.size()));
          if (k.leaf_planes[n] >= 0 && k.child_offsets[n] == k.child_offsets[n + 1]) {
            for (int c = 0; c < 3; ++c) {
              sum_u += k.vertices_uv[2 * tri[c]];
              sum_v += k.vertices_uv[2 * tri[c] + 1];
            }
            ++faces;
          }
        }
        // The mean of the face leaves' vertices: a convex combination of points of the (convex)
        // projected hull with positive weights, so strictly inside it.
        out.interior_u = sum_u / (3.0 * faces);
        out.interior_v = sum_v / (3.0 * faces);
      }
    }
  }
  // The map table: cell offsets into one list of hull-relative triangles.
  static void AppendMapTable(const HullColliderData& h, HullRecord* r, HullColliderSet* set) {
    const MapTableData& t = h.map;
    r->has_map = !(t.rows == 0 && t.cols == 0 && t.cell_offsets.empty());
    if (r->has_map) {
      r->map_kind = t.kind;
      r->map_rows = t.rows;
      r->map_cols = t.cols;
      r->map_row_scale = static_cast<float>(t.rows) / kPi;
      r->map_col_scale = static_cast<float>(t.cols) / (2.f * kPi);
      r->map_origin = t.origin;
      r->map_axis = t.axis;
      r->map_reference = t.reference;
      r->map_binormal = Cross(t.axis, t.reference);
      r->map_length = t.kind == MapTableKind::kCylinder ? t.length : 0.f;
      r->map_cell_begin = static_cast<uint32_t>(set->map_cell_offsets_.size());
      const uint32_t list_base = static_cast<uint32_t>(set->map_triangles_.size());
      for (uint32_t offset : t.cell_offsets) set->map_cell_offsets_.push_back(list_base + offset);
      set->map_triangles_.insert(set->map_triangles_.end(), t.cell_triangles.begin(),
                                 t.cell_triangles.end());
    }
  }
};

void HullColliderSet::Clear() { *this = HullColliderSet(); }

Status HullColliderSet::ValidateOptions(const HullColliderOptions& options) const {
  if (options.gauss_seidel_passes < 1 || options.gauss_seidel_passes > 16)
    return HullError("options.gauss_seidel_passes", "is not in [1, 16]");
  if (static_cast<uint8_t>(options.inside_test) > 1)
    return HullError("options.inside_test", "is unknown");
  if (static_cast<uint8_t>(options.response) > 1)
    return HullError("options.response", "is unknown");
  if (static_cast<uint8_t>(options.entry_response) > 1)
    return HullError("options.entry_response", "is unknown");
  if (static_cast<uint8_t>(options.instruction_set) > static_cast<uint8_t>(InstructionSet::kAvx2))
    return HullError("options.instruction_set", "is unknown");
  for (size_t i = 0; i < hulls_.size(); ++i) {
    if (options.inside_test == InsideTest::kKirkpatrick && !hulls_[i].has_hierarchy)
      return HullError(HullField("hulls", i, "upper/lower"),
                       "are empty but the Kirkpatrick inside test was chosen");
    if (options.response == HullResponse::kMapTableRay && !hulls_[i].has_map)
      return HullError(HullField("hulls", i, "map"),
                       "is empty but the map-table response was chosen");
  }
  return Status::Ok();
}

Status HullColliderSet::SetOptions(const HullColliderOptions& options) {
  Status status = ValidateOptions(options);
  if (status.ok()) {
    options_ = options;
    kernels_ = &detail::PlaneKernelsFor(UsableInstructionSet(options.instruction_set));
  }
  return status;
}

Status HullColliderSet::Build(std::span<const HullColliderData> hulls,
                              std::span<const JointSphereData> spheres, uint32_t joint_count,
                              const HullColliderOptions& options) {
  Clear();
  for (size_t i = 0; i < hulls.size(); ++i) {
    Status s = detail::ValidateHullData(hulls[i], i, joint_count);
    if (!s.ok()) return s;
  }
  for (size_t i = 0; i < spheres.size(); ++i) {
    Status s = detail::ValidateJointSphereData(spheres[i], i, joint_count);
    if (!s.ok()) return s;
  }
  joint_count_ = joint_count;
  for (const HullColliderData& h : hulls) {
    HullRecord r;
    r.joint = h.joint;
    r.bind_frame = h.bind_frame;
    BuildStages::AppendPlanes(h, &r, this);
    BuildStages::GrowObb(h, &r);
    BuildStages::AppendRayTriangles(h, &r, this);
    BuildStages::AppendHierarchies(h, &r, this);
    BuildStages::AppendMapTable(h, &r, this);
    hulls_.push_back(r);
  }
  // The map-table ray loads each vertex as 4 floats: the last triangle's third vertex reads 3
  // floats past it.
  ray_triangles_.insert(ray_triangles_.end(), 3, 0.f);
  for (const JointSphereData& s : spheres) spheres_.push_back({s.joint, s.center, s.radius});

  Status status = ValidateOptions(options);
  if (!status.ok()) {
    Clear();
    return status;
  }
  options_ = options;
  kernels_ = &detail::PlaneKernelsFor(UsableInstructionSet(options.instruction_set));

  const size_t colliders = hulls_.size() + spheres_.size();
  collider_count_ = static_cast<uint32_t>(colliders);
  motions_.assign(colliders, Motion{});
  active_.assign(colliders, ActiveFrames{});
  obb_start_.assign(hulls_.size(), Mat34{});
  obb_end_.assign(hulls_.size(), Mat34{});
  obb_half_.resize(hulls_.size());
  for (size_t h = 0; h < hulls_.size(); ++h) obb_half_[h] = hulls_[h].obb_half;
  const size_t padded = (colliders + 7) / 8 * 8;
  for (auto* v : {&sweep_x_, &sweep_y_, &sweep_z_, &full_x_, &full_y_, &full_z_})
    v->assign(padded, kPadCenter);
  sweep_r_.assign(padded, 0.f);
  full_r_.assign(padded, 0.f);
  // Bind pose: identity skinning.
  std::vector<Mat34> identity(joint_count_ > 0 ? joint_count_ : 1);
  return SetPose(identity, identity);
}

InstructionSet HullColliderSet::instruction_set() const {
  return UsableInstructionSet(options_.instruction_set);
}

size_t HullColliderSet::memory_bytes() const {
  return sizeof(*this) + hulls_.size() * sizeof(HullRecord) +
         spheres_.size() * sizeof(SphereRecord) + (plane_nx_.size() * 5) * sizeof(float) +
         planes_.size() * sizeof(Plane) + plane_internal_.size() +
         ray_triangles_.size() * sizeof(float) + ray_triangle_planes_.size() * sizeof(uint32_t) +
         node_edges_.size() * sizeof(EdgeFunction) + node_leaf_plane_.size() * sizeof(int32_t) +
         (node_guard_begin_.size() + node_guard_planes_.size()) * sizeof(uint32_t) +
         (node_child_begin_.size() + node_children_.size() + map_cell_offsets_.size() +
          map_triangles_.size()) *
             sizeof(uint32_t) +
         motions_.size() * sizeof(Motion) + active_.size() * sizeof(ActiveFrames) +
         (obb_start_.size() + obb_end_.size()) * sizeof(Mat34) + obb_half_.size() * sizeof(Float3) +
         (sweep_x_.size() * 8) * sizeof(float);
}

}  // namespace drape

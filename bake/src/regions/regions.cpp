#include "drape/bake/regions.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"

namespace drape::bake {
namespace {

// The rigid part of an affine joint matrix: columns orthonormalised (Gram-Schmidt in double),
// translation kept. Joint matrices carry the unit scale and sometimes authored scale.
Mat34 RigidPart(const Mat34& m) {
  double c[3][3];
  for (int col = 0; col < 3; ++col)
    for (int row = 0; row < 3; ++row) c[col][row] = m.m[4 * row + col];
  auto normalize = [](double* v) {
    const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int k = 0; k < 3; ++k) v[k] = n > 0 ? v[k] / n : (k == 0 ? 1.0 : 0.0);
  };
  normalize(c[0]);
  const double d01 = c[0][0] * c[1][0] + c[0][1] * c[1][1] + c[0][2] * c[1][2];
  for (int k = 0; k < 3; ++k) c[1][k] -= d01 * c[0][k];
  normalize(c[1]);
  c[2][0] = c[0][1] * c[1][2] - c[0][2] * c[1][1];
  c[2][1] = c[0][2] * c[1][0] - c[0][0] * c[1][2];
  c[2][2] = c[0][0] * c[1][1] - c[0][1] * c[1][0];
  Mat34 r;
  for (int col = 0; col < 3; ++col)
    for (int row = 0; row < 3; ++row) r.m[4 * row + col] = static_cast<float>(c[col][row]);
  r.m[3] = m.m[3];
  r.m[7] = m.m[7];
  r.m[11] = m.m[11];
  return r;
}

bool IsAncestor(const SkeletonData& s, int32_t ancestor, int32_t joint) {
  for (int32_t j = s.parents[joint]; j >= 0; j = s.parents[j])
    if (j == ancestor) return true;
  return false;
}

// shape_threshold 0: every triangle shapes the hull of the bone with the largest summed weight
// over its three corners, all three corners included, so the hulls hold the whole rest-pose
// surface (on a low-poly mesh a triangle between two bones' vertices is a large part of it).
// Neighbouring hulls then overlap by the triangles along their seam.
void AssignTriangles(const MeshData& mesh, Regions* regions) {
  const size_t joints = regions->shaping_vertices.size();
  std::vector<int32_t> rigid_to(mesh.vertex_count(), -1);
  for (size_t j = 0; j < joints; ++j) {
    for (uint32_t v : regions->rigid_vertices[j]) rigid_to[v] = static_cast<int32_t>(j);
  }
  const std::vector<int32_t> bones = TriangleBones(mesh, static_cast<uint32_t>(joints));
  for (size_t t = 0; t < bones.size(); ++t) {
    const int32_t best = bones[t];
    if (best < 0) continue;
    for (size_t c = 0; c < 3; ++c) {
      const uint32_t v = mesh.triangles[3 * t + c];
      if (rigid_to[v] != best) regions->shaping_vertices[best].push_back(v);
    }
  }
  for (std::vector<uint32_t>& list : regions->shaping_vertices) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
}

}  // namespace

std::vector<int32_t> TriangleBones(const MeshData& mesh, uint32_t joint_count) {
  std::vector<int32_t> bones(mesh.triangles.size() / 3, -1);
  std::vector<float> weight(joint_count, 0.f);
  std::vector<int32_t> touched;
  for (size_t t = 0; t < bones.size(); ++t) {
    touched.clear();
    for (size_t c = 0; c < 3; ++c) {
      const uint32_t v = mesh.triangles[3 * t + c];
      if (size_t{v} + 1 >= mesh.influence_offsets.size()) continue;
      for (uint32_t k = mesh.influence_offsets[v]; k < mesh.influence_offsets[v + 1]; ++k) {
        const int32_t j = mesh.influence_joints[k];
        if (static_cast<uint32_t>(j) >= joint_count) continue;
        if (weight[j] == 0.f) touched.push_back(j);
        weight[j] += mesh.influence_weights[k];
      }
    }
    int32_t best = -1;
    for (int32_t j : touched) {
      if (best < 0 || weight[j] > weight[best] || (weight[j] == weight[best] && j < best)) best = j;
    }
    for (int32_t j : touched) weight[j] = 0.f;
    bones[t] = best;
  }
  return bones;
}

Status SplitRegions(const Character& character, float rigid_threshold, Regions* regions,
                    float shape_threshold) {
  if (!(rigid_threshold > 0.5f && rigid_threshold <= 1.f)) {
    return Status(StatusCode::kInvalidArgument, "hulls.rigid_threshold must be in (0.5, 1]");
  }
  if (!(shape_threshold >= 0.f && shape_threshold <= 1.f)) {
    return Status(StatusCode::kInvalidArgument, "hulls.shape_threshold must be in [0, 1]");
  }
  *regions = Regions{};
  regions->rigid_threshold = rigid_threshold;
  const float shaping = std::min(shape_threshold, rigid_threshold);  // the effective threshold
  const SkeletonData& skeleton = character.skeleton;
  const MeshData& mesh = character.mesh;
  const uint32_t joints = skeleton.joint_count();

  SkeletonPose pose;
  if (Status s = pose.Init(skeleton); !s.ok()) return s;
  pose.SetRest();
  regions->rest_positions.resize(mesh.vertex_count());
  if (Status s = SkinMesh(mesh, pose.skinning(), regions->rest_positions); !s.ok()) return s;
  regions->rest_skinning.assign(pose.skinning().begin(), pose.skinning().end());
  regions->collider_frames.resize(joints);
  for (uint32_t j = 0; j < joints; ++j) regions->collider_frames[j] = RigidPart(pose.world()[j]);

  regions->rigid_vertices.assign(joints, {});
  regions->shaping_vertices.assign(joints, {});
  std::map<std::pair<int32_t, int32_t>, size_t> joint_index;  // (child, parent) -> regions->joints
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    // The two heaviest influences, ties broken by the lower joint index (deterministic).
    int32_t first = -1, second = -1;
    float w_first = 0.f, w_second = 0.f;
    for (uint32_t k = mesh.influence_offsets[v]; k < mesh.influence_offsets[v + 1]; ++k) {
      const int32_t j = mesh.influence_joints[k];
      const float w = mesh.influence_weights[k];
      if (w > w_first || (w == w_first && j < first)) {
        second = first, w_second = w_first;
        first = j, w_first = w;
      } else if (w > w_second || (w == w_second && j < second)) {
        second = j, w_second = w;
      }
    }
    if (first < 0) continue;
    if (w_first >= rigid_threshold || second < 0) {
      regions->rigid_vertices[first].push_back(v);
      continue;
    }
    if (w_first >= shaping) regions->shaping_vertices[first].push_back(v);
    // The joint between the two bones: the descendant carries it.
    int32_t child = first, parent = second;
    if (IsAncestor(skeleton, first, second)) child = second, parent = first;
    auto [it, inserted] =
        joint_index.emplace(std::make_pair(child, parent), regions->joints.size());
    if (inserted) {
      JointRegion region;
      region.child = child;
      region.parent = parent;
      if (IsAncestor(skeleton, parent, child)) {
        const Mat34& world = pose.world()[child];
        region.center = {world.m[3], world.m[7], world.m[11]};
      }
      regions->joints.push_back(region);
    }
    regions->joints[it->second].flexible_vertices.push_back(v);
  }
  if (shape_threshold == 0.f) AssignTriangles(character.mesh, regions);
  // Bones that are not ancestor and descendant have no joint origin: centre on the vertices.
  for (JointRegion& region : regions->joints) {
    if (IsAncestor(skeleton, region.parent, region.child)) continue;
    double sum[3] = {0, 0, 0};
    for (uint32_t v : region.flexible_vertices) {
      sum[0] += regions->rest_positions[v].x;
      sum[1] += regions->rest_positions[v].y;
      sum[2] += regions->rest_positions[v].z;
    }
    const double n = static_cast<double>(region.flexible_vertices.size());
    region.center = {static_cast<float>(sum[0] / n), static_cast<float>(sum[1] / n),
                     static_cast<float>(sum[2] / n)};
  }
  return Status::Ok();
}

std::vector<JointSphereData> BuildJointSpheres(const Regions& regions, float delta,
                                               const std::vector<HullColliderData>& hulls,
                                               const std::vector<uint32_t>& triangles) {
  // The vertices each sphere must hold (the radius reaches the farthest). Without hulls: every
  // flexible vertex of the joint (paper B).
  std::vector<std::vector<uint32_t>> held(regions.joints.size());
  if (hulls.empty()) {
    for (size_t r = 0; r < regions.joints.size(); ++r)
      held[r] = regions.joints[r].flexible_vertices;
  } else {
    // Only the rest-pose triangles that no single hull holds (a triangle whose three corners are
    // in one convex hull lies in it). Such a triangle's flexible corners go to their own joint's
    // sphere, so no sphere is larger than paper B's. Its other corners do not: on smoothly
    // weighted rigs they lie far from the joint, and the sphere would swallow the body
    // (RiggedFigure: 82 % false contacts; Spider: 10x the radius).
    const size_t vertex_count = regions.rest_positions.size();
    std::vector<int32_t> region_of(vertex_count, -1), rigid_bone(vertex_count, -1);
    for (size_t r = 0; r < regions.joints.size(); ++r) {
      for (uint32_t v : regions.joints[r].flexible_vertices) region_of[v] = static_cast<int32_t>(r);
    }
    for (size_t j = 0; j < regions.rigid_vertices.size(); ++j) {
      for (uint32_t v : regions.rigid_vertices[j]) rigid_bone[v] = static_cast<int32_t>(j);
    }
    std::vector<std::vector<const HullColliderData*>> hulls_of(regions.collider_frames.size());
    for (const HullColliderData& h : hulls) hulls_of[static_cast<size_t>(h.joint)].push_back(&h);
    std::vector<Mat34> to_collider(regions.collider_frames.size());
    for (size_t j = 0; j < to_collider.size(); ++j) {
      to_collider[j] = InverseRigid(regions.collider_frames[j]);
    }
    const auto in_hull = [&](const HullColliderData& h, uint32_t v) {
      const Float3 local =
          TransformPoint(to_collider[static_cast<size_t>(h.joint)], regions.rest_positions[v]);
      for (const Plane& plane : h.planes) {
        if (Dot(plane.normal, local) > plane.offset) return false;
      }
      return true;
    };
    // The bones whose hulls could hold a corner: its rigid bone, or its joint's two bones.
    const auto bones_of = [&](uint32_t v, int32_t out[2]) {
      if (region_of[v] >= 0) {
        const JointRegion& region = regions.joints[static_cast<size_t>(region_of[v])];
        out[0] = region.child, out[1] = region.parent;
      } else {
        out[0] = rigid_bone[v], out[1] = -1;
      }
    };
    for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
      const uint32_t corner[3] = {triangles[t], triangles[t + 1], triangles[t + 2]};
      if (region_of[corner[0]] < 0 && region_of[corner[1]] < 0 && region_of[corner[2]] < 0) {
        continue;  // no flexible corner: nothing for a sphere to hold
      }
      bool covered = false;
      for (uint32_t c = 0; c < 3 && !covered; ++c) {
        int32_t bones[2];
        bones_of(corner[c], bones);
        for (int32_t bone : bones) {
          if (bone < 0) continue;
          for (const HullColliderData* h : hulls_of[static_cast<size_t>(bone)]) {
            covered = covered ||
                      (in_hull(*h, corner[0]) && in_hull(*h, corner[1]) && in_hull(*h, corner[2]));
          }
        }
      }
      if (covered) continue;
      for (uint32_t v : corner) {
        if (region_of[v] >= 0) held[static_cast<size_t>(region_of[v])].push_back(v);
      }
    }
  }
  std::vector<JointSphereData> spheres;
  for (size_t r = 0; r < regions.joints.size(); ++r) {
    const JointRegion& region = regions.joints[r];
    float radius = 0.f;
    for (uint32_t v : held[r]) {
      radius = std::max(radius, Length(regions.rest_positions[v] - region.center));
    }
    Mat34 rest_to_bind;
    if (!InverseAffine(regions.rest_skinning[region.child], &rest_to_bind)) continue;
    JointSphereData sphere;
    sphere.joint = region.child;
    sphere.parent_joint = region.parent;
    sphere.center = TransformPoint(rest_to_bind, region.center);
    // Round outward so every held vertex stays inside in float.
    sphere.radius = std::nextafter(radius + delta, INFINITY);
    spheres.push_back(sphere);
  }
  return spheres;
}

}  // namespace drape::bake

// BakeBoneMaps: per bone, its part of the body, the view axis with the least air, and the maps of
// the part in that view frame (docs/ALGORITHMS.md §7.10).
#include "drape/bake/bone_map_baker.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include "drape/bake/regions.h"
#include "drape/runtime/math.h"

namespace drape::bake {
namespace {

Status Invalid(const std::string& message) {
  return Status(StatusCode::kInvalidArgument, "bone maps: " + message);
}

Status CheckOptions(const BoneMapOptions& o) {
  if (!(o.texel_size >= 1e-4f && o.texel_size <= 1.f))
    return Invalid("texel_size " + std::to_string(o.texel_size) + " is outside [1e-4, 1] m");
  if (!(o.epsilon >= 0.f && o.epsilon <= 0.1f))
    return Invalid("epsilon " + std::to_string(o.epsilon) + " is outside [0, 0.1] m");
  if (!(o.min_weight > 0.f && o.min_weight <= 1.f))
    return Invalid("min_weight " + std::to_string(o.min_weight) + " is outside (0, 1]");
  if (o.layers < 1 || o.layers > kMaxBodyMapLayers)
    return Invalid("layers " + std::to_string(o.layers) + " is outside [1, 4]");
  return Status::Ok();
}

// Per joint, the triangles of its part: those it carries, and those with a corner weighing at
// least min_weight on it. Ascending.
std::vector<std::vector<uint32_t>> BoneParts(const MeshData& mesh, uint32_t joints,
                                             float min_weight) {
  std::vector<std::vector<uint32_t>> parts(joints);
  const std::vector<int32_t> carriers = TriangleBones(mesh, joints);
  const bool skinned = mesh.influence_offsets.size() == size_t{mesh.vertex_count()} + 1;
  std::vector<uint32_t> joined;  // joints of one triangle, few
  for (uint32_t t = 0; t < mesh.triangle_count(); ++t) {
    joined.clear();
    if (carriers[t] >= 0) joined.push_back(static_cast<uint32_t>(carriers[t]));
    for (int k = 0; k < 3 && skinned; ++k) {
      const uint32_t v = mesh.triangles[3 * t + k];
      for (uint32_t i = mesh.influence_offsets[v]; i < mesh.influence_offsets[v + 1]; ++i) {
        if (mesh.influence_weights[i] >= min_weight && mesh.influence_joints[i] < joints)
          joined.push_back(mesh.influence_joints[i]);
      }
    }
    std::sort(joined.begin(), joined.end());
    joined.erase(std::unique(joined.begin(), joined.end()), joined.end());
    for (uint32_t j : joined) parts[j].push_back(t);
  }
  return parts;
}

// The part's triangles as a mesh of their own, in the frame `frame` (rows: x, y, z axes) about
// `centre`.
void PartMesh(const MeshData& mesh, const std::vector<uint32_t>& part, const Eigen::Matrix3d& frame,
              const Eigen::Vector3d& centre, std::vector<Float3>* positions,
              std::vector<uint32_t>* triangles) {
  std::vector<uint32_t> remap(mesh.vertex_count(), std::numeric_limits<uint32_t>::max());
  positions->clear();
  triangles->clear();
  for (uint32_t t : part) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = mesh.triangles[3 * t + k];
      if (remap[v] == std::numeric_limits<uint32_t>::max()) {
        remap[v] = static_cast<uint32_t>(positions->size());
        const Float3 p = mesh.positions[v];
        const Eigen::Vector3d q = frame * (Eigen::Vector3d(p.x, p.y, p.z) - centre);
        positions->push_back(
            {static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z())});
      }
      triangles->push_back(remap[v]);
    }
  }
}

// The part's view frame: z is the direction most of its surface faces (the eigenvector of the
// area-weighted normal covariance with the largest eigenvalue), so each view ray crosses the
// surface about twice, as a slab needs. A limb or a torso ring is seen from its side, never along
// its length, where an open tube shows nothing but its rim. x, y: the other two eigenvectors,
// right-handed. *facing: that eigenvalue over the total, the share of the surface facing the
// view, [1/3, 1]. The centre is the area-weighted centroid.
void ViewFrame(const MeshData& mesh, const std::vector<uint32_t>& part, Eigen::Vector3d* centre,
               Eigen::Matrix3d* frame, double* facing) {
  double area_sum = 0.0;
  Eigen::Vector3d first = Eigen::Vector3d::Zero();
  Eigen::Matrix3d normals = Eigen::Matrix3d::Zero();
  for (uint32_t t : part) {
    Eigen::Vector3d c[3];
    for (int k = 0; k < 3; ++k) {
      const Float3 p = mesh.positions[mesh.triangles[3 * t + k]];
      c[k] = Eigen::Vector3d(p.x, p.y, p.z);
    }
    const Eigen::Vector3d cross = (c[1] - c[0]).cross(c[2] - c[0]);
    const double area = 0.5 * cross.norm();
    if (area > 0.0) normals += (0.5 / area) * cross * cross.transpose();  // area * n n^T
    first += (area + 1e-30) / 3.0 * (c[0] + c[1] + c[2]);
    area_sum += area + 1e-30;
  }
  *centre = first / area_sum;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(normals);
  // Eigen sorts ascending: the largest is the view axis.
  frame->row(0) = solver.eigenvectors().col(0).transpose();
  frame->row(1) = solver.eigenvectors().col(1).transpose();
  frame->row(2) = solver.eigenvectors().col(2).transpose();
  if (frame->determinant() < 0.0) frame->row(0) *= -1.0;
  const double trace = solver.eigenvalues().sum();
  *facing = trace > 0.0 ? solver.eigenvalues()(2) / trace : 1.0 / 3.0;
}

// Options giving about `texel` metres per texel over the part's x-y box (fitted window).
BodyMapOptions MapOptionsFor(const BoneMapOptions& o, const std::vector<Float3>& positions,
                             float texel) {
  float lo_x = std::numeric_limits<float>::infinity(), hi_x = -lo_x, lo_y = lo_x, hi_y = -lo_x;
  for (const Float3& p : positions) {
    lo_x = std::min(lo_x, p.x);
    hi_x = std::max(hi_x, p.x);
    lo_y = std::min(lo_y, p.y);
    hi_y = std::max(hi_y, p.y);
  }
  BodyMapOptions m;
  m.fitted_window = true;
  m.epsilon = o.epsilon;
  m.margin = 2.f * texel;  // in the part's units (a rig bound in centimetres)
  const double pad = 2.0 * (double(o.epsilon) + m.margin);
  const double area = (double(hi_x) - lo_x + pad) * (double(hi_y) - lo_y + pad);
  m.resolution =
      static_cast<uint32_t>(std::clamp(std::ceil(std::sqrt(area) / texel), 16.0, 4096.0));
  m.depth_encoding = o.depth_encoding;
  m.layout = BodyMapLayout::kRowSpans;
  m.layers = o.layers;
  return m;
}

Mat34 ToMat34(const Eigen::Matrix3d& frame, const Eigen::Vector3d& centre) {
  const Eigen::Vector3d t = -(frame * centre);
  Mat34 m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m.m[4 * r + c] = static_cast<float>(frame(r, c));
    m.m[4 * r + 3] = static_cast<float>(t(r));
  }
  return m;
}

}  // namespace

float AutomaticBoneMapTexel(std::span<const Float3> rest_positions) {
  constexpr float kTexelsPerBody = 600.f;
  if (rest_positions.empty()) return 0.003f;
  Float3 lo = rest_positions[0], hi = lo;
  for (const Float3& p : rest_positions) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const float longest = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  return std::clamp(longest / kTexelsPerBody, 1e-4f, 1.f);
}

Status BakeBoneMaps(const MeshData& mesh, const SkeletonData& skeleton,
                    std::span<const Mat34> rest_skinning, const BoneMapOptions& options,
                    BoneMapSet* maps, std::vector<BoneMapStats>* stats) {
  if (Status s = CheckOptions(options); !s.ok()) return s;
  const uint32_t joints = skeleton.joint_count();
  if (joints == 0) return Invalid("the skeleton has no joint");
  BoneMapSet result;
  result.epsilon = options.epsilon;
  std::vector<BoneMapStats> all;
  const std::vector<std::vector<uint32_t>> parts = BoneParts(mesh, joints, options.min_weight);
  std::vector<Float3> positions;
  std::vector<uint32_t> triangles;
  for (uint32_t j = 0; j < joints; ++j) {
    const std::vector<uint32_t>& part = parts[j];
    if (part.empty()) continue;
    Eigen::Vector3d centre;
    Eigen::Matrix3d frame;
    double facing = 0.0;
    ViewFrame(mesh, part, &centre, &frame, &facing);
    // Texel and epsilon in the bind frame, so that they are the options' on the posed body.
    BoneMapOptions bind_options = options;
    double scale = j < rest_skinning.size() ? UniformScale(rest_skinning[j]) : 1.0;
    if (!(scale > 1e-6 && scale < 1e6)) scale = 1.0;  // a degenerate or hostile matrix
    bind_options.texel_size = static_cast<float>(options.texel_size / scale);
    bind_options.epsilon = static_cast<float>(options.epsilon / scale);
    PartMesh(mesh, part, frame, centre, &positions, &triangles);
    BoneMapData bone;
    bone.joint = static_cast<uint16_t>(j);
    bone.view_from_bind = ToMat34(frame, centre);
    BodyMapPoseStats pose_stats;
    // A part too small to cover a texel centre (a fingertip at coarse texels) gets no maps.
    if (!BakeBodyMapPose(positions, triangles,
                         MapOptionsFor(bind_options, positions, bind_options.texel_size),
                         &bone.pose, &pose_stats)
             .ok()) {
      continue;
    }
    bone.pose.clip = -1;
    bone.pose.time = 0.f;
    BoneMapStats s;
    s.joint = bone.joint;
    s.triangles = static_cast<uint32_t>(part.size());
    s.facing = static_cast<float>(facing);
    s.width = bone.pose.width;
    s.height = bone.pose.height;
    s.bytes = pose_stats.bytes;
    all.push_back(s);
    result.maps.push_back(std::move(bone));
  }
  *maps = std::move(result);
  if (stats != nullptr) *stats = std::move(all);
  return Status::Ok();
}

}  // namespace drape::bake

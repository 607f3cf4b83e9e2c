#include "fcl_mesh_peer.h"

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/distance.h>

#include <limits>
#include <vector>

namespace drape::peers {

struct FclMeshPeer::Impl {
  fcl::BVHModel<fcl::OBBRSSd> model;
  size_t triangle_count = 0;
  bool valid = false;
};

FclMeshPeer::FclMeshPeer(std::span<const Float3> positions, std::span<const uint32_t> triangles)
    : impl_(std::make_unique<Impl>()) {
  if (positions.empty() || triangles.empty() || triangles.size() % 3 != 0) return;
  std::vector<fcl::Vector3d> vertices;
  vertices.reserve(positions.size());
  for (const Float3& p : positions) vertices.emplace_back(p.x, p.y, p.z);
  std::vector<fcl::Triangle> faces;
  faces.reserve(triangles.size() / 3);
  for (size_t t = 0; t < triangles.size(); t += 3) {
    if (triangles[t] >= positions.size() || triangles[t + 1] >= positions.size() ||
        triangles[t + 2] >= positions.size())
      return;
    faces.emplace_back(triangles[t], triangles[t + 1], triangles[t + 2]);
  }
  // BVH_OK is 0; the build splits by the mean of the vertices along the OBB's longest axis
  // (FCL's default splitter).
  if (impl_->model.beginModel(static_cast<int>(faces.size()), static_cast<int>(vertices.size())) !=
          fcl::BVH_OK ||
      impl_->model.addSubModel(vertices, faces) != fcl::BVH_OK ||
      impl_->model.endModel() != fcl::BVH_OK)
    return;
  impl_->triangle_count = faces.size();
  impl_->valid = true;
}

FclMeshPeer::~FclMeshPeer() = default;

double FclMeshPeer::Distance(Float3 p, Float3* closest) const {
  if (!impl_->valid) return std::numeric_limits<double>::infinity();
  // A zero-radius sphere: FCL's mesh-shape distance calls its exact sphere-triangle distance at
  // the leaves (no GJK iteration), so this is the point-to-mesh distance.
  const fcl::Sphered point(0.0);
  fcl::Transform3d point_pose = fcl::Transform3d::Identity();
  point_pose.translation() = fcl::Vector3d(p.x, p.y, p.z);
  fcl::DistanceRequestd request;
  request.enable_nearest_points = closest != nullptr;
  fcl::DistanceResultd result;
  const double distance = fcl::distance(&impl_->model, fcl::Transform3d::Identity(), &point,
                                        point_pose, request, result);
  if (closest != nullptr) {
    const fcl::Vector3d& c = result.nearest_points[0];  // on the mesh (world frame = mesh frame)
    *closest = {static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(c.z())};
  }
  return distance < 0.0 ? 0.0 : distance;  // touching: FCL reports a collision as -1
}

size_t FclMeshPeer::triangle_count() const { return impl_->triangle_count; }

size_t FclMeshPeer::memory_bytes() const {
  // BVHModel::memUsage only prints (it returns BVH_OK): count the same arrays here.
  if (!impl_->valid) return 0;
  const fcl::BVHModel<fcl::OBBRSSd>& m = impl_->model;
  return sizeof(m) + static_cast<size_t>(m.getNumBVs()) * sizeof(fcl::BVNode<fcl::OBBRSSd>) +
         static_cast<size_t>(m.num_tris) * sizeof(fcl::Triangle) +
         static_cast<size_t>(m.num_vertices) * sizeof(fcl::Vector3d);
}

}  // namespace drape::peers

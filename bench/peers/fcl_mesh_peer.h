#pragma once
// FCL's BVH distance query as a per-particle peer of drape's collision queries (issue #6): the
// mesh in an fcl::BVHModel<OBBRSS> (the bounding volume FCL recommends for distance; FCL is the
// successor of the RAPID library paper A compares against), queried with a zero-radius sphere,
// which FCL answers with its exact sphere-triangle distance at the leaves.
// Benchmark-side code: the constructor allocates; fcl types stay in the .cpp (pimpl).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

#include "drape/formats/types.h"

namespace drape::peers {

class FclMeshPeer {
 public:
  // positions: metres; triangles: 3 indices per triangle, each < positions.size() (checked by
  // the caller; an empty or malformed mesh gives a peer whose Distance returns +inf). The mesh
  // is copied.
  FclMeshPeer(std::span<const Float3> positions, std::span<const uint32_t> triangles);
  ~FclMeshPeer();
  FclMeshPeer(const FclMeshPeer&) = delete;
  FclMeshPeer& operator=(const FclMeshPeer&) = delete;

  // Unsigned distance (metres, >= 0) from p to the mesh surface, and the closest point on the
  // mesh in *closest (optional), by FCL's BVH distance traversal. Computed in double, from the
  // float input. Thread-safe (const, no shared scratch). A point exactly on a triangle (distance
  // 0 in double) gives 0 without `closest`; with it FCL 0.7 leaves that triangle's distance
  // unset (sphereTriangleDistance returns early), so the result is then unspecified.
  double Distance(Float3 p, Float3* closest) const;

  size_t triangle_count() const;
  // Bytes of FCL's model: vertices, triangles and BV tree (the arrays BVHModel::memUsage lists).
  size_t memory_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace drape::peers

#pragma once
// Paper B's per-bone proxy collider: an inflated, simplified convex hull with its OBB, the
// Kirkpatrick point-location hierarchies of its upper and lower faces, and the map table that
// lists, per direction cell, the triangles a response ray can hit. Also the joint spheres.

#include <cstdint>
#include <vector>

#include "drape/formats/types.h"

namespace drape {

struct Plane {  // inside when dot(normal, p) <= offset; normal is unit length
  Float3 normal;
  float offset = 0.f;  // metres
};

struct Obb {  // in the collider frame
  Float3 center;
  Float3 axes[3];       // orthonormal, right-handed
  Float3 half_extents;  // metres along axes[k], >= 0
};

// A planar triangulation and its Kirkpatrick hierarchy as flat arrays. Nodes of all levels are
// stored finest level first, so every child index is smaller than its parent's index: a walk
// from the roots always ends. Leaves are the nodes with no children.
struct KirkpatrickHierarchy {
  std::vector<float> vertices_uv;         // 2 floats per vertex, in the projection plane
  std::vector<uint32_t> node_triangles;   // 3 vertex indices per node, counter-clockwise in (u, v)
  std::vector<uint32_t> child_offsets;    // node_count + 1 entries (compressed rows)
  std::vector<uint32_t> children;         // node indices of the next finer level that overlap
  std::vector<int32_t> leaf_planes;       // per node: the hull plane a leaf lies on, -1 if none
  uint32_t root_begin = 0, root_end = 0;  // the coarsest level's node range

  uint32_t node_count() const { return static_cast<uint32_t>(node_triangles.size() / 3); }
};

enum class MapTableKind : uint8_t {
  kSphere = 0,    // cells over (theta = polar angle from axis, phi = azimuth), rays from origin
  kCylinder = 1,  // cells over (z along axis, phi = azimuth), rays from the axis point at z
};

struct MapTableData {
  MapTableKind kind = MapTableKind::kSphere;
  uint32_t rows = 0;   // sphere: theta cells over [0, pi]; cylinder: z cells over [0, length]
  uint32_t cols = 0;   // phi cells over [0, 2 pi)
  Float3 origin;       // sphere centre, or the cylinder axis point at z = 0 (collider frame)
  Float3 axis;         // unit: polar axis (sphere) or cylinder axis
  Float3 reference;    // unit, perpendicular to axis: phi = 0
  float length = 0.f;  // metres, cylinder axis length (0 for a sphere)
  std::vector<uint32_t> cell_offsets;  // rows * cols + 1 entries (compressed rows)
  std::vector<uint32_t> cell_triangles;
};

struct HullColliderData {
  int32_t joint = -1;  // the bone that carries it
  // Collider frame -> bind-pose asset frame. At a pose the collider's world transform is
  // skinning(joint) * bind_frame, which is rigid (the collider frame is the joint's rest-pose
  // frame without scale). bind_frame itself is affine: where the bind pose is scaled against the
  // rest pose (Animated_Human.fbx: about 65x), it carries that scale.
  Mat34 bind_frame;
  std::vector<Float3> vertices;           // collider surface, collider frame, metres
  std::vector<uint32_t> triangles;        // 3 per triangle, counter-clockwise outside
  std::vector<uint32_t> triangle_planes;  // plane index of each triangle
  std::vector<Plane> planes;              // coplanar triangles share one plane
  // Per plane, 1 when its face lies inside the body: the cut between two convex pieces of one
  // bone, or a bone's end buried in its neighbour. A particle inside leaves through the nearest
  // other face (leaving through it would put it in the neighbouring collider). Empty: no such
  // face.
  std::vector<uint8_t> plane_internal;
  Obb obb;
  Float3 projection_axis;             // unit; "upper" faces have dot(n, axis) > 0
  Float3 projection_u, projection_v;  // unit, (u, v, axis) right-handed
  KirkpatrickHierarchy upper, lower;
  MapTableData map;
};

struct JointSphereData {
  int32_t joint = -1;         // the child bone of the joint; the sphere moves with it
  int32_t parent_joint = -1;  // the other bone of the joint (-1 when none)
  Float3 center;              // bind-pose asset frame; at a pose: skinning(joint) * center
  float radius = 0.f;         // metres in the rest pose (the animation's scale), > 0
};

// A tapered capsule (round cone: the convex hull of two spheres) carried by one bone, fitted to
// the cross-section of the body the bone carries: the proxy shape engines know (NvCloth, Unity,
// Chaos, Jolt). Posed by the runtime into a ShapeColliderSet (drape/runtime/capsule_colliders.h).
struct CapsuleColliderData {  // 36 bytes
  int32_t joint = -1;         // the bone that carries it
  Float3 from, to;            // the end spheres' centres, bind-pose asset frame; at a pose:
                              // skinning(joint) * from, skinning(joint) * to
  float radius_from = 0.f;    // metres in the rest pose (as a joint sphere's), > 0
  float radius_to = 0.f;      // metres in the rest pose, > 0
};

}  // namespace drape

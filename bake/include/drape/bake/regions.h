#pragma once
// Paper B §3.1: the body split by skin weight into rigid regions (one bone) and flexible regions
// (blended, near joints). Positions are taken in the rest pose, whose scale is the animation's.

#include <cstdint>
#include <string>
#include <vector>

#include "drape/bake/character.h"
#include "drape/formats/status.h"

namespace drape::bake {

struct JointRegion {
  int32_t child = -1;   // the joint sphere moves with this bone
  int32_t parent = -1;  // the other bone of the pair (-1 if none)
  Float3 center;        // rest-pose asset frame, metres
  std::vector<uint32_t> flexible_vertices;
};

struct Regions {
  float rigid_threshold = 0.99f;
  std::vector<Float3> rest_positions;  // the rest-pose skinned mesh
  std::vector<Mat34> rest_skinning;    // per joint: bind -> rest
  std::vector<Mat34> collider_frames;  // per joint: rigid rest-pose joint frame -> asset
  std::vector<std::vector<uint32_t>> rigid_vertices;  // per joint
  // Per joint: flexible vertices whose heaviest bone it is, at a weight in [shape_threshold,
  // rigid_threshold) (ties go to the lower joint index); with shape_threshold 0, the corners of
  // the triangles the bone carries most of. They shape the bone's hull (flexible ones stay in
  // their joint sphere too).
  std::vector<std::vector<uint32_t>> shaping_vertices;
  std::vector<JointRegion> joints;  // one per bone pair with flexible vertices
};

// rigid_threshold in (0.5, 1]: a vertex is rigid to its heaviest bone when that weight reaches it.
// shape_threshold in [0, 1]: a flexible vertex also shapes its heaviest bone's hull when that
// weight reaches min(shape_threshold, rigid_threshold) (1: none does). 0: every triangle shapes
// the hull of the bone with the largest summed weight over its corners (all three corners), so
// the hulls hold the whole rest-pose surface.
Status SplitRegions(const Character& character, float rigid_threshold, Regions* regions,
                    float shape_threshold = 1.f);

// Per triangle (mesh.triangles / 3): the joint with the largest summed skin weight over its three
// corners (ties: the lower index), the bone that carries it; -1 when no corner has an influence
// below joint_count.
std::vector<int32_t> TriangleBones(const MeshData& mesh, uint32_t joint_count);

// Joint spheres (paper B §1.3, §3.1): centred on the joint, radius covering its flexible vertices
// plus delta (metres). Written into the bind-pose frame the runtime expects. With the bones' hulls
// (inflated, built from `regions`) and the mesh's triangles, a sphere covers only what the hulls
// leave out: the flexible corners of rest-pose triangles that no single hull holds.
std::vector<JointSphereData> BuildJointSpheres(const Regions& regions, float delta,
                                               const std::vector<HullColliderData>& hulls = {},
                                               const std::vector<uint32_t>& triangles = {});

}  // namespace drape::bake

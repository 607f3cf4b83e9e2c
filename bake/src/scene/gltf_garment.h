#pragma once
// glTF garments (`"type": "gltf"`): the mesh of a glTF 2.0 file (.gltf or .glb), with its skin
// bound to the character's skeleton by joint name, and distances painted per vertex.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "drape/bake/gltf_export.h"
#include "drape/formats/skeleton_data.h"
#include "drape/formats/status.h"
#include "drape/formats/types.h"
#include "drape/runtime/cloth.h"

namespace drape::bake::detail {

// Per-vertex distances a garment file may paint, as glTF application-specific attributes
// (SCALAR float, drape/bake/gltf_export.h): file units; a negative value means unlimited.
inline constexpr const char* kMaxDistanceAttribute = kGltfMaxDistanceAttribute;
inline constexpr const char* kBackstopAttribute = kGltfBackstopAttribute;

// One mesh of a glTF file, its vertices welded (vertices that a glTF exporter split at UV or
// normal seams, with equal positions and skin, become one particle).
struct GltfGarmentMesh {
  std::string name;  // the node's name, else its mesh's
  // Skinned: the bind-space positions (POSITION as stored); else POSITION moved by the node's
  // world transform in the file's default scene.
  std::vector<Float3> positions;
  std::vector<uint32_t> triangles;  // 3 per triangle, welded indices
  std::vector<Float3> colors;       // COLOR_0 as linear RGB in [0, 1]; empty: none
  std::vector<float> max_distance;  // kMaxDistanceAttribute; empty: none
  std::vector<float> backstop;      // kBackstopAttribute; empty: none
  // The skin (joint_names empty: not skinned): the skin's joints by node name and inverse bind
  // matrices, and per vertex up to four (skin joint, weight) pairs from JOINTS_0 / WEIGHTS_0.
  std::vector<std::string> joint_names;
  std::vector<Mat34> inverse_bind;
  std::vector<std::array<uint16_t, 4>> vertex_joints;
  std::vector<std::array<float, 4>> vertex_weights;
};

// Reads the mesh node called `mesh` (a node's or its mesh's name; empty: the file must hold one
// mesh node) of `file`: every TRIANGLES primitive of it, merged. Messages start with `where`
// and say why (not glTF, no such mesh with the names there are, an accessor beyond its buffer,
// an index out of range, a primitive that is not triangles, sparse accessors ...). Images are not
// decoded.
Status ReadGltfGarment(const std::string& file, const std::string& where, const std::string& mesh,
                       GltfGarmentMesh* out);

// A skinned garment file bound to the character: each vertex's weights renamed to the skeleton's
// joints, and its bind-pose position in the asset frame: the weighted sum over its joints j of
// bind_j * inverse_bind_file_j * position (identity when the file's skeleton is the character's).
struct GltfGarmentBinding {
  std::vector<ClothSkinWeights> skin;  // per vertex, the skeleton's joint indices
  std::vector<Float3> bind_positions;  // per vertex, metres in the bind-pose asset frame
  float scale = 1.f;                   // asset metres per file unit (the painted distances)
};

// The file's skeleton may differ from the character's by one transform of the whole (other
// units, an armature placed elsewhere): the painted distances then scale with it. Errors
// (starting with `where`) name a weighted joint the skeleton lacks (with the nearest names), a
// vertex without weight, and a joint that disagrees with the most weighted one: it places a
// vertex more than `tolerance` metres from where that joint does (another rig or bind pose).
Status BindGltfGarment(const GltfGarmentMesh& mesh, const SkeletonData& skeleton, float tolerance,
                       const std::string& where, GltfGarmentBinding* out);

}  // namespace drape::bake::detail

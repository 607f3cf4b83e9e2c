#pragma once
// Everything one .drape file holds. Plain data: the bake fills it, the file container writes and
// reads it, and the runtime builds its immutable objects from it.

#include <string>
#include <vector>

#include "drape/formats/body_map_data.h"
#include "drape/formats/clip_data.h"
#include "drape/formats/hull_collider_data.h"
#include "drape/formats/mesh_data.h"
#include "drape/formats/skeleton_data.h"
#include "drape/formats/types.h"

namespace drape {

struct AssetInfo {
  std::string source_name;     // file name of the character the asset was baked from
  std::string tool_version;    // drape version that baked it
  float unit_scale = 1.f;      // metres per source unit that was applied
  std::string up_axis = "+Y";  // the source's up axis that was mapped to +Y
  Mat34 source_to_asset;       // source scene-root frame -> asset frame (scale and rotation)
};

struct CharacterAsset {
  AssetInfo info;
  SkeletonData skeleton;
  std::vector<ClipData> clips;
  MeshData mesh;
  BodyMapSet body_maps;
  std::vector<HullColliderData> hulls;
  std::vector<JointSphereData> joint_spheres;
  BoneMapSet bone_maps;  // per-bone local maps; empty unless the bake was asked for them
  std::vector<CapsuleColliderData> capsules;  // one per bone that carries skin (format 6)
  // The bind mesh simplified for drawing body maps at run time (BodyMapRenderer): a subset of
  // mesh's vertices with their influences, within the bake's maps.render_tolerance of its
  // surface. Empty when the bake kept none (format 8; older files, or nothing to gain).
  MeshData render_mesh;
};

// The mesh to render body maps from: the render mesh when the asset has one, else the bind mesh.
inline const MeshData& RenderMeshOf(const CharacterAsset& asset) {
  return asset.render_mesh.positions.empty() ? asset.mesh : asset.render_mesh;
}

}  // namespace drape

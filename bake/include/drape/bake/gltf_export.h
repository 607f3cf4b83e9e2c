#pragma once
// A baked asset as glTF 2.0, to look at in Blender or any glTF viewer: the skeleton as nodes
// (rest pose) with the skinned bind mesh, every hull as a translucent mesh on a node attached to
// its joint, every joint sphere and capsule likewise, and the clips as animations, so the
// colliders move with the character.

#include <string>
#include <vector>

#include "drape/formats/character_asset.h"
#include "drape/formats/status.h"
#include "drape/runtime/cloth.h"

namespace drape::bake {

// Binary glTF (.glb) when `path` ends in .glb, else .gltf with its buffer embedded. Written
// atomically: nothing on error.
Status WriteAssetGltf(const CharacterAsset& asset, const std::string& path);

// A simulation as recorded frame by frame: the character's skinning matrices and each garment's
// particle positions, frame_seconds apart.
struct SimulationRecording {
  float frame_seconds = 1.f / 60.f;          // > 0
  std::vector<std::vector<Mat34>> skinning;  // per frame: one matrix per joint
  struct Garment {
    std::string name;
    std::vector<uint32_t> triangles;             // 3 particle indices each
    std::vector<std::vector<Float3>> positions;  // per frame: one per particle
  };
  std::vector<Garment> garments;
};

// The simulation as one animated glTF: the skinned body animated by the recorded poses (each
// joint's local transform per frame) and each garment as a mesh whose per-frame shapes are morph
// targets switched frame by frame (STEP weights), all in one animation "simulation".
Status WriteSimulationGltf(const CharacterAsset& asset, const SimulationRecording& recording,
                           const std::string& path);

// A garment bound to the character's skeleton, to paint or refit in a DCC tool and read back as
// a scene's `gltf` garment (docs/SCENES.md).
struct GarmentExport {
  std::string name;                    // the garment's node and mesh
  std::vector<Float3> bind_positions;  // metres, the bind-pose asset frame
  std::vector<uint32_t> triangles;     // 3 particle indices each
  std::vector<ClothSkinWeights> skin;  // per particle, the skeleton's joints
  // Per particle, metres (+inf: unlimited), written as _MAX_DISTANCE / _BACKSTOP attributes with
  // -1 for unlimited; empty: not written.
  std::vector<float> max_distance, backstop;
};

// The character (skeleton at rest, its skin, the skinned body, named "body") and the garment as a
// mesh skinned by the same skin (JOINTS_0 / WEIGHTS_0) at its bind positions. Binary (.glb) when
// `path` ends in .glb. Written atomically: nothing on error.
Status WriteGarmentGltf(const CharacterAsset& asset, const GarmentExport& garment,
                        const std::string& path);

namespace detail {
inline constexpr const char* kGltfMaxDistanceAttribute = "_MAX_DISTANCE";
inline constexpr const char* kGltfBackstopAttribute = "_BACKSTOP";
}  // namespace detail

}  // namespace drape::bake

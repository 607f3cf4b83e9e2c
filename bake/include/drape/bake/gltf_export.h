#pragma once
// A baked asset as glTF 2.0, to look at in Blender or any glTF viewer: the skeleton as nodes
// (rest pose) with the skinned bind mesh, every hull as a translucent mesh on a node attached to
// its joint, every joint sphere likewise, and the clips as animations, so the colliders move
// with the character.

#include <string>

#include "drape/formats/character_asset.h"
#include "drape/formats/status.h"

namespace drape::bake {

// Binary glTF (.glb) when `path` ends in .glb, else .gltf with its buffer embedded. Written
// atomically: nothing on error.
Status WriteAssetGltf(const CharacterAsset& asset, const std::string& path);

}  // namespace drape::bake

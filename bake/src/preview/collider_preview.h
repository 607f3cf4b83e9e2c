#pragma once
// Private to the bake pipeline: the --preview picture of paper B's colliders over the body.

#include <span>
#include <string>

#include "drape/formats/character_asset.h"
#include "drape/formats/status.h"

namespace drape::bake {

// Writes <directory>/colliders_front.png and colliders_side.png: the rest-pose body in grey with
// the hulls (one colour per bone) and joint spheres (translucent white) drawn over it, flat
// shaded, orthographic, about `height` pixels tall. rest_skinning: bind -> rest per joint.
Status WriteColliderPreview(const CharacterAsset& asset, std::span<const Float3> rest_positions,
                            std::span<const Mat34> rest_skinning, const std::string& directory,
                            uint32_t height = 800);

}  // namespace drape::bake

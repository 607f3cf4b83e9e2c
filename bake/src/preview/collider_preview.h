#pragma once
// Private to the bake pipeline: the --preview picture of paper B's colliders over the body.

#include <span>
#include <string>
#include <vector>

#include "drape/formats/character_asset.h"
#include "drape/formats/status.h"

namespace drape::bake {

// How far each collider bulges out of the body (fit/collider_fit.h), for colouring it: green at
// 0, yellow at red_mm / 2, red at red_mm and beyond.
struct PreviewBloat {
  std::vector<double> hull_mm;    // per hull of the asset, in its order
  std::vector<double> sphere_mm;  // per joint sphere of the asset, in its order
  double red_mm = 15.0;           // > 0
};

// Writes <directory>/colliders_front.png and colliders_side.png: the rest-pose body in grey with
// the hulls and the translucent joint spheres drawn over it, flat shaded, orthographic, about
// `height` pixels tall. rest_skinning: bind -> rest per joint. Without `bloat` each hull has a
// colour of its own and the spheres are white; with it every collider is coloured by its bloat.
Status WriteColliderPreview(const CharacterAsset& asset, std::span<const Float3> rest_positions,
                            std::span<const Mat34> rest_skinning, const std::string& directory,
                            uint32_t height = 800, const PreviewBloat* bloat = nullptr);

}  // namespace drape::bake

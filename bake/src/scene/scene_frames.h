#pragma once
// The frames a scene plays (drape/bake/scene.h, "Frames of a scene"): how many, and which clip
// time a scene time plays.

#include <cstdint>

#include "drape/formats/character_asset.h"

namespace drape::bake::detail {

// ceil(duration / dt) frames (1e-4 frame of slack for a dt written with few digits), in [1, 1e7].
uint32_t FrameCountFor(float duration, float dt);

// The clip time a scene time plays (what SkeletonPose::SampleClip does with it).
float ClipTime(const ClipData& clip, float time, bool loop);

}  // namespace drape::bake::detail

#pragma once
// A configuration value that names a clip (a bake config's /maps/clip, a scene's
// /animation/clip), looked up in a character's clips with one refusal for every caller.

#include <cstdint>
#include <span>
#include <string>

#include "drape/formats/clip_data.h"
#include "drape/formats/status.h"

namespace drape::bake::detail {

// The index of the clip called `name` in `clips`. Else kInvalidArgument:
// "<origin>: no clip named 'walkk' in '<character>' (clips: walk | run)", where origin is the
// file and JSON path that named the clip.
Status FindClipNamed(std::span<const ClipData> clips, const std::string& name,
                     const std::string& origin, const std::string& character, int32_t* index);

}  // namespace drape::bake::detail

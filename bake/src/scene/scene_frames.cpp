#include "scene/scene_frames.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "config/clip_lookup.h"
#include "drape/bake/scene.h"
#include "scene/scene_messages.h"

namespace drape::bake {
namespace detail {

uint32_t FrameCountFor(float duration, float dt) {
  const double frames = std::ceil(static_cast<double>(duration) / dt - 1e-4);
  return static_cast<uint32_t>(std::clamp(frames, 1.0, 1e7));
}

float ClipTime(const ClipData& clip, float time, bool loop) {
  if (loop && clip.duration > 0.f) {
    time = std::fmod(time, clip.duration);
    if (time < 0.f) time += clip.duration;
  }
  return std::fmin(std::fmax(time, 0.f), clip.duration);
}

}  // namespace detail

using namespace detail;

Status ResolveSceneClip(const CharacterAsset& asset, Scene* scene, int32_t* clip) {
  *clip = -1;
  if (scene->animation.clip.empty()) {
    if (scene->frame_count == 0) scene->frame_count = FrameCountFor(1.f, scene->dt);
    return Status::Ok();
  }
  DRAPE_RETURN_IF_ERROR(FindClipNamed(asset.clips, scene->animation.clip,
                                      scene->source + ": /animation/clip", scene->character, clip));
  if (scene->frame_count == 0) {
    const float duration = asset.clips[static_cast<size_t>(*clip)].duration;
    scene->frame_count = FrameCountFor(duration > 0.f ? duration : scene->dt, scene->dt);
  }
  return Status::Ok();
}

}  // namespace drape::bake

#pragma once
// An animation clip resampled at a fixed rate into local joint transforms.

#include <cstdint>
#include <string>
#include <vector>

#include "drape/formats/types.h"

namespace drape {

struct ClipData {
  std::string name;
  float duration = 0.f;      // seconds, >= 0
  float sample_rate = 30.f;  // frames per second, > 0
  uint32_t frame_count = 0;  // >= 1; frame k is at time min(k / sample_rate, duration)
  // Frame-major local transforms: keys[frame * joint_count + joint]. Joints without a channel
  // in the source keep their rest transform here, so sampling needs nothing else.
  std::vector<Transform> keys;
};

}  // namespace drape

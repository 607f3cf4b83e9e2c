#pragma once
// The skeleton as stored in a .drape file: joints in parent-before-child order.

#include <cstdint>
#include <string>
#include <vector>

#include "drape/formats/types.h"

namespace drape {

struct SkeletonData {
  std::vector<std::string> joint_names;  // unique, non-empty
  std::vector<int32_t> parents;          // -1 for a root, otherwise < own index
  // Local transform of each joint in the rest pose (the node hierarchy as authored). For a root,
  // relative to the asset frame: it already contains the source-to-asset unit scale and up axis.
  std::vector<Transform> rest_local;
  // Asset frame at bind -> joint frame (the inverse bind or "offset" matrix, re-expressed in the
  // asset frame). Skinning matrix of joint j at a pose: global(j) * inverse_bind[j].
  std::vector<Mat34> inverse_bind;

  uint32_t joint_count() const { return static_cast<uint32_t>(parents.size()); }
};

}  // namespace drape

#pragma once
// Private to the runtime: the checks HullColliderSet::Build runs on untrusted collider data, and
// the shape of their messages ("HullColliderSet: hulls[3].planes[7].normal is not unit length").

#include <cstddef>
#include <cstdint>
#include <string>

#include "drape/formats/hull_collider_data.h"
#include "drape/formats/status.h"

namespace drape::detail {

inline constexpr uint32_t kMaxHullPlanes = 4096;
inline constexpr float kHullUnitTolerance = 1e-3f;  // |1 - |n|| and |a . b| for unit and orthogonal

// "kind[index].field"
inline std::string HullField(const char* kind, size_t index, const std::string& field) {
  return std::string(kind) + "[" + std::to_string(index) + "]." + field;
}
inline Status HullError(const std::string& where, const std::string& why) {
  return Status(StatusCode::kInvalidArgument, "HullColliderSet: " + where + " " + why);
}

// Every count, index, float and frame of hull `index` (see HullColliderSet::Build).
Status ValidateHullData(const HullColliderData& hull, size_t index, uint32_t joint_count);
Status ValidateJointSphereData(const JointSphereData& sphere, size_t index, uint32_t joint_count);

}  // namespace drape::detail

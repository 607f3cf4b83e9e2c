#include "drape/runtime/capsule_colliders.h"

#include <cmath>
#include <string>

#include "drape/runtime/math.h"

namespace drape {
namespace {

Float3 Column(const Mat34& m, int c) { return {m.m[c], m.m[4 + c], m.m[8 + c]}; }

// The part of v normal to the unit x, normalised (Gram-Schmidt twice, so that it is orthogonal
// to x to float precision); zero when v lies within 30 degrees of x, where the cancellation would
// leave it visibly off (one of two orthonormal columns is always 45 degrees or more from x).
Float3 NormalPart(Float3 v, Float3 x) {
  Float3 n = v - x * Dot(v, x);
  const float length = Length(n);
  if (!(length > 0.5f * Length(v))) return Float3{};
  n = n * (1.f / length);
  n = n - x * Dot(n, x);
  return n * (1.f / Length(n));
}

}  // namespace

Mat34 CapsuleFrame(const CapsuleColliderData& capsule, const Mat34& skinning, float* half_length) {
  const Float3 a = TransformPoint(skinning, capsule.from);
  const Float3 b = TransformPoint(skinning, capsule.to);
  const float length = Length(b - a);
  *half_length = 0.5f * length;
  // x along the capsule (the bone's first axis for a sphere); y from the bone's next axis that
  // is not along x, so the frame turns with the bone; z completes it.
  Float3 x = length > 0.f ? (b - a) * (1.f / length) : NormalizeOr(Column(skinning, 0), {1, 0, 0});
  Float3 y = NormalPart(Column(skinning, 1), x);
  if (Length(y) == 0.f) y = NormalPart(Column(skinning, 2), x);
  if (Length(y) == 0.f) y = NormalPart(Float3{0.f, 1.f, 0.f}, x);
  if (Length(y) == 0.f) y = NormalPart(Float3{1.f, 0.f, 0.f}, x);
  const Float3 z = Cross(x, y);
  const Float3 middle = (a + b) * 0.5f;
  Mat34 frame;
  const Float3 axes[3] = {x, y, z};
  for (int c = 0; c < 3; ++c) {
    frame.m[c] = axes[c].x, frame.m[4 + c] = axes[c].y, frame.m[8 + c] = axes[c].z;
  }
  frame.m[3] = middle.x, frame.m[7] = middle.y, frame.m[11] = middle.z;
  return frame;
}

Status AddCapsuleColliders(std::span<const CapsuleColliderData> capsules,
                           std::span<const Mat34> skinning_start,
                           std::span<const Mat34> skinning_end, ShapeColliderSet* shapes) {
  for (size_t i = 0; i < capsules.size(); ++i) {
    const CapsuleColliderData& c = capsules[i];
    if (c.joint < 0 || static_cast<size_t>(c.joint) >= skinning_start.size() ||
        static_cast<size_t>(c.joint) >= skinning_end.size()) {
      return Status(StatusCode::kInvalidArgument, "capsule " + std::to_string(i) + ": joint " +
                                                      std::to_string(c.joint) +
                                                      " has no skinning matrix");
    }
    float half_start = 0.f, half_end = 0.f;
    const Mat34 start = CapsuleFrame(c, skinning_start[static_cast<size_t>(c.joint)], &half_start);
    const Mat34 end = CapsuleFrame(c, skinning_end[static_cast<size_t>(c.joint)], &half_end);
    // A bone that stretches within the frame: the capsule keeps the end pose's length (the
    // set's shapes are rigid over a frame).
    if (Status s = shapes->AddCapsule(start, end, half_end, c.radius_from, c.radius_to); !s.ok())
      return Status(s.code(), "capsule " + std::to_string(i) + ": " + s.message());
  }
  return Status::Ok();
}

}  // namespace drape

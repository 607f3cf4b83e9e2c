#include "scene_shapes.h"

#include <cmath>
#include <string>

#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"

namespace drape::sim {
namespace {

// A rotation whose column `axis` (0 = x, 1 = y) is the unit `direction`, the others completing a
// right-handed frame.
Mat34 FrameAlong(Float3 direction, int axis, Float3 origin) {
  const Float3 d = NormalizeOr(direction, {0.f, 1.f, 0.f});
  const Float3 helper = std::abs(d.x) < 0.9f ? Float3{1.f, 0.f, 0.f} : Float3{0.f, 0.f, 1.f};
  const Float3 a = NormalizeOr(Cross(helper, d), {0.f, 0.f, 1.f});  // perpendicular to d
  const Float3 b = Cross(d, a);
  // Columns (x, y, z): axis 0 -> (d, a, b); axis 1 -> (b, d, a), both right-handed.
  const Float3 c0 = axis == 0 ? d : b, c1 = axis == 0 ? a : d, c2 = axis == 0 ? b : a;
  Mat34 m;
  m.m[0] = c0.x, m.m[1] = c1.x, m.m[2] = c2.x, m.m[3] = origin.x;
  m.m[4] = c0.y, m.m[5] = c1.y, m.m[6] = c2.y, m.m[7] = origin.y;
  m.m[8] = c0.z, m.m[9] = c1.z, m.m[10] = c2.z, m.m[11] = origin.z;
  return m;
}

}  // namespace

Status SceneShapes::Init(const bake::Scene& scene, const SkeletonData& skeleton,
                         std::span<const Mat34> rest_skinning) {
  shapes_.clear();
  for (const bake::SceneShape& shape : scene.shapes) {
    Posed p;
    p.shape = &shape;
    if (!shape.joint.empty()) {
      p.joint = FindJoint(skeleton, shape.joint);
      if (p.joint < 0)
        return Status(
            StatusCode::kInvalidArgument,
            scene.source + ": " + shape.path + "/joint: no joint named '" + shape.joint + "'");
      if (!InverseAffine(rest_skinning[static_cast<size_t>(p.joint)], &p.inverse_rest))
        return Status(StatusCode::kInvalidArgument, scene.source + ": " + shape.path +
                                                        "/joint: its rest skinning matrix is "
                                                        "singular");
    }
    switch (shape.type) {
      case bake::SceneShapeType::kPlane:
        p.local = FrameAlong(shape.normal, 1, shape.center);
        break;
      case bake::SceneShapeType::kCapsule: {
        const Float3 axis = shape.to - shape.from;
        p.half_length = 0.5f * Length(axis);
        p.local = FrameAlong(axis, 0, (shape.from + shape.to) * 0.5f);
        break;
      }
      case bake::SceneShapeType::kSphere:
      case bake::SceneShapeType::kBox:
        p.local = TranslationMatrix(shape.center);
        break;
    }
    shapes_.push_back(p);
  }
  return Status::Ok();
}

Status SceneShapes::Pose(std::span<const Mat34> skinning_start, std::span<const Mat34> skinning_end,
                         ShapeColliderSet* set) const {
  set->Clear();
  for (const Posed& p : shapes_) {
    Mat34 start = p.local, end = p.local;
    if (p.joint >= 0) {  // the joint's motion since the rest pose: S(t) * S(rest)^-1
      const size_t j = static_cast<size_t>(p.joint);
      start = Multiply(Multiply(skinning_start[j], p.inverse_rest), p.local);
      end = Multiply(Multiply(skinning_end[j], p.inverse_rest), p.local);
    }
    const bake::SceneShape& s = *p.shape;
    Status added;
    switch (s.type) {
      case bake::SceneShapeType::kPlane:
        added = set->AddPlane(start, end);
        break;
      case bake::SceneShapeType::kSphere:
        added = set->AddSphere(start, end, s.radius);
        break;
      case bake::SceneShapeType::kCapsule:
        added = set->AddCapsule(start, end, p.half_length, s.radius,
                                s.radius_to > 0.f ? s.radius_to : s.radius);
        break;
      case bake::SceneShapeType::kBox:
        added = set->AddBox(start, end, s.half_extents);
        break;
    }
    if (!added.ok()) return Status(added.code(), s.path + ": " + added.message());
  }
  return Status::Ok();
}

}  // namespace drape::sim

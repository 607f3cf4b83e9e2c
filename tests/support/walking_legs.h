#pragma once
// A walking pair of legs made of 20 colliders, shared by the cloth benchmark and the cloth tests:
// 4 box hulls (thighs and shins) and 16 joint spheres (hips, belly, thighs, knees, shins) on 5
// joints, posed by a 1 Hz walk cycle (WalkPose), with a skirt that fits them (WalkingSkirt).

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <vector>

#include "drape/formats/hull_collider_data.h"
#include "drape/runtime/garments.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"

namespace drape::test {

constexpr int kJoints = 5;  // 0 hips, 1 left thigh, 2 right thigh, 3 left shin, 4 right shin
constexpr float kHipY = 0.95f, kKneeY = 0.52f, kLegX = 0.09f;

// An axis-aligned box hull (bind frame = asset frame) carried by `joint`.
inline HullColliderData BoxHull(int32_t joint, Float3 center, Float3 half) {
  HullColliderData h;
  h.joint = joint;
  for (int k = 0; k < 8; ++k) {
    h.vertices.push_back({center.x + ((k & 1) ? half.x : -half.x),
                          center.y + ((k & 2) ? half.y : -half.y),
                          center.z + ((k & 4) ? half.z : -half.z)});
  }
  // Faces (-x, +x, -y, +y, -z, +z) as quads counter-clockwise seen from outside.
  const uint32_t quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  const Float3 normals[6] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
  for (uint32_t f = 0; f < 6; ++f) {
    const uint32_t* q = quads[f];
    h.triangles.insert(h.triangles.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
    h.triangle_planes.insert(h.triangle_planes.end(), {f, f});
    Plane plane;
    plane.normal = normals[f];
    plane.offset = Dot(plane.normal, h.vertices[q[0]]);
    h.planes.push_back(plane);
  }
  h.obb.center = center;
  h.obb.axes[0] = {1.f, 0.f, 0.f};
  h.obb.axes[1] = {0.f, 1.f, 0.f};
  h.obb.axes[2] = {0.f, 0.f, 1.f};
  h.obb.half_extents = half;
  h.projection_axis = {0.f, 1.f, 0.f};
  h.projection_u = {0.f, 0.f, 1.f};
  h.projection_v = {1.f, 0.f, 0.f};
  return h;
}

// Rotation about +x by `angle` radians about the point `pivot`.
inline Mat34 RotateXAbout(float angle, Float3 pivot) {
  Mat34 r;
  const float c = std::cos(angle), s = std::sin(angle);
  r.m[5] = c;
  r.m[6] = -s;
  r.m[9] = s;
  r.m[10] = c;
  const Float3 moved = TransformVector(r, pivot);
  r.m[3] = pivot.x - moved.x;
  r.m[7] = pivot.y - moved.y;
  r.m[11] = pivot.z - moved.z;
  return r;
}

// A walk cycle at 1 Hz: the thighs swing +-0.45 rad in antiphase, the shins bend back up to
// 0.6 rad; the hips move forward at 1.2 m/s and bob by 1 cm.
inline void WalkPose(float t, Mat34 skinning[kJoints]) {
  const float phase = 2.f * std::numbers::pi_v<float> * t;
  Mat34 hips;
  hips.m[7] = 0.01f * std::sin(2.f * phase);
  hips.m[11] = 1.2f * t;
  skinning[0] = hips;
  for (int side = 0; side < 2; ++side) {
    const float sign = side == 0 ? 1.f : -1.f;
    const float swing = 0.45f * sign * std::sin(phase);
    const float bend =
        0.3f * (1.f - std::cos(phase + (side == 0 ? 0.f : std::numbers::pi_v<float>)));
    const Float3 hip{sign * kLegX, kHipY, 0.f}, knee{sign * kLegX, kKneeY, 0.f};
    const Mat34 thigh = Multiply(hips, RotateXAbout(-swing, hip));
    skinning[1 + side] = thigh;
    skinning[3 + side] = Multiply(thigh, RotateXAbout(bend, knee));
  }
}

// The legs' colliders in their bind frame (skinning = identity at the bind pose).
struct WalkingLegs {
  std::vector<HullColliderData> boxes;
  std::vector<JointSphereData> spheres;
  size_t size() const { return boxes.size() + spheres.size(); }
};

inline WalkingLegs MakeWalkingLegs() {
  WalkingLegs legs;
  const auto sphere = [&](int32_t joint, Float3 c, float r) {
    JointSphereData s;
    s.joint = joint;
    s.center = c;
    s.radius = r;
    legs.spheres.push_back(s);
  };
  sphere(0, {0.f, kHipY, 0.f}, 0.15f);
  sphere(0, {0.f, kHipY + 0.12f, 0.03f}, 0.14f);
  for (int side = 0; side < 2; ++side) {
    const float x = (side == 0 ? 1.f : -1.f) * kLegX;
    legs.boxes.push_back(
        BoxHull(1 + side, {x, (kHipY + kKneeY) * 0.5f, 0.f}, {0.06f, 0.2f, 0.06f}));
    legs.boxes.push_back(BoxHull(3 + side, {x, kKneeY - 0.22f, 0.f}, {0.045f, 0.2f, 0.045f}));
    for (int k = 0; k < 3; ++k) {
      const float kf = static_cast<float>(k);
      const float f = (kf + 1.f) / 4.f;
      sphere(1 + side, {x, kHipY + (kKneeY - kHipY) * f, 0.f}, 0.085f - 0.01f * kf);
      sphere(3 + side, {x, kKneeY - 0.4f * f, 0.f}, 0.06f - 0.005f * kf);
    }
    sphere(3 + side, {x, kKneeY, 0.f}, 0.065f);
  }
  return legs;
}

// Penetration of the particles into the posed boxes and spheres (the colliders themselves, not
// the solvers' margins): the deepest particle (metres, 0 when none is inside) and how many are
// inside any collider. Brute force over particles x colliders (about 1 ms for the skirt).
struct Penetration {
  float max_depth = 0.f;
  uint32_t inside = 0;
};
inline Penetration MeasurePenetration(const WalkingLegs& scene, const Mat34 skinning[kJoints],
                                      std::span<const Float3> positions) {
  std::vector<Mat34> box_inverse;  // world -> box frame
  for (const HullColliderData& box : scene.boxes)
    box_inverse.push_back(InverseRigid(Multiply(skinning[box.joint], box.bind_frame)));
  std::vector<Float3> sphere_centres;
  for (const JointSphereData& sphere : scene.spheres)
    sphere_centres.push_back(TransformPoint(skinning[sphere.joint], sphere.center));
  Penetration result;
  for (const Float3 p : positions) {
    float depth = 0.f;  // deepest over the colliders containing p
    for (size_t b = 0; b < scene.boxes.size(); ++b) {
      const Obb& obb = scene.boxes[b].obb;  // axis-aligned in the box frame (BoxHull)
      const Float3 q = TransformPoint(box_inverse[b], p) - obb.center;
      const float inside_by =
          std::min({obb.half_extents.x - std::abs(q.x), obb.half_extents.y - std::abs(q.y),
                    obb.half_extents.z - std::abs(q.z)});
      depth = std::max(depth, inside_by);
    }
    for (size_t s = 0; s < scene.spheres.size(); ++s)
      depth = std::max(depth, scene.spheres[s].radius - Length(p - sphere_centres[s]));
    if (depth > 0.f) {
      ++result.inside;
      result.max_depth = std::max(result.max_depth, depth);
    }
  }
  return result;
}

// A flared skirt hanging from just above the hips: `length` metres, segments x rings cells.
inline SkirtShape WalkingSkirt(float length, uint32_t segments, uint32_t rings) {
  SkirtShape shape;
  shape.top_center = {0.f, kHipY + 0.05f, 0.f};
  shape.top_radius = 0.17f;
  shape.bottom_radius = 0.36f;
  shape.length = length;
  shape.segments = segments;
  shape.rings = rings;
  return shape;
}

}  // namespace drape::test

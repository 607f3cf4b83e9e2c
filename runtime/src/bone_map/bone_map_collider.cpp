// BoneMapCollider: per-bone maps posed by the skinning matrices; each motion tested in the view
// frames of the bones whose posed bounds it reaches (docs/ALGORITHMS.md §7.10).
#include "drape/runtime/bone_map_collider.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "drape/runtime/math.h"
#include "tasks/parallel_for.h"

namespace drape {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
// Passes of CollideBatch: a particle pushed out of one part into its neighbour (a thigh's slab
// into the pelvis's) leaves that one in the second.
constexpr int kPasses = 2;

Float3 Min(Float3 a, Float3 b) {
  return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
Float3 Max(Float3 a, Float3 b) {
  return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}

bool Finite(const Mat34& m) {
  for (float v : m.m)
    if (!std::isfinite(v)) return false;
  return true;
}

}  // namespace

Status BoneMapCollider::Build(const BoneMapSet& maps, uint32_t joint_count,
                              DepthSampling sampling) {
  bones_.clear();
  posed_.clear();
  joint_count_ = joint_count;
  std::vector<Bone> bones(maps.maps.size());
  for (size_t b = 0; b < maps.maps.size(); ++b) {
    const BoneMapData& data = maps.maps[b];
    const std::string at = "BoneMapCollider::Build: bone map " + std::to_string(b);
    if (data.joint >= joint_count) {
      return Status(StatusCode::kInvalidArgument, at + ": joint " + std::to_string(data.joint) +
                                                      " of " + std::to_string(joint_count));
    }
    Mat34 inverse;
    if (!Finite(data.view_from_bind) || !InverseAffine(data.view_from_bind, &inverse)) {
      return Status(StatusCode::kInvalidArgument,
                    at + ": view_from_bind is not a finite invertible transform");
    }
    if (Status s = bones[b].maps.Build(data.pose, sampling); !s.ok()) {
      return Status(s.code(), at + ": " + s.message());
    }
    bones[b].joint = data.joint;
    bones[b].view_from_bind = data.view_from_bind;
  }
  bones_ = std::move(bones);
  posed_.resize(bones_.size());
  const std::vector<Mat34> bind(joint_count);  // identity: the bind pose until SetPose
  return SetPose(bind, bind);
}

Status BoneMapCollider::SetPose(std::span<const Mat34> skinning_start,
                                std::span<const Mat34> skinning_end) {
  if (skinning_start.size() < joint_count_ || skinning_end.size() < joint_count_) {
    return Status(StatusCode::kInvalidArgument,
                  "BoneMapCollider::SetPose: " + std::to_string(skinning_start.size()) + " and " +
                      std::to_string(skinning_end.size()) + " matrices for " +
                      std::to_string(joint_count_) + " joints");
  }
  // Every matrix first, so a bad one leaves the previous pose.
  for (const Bone& bone : bones_) {
    Mat34 unused;
    for (const Mat34& m : {skinning_start[bone.joint], skinning_end[bone.joint]}) {
      if (!Finite(m) || !InverseAffine(m, &unused)) {
        return Status(StatusCode::kInvalidArgument,
                      "BoneMapCollider::SetPose: the skinning matrix of joint " +
                          std::to_string(bone.joint) + " is not finite or not invertible");
      }
    }
  }
  for (size_t b = 0; b < bones_.size(); ++b) {
    const Bone& bone = bones_[b];
    PosedBone& p = posed_[b];
    Mat34 bind_from_world_start, bind_from_world_end, bind_from_view;
    (void)InverseAffine(skinning_start[bone.joint], &bind_from_world_start);
    (void)InverseAffine(skinning_end[bone.joint], &bind_from_world_end);
    (void)InverseAffine(bone.view_from_bind, &bind_from_view);
    p.view_from_world_start = Multiply(bone.view_from_bind, bind_from_world_start);
    p.view_from_world_end = Multiply(bone.view_from_bind, bind_from_world_end);
    p.world_from_view_end = Multiply(skinning_end[bone.joint], bind_from_view);
    p.scale_end = UniformScale(p.world_from_view_end);
    const Mat34 world_from_view_start = Multiply(skinning_start[bone.joint], bind_from_view);
    p.lo = {kInf, kInf, kInf};
    p.hi = {-kInf, -kInf, -kInf};
    const Float3 lo = bone.maps.bounds_min(), hi = bone.maps.bounds_max();
    if (!(lo.x <= hi.x)) continue;  // empty maps: a box nothing reaches
    for (int corner = 0; corner < 8; ++corner) {
      const Float3 c{corner & 1 ? hi.x : lo.x, corner & 2 ? hi.y : lo.y, corner & 4 ? hi.z : lo.z};
      for (const Mat34& m : {world_from_view_start, p.world_from_view_end}) {
        const Float3 w = TransformPoint(m, c);
        p.lo = Min(p.lo, w);
        p.hi = Max(p.hi, w);
      }
    }
  }
  return Status::Ok();
}

ContactQuery BoneMapCollider::QueryBone(size_t bone, Float3 p0, Float3 p1) const {
  const PosedBone& p = posed_[bone];
  ContactQuery c = bones_[bone].maps.Query(TransformPoint(p.view_from_world_start, p0),
                                           TransformPoint(p.view_from_world_end, p1));
  if (c.contact) {
    c.point = TransformPoint(p.world_from_view_end, c.point);
    // Normals map by the inverse transpose of world_from_view: view_from_world transposed.
    c.normal = NormalizeOr(TransformVectorTransposed(p.view_from_world_end, c.normal), c.normal);
    c.depth *= p.scale_end;
  }
  return c;
}

bool BoneMapCollider::IsInside(Float3 p) const {
  for (size_t b = 0; b < bones_.size(); ++b) {
    const PosedBone& posed = posed_[b];
    if (p.x < posed.lo.x || p.y < posed.lo.y || p.z < posed.lo.z || p.x > posed.hi.x ||
        p.y > posed.hi.y || p.z > posed.hi.z) {
      continue;
    }
    if (bones_[b].maps.IsInside(TransformPoint(posed.view_from_world_end, p))) return true;
  }
  return false;
}

ContactQuery BoneMapCollider::Query(Float3 p0, Float3 p1) const {
  ContactQuery best;
  if (!IsFinite(p0) || !IsFinite(p1)) {
    best.flags = kCollisionInvalidInput;
    return best;
  }
  const Float3 lo = Min(p0, p1), hi = Max(p0, p1);
  for (size_t b = 0; b < bones_.size(); ++b) {
    const PosedBone& posed = posed_[b];
    if (hi.x < posed.lo.x || hi.y < posed.lo.y || hi.z < posed.lo.z || lo.x > posed.hi.x ||
        lo.y > posed.hi.y || lo.z > posed.hi.z) {
      continue;
    }
    const ContactQuery c = QueryBone(b, p0, p1);
    best.inside_end = best.inside_end || c.inside_end;
    if (!c.contact) continue;
    // The earliest entry; among motions starting inside (t = 0), the nearest exit.
    const bool earlier = !best.contact || c.t < best.t || (c.t == best.t && c.depth < best.depth);
    if (earlier) {
      const bool inside_end = best.inside_end;
      best = c;
      best.inside_end = inside_end;
    }
  }
  return best;
}

uint8_t BoneMapCollider::CollideOne(Float3 from, Float3* position, Float3* velocity,
                                    const ResponseParams& params) const {
  if (!IsFinite(from) || !IsFinite(*position) || !IsFinite(*velocity)) {
    return kCollisionInvalidInput;
  }
  uint8_t flags = kCollisionNone;
  for (int pass = 0; pass < kPasses; ++pass) {
    const ContactQuery c = Query(from, *position);
    if (!c.contact) break;
    ApplyResponse(c, params, position, velocity);
    flags = static_cast<uint8_t>(flags | kCollisionContact | c.flags);
  }
  return flags;
}

Status BoneMapCollider::CollideBatch(std::span<const Float3> previous, std::span<Float3> positions,
                                     std::span<Float3> velocities, std::span<uint8_t> flags,
                                     const ResponseParams& params, uint32_t* contact_count) const {
  const size_t n = positions.size();
  if (previous.size() != n || velocities.size() != n || flags.size() != n) {
    return Status(StatusCode::kInvalidArgument,
                  "BoneMapCollider::CollideBatch: spans of different sizes");
  }
  if (!ValidResponse(params)) {
    return Status(StatusCode::kInvalidArgument,
                  "BoneMapCollider::CollideBatch: response parameters out of range"
                  " (friction in [0, 1], static_friction in [0, 4], restitution in [0, 1], "
                  "separation finite and >= 0)");
  }
  // Chunks of 256 particles (a particle costs up to microseconds here); integer contact sums.
  detail::ChunkSum contacts;
  detail::ParallelRanges(static_cast<int64_t>(n), 256, [&](int64_t begin, int64_t end) {
    uint32_t chunk_contacts = 0;
    for (int64_t i = begin; i < end; ++i) {
      flags[i] = CollideOne(previous[i], &positions[i], &velocities[i], params);
      chunk_contacts += (flags[i] & kCollisionContact) != 0 ? 1u : 0u;
    }
    contacts.Add(chunk_contacts);
  });
  if (contact_count != nullptr) *contact_count = contacts.total();
  return Status::Ok();
}

size_t BoneMapCollider::memory_bytes() const {
  size_t bytes =
      sizeof(*this) + posed_.capacity() * sizeof(PosedBone) + bones_.capacity() * sizeof(Bone);
  for (const Bone& b : bones_) bytes += b.maps.memory_bytes() - sizeof(BodyMapCollider);
  return bytes;
}

}  // namespace drape

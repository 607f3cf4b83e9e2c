#include "methods.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <utility>

#include "fcl_mesh_peer.h"

namespace drape::bench {
namespace {

void DieOnError(const Status& status, const std::string& what) {
  if (status.ok()) return;
  std::fprintf(stderr, "speed_vs_error: %s: %s\n", what.c_str(), status.message().c_str());
  std::exit(1);
}

class BodyMapMethod final : public Method {
 public:
  // lanes: the widest instruction set CollideBatch may use (kNearest); every set gives the
  // same bits.
  BodyMapMethod(const BodyMapPose& pose, DepthSampling sampling, InstructionSet lanes) {
    collider_.LimitInstructionSet(lanes);
    DieOnError(collider_.Build(pose, sampling), "body maps");
  }
  explicit BodyMapMethod(BodyMapCollider&& collider) : collider_(std::move(collider)) {}
  void Collide(std::span<const Float3> previous, std::span<Float3> positions,
               std::span<Float3> velocities, std::span<uint8_t> flags) const override {
    DieOnError(collider_.CollideBatch(previous, positions, velocities, flags, BenchResponse()),
               setting);
  }
  ContactQuery Query(Float3 p0, Float3 p1) const override { return collider_.Query(p0, p1); }
  bool QueryEachAndRespond(std::span<const Float3> previous, std::span<Float3> positions,
                           std::span<Float3> velocities, std::span<uint8_t> flags) const override {
    for (size_t k = 0; k < positions.size(); ++k) {
      if (!IsFinite(previous[k]) || !IsFinite(positions[k]) || !IsFinite(velocities[k])) {
        flags[k] = kCollisionInvalidInput;
        continue;
      }
      const ContactQuery c = collider_.Query(previous[k], positions[k]);
      flags[k] = c.contact ? static_cast<uint8_t>(kCollisionContact | c.flags)
                           : static_cast<uint8_t>(kCollisionNone);
      if (c.contact) RespondInViewFrame(c, &positions[k], &velocities[k]);
    }
    return true;
  }
  const BodyMapCollider& collider() const { return collider_; }

 private:
  // The response as the batch applies it: in the maps' view frame (body_map_collider.h), whose
  // sums run in another order than the asset frame's for a view axis other than z. The
  // permutation is exact, so Query's answer maps back to the view frame's bits.
  void RespondInViewFrame(ContactQuery c, Float3* position, Float3* velocity) const {
    const BodyMapViewAxis axis = collider_.view_axis();
    c.point = ToBodyMapView(axis, c.point);
    c.normal = ToBodyMapView(axis, c.normal);
    Float3 p = ToBodyMapView(axis, *position), v = ToBodyMapView(axis, *velocity);
    ApplyResponse(c, BenchResponse(), &p, &v);
    *position = FromBodyMapView(axis, p);
    *velocity = FromBodyMapView(axis, v);
  }

  BodyMapCollider collider_;
};

class BoneMapMethod final : public Method {
 public:
  BoneMapMethod(const BoneMapSet& maps, uint32_t joint_count, std::span<const Mat34> skinning) {
    DieOnError(collider_.Build(maps, joint_count), "bone maps");
    DieOnError(collider_.SetPose(skinning, skinning), "bone maps pose");
  }
  void Collide(std::span<const Float3> previous, std::span<Float3> positions,
               std::span<Float3> velocities, std::span<uint8_t> flags) const override {
    DieOnError(collider_.CollideBatch(previous, positions, velocities, flags, BenchResponse()),
               setting);
  }
  ContactQuery Query(Float3 p0, Float3 p1) const override { return collider_.Query(p0, p1); }
  const BoneMapCollider& collider() const { return collider_; }

 private:
  BoneMapCollider collider_;
};

class HullMethod final : public Method {
 public:
  HullMethod(std::span<const HullColliderData> hulls, std::span<const JointSphereData> spheres,
             uint32_t joint_count, std::span<const Mat34> skinning,
             const HullColliderOptions& options)
      : hulls_(hulls.begin(), hulls.end()), spheres_(spheres.begin(), spheres.end()) {
    DieOnError(set_.Build(hulls, spheres, joint_count, options), "hull colliders");
    DieOnError(set_.SetPose(skinning, skinning), "hull pose");
    HullColliderOptions four_wide = options;
    four_wide.instruction_set = InstructionSet::kSse2;
    DieOnError(four_wide_set_.Build(hulls, spheres, joint_count, four_wide), "hull colliders");
    DieOnError(four_wide_set_.SetPose(skinning, skinning), "hull pose");
  }
  // The particles one at a time, with the plane loops four wide (SSE2): no eight-particle broad
  // phase, which CollideBatch documents to give the same bits.
  bool QueryEachAndRespond(std::span<const Float3> previous, std::span<Float3> positions,
                           std::span<Float3> velocities, std::span<uint8_t> flags) const override {
    for (size_t k = 0; k < positions.size(); ++k) {
      DieOnError(four_wide_set_.CollideBatch(previous.subspan(k, 1), positions.subspan(k, 1),
                                             velocities.subspan(k, 1), flags.subspan(k, 1),
                                             BenchResponse()),
                 setting);
    }
    return true;
  }
  long OwnSurfaceMisses(std::span<const Float3> previous, std::span<const Float3> current,
                        std::span<const uint8_t> flags) const override {
    long misses = 0;
    for (size_t i = 0; i < current.size(); ++i) {
      if ((flags[i] & kCollisionContact) == 0 && EntersOwnSurface(previous[i], current[i])) {
        ++misses;
      }
    }
    return misses;
  }
  void Collide(std::span<const Float3> previous, std::span<Float3> positions,
               std::span<Float3> velocities, std::span<uint8_t> flags) const override {
    DieOnError(set_.CollideBatch(previous, positions, velocities, flags, BenchResponse()), setting);
  }
  ContactQuery Query(Float3 p0, Float3 p1) const override { return set_.Query(p0, p1); }
  size_t memory_bytes() const { return set_.memory_bytes(); }

 private:
  static constexpr double kDeep = 1e-5;  // metres inside a surface that must be caught

  // Does the motion a -> b penetrate a posed hull or sphere by more than kDeep: b inside it, or
  // a outside it and the segment passing through it (a motion that starts inside and leaves is
  // no penetration)? Double precision, from the baked planes: Cyrus-Beck clip, then the depth at
  // the middle of the inside interval.
  bool EntersOwnSurface(Float3 a, Float3 b) const {
    for (uint32_t h = 0; h < hulls_.size(); ++h) {
      const Mat34 to_local = InverseRigid(set_.HullWorldTransform(h, 0.f));
      const Float3 la = TransformPoint(to_local, a), lb = TransformPoint(to_local, b);
      const auto max_distance = [&](double t) {
        const double p[3] = {la.x + (double(lb.x) - la.x) * t, la.y + (double(lb.y) - la.y) * t,
                             la.z + (double(lb.z) - la.z) * t};
        double worst = -1e30;
        for (const Plane& plane : hulls_[h].planes) {
          worst = std::max(worst, double(plane.normal.x) * p[0] + double(plane.normal.y) * p[1] +
                                      double(plane.normal.z) * p[2] - plane.offset);
        }
        return worst;
      };
      if (max_distance(1.0) < -kDeep) return true;
      if (max_distance(0.0) <= 0.0) continue;  // started inside this hull
      double t_in = 0.0, t_out = 1.0;
      bool empty = false;
      for (const Plane& plane : hulls_[h].planes) {
        const double da = double(plane.normal.x) * la.x + double(plane.normal.y) * la.y +
                          double(plane.normal.z) * la.z - plane.offset;
        const double db = double(plane.normal.x) * lb.x + double(plane.normal.y) * lb.y +
                          double(plane.normal.z) * lb.z - plane.offset;
        if (da > 0.0 && db > 0.0) {
          empty = true;
          break;
        }
        if (da > 0.0) t_in = std::max(t_in, da / (da - db));
        if (db > 0.0) t_out = std::min(t_out, da / (da - db));
      }
      if (!empty && t_in <= t_out && max_distance(0.5 * (t_in + t_out)) < -kDeep) return true;
    }
    for (uint32_t s = 0; s < spheres_.size(); ++s) {
      const Float3 c = set_.SphereCenter(s, 0.f);
      const double r = spheres_[s].radius;
      const double d[3] = {double(b.x) - a.x, double(b.y) - a.y, double(b.z) - a.z};
      const double m[3] = {double(a.x) - c.x, double(a.y) - c.y, double(a.z) - c.z};
      const auto distance_at = [&](double t) {
        const double q[3] = {m[0] + d[0] * t, m[1] + d[1] * t, m[2] + d[2] * t};
        return std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
      };
      if (distance_at(1.0) < r - kDeep) return true;
      if (distance_at(0.0) <= r) continue;  // started inside this sphere
      const double dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
      const double t =
          dd > 0.0 ? std::clamp(-(m[0] * d[0] + m[1] * d[1] + m[2] * d[2]) / dd, 0.0, 1.0) : 0.0;
      if (distance_at(t) < r - kDeep) return true;
    }
    return false;
  }

  HullColliderSet set_;
  HullColliderSet four_wide_set_;  // QueryEachAndRespond's
  std::vector<HullColliderData> hulls_;
  std::vector<JointSphereData> spheres_;
};

class CombinedMethod final : public Method {
 public:
  CombinedMethod(std::unique_ptr<Method> first, std::unique_ptr<Method> second)
      : first_(std::move(first)), second_(std::move(second)) {}
  void Collide(std::span<const Float3> previous, std::span<Float3> positions,
               std::span<Float3> velocities, std::span<uint8_t> flags) const override {
    first_->Collide(previous, positions, velocities, flags);
    // The second method sees the motion previous -> (first's answer); its flags are merged.
    std::vector<uint8_t>& second_flags = scratch_flags_;
    second_flags.resize(flags.size());
    second_->Collide(previous, positions, velocities, second_flags);
    for (size_t i = 0; i < flags.size(); ++i) flags[i] |= second_flags[i];
  }
  ContactQuery Query(Float3 p0, Float3 p1) const override {
    const ContactQuery a = first_->Query(p0, p1);
    return a.contact ? a : second_->Query(p0, p1);
  }

 private:
  std::unique_ptr<Method> first_, second_;
  mutable std::vector<uint8_t> scratch_flags_;  // sized once per query set; not thread-shared
};

void ToDouble(Float3 p, double out[3]) {
  out[0] = p.x;
  out[1] = p.y;
  out[2] = p.z;
}

Float3 ToFloat(const double p[3]) {
  return {static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2])};
}

// The peers' batch: Query per particle, then paper A's response (OpenMP over particles).
void CollideOneByOne(const Method& method, std::span<const Float3> previous,
                     std::span<Float3> positions, std::span<Float3> velocities,
                     std::span<uint8_t> flags) {
  const long count = static_cast<long>(positions.size());
#pragma omp parallel for schedule(dynamic, 64)
  for (long i = 0; i < count; ++i) {
    const size_t k = static_cast<size_t>(i);
    const ContactQuery c = method.Query(previous[k], positions[k]);
    flags[k] = c.contact ? kCollisionContact : kCollisionNone;
    if (c.contact) ApplyResponse(c, BenchResponse(), &positions[k], &velocities[k]);
  }
}

class ExactMeshPeer final : public Method {
 public:
  explicit ExactMeshPeer(const bake::MeshReference& reference) : reference_(reference) {}
  void Collide(std::span<const Float3> previous, std::span<Float3> positions,
               std::span<Float3> velocities, std::span<uint8_t> flags) const override {
    CollideOneByOne(*this, previous, positions, velocities, flags);
  }
  ContactQuery Query(Float3 p0, Float3 p1) const override {
    ContactQuery c;
    double a[3], b[3];
    ToDouble(p0, a);
    ToDouble(p1, b);
    c.inside_end = reference_.Inside(b);
    if (!reference_.Inside(a)) {
      const bake::SurfaceHit hit = reference_.FirstCrossing(a, b);
      if (hit.hit) {
        c.contact = true;
        c.t = static_cast<float>(hit.t);
        c.point = ToFloat(hit.point);
        c.normal = ToFloat(hit.normal);
        return c;
      }
    }
    if (c.inside_end) {
      double point[3], normal[3];
      uint32_t triangle = 0;
      c.depth = static_cast<float>(reference_.ClosestPoint(b, point, &triangle, normal));
      c.contact = true;
      c.point = ToFloat(point);
      c.normal = ToFloat(normal);
      c.flags = kCollisionStartedInside;
    }
    return c;
  }

 private:
  const bake::MeshReference& reference_;
};

class FclPeer final : public Method {
 public:
  FclPeer(std::span<const Float3> positions, std::span<const uint32_t> triangles)
      : fcl_(std::make_unique<peers::FclMeshPeer>(positions, triangles)) {}
  // Query ignores p0: FCL answers a distance at the current position.
  void Collide(std::span<const Float3> previous, std::span<Float3> positions,
               std::span<Float3> velocities, std::span<uint8_t> flags) const override {
    CollideOneByOne(*this, previous, positions, velocities, flags);
  }
  ContactQuery Query(Float3 p0, Float3 p1) const override {
    (void)p0;
    ContactQuery c;
    Float3 closest;
    const double distance = fcl_->Distance(p1, &closest);
    if (distance < BenchResponse().separation) {
      c.contact = true;
      c.point = closest;
      c.normal = NormalizeOr(p1 - closest, Float3{0.f, 1.f, 0.f});
    }
    return c;
  }
  size_t memory_bytes() const { return fcl_->memory_bytes(); }

 private:
  std::unique_ptr<peers::FclMeshPeer> fcl_;
};

// The bake's tapered capsules posed into the engine shapes' set (still over the step).
class CapsuleMethod final : public Method {
 public:
  CapsuleMethod(std::span<const CapsuleColliderData> capsules, std::span<const Mat34> skinning) {
    set_.Reserve(static_cast<uint32_t>(capsules.size()), 0);
    DieOnError(AddCapsuleColliders(capsules, skinning, skinning, &set_), "capsules");
  }
  void Collide(std::span<const Float3> previous, std::span<Float3> positions,
               std::span<Float3> velocities, std::span<uint8_t> flags) const override {
    DieOnError(set_.CollideBatch(previous, positions, velocities, flags, BenchResponse(), 0.f, 1.f,
                                 kStepSeconds),
               setting);
  }
  ContactQuery Query(Float3 p0, Float3 p1) const override { return set_.Query(p0, p1, 0.f, 1.f); }

 private:
  ShapeColliderSet set_;
};

}  // namespace

ResponseParams BenchResponse() {
  ResponseParams params;
  params.friction = 0.2f;
  params.restitution = 0.f;
  params.separation = 1e-4f;
  return params;
}

std::unique_ptr<Method> MakeBodyMapMethod(const BodyMapPose& pose, DepthSampling sampling,
                                          std::string setting, size_t baked_bytes,
                                          InstructionSet lanes) {
  auto method = std::make_unique<BodyMapMethod>(pose, sampling, lanes);
  method->family = "maps";
  method->setting = std::move(setting);
  method->baked_bytes = baked_bytes;
  method->runtime_bytes = method->collider().memory_bytes();
  return method;
}

std::unique_ptr<Method> MakeBodyMapMethod(BodyMapCollider&& collider, std::string setting,
                                          size_t baked_bytes) {
  auto method = std::make_unique<BodyMapMethod>(std::move(collider));
  method->family = "maps";
  method->setting = std::move(setting);
  method->baked_bytes = baked_bytes;
  method->runtime_bytes = method->collider().memory_bytes();
  return method;
}

std::unique_ptr<Method> MakeBoneMapMethod(const BoneMapSet& maps, uint32_t joint_count,
                                          std::span<const Mat34> skinning, std::string setting,
                                          size_t baked_bytes) {
  auto method = std::make_unique<BoneMapMethod>(maps, joint_count, skinning);
  method->family = "bone maps";
  method->setting = std::move(setting);
  method->baked_bytes = baked_bytes;
  method->runtime_bytes = method->collider().memory_bytes();
  return method;
}

std::unique_ptr<Method> MakeCapsuleMethod(std::span<const CapsuleColliderData> capsules,
                                          std::span<const Mat34> skinning, std::string setting) {
  auto method = std::make_unique<CapsuleMethod>(capsules, skinning);
  method->family = "capsules";
  method->setting = std::move(setting);
  method->baked_bytes = capsules.size() * sizeof(CapsuleColliderData);
  method->runtime_bytes = capsules.size() * 160;  // ShapeColliderSet's 160-byte shapes
  return method;
}

std::unique_ptr<Method> MakeHullMethod(std::span<const HullColliderData> hulls,
                                       std::span<const JointSphereData> spheres,
                                       uint32_t joint_count, std::span<const Mat34> skinning,
                                       const HullColliderOptions& options, std::string family,
                                       std::string setting, size_t baked_bytes) {
  auto method = std::make_unique<HullMethod>(hulls, spheres, joint_count, skinning, options);
  method->family = std::move(family);
  method->setting = std::move(setting);
  method->baked_bytes = baked_bytes;
  method->runtime_bytes = method->memory_bytes();
  return method;
}

std::unique_ptr<Method> MakeCombinedMethod(std::unique_ptr<Method> maps,
                                           std::unique_ptr<Method> hulls, std::string setting) {
  const size_t baked = maps->baked_bytes + hulls->baked_bytes;
  const size_t runtime = maps->runtime_bytes + hulls->runtime_bytes;
  auto method = std::make_unique<CombinedMethod>(std::move(maps), std::move(hulls));
  method->family = "maps+hulls";
  method->setting = std::move(setting);
  method->baked_bytes = baked;
  method->runtime_bytes = runtime;
  return method;
}

std::unique_ptr<Method> MakeExactMeshPeer(const bake::MeshReference& reference) {
  auto method = std::make_unique<ExactMeshPeer>(reference);
  method->family = "peer";
  method->setting = "exact mesh (winding number + CGAL AABB tree)";
  method->runtime_bytes = reference.memory_bytes();
  method->peer = true;
  return method;
}

std::unique_ptr<Method> MakeFclPeer(std::span<const Float3> positions,
                                    std::span<const uint32_t> triangles) {
  auto method = std::make_unique<FclPeer>(positions, triangles);
  method->family = "peer";
  method->setting = "FCL BVH point distance (OBBRSS)";
  method->runtime_bytes = method->memory_bytes();
  method->peer = true;
  method->speed_only = true;
  return method;
}

}  // namespace drape::bench

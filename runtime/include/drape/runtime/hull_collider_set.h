#pragma once
// Paper B's proxy colliders at run time: the per-bone convex hulls and the joint spheres of a
// .drape asset, posed from the skeleton at the start and the end of each step, answering
// continuous particle queries with a response. How it works: docs/ALGORITHMS.md §8 (screw motion,
// inside tests, responses, Gauss-Seidel) and §9 (joint spheres); figures: docs/PERFORMANCE.md.
//
//   HullColliderSet set;
//   set.Build(asset.hulls, asset.joint_spheres, joint_count);         // once: allocates
//   set.SetPose(skinning_at_step_start, skinning_at_step_end);        // per step
//   set.CollideBatch(previous, positions, velocities, flags, params); // per step (or substep)

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <new>
#include <span>
#include <vector>

#include "drape/formats/hull_collider_data.h"
#include "drape/formats/status.h"
#include "drape/formats/types.h"
#include "drape/runtime/collision_types.h"
#include "drape/runtime/instruction_set.h"
#include "drape/runtime/math.h"

namespace drape {

namespace detail {
struct PlaneKernels;
}  // namespace detail

enum class InsideTest : uint8_t {
  kPlanes = 0,       // max over the hull's planes <= 0, 4 or 8 planes per instruction
  kKirkpatrick = 1,  // paper B: point location in the upper and lower projected hierarchies
};

enum class HullResponse : uint8_t {
  kPushOut = 0,      // the exact minimal push-out, through the face of the max plane
  kMapTableRay = 1,  // paper B's map sphere / map cylinder ray; push-out where it finds nothing
};

enum class EntryResponse : uint8_t {
  kProjectEnd = 0,  // the end position projected onto the entry plane (keeps tangential motion)
  kEntryPoint = 1,  // the first intersection of the segment with the surface (paper A's C_p)
};

// Which colliders a Query considers (bit mask).
enum ColliderKinds : uint8_t {
  kColliderHulls = 1 << 0,
  kColliderSpheres = 1 << 1,
  kColliderAll = kColliderHulls | kColliderSpheres,
};

struct HullColliderOptions {
  InsideTest inside_test = InsideTest::kPlanes;
  HullResponse response = HullResponse::kPushOut;
  bool continuous = true;  // test the segment previous -> current, not only the end position
  EntryResponse entry_response = EntryResponse::kProjectEnd;
  // Passes over the colliders per particle, [1, 16]; extra passes run only while in contact. 4
  // keeps a skirt pinched between thigh and shin hulls within 1 mm at 1/30 s (2: 3.7 mm).
  uint32_t gauss_seidel_passes = 4;
  // The widest instruction set the kernels may use (narrowed to the CPU's); every set gives the
  // same bits.
  InstructionSet instruction_set = InstructionSet::kAvx2;
};

// A collider-frame point projected for the Kirkpatrick test: u = (p - origin) . u_axis, v likewise,
// in float. The bake stores the hull vertices' (u, v) with this very function, so a query at a
// vertex reproduces it bit for bit.
struct HullUv {
  float u = 0.f, v = 0.f;
};
inline HullUv ProjectHullUv(Float3 p, Float3 origin, Float3 u_axis, Float3 v_axis) {
  const Float3 d = p - origin;
  return {Dot(d, u_axis), Dot(d, v_axis)};
}

// ((nx px + ny py) + nz pz) - d in float, the plane test's expression: <= 0 is inside.
inline float PlaneSignedDistance(const Plane& plane, Float3 p) {
  return Dot(plane.normal, p) - plane.offset;
}

// The colliders of one character. Build allocates; SetPose and SelectSubstep work in place; the
// queries and CollideBatch are const, allocation-free and thread-safe.
class HullColliderSet {
 public:
  // Validates the untrusted data and copies it into flat arrays. joint_count: the skeleton's
  // joints. Any bad count, index, float, frame, hierarchy or map table is kInvalidArgument naming
  // the collider and the field; so are options needing data a hull lacks (kKirkpatrick without
  // hierarchies, kMapTableRay without a map table). On error the set is empty. The pose starts as
  // the bind pose.
  Status Build(std::span<const HullColliderData> hulls, std::span<const JointSphereData> spheres,
               uint32_t joint_count, const HullColliderOptions& options = {});

  // Fails, keeping the old options, when a hull lacks the data they need or a value is out of
  // range.
  Status SetOptions(const HullColliderOptions& options);
  const HullColliderOptions& options() const { return options_; }
  InstructionSet instruction_set() const;  // what the kernels use: the option narrowed to the CPU

  // Skinning matrices (world(j) * inverse_bind(j)) at the start and the end of the step, at least
  // joint_count each, finite. Selects the whole step, SelectSubstep(0, 1).
  Status SetPose(std::span<const Mat34> skinning_start, std::span<const Mat34> skinning_end);

  // Caches the transforms and swept spheres at the fractions 0 <= s0 <= s1 <= 1 of the step, so
  // that CollideBatch and Query with these fractions run at full speed (other fractions give the
  // same bits, several times slower). A solver calls it once per substep.
  Status SelectSubstep(float s0, float s1);

  // The response bound: no response leaves a particle farther from previous[i] than its motion
  // relative to the colliders plus kUnionDepthFactor times the sum of the depths of the end in
  // them (plus the separation). Inside two overlapping colliders the nearest exit of their union
  // is their crease, within twice the sum of the depths when the faces meet at 60 degrees or
  // more; in a narrower pinch the particle stays rather than be thrown along it.
  static constexpr double kUnionDepthFactor = 2.0;

  // Collides particles moving previous[i] -> positions[i] over the fractions [substep_start,
  // substep_end] of the step and applies the response (collision_types.h) to positions[i] and
  // velocities[i] in place. flags[i] is always written (CollisionFlags); a non-finite input is
  // flagged kCollisionInvalidInput and left untouched. Spans of one size; params finite, friction
  // and restitution in [0, 1], separation >= 0. Bitwise identical at any thread count.
  Status CollideBatch(std::span<const Float3> previous, std::span<Float3> positions,
                      std::span<Float3> velocities, std::span<uint8_t> flags,
                      const ResponseParams& params, float substep_start = 0.f,
                      float substep_end = 1.f, uint32_t* contact_count = nullptr) const;

  // One segment p0 -> p1 over the selected substep, no response: among the colliders in `kinds`,
  // the deepest contact, else the earliest entry; inside_end when p1 is inside any of them, depth
  // the deepest. Inside overlapping colliders, the contact is the nearest exit of their union
  // (within the motion plus the sum of the depths) when the deepest one's exit lies inside
  // another.
  ContactQuery Query(Float3 p0, Float3 p1, uint8_t kinds = kColliderAll) const;

  // Posed at fraction s of the step: a hull's collider frame -> world (rigid), a sphere's centre.
  Mat34 HullWorldTransform(uint32_t hull, float s) const;
  Float3 SphereCenter(uint32_t sphere, float s) const;

  uint32_t hull_count() const { return static_cast<uint32_t>(hulls_.size()); }
  uint32_t sphere_count() const { return static_cast<uint32_t>(spheres_.size()); }
  uint32_t plane_count(uint32_t hull) const { return hulls_[hull].plane_count; }
  bool empty() const { return hulls_.empty() && spheres_.empty(); }
  size_t memory_bytes() const;

 private:
  friend struct HullColliderSetAccess;  // tests and benchmarks: hull/hull_collider_set_access.h
  struct BuildStages;                   // hull/hull_collider_set.cpp

  // A Kirkpatrick node's canonical edge A -> B, sign folded in: E(q) = du (qv - av) - dv (qu - au).
  struct EdgeFunction {  // 32 bytes
    double au, av, du, dv;
  };
  struct Hierarchy {
    uint32_t node_begin = 0, node_count = 0;    // into the node arrays
    uint32_t root_begin = 0, root_end = 0;      // absolute node indices
    double interior_u = 0.0, interior_v = 0.0;  // tie-break target, strictly inside the shadow
  };
  struct HullRecord {
    int32_t joint = -1;
    Mat34 bind_frame;
    uint32_t plane_begin = 0, plane_count = 0, plane_padded = 0;  // SoA plane range
    uint32_t triangle_begin = 0, triangle_count = 0;              // ray_triangles_ range
    Float3 obb_center;
    Float3 obb_axes[3];
    Float3 obb_half;           // grown for float safety
    float bound_radius = 0.f;  // sphere around obb_center holding the OBB
    bool has_hierarchy = false;
    Hierarchy upper, lower;
    Float3 uv_origin, uv_u, uv_v;
    bool has_map = false;
    MapTableKind map_kind = MapTableKind::kSphere;
    uint32_t map_rows = 0, map_cols = 0, map_cell_begin = 0;
    Float3 map_origin, map_axis, map_reference, map_binormal;
    float map_length = 0.f;
    float map_row_scale = 0.f, map_col_scale = 0.f;  // rows / pi and cols / (2 pi)
  };
  struct SphereRecord {
    int32_t joint = -1;
    Float3 center;  // bind pose, asset frame
    float radius = 0.f;
  };
  // One collider's screw motion over the step (hulls: collider frame; spheres: translation).
  struct Motion {
    Quat rotation0;           // W(0) rotation
    Float3 translation0;      // W(0) translation
    Quat relative;            // rotation of D = W(1) W(0)^-1, w >= 0
    Float3 pivot;             // a point on D's screw axis (or the start centre)
    Float3 shift;             // D(pivot) - pivot
    Float3 center0, center1;  // bounding-sphere centre at s = 0 and 1 (world)
  };
  // Transforms at the selected substep's fractions.
  struct ActiveFrames {                  // 240 bytes
    Mat34 to_local_start, to_local_end;  // world -> collider frame
    Mat34 to_obb_start, to_obb_end;      // world -> OBB frame
    Mat34 to_world_end;                  // collider frame -> world at the end fraction
  };

  Status ValidateOptions(const HullColliderOptions& options) const;
  void ComputeFrames(uint32_t collider, float s0, float s1, ActiveFrames* frames) const;
  Mat34 ColliderWorldAt(uint32_t collider, float s) const;
  void ComputeSweep(uint32_t collider, float s0, float s1, Float3* center, float* radius) const;
  // Narrow phases in the collider frame.
  float PlaneMax(const HullRecord& h, Float3 p, uint32_t* arg) const;
  uint32_t Locate(const Hierarchy& k, HullUv q, uint32_t* steps) const;  // the leaf node
  bool InsideKirkpatrick(const HullRecord& h, Float3 p) const;
  bool MapRay(const HullRecord& h, Float3 p, Float3* point, uint32_t* plane) const;
  void PushOut(const HullRecord& h, Float3 p, float max_value, ContactQuery* c) const;
  ContactQuery HullNarrow(const HullRecord& h, Float3 a, Float3 b) const;
  ContactQuery SphereNarrow(float radius, Float3 a, Float3 b) const;
  // Collider k (hulls first, then spheres) against the world-space segment p0 -> p1.
  ContactQuery ColliderContact(uint32_t collider, const ActiveFrames& frames, Float3 p0,
                               Float3 p1) const;
  // At most this many colliders are resolved per particle (the lowest indices).
  static constexpr uint32_t kMaxCandidates = 32;
  // CollideBatch's grouped broad phase (bit masks of 32-collider words on the stack) up to this
  // many colliders; beyond, each particle runs its own.
  static constexpr uint32_t kMaxGroupedColliders = 256;
  uint32_t BroadPhase(Float3 p0, Float3 p1, float s0, float s1, bool active, uint32_t* out) const;
  // One particle's candidates, their transforms and contacts, on the stack (raw storage: only
  // the first `count` are constructed, so the common path does not pay for the rest).
  struct ContactFrames {
    uint32_t candidates[kMaxCandidates];
    uint32_t order[kMaxCandidates];  // indices of the contacts that hit, `hits` of them
    uint32_t count = 0, hits = 0;
    const ActiveFrames* frames[kMaxCandidates];
    alignas(ActiveFrames) unsigned char storage[kMaxCandidates * sizeof(ActiveFrames)];
    alignas(ContactQuery) unsigned char contact_storage[kMaxCandidates * sizeof(ContactQuery)];
    ContactQuery* contacts() { return reinterpret_cast<ContactQuery*>(contact_storage); }
    const ContactQuery* contacts() const {
      return reinterpret_cast<const ContactQuery*>(contact_storage);
    }
  };
  // Candidates (the first-pass mask, or the broad phase of p0 -> p1) and their contacts; the
  // collider `skip` counts as no contact. Returns the candidate count.
  template <bool kActive>
  uint32_t ParticleContacts(Float3 p0, Float3 p1, float s0, float s1,
                            const uint32_t* first_candidates, uint32_t skip,
                            ContactFrames* out) const;
  // Exits from a point inside overlapping colliders (union_exit.cpp): a hull's outer face (the
  // point projected onto its plane) or a sphere's radial exit (plane kSphereExit), tried nearest
  // first.
  static constexpr uint32_t kSphereExit = UINT32_MAX;
  static constexpr uint32_t kMaxExitTries = 16;  // exits tested for being outside everything
  struct ExitKey {                               // 16 bytes
    float distance;                              // metres from the point to the exit
    uint32_t collider, plane;
    uint32_t holder;                          // index into ExitHolders (not part of the order)
    bool operator<(const ExitKey& o) const {  // by distance, then collider, then plane
      return distance < o.distance ||
             (distance == o.distance &&
              (collider < o.collider || (collider == o.collider && plane < o.plane)));
    }
  };
  struct ExitHolders {  // the colliders holding the point, and the point in their frames
    uint32_t count = 0;
    uint32_t colliders[kMaxCandidates];
    const ActiveFrames* frames[kMaxCandidates];
    Float3 local[kMaxCandidates];
  };
  static constexpr uint32_t kMaxExits = 512;  // exits considered per point
  // CollideBatch searches the union's exits for a particle still this deep after every pass
  // (metres): a shallower best iterate stays (moving it across the union would be a jump).
  static constexpr float kUnionExitMinDepth = 1e-3f;
  // The holders' exits, the nearest kMaxExitTries first and in order; returns how many to try.
  uint32_t CollectExits(const ExitHolders& holders, ExitKey* keys) const;
  ContactQuery ExitContact(const ExitHolders& holders, const ExitKey& key) const;
  // The first of the holders' nearest exits, within max_distance of p0, whose probe is_free
  // accepts (union_exit.cpp: the batch's candidates, or Query's colliders of some kinds).
  template <typename IsFree>
  bool FirstFreeExit(Float3 p0, const ExitHolders& holders, double max_distance, IsFree is_free,
                     ContactQuery* exit) const;
  // The nearest exit of x (the end of the segment) from the candidates that hold it that lies
  // outside every candidate and within max_distance of p0; false when none of the nearest
  // kMaxExitTries does (a pinch, or the crease of two colliders).
  bool NearestUnionExit(Float3 p0, Float3 x, const ContactFrames& candidates, double max_distance,
                        ContactQuery* exit) const;
  bool InsideAnyCandidate(Float3 x, const ContactFrames& candidates) const;
  // The distance from p0 a response may leave the particle at (kUnionDepthFactor), from the
  // first pass's contacts; computed when a response first reaches beyond its floor
  // (contact_resolution.cpp).
  class ResponseBound;
  // Query's helpers: whether collider k is of a kind in `kinds`; the point just outside the
  // surface a contact resolves to; whether x is inside any collider of `kinds`; the nearest exit
  // of the union of the colliders p1 is inside (replaces *best when one is found).
  bool HasKind(uint32_t collider, uint8_t kinds) const;
  static Float3 ExitProbe(const ContactQuery& c);
  bool InsideAny(Float3 x, uint8_t kinds) const;
  void UnionExit(Float3 p0, Float3 p1, uint8_t kinds, ContactQuery* best) const;
  // kActive: the fractions are the selected substep's. first_candidates: the first pass's broad
  // phase already done, as bit masks of 32 colliders each (ceil(collider count / 32) words).
  template <bool kActive>
  void ResolveParticle(Float3 p0, Float3* p1, Float3* velocity, uint8_t* flags,
                       const ResponseParams& params, float s0, float s1,
                       const uint32_t* first_candidates = nullptr) const;
  void Clear();

  // 64-byte aligned storage for the arrays the kernels load 8 floats at a time from, so a hull's
  // plane range never splits a load across cache lines.
  template <typename T>
  struct SimdAllocator {
    using value_type = T;
    SimdAllocator() = default;
    template <typename U>
    SimdAllocator(const SimdAllocator<U>&) {}
    T* allocate(size_t n) {
      return static_cast<T*>(::operator new (n * sizeof(T), std::align_val_t{64}));
    }
    void deallocate(T* p, size_t) { ::operator delete (p, std::align_val_t{64}); }
    template <typename U>
    bool operator==(const SimdAllocator<U>&) const {
      return true;
    }
  };
  using SimdFloats = std::vector<float, SimdAllocator<float>>;

  HullColliderOptions options_;
  const detail::PlaneKernels* kernels_ = nullptr;  // options_.instruction_set's, set by Build
  uint32_t joint_count_ = 0;
  uint32_t collider_count_ = 0;  // hulls + spheres
  std::vector<HullRecord> hulls_;
  std::vector<SphereRecord> spheres_;
  // Planes, SoA, each hull's range padded to a multiple of 8 with planes that never win.
  SimdFloats plane_nx_, plane_ny_, plane_nz_, plane_d_;
  std::vector<Plane> planes_;            // unpadded copy, plane_begin-relative as in the SoA
  std::vector<uint8_t> plane_internal_;  // per plane as planes_: 1 for a face inside the body
  SimdFloats outer_plane_d_;  // plane_d_ with the internal planes' offsets padded (never win)
  // Triangles for the map-table ray: 9 floats (3 vertices) each, plus their planes.
  std::vector<float> ray_triangles_;
  std::vector<uint32_t> ray_triangle_planes_;  // hull-relative plane index
  // Kirkpatrick nodes of all hierarchies: 3 edge functions each; children are absolute.
  std::vector<EdgeFunction> node_edges_;
  std::vector<int32_t> node_leaf_plane_;
  std::vector<uint32_t> node_guard_begin_;   // node_count + 1, CSR of guard planes
  std::vector<uint32_t> node_guard_planes_;  // hull-relative planes of fill leaves' rims
  std::vector<uint32_t> node_child_begin_;   // node_count + 1 over all hierarchies
  std::vector<uint32_t> node_children_;
  // Map tables: cell offsets (absolute into map_triangles_), lists of hull-relative triangles.
  std::vector<uint32_t> map_cell_offsets_;
  std::vector<uint32_t> map_triangles_;

  // Pose.
  std::vector<Motion> motions_;  // hulls then spheres
  std::vector<ActiveFrames> active_;
  // Per hull, from active_: the boxes the batch's group filter tests (plane_kernels.h).
  std::vector<Mat34> obb_start_, obb_end_;  // world -> OBB frame at the substep's ends
  std::vector<Float3> obb_half_;            // metres
  float active_s0_ = 0.f, active_s1_ = 1.f;
  bool selection_current_ = false;  // active_ and sweep_* hold [active_s0_, active_s1_] of the pose
  // Swept spheres, SoA padded to a multiple of 8: over the selected substep and the whole step.
  SimdFloats sweep_x_, sweep_y_, sweep_z_, sweep_r_;
  SimdFloats full_x_, full_y_, full_z_, full_r_;
  // A sphere around all swept spheres of the selected substep, grown to cover the rounding of the
  // per-collider test: a group of particles outside it skips the per-collider tests.
  Float3 sweep_union_center_;
  float sweep_union_radius_ = 0.f;
};

}  // namespace drape

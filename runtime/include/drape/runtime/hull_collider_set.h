#pragma once
// Paper B's skeleton-driven proxy colliders at run time: the per-bone convex hulls of
// drape/formats/hull_collider_data.h and the joint spheres, posed by the skinning matrices at the
// start and at the end of a step, with discrete and continuous particle tests and the responses of
// notes/algorithms.md §3.3-§3.5 and §5.2.
//
// Frames. A hull is stored in its collider frame; its world transform at a pose is
// skinning(joint) * bind_frame, made rigid (the rotation is re-orthonormalised through a
// quaternion; any scale in the skinning matrix is ignored). A joint sphere's world centre is
// skinning(joint) * center.
//
// Motion inside a step. SetPose takes the skinning matrices at the start (s = 0) and the end
// (s = 1) of the step. A collider at fraction s in [0, 1] is placed by screw interpolation: the
// relative motion D = W(1) * W(0)^-1 is a rotation by angle theta about an axis line plus a
// shift along that line (Chasles); D_s rotates by nlerp(identity, rotation(D), s) about the same
// line and shifts by s times the shift. A bone that turns about a fixed joint is therefore moved
// exactly along its arc (the screw line passes through the joint), whatever the collider frame's
// origin is. Angles below 1e-4 rad pivot about the collider's OBB centre instead (a translation).
// A joint sphere's centre moves linearly. Particles are not interpolated: a particle moving
// previous -> current over the fractions [s0, s1] is tested as the straight segment from
// previous in the collider frame at s0 to current in the collider frame at s1.
//
// Inside test (InsideTest): kPlanes (default) is max_i(n_i . p - d_i) <= 0 over the hull's
// planes in float, 4 (SSE2) or 8 (AVX2) planes per instruction. kKirkpatrick (paper B §2.3)
// projects p with ProjectHullUv and locates it in the upper and the lower hierarchy; each side
// contributes the located leaf's plane, or, for a fill leaf (outside that side's projected faces),
// its guard planes: the planes of the hull faces around the silhouette vertices the fill triangle
// touches (computed at Build by matching the hull vertices' projections). Every fill triangle lies
// beyond one silhouette edge or vertex, and a point projecting beyond a silhouette edge is outside
// one of the two faces that meet at that rim edge (the vertical supporting plane's normal is a
// positive combination of theirs), so in exact arithmetic this is exactly the hull; in float it
// gives points over vertical faces and points within the planes' outward rounding of the silhouette
// the plane test's answer too. p is inside when every contributed plane holds (<= 0): points on the
// surface count as inside for both tests. Node edge functions are evaluated in double, computed
// once per undirected edge (canonical vertex order, negated for the other side) so neighbours
// never leave a crack; 2D ties (a point on a shared edge or vertex) are broken by simulation of
// simplicity, perturbing the point towards the interior of the projected hull.
// Measured: the two tests agree on all of 5 x 10^6 random, near-surface and on-surface points of
// five hulls, vertices, edges and vertical faces included
// (tests/bake/kirkpatrick_builder_test.cpp).
//
// Response for an end position inside a hull:
//  - HullResponse::kPushOut (default): the plane with the maximum signed distance is the nearest
//    boundary plane, and for a point inside a convex polytope with unit normals its projection
//    onto that plane stays inside every other half-space (n_i.n_j <= 1 and the other planes are
//    at least as far), so it lands on the face: the exact minimal push-out. In float the
//    projection is nudged outward until that plane's signed distance is >= 0, so the result is
//    on or outside the hull in the runtime's arithmetic.
//  - HullResponse::kMapTableRay (paper B §2.4): the ray from the map table's source (sphere centre,
//    or the cylinder axis point at the particle's height clamped to the axis part inside the hull)
//    through the particle, intersected with the triangles listed in its (theta, phi) or (z, phi)
//    cell by the watertight test of Woop, Benthin and Wald (JCGT 2013; edge functions redone in
//    double when one is 0). The nearest hit with positive ray parameter is the contact point, the
//    hit triangle's plane gives the normal. No hit (or a particle on the source): the push-out,
//    flagged kCollisionFallback. Cell angles come from a polynomial atan2 (max error ~1e-5 rad,
//    inside the builder's cell margin of >= 1e-4 rad). The cell's triangles are tested four at a
//    time (SSE), each lane with the scalar test's operations in its order, so the same bits.
// Continuous handling (HullColliderOptions::continuous, default on): if the segment starts outside
// the hull (or sphere), it is clipped by the half-spaces (Cyrus-Beck: entering t = max over planes
// of the entry t, valid if <= the min exit t). When it enters within [0, 1], the contact is on the
// entry plane: EntryResponse::kProjectEnd (default) projects the end position onto the entry plane
// (keeps the tangential motion; never pushes through the far side of a thin hull, since the start
// is on the outer side of that plane), kEntryPoint uses the first intersection point itself (paper
// A's C_p). A segment that crosses a thin hull in one step is caught this way even though its end
// is outside. A segment that starts inside and ends inside gets the discrete response and
// kCollisionStartedInside (the bone moved into the particle, or an earlier response was
// incomplete); one that starts inside and ends outside has no contact.
// Joint spheres: |p - c| <= r pushes out radially; continuous entries project onto the tangent
// plane at the entry point; a particle at the centre is pushed along the direction it came from.
// ContactQuery::t is the entry parameter for an entry, 0 for a segment that started inside, and 1
// for an end-point contact without a found entry (continuous off, or rounding).
//
// Several colliders: a particle is resolved in Gauss-Seidel passes (default 4). Each pass runs the
// broad phase on the current segment (a response may push the particle towards another
// collider), evaluates every candidate at the current position, applies the deepest contact
// first and re-queries the others in order of decreasing depth. A pass with no contact ends the
// loop, and so does a pass whose only candidate is the collider the previous pass resolved alone
// (its response left the particle on or outside it). Velocities get paper A's response
// (collision_types.h ApplyResponse: only when V.N < 0) for every applied contact.
//
// Per particle and step: broad phase against the swept bounding spheres of all colliders (the
// sphere around each hull's OBB, swept along its interpolated path, 4 or 8 colliders per
// instruction), then the OBB test of the segment in the collider frame (reject when both ends are
// beyond the same face), then the plane kernel (one pass giving the max signed distance of both
// ends, stopping early once one plane has both ends outside: no contact; a segment with both ends
// equal evaluates one point), then the vectorised clip or the response. CollideBatch at the
// selected substep with AVX2 and at most 32 colliders runs the first broad phase for eight
// particles at a time (8 particles per instruction, one bit mask of candidates per particle,
// after one test of the group against a sphere around all swept spheres) and resolves only the
// particles with candidates; the candidates and all answers are the same bits as one particle at
// a time. Measured figures: tests/bench/hull_query_bench.cpp, docs/PERFORMANCE.md.

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
#include "drape/runtime/math.h"

namespace drape {

enum class InsideTest : uint8_t {
  kPlanes = 0,       // max over planes <= 0 (SIMD float loop)
  kKirkpatrick = 1,  // paper B: point location in the upper and lower hierarchies
};

enum class HullResponse : uint8_t {
  kPushOut = 0,      // exact minimal push-out through the max-plane face
  kMapTableRay = 1,  // paper B's map sphere / map cylinder ray, push-out fallback
};

enum class EntryResponse : uint8_t {
  kProjectEnd = 0,  // end position projected onto the entry plane (tangent plane for spheres)
  kEntryPoint = 1,  // the first intersection of the segment with the surface
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
  // in [1, 16]; 4 keeps a skirt pinched between thigh and shin hulls within 1 mm at 1/30 s
  // (2 passes: 3.7 mm; tests/bake/walk_cycle_test.cpp). Extra passes run only while in contact.
  uint32_t gauss_seidel_passes = 4;
  // Plane loops 8 floats wide (AVX2) when the CPU has AVX2, else 4 (SSE2). The results are
  // bitwise identical either way (same per-plane arithmetic; max/min/or reductions).
  bool allow_avx2 = true;
};

// The Kirkpatrick projection of a collider-frame point: u = (p - origin) . u_axis, v likewise,
// evaluated left to right in float. The bake stores the hull vertices' (u, v) with this very
// function (origin = obb.center, axes = projection_u / projection_v), so a query at a hull vertex
// reproduces the stored vertex bit for bit and ties on vertices and edges are exact.
struct HullUv {
  float u = 0.f, v = 0.f;
};
inline HullUv ProjectHullUv(Float3 p, Float3 origin, Float3 u_axis, Float3 v_axis) {
  const Float3 d = p - origin;
  return {Dot(d, u_axis), Dot(d, v_axis)};
}

// The signed distance the plane test uses: ((nx px + ny py) + nz pz) - d in float, the same
// expression (and rounding) as the SIMD loop. <= 0 is inside the plane's half-space.
inline float PlaneSignedDistance(const Plane& plane, Float3 p) {
  return Dot(plane.normal, p) - plane.offset;
}

// The colliders of one character. Build allocates; SetPose and SelectSubstep work in place; the
// queries and CollideBatch are const, allocation-free and thread-safe (they only read).
class HullColliderSet {
 public:
  // Validates and copies the colliders into flat arrays. joint_count: the skeleton's joints (every
  // joint index must be below it). Rejected (kInvalidArgument, message names the collider and
  // field): no planes, more than 4096 planes, non-finite or non-unit (|1 - |n|| > 1e-3) plane
  // normals, non-finite offsets, vertices or bind frame, triangle or plane indices out of range,
  // triangles without planes, a degenerate or non-finite OBB (negative half extents, axes not
  // orthonormal within 1e-3), a hierarchy whose sizes do not match, whose child indices are not
  // below their parent, whose vertex or plane indices are out of range, whose nodes are not
  // strictly counter-clockwise, whose root range is empty or that has no face leaf; a map table
  // with rows or cols of 0, more than 2^20 cells, offsets that are not non-decreasing from 0 to its
  // list size, triangle indices out of range, a non-unit axis or reference, or a cylinder length <
  // 0; a joint sphere with a non-finite centre or a radius that is not finite and > 0. Options that
  // need data a hull lacks (kKirkpatrick without hierarchies, kMapTableRay without a map table) are
  // rejected too. On error the set is left empty. The pose starts as the bind pose (identity
  // skinning).
  Status Build(std::span<const HullColliderData> hulls, std::span<const JointSphereData> spheres,
               uint32_t joint_count, const HullColliderOptions& options = {});

  // Changes the options; fails (and keeps the old ones) when a hull lacks the data they need or
  // gauss_seidel_passes is not in [1, 16].
  Status SetOptions(const HullColliderOptions& options);
  const HullColliderOptions& options() const { return options_; }

  // Skinning matrices (world(j) * inverse_bind(j)) at the start and at the end of the step, at
  // least joint_count each, finite. Also selects the whole step [0, 1] (SelectSubstep(0, 1)).
  Status SetPose(std::span<const Mat34> skinning_start, std::span<const Mat34> skinning_end);

  // Precomputes the colliders' transforms and swept spheres at fractions s0 <= s1 of the step, so
  // that a CollideBatch or Query with exactly these fractions runs at full speed. Other fractions
  // give the same bits but interpolate (in double) per particle and candidate collider, several
  // times slower. Requires 0 <= s0 <= s1 <= 1. A solver with substeps calls this per substep.
  Status SelectSubstep(float s0, float s1);

  // Collides particles moving previous[i] -> positions[i] over the fractions [substep_start,
  // substep_end] of the step; on contact applies ApplyResponse (paper A eq. 5, velocity changed
  // only when V.N < 0) in place to positions[i] and velocities[i]. flags[i] is always written
  // (CollisionFlags). A particle with a non-finite previous or current position or velocity gets
  // kCollisionInvalidInput and is left untouched. OpenMP over particles, no allocation, bitwise
  // identical at any thread count. All four spans must have the same size; params must be finite
  // with friction and restitution in [0, 1] and separation >= 0; 0 <= substep_start <=
  // substep_end <= 1. contact_count (optional) receives the number of particles with
  // kCollisionContact.
  Status CollideBatch(std::span<const Float3> previous, std::span<Float3> positions,
                      std::span<Float3> velocities, std::span<uint8_t> flags,
                      const ResponseParams& params, float substep_start = 0.f,
                      float substep_end = 1.f, uint32_t* contact_count = nullptr) const;

  // The answer for one segment p0 -> p1 over the selected substep (no response applied, no
  // Gauss-Seidel): over the colliders in `kinds`, the contact with the greatest depth, else the
  // earliest entry (smallest t); inside_end when p1 is inside any of them; depth the greatest.
  // Non-finite input: contact = false, flags = kCollisionInvalidInput.
  ContactQuery Query(Float3 p0, Float3 p1, uint8_t kinds = kColliderAll) const;

  // ---- Per collider, in the collider frame (tests, tools, benchmarks). Indices must be valid.
  bool InsideLocal(uint32_t hull, Float3 p, InsideTest test) const;
  // max_i (n_i . p - d_i) and its plane (the first index attaining it).
  float MaxPlaneDistanceLocal(uint32_t hull, Float3 p, uint32_t* plane = nullptr) const;
  // Kirkpatrick point location of p's projection: the located leaf's plane, -1 outside the
  // projected hull (or when the hull has no hierarchy). steps (optional) receives the number of
  // node tests.
  int32_t LocateLocal(uint32_t hull, Float3 p, bool upper, uint32_t* steps = nullptr) const;
  // The OBB quick rejection: false means p is certainly outside the hull. Inline, as on the
  // query path (which applies it with the OBB frame folded into the pose transform).
  bool ObbMayContainLocal(uint32_t hull, Float3 p) const {
    const HullRecord& h = hulls_[hull];
    const Float3 d = p - h.obb_center;
    return (std::fabs(Dot(d, h.obb_axes[0])) <= h.obb_half.x) &
           (std::fabs(Dot(d, h.obb_axes[1])) <= h.obb_half.y) &
           (std::fabs(Dot(d, h.obb_axes[2])) <= h.obb_half.z);
  }
  // The full narrow phase for the collider-frame segment a -> b with the current options (point
  // and normal in the collider frame).
  ContactQuery QueryHullLocal(uint32_t hull, Float3 a, Float3 b) const;
  // The map-table response ray through p: false when the ray finds no listed triangle.
  bool MapTableRayLocal(uint32_t hull, Float3 p, Float3* point, Float3* normal) const;

  // Posed transforms at a fraction s of the step (rigid): collider frame -> world, and a joint
  // sphere's world centre.
  Mat34 HullWorldTransform(uint32_t hull, float s) const;
  Float3 SphereCenter(uint32_t sphere, float s) const;

  uint32_t hull_count() const { return static_cast<uint32_t>(hulls_.size()); }
  uint32_t sphere_count() const { return static_cast<uint32_t>(spheres_.size()); }
  uint32_t plane_count(uint32_t hull) const { return hulls_[hull].plane_count; }
  bool empty() const { return hulls_.empty() && spheres_.empty(); }
  size_t memory_bytes() const;

 private:
  struct EdgeFunction {  // canonical edge A->B of a node, sign folded in: E(q) = du*(qv-av) -
                         // dv*(qu-au)
    double au, av, du, dv;
  };
  struct Hierarchy {
    uint32_t node_begin = 0, node_count = 0;    // into nodes_ / node_leaf_plane_ / child_offsets_
    uint32_t root_begin = 0, root_end = 0;      // absolute node indices
    double interior_u = 0.0, interior_v = 0.0;  // tie-break target, strictly inside the shadow
  };
  struct HullRecord {
    int32_t joint = -1;
    Mat34 bind_frame;
    uint32_t plane_begin = 0, plane_count = 0, plane_padded = 0;  // planes_ SoA range
    uint32_t triangle_begin = 0, triangle_count = 0;              // ray_triangles_ range
    Float3 obb_center;
    Float3 obb_axes[3];
    Float3 obb_half;           // inflated for float safety
    float bound_radius = 0.f;  // sphere around obb_center containing the OBB
    bool has_hierarchy = false;
    Hierarchy upper, lower;
    Float3 uv_origin, uv_u, uv_v;
    bool has_map = false;
    MapTableKind map_kind = MapTableKind::kSphere;
    uint32_t map_rows = 0, map_cols = 0, map_cell_begin = 0;  // map_cell_offsets_ base
    Float3 map_origin, map_axis, map_reference, map_binormal;
    float map_length = 0.f;
    float map_row_scale = 0.f, map_col_scale = 0.f;  // rows / pi and cols / (2 pi), in float
  };
  struct SphereRecord {
    int32_t joint = -1;
    Float3 center;  // bind pose, asset frame
    float radius = 0.f;
  };
  // One collider's motion over the step (hulls: collider frame; spheres: a translation frame).
  struct Motion {
    Quat rotation0;           // W(0) rotation
    Float3 translation0;      // W(0) translation
    Quat relative;            // rotation of D = W(1) W(0)^-1, w >= 0
    Float3 pivot;             // a point on D's screw axis (or the start centre)
    Float3 shift;             // D(pivot) - pivot
    Float3 center0, center1;  // bounding-sphere centre at s = 0 and 1 (world)
  };
  // Transforms at the selected substep fractions (see SelectSubstep).
  struct ActiveFrames {
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

  // World-space contact of particle segment p0 -> p1 against collider k (hulls first, then
  // spheres) with its transforms at the segment's fractions.
  ContactQuery ColliderContact(uint32_t collider, const ActiveFrames& frames, Float3 p0,
                               Float3 p1) const;
  // At most this many colliders are resolved per particle (those with the lowest indices when
  // more swept bounds overlap one particle's segment, which a character never comes close to).
  static constexpr uint32_t kMaxCandidates = 32;
  uint32_t BroadPhase(Float3 p0, Float3 p1, float s0, float s1, bool active, uint32_t* out) const;
  // kActive: the fractions are the selected substep's (cached transforms and swept spheres).
  // first_candidates (optional): the first pass's broad phase already done, as a bit mask of
  // collider indices (only with at most 32 colliders).
  template <bool kActive>
  void ResolveParticle(Float3 p0, Float3* p1, Float3* velocity, uint8_t* flags,
                       const ResponseParams& params, float s0, float s1,
                       const uint32_t* first_candidates = nullptr) const;
  void Clear();

  // Storage for the arrays the SIMD kernels load 8 floats at a time from: 64-byte aligned, so a
  // hull's plane range (a multiple of 8 floats from the start) never splits a load across cache
  // lines, whatever the heap handed out.
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
  uint8_t simd_level_ = 1;  // plane kernels: 0 scalar, 1 SSE2, 2 AVX2
  uint32_t joint_count_ = 0;
  uint32_t collider_count_ = 0;  // hulls + spheres
  std::vector<HullRecord> hulls_;
  std::vector<SphereRecord> spheres_;
  // Planes, SoA, each hull's range padded to a multiple of 8 with planes that never win.
  SimdFloats plane_nx_, plane_ny_, plane_nz_, plane_d_;
  std::vector<Plane> planes_;  // unpadded copy, plane_begin-relative as in the SoA
  // Triangles for the map-table ray: 9 floats (3 vertices) each, plus their planes.
  std::vector<float> ray_triangles_;
  std::vector<uint32_t> ray_triangle_planes_;  // hull-relative plane index
  // Kirkpatrick nodes of all hierarchies: 3 edge functions each; children are absolute.
  std::vector<EdgeFunction> node_edges_;
  std::vector<int32_t> node_leaf_plane_;
  std::vector<uint32_t> node_guard_begin_;   // node_count + 1 (absolute), CSR of guard planes
  std::vector<uint32_t> node_guard_planes_;  // hull-relative plane indices of fill leaves' rims
  std::vector<uint32_t> node_child_begin_;   // node_count + 1 over all hierarchies (absolute)
  std::vector<uint32_t> node_children_;
  // Map tables: cell offsets (absolute into map_triangles_), lists of hull-relative triangles.
  std::vector<uint32_t> map_cell_offsets_;
  std::vector<uint32_t> map_triangles_;

  // Pose.
  std::vector<Motion> motions_;  // hulls then spheres
  std::vector<ActiveFrames> active_;
  float active_s0_ = 0.f, active_s1_ = 1.f;
  // Broad phase, SoA padded to a multiple of 8 (padding never overlaps): swept spheres over the
  // selected substep and over the whole step.
  SimdFloats sweep_x_, sweep_y_, sweep_z_, sweep_r_;
  SimdFloats full_x_, full_y_, full_z_, full_r_;
  // A sphere around all swept spheres of the selected substep, grown to cover the rounding of the
  // per-collider test: a group of particles outside it skips the per-collider tests.
  Float3 sweep_union_center_;
  float sweep_union_radius_ = 0.f;
};

}  // namespace drape

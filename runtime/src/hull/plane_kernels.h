#pragma once
// Private to the runtime: the hulls' inner loops over their planes and over the colliders' swept
// spheres, written once in the lane operations (plane_kernels.inl) and instantiated for each
// instruction set: ScalarLanes and SSE2 in plane_kernels.cpp, AVX2 in plane_kernels_avx2.cpp.
// Every instantiation gives the same bits: each plane value is ((nx px + ny py) + nz pz) - d in
// float (PlaneSignedDistance's expression), plane i sits in lane i % 8 of the same position in
// every pack, and the reductions (max, min, or) are taken in the same order.

#include <cstdint>

#include "drape/formats/types.h"
#include "drape/runtime/instruction_set.h"

namespace drape::detail {

inline constexpr uint32_t kPlanePad = 8;      // planes per hull padded to a multiple of this
inline constexpr float kPadOffset = 3.0e38f;  // padded planes: 0 . p - 3e38, never the max
inline constexpr float kPadCenter = 3.0e38f;  // padded broad-phase spheres: never reached

// One hull's planes, SoA, padded to a multiple of 8 with planes (0, 0, 0, 3e38) that never win a
// max, never separate and never clip.
struct PlaneSoa {  // 40 bytes
  const float* nx;
  const float* ny;
  const float* nz;
  const float* d;
  uint32_t padded;  // multiple of kPlanePad
};
struct DualResult {
  float max_a, max_b;  // valid only when !separated
  bool separated;      // one plane has both ends strictly outside: the segment misses the hull
};
struct ClipResult {
  float t_in, t_out;  // max entering t (-1: none), min leaving t (1: none)
};

struct PlaneKernels {
  uint32_t group_width;  // particles per SphereMasks call: the pack's lane count
  // max over planes of the plane value at p.
  float (*max)(const PlaneSoa&, Float3 p);
  // The first plane whose value at p equals `value` (0 if none).
  uint32_t (*first_equal)(const PlaneSoa&, Float3 p, float value);
  // Both ends' max values at once, stopping at a plane with both ends outside.
  DualResult (*dual)(const PlaneSoa&, Float3 a, Float3 b);
  DualResult (*dual_same)(const PlaneSoa&, Float3 a);  // dual(s, a, a) with half the work
  // Cyrus-Beck: entering and leaving parameters of the segment a -> b.
  ClipResult (*clip)(const PlaneSoa&, Float3 a, Float3 b);
  // The first plane entering at exactly t_in (0 if none).
  uint32_t (*entry)(const PlaneSoa&, Float3 a, Float3 b, float t_in);
  // Broad phase: indices k < total with |mid - c_k|^2 <= (r_k + half)^2 (SoA padded to a multiple
  // of 8 with spheres that never pass), at most `capacity`, in index order.
  uint32_t (*spheres)(const float* xs, const float* ys, const float* zs, const float* rs,
                      uint32_t total, Float3 mid, float half, uint32_t* out, uint32_t capacity);
  // The broad phase of group_width particles at once (lanes at and beyond `lanes` repeat the
  // first): per particle, the bit mask of the colliders k < total that `spheres` keeps for its
  // segment p0 -> p1 (mid = (p0 + p1) * 0.5, half = |p1 - p0| * 0.50001), in words of 32
  // colliders: lane l's word w (colliders 32w .. 32w + 31) at masks[l * words + w], words =
  // ceil(total / 32). A group wholly outside the union sphere gets empty masks without the
  // per-collider tests. Returns the lanes whose previous and current positions and velocity are
  // all finite (bit l for lane l).
  uint32_t (*sphere_masks)(const Float3* p0, const Float3* p1, const Float3* velocity,
                           uint32_t lanes, const float* xs, const float* ys, const float* zs,
                           const float* rs, uint32_t total, Float3 union_center, float union_radius,
                           uint32_t* masks);
  // The group's OBB filter after sphere_masks (the same lanes and masks): for every hull k <
  // hulls whose bit a lane holds, clears the bit of each lane whose segment p0 -> p1 the OBB test
  // of ColliderContact rejects (the end outside the box and, when continuous, both ends beyond
  // one face), with the same arithmetic. Hull k's box: world -> box frames obb_start[k] at the
  // substep's start and obb_end[k] at its end, half extents half[k]. `total`: the colliders the
  // masks count. Lanes with more than max_candidates candidates keep theirs (the resolution then
  // keeps the lowest indices, which the filter would change). Skipped (the masks left as they
  // are) when the lanes share fewer than half their hulls: each test serves all lanes.
  void (*obb_masks)(const Float3* p0, const Float3* p1, uint32_t lanes, const Mat34* obb_start,
                    const Mat34* obb_end, const Float3* half, uint32_t hulls, uint32_t total,
                    bool continuous, uint32_t max_candidates, uint32_t* masks);
};

// The kernels of `set`, which the CPU must run (BestInstructionSet() or narrower).
const PlaneKernels& PlaneKernelsFor(InstructionSet set);
// The AVX2 instantiation (plane_kernels_avx2.cpp); on targets without it, the SSE2 one.
const PlaneKernels& Avx2PlaneKernels();

}  // namespace drape::detail

#pragma once
// Advances a ClothState by one frame: paper A's or paper B's integrator, substeps, continuous
// collision against the character's colliders and the engine's shapes in every substep,
// attachments to joints, long-range tethers and a strain limit, skinned garments' max distance
// and backstop, and inertia relative to the character's root. Init allocates; Step allocates
// nothing and gives the same bits at any thread count. How a substep runs and how to choose
// substeps and iterations: docs/ALGORITHMS.md §10; figures: docs/PERFORMANCE.md.
//
//   ClothSolver solver;
//   solver.Init(cloth, ClothSolverSettings::PaperB());          // once
//   solver.Step(&state, {&body_map, &hulls, &shapes, response}, frame);   // per frame

#include <cstdint>
#include <span>
#include <vector>

#include "drape/formats/status.h"
#include "drape/formats/types.h"
#include "drape/runtime/body_map_collider.h"
#include "drape/runtime/cloth.h"
#include "drape/runtime/collision_types.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/instruction_set.h"

namespace drape {

enum class ClothIntegrator : uint8_t {
  kVerlet = 0,         // paper B: Verlet + iterative spring correction (stable at any step)
  kExplicitEuler = 1,  // paper A: explicit (symplectic) Euler with spring forces; needs
                       // h < Cloth::MaxStableEulerStep()
};

struct ClothSolverSettings {
  ClothIntegrator integrator = ClothIntegrator::kVerlet;
  uint32_t substeps = 1;    // per frame, in [1, 256]
  uint32_t iterations = 3;  // Verlet spring-correction passes per substep, in [1, 256] (paper B: 3)
  bool buckling = false;  // paper A's buckling model: stretch springs only stretch, bend only bend
  Float3 gravity{0.f, -9.81f, 0.f};  // m/s^2
  float damping = 0.1f;              // 1/s, finite, >= 0: F_damp = -damping * m * v
  float drag = 0.f;  // kg/(m^2 s), finite, >= 0: F_fluid = -drag * area * (v - wind)
  Float3 wind;       // m/s, the air's velocity for the fluid drag
  // The character's root: its joint (-1: none) and its position in the bind-pose asset frame
  // (the translation of inverse(inverse_bind[root])). Needed for inertia below 1.
  int32_t root_joint = -1;
  Float3 root_bind_position;
  // Inertia, in [0, 1]: how much of the root's motion the cloth resists. 1 = simulate in the
  // world (the root's motion drags the cloth through its attachments only); 0 = the cloth is
  // carried with the root (simulated in the character's frame: a running character's skirt does
  // not trail). Linear for the root's translation, angular for its rotation; centrifugal scales
  // the outward push a carried rotation gives (1: a spinning skirt flares as in the world).
  float linear_inertia = 1.f;
  float angular_inertia = 1.f;
  float centrifugal_inertia = 1.f;
  // Long-range tethers (the cloth's, Cloth::tethers()) and the strain limit of stretch springs:
  // after the spring iterations a stretch spring longer than rest * (1 + max_stretch) is
  // shortened to it (+inf: no limit). Verlet only. What keeps a garment from stretching at few
  // iterations; PaperA() and PaperB() turn both off (the papers' integrators as published).
  bool tethers = true;
  float max_stretch = 0.1f;  // >= 0, or +inf
  // The widest instruction set the spring kernel may use (narrowed to the CPU's): four springs
  // per instruction in SSE2 (AVX2 too), or the scalar reference pack. The same bits (tested).
  InstructionSet instruction_set = InstructionSet::kAvx2;
  // Measure the worst stretch spring after each step (ClothStepStats::max_stretch; 0 when off):
  // one pass over the stretch springs, about 6 % of a 10k-particle skirt's frame.
  bool measure_stretch = true;
  // Guard each substep against a blow-up: back the state up and check every particle is finite
  // after it; a non-finite particle stops the step with kInvalidState and the state of the last
  // valid substep (two passes over the particles per substep, about 5 % of a 10k-particle skirt's
  // frame). Off: neither pass; a blow-up then spreads NaN through the state unreported (the
  // input state is still checked at the start of Step).
  bool guard_blowups = true;
  // Time each stage of Step into ClothStepStats::stage_seconds (two steady_clock reads per stage
  // and substep; no effect on the results).
  bool measure_stages = false;

  // Paper A: explicit Euler with the buckling model. substeps must still satisfy the stability
  // bound of the cloth (see RecommendedEulerSubsteps).
  static ClothSolverSettings PaperA(uint32_t substeps);
  // Paper B: Verlet with 3 spring-correction iterations, springs acting both ways.
  static ClothSolverSettings PaperB();
};

// The smallest substep count for which explicit Euler at frame length dt stays within `safety`
// (in (0, 1]) of cloth.MaxStableEulerStep(damping).
uint32_t RecommendedEulerSubsteps(const Cloth& cloth, float dt, float damping, float safety = 0.8f);

class ShapeColliderSet;

// The colliders one step tests, each optional. The broad phase is inside the colliders.
struct ClothColliders {
  const BodyMapCollider* body_map = nullptr;  // one pose (the caller picks it for the frame)
  // Posed by Step (SetPose with the frame's skinning matrices) and switched to each substep
  // (SelectSubstep), hence not const.
  HullColliderSet* hulls = nullptr;
  // The engine's own shapes (floor, props, capsules), posed by the caller for this frame.
  const ShapeColliderSet* shapes = nullptr;
  ResponseParams response;  // friction, restitution, separation
};

// Solver-internal layouts (see ClothSolver::BuildSpringGroups); not part of the API.
namespace internal {
struct alignas(16) Particle4 {  // 16 bytes
  float x = 0.f, y = 0.f, z = 0.f, w = 0.f;
};
// Four springs that share no particle, lane by lane (80 bytes). An unused lane is a null spring
// (a == b on a spare slot, rest length and weights 0).
struct alignas(16) SpringBlock {
  float rest_length[4] = {0.f, 0.f, 0.f, 0.f};
  float weight_a[4] = {0.f, 0.f, 0.f, 0.f};
  float weight_b[4] = {0.f, 0.f, 0.f, 0.f};
  uint32_t a[4] = {0, 0, 0, 0};
  uint32_t b[4] = {0, 0, 0, 0};
};
// A run of blocks of springs of one kind (a chunk's or zone's, solved in order, or one colour
// of far springs, whose blocks share no particle).
struct SpringRun {
  uint32_t begin = 0, end = 0;  // into the solver's blocks
  SpringKind kind = SpringKind::kStretch;
};
// The runs of one chunk or zone, solved in order by one thread.
struct SpringGroup {
  uint32_t run_begin = 0, run_end = 0;
};
}  // namespace internal

// The frame one Step advances.
struct ClothFrame {
  float dt = 1.f / 60.f;  // seconds, finite, > 0
  // Skinning matrices (world * inverse bind) at the start and end of the frame. Needed (at least
  // Cloth::required_joint_count(), the hull set's joint count and root_joint + 1) when the cloth
  // has attachments, hulls are given, or relative simulation is on; else may be empty.
  std::span<const Mat34> skinning_start;
  std::span<const Mat34> skinning_end;
};

// Where a step's time goes, in seconds summed over its substeps (measure_stages on).
struct ClothStageSeconds {
  double integrate = 0.0;    // backup and input check, root motion, integration, attachments
  double springs = 0.0;      // spring correction (Verlet) or forces (Euler), strain limit
  double constraints = 0.0;  // skinned targets, tethers, max distance, backstop, velocities
  double collide = 0.0;      // colliders' poses, every collider's batch
  double bookkeeping = 0.0;  // contact count with the blow-up check, stretch measure
};

struct ClothStepStats {
  uint32_t substeps = 0;           // substeps completed
  uint32_t contacts = 0;           // particles with a contact in the last substep
  uint32_t hull_contacts = 0;      // sum over substeps of the hulls' contact counts
  uint32_t body_map_contacts = 0;  // sum over substeps of the body map's contact counts
  uint32_t shape_contacts = 0;     // sum over substeps of the engine shapes' contact counts
  // After the step (both 0 when measure_stretch is off): max over stretch springs of L / R - 1,
  // and how many stretch springs are longer than the strain limit allows, R (1 + max_stretch)
  // (R 1.1 when the limit is off), by more than rounding: one spring far off, or the garment
  // stretched all over.
  float max_stretch = 0.f;
  uint32_t overstretched_springs = 0;
  ClothStageSeconds stage_seconds;  // zeros unless ClothSolverSettings::measure_stages
};

class ClothSolver {
 public:
  // Binds the solver to `cloth` (kept by pointer: it must outlive the solver) and allocates the
  // scratch. Rejected (kInvalidArgument): an empty cloth, substeps or iterations out of range,
  // non-finite gravity or wind, damping or drag not finite and >= 0, a non-finite root bind
  // position, root_joint < -1.
  Status Init(const Cloth& cloth, const ClothSolverSettings& settings);
  Status SetSettings(const ClothSolverSettings& settings);
  const ClothSolverSettings& settings() const { return settings_; }

  // Advances `state` by frame.dt. Errors (state untouched): kInvalidArgument for a bad frame or
  // colliders (sizes, dt, skinning too short or not finite) or a state that does not match the
  // cloth; kInvalidState when the input state holds a non-finite position or velocity (the
  // message names the first such particle). A substep that produces a non-finite value (a
  // blow-up: e.g. explicit Euler past its stability bound) also returns kInvalidState naming the
  // first bad particle, with the state restored to the end of the last valid substep
  // (previous_positions = positions). stats (optional) is filled in every case.
  Status Step(ClothState* state, const ClothColliders& colliders, const ClothFrame& frame,
              ClothStepStats* stats = nullptr);

  // Collision flags (CollisionFlags, OR over hulls, body map and shapes) of the last substep.
  std::span<const uint8_t> contact_flags() const { return flags_; }

  // Moves the cloth rigidly by `transform` (a rotation and a translation: positions, previous
  // positions and velocities), for a character that teleports. The next Step's skinning_start
  // must then be the pose at the new place. kInvalidArgument for a non-rigid or non-finite
  // transform or a state that does not match.
  Status Teleport(ClothState* state, const Mat34& transform) const;

  // Puts every particle at its skinned position at the pose `skinning` with zero velocity:
  // skinned garments by their weights, attached particles by their joint, the rest carried
  // rigidly by the root joint from the rest shape (or at rest without a root). Then pushes out
  // of the given colliders (posed at `skinning` for the whole frame) whatever lies inside.
  Status Reset(ClothState* state, const ClothColliders& colliders, std::span<const Mat34> skinning);

 private:
  struct Substep {
    float s0 = 0.f, s1 = 1.f;  // fractions of the frame
    float h = 0.f;             // seconds
  };

  Status ValidateFrame(const ClothState& state, const ClothColliders& colliders,
                       const ClothFrame& frame) const;
  // The root's motion over the frame and the share of it each substep carries the cloth.
  struct RootMotion {
    bool carry = false;        // linear or angular inertia below 1
    bool centrifugal = false;  // a carried rotation pushes outward
    Float3 pivot0, pivot1;     // root position at the frame's start and end, metres
    Quat rotation;             // the root's rotation over the frame (start -> end)
    Float3 omega;              // rad/s: the root's angular velocity
  };
  RootMotion ComputeRootMotion(const ClothFrame& frame) const;
  // The carried share of the root's motion over a substep, as a rigid transform.
  Mat34 CarriedMotion(const RootMotion& root, const Substep& sub) const;
  // The stages of one substep, in order.
  bool CheckInputAndBackUp(ClothState* state, bool carry);
  void BackUpRange(const ClothState& state, bool positions, int64_t begin, int64_t end);
  void BeginSubstep(ClothState* state, const RootMotion& root, const Substep& sub, bool back_up);
  void ComputeSkinnedTargets(const ClothFrame& frame);
  void IndexConstraints();
  Float3 SkinLimit(uint32_t target, Float3 x, float s) const;
  // Tethers and skinned limits, and the velocities (Verlet: re-estimated from the positions).
  void ConstrainAndUpdateVelocities(ClothState* state, const Substep& sub);
  void AccumulateSpringForces(const ClothState& state);
  void Integrate(ClothState* state, const Substep& sub, const RootMotion& root);
  void ApplyAttachments(ClothState* state, const ClothFrame& frame, const Substep& sub);
  void SolveSprings();
  void BuildSpringGroups(const Cloth& cloth);
  // limit: the strain limit's pass (stretch runs only, acting beyond rest * (1 + max_stretch)).
  void CorrectGroup(const internal::SpringGroup& group, bool limit, internal::Particle4* p) const;
  void CorrectRun(const internal::SpringRun& run, bool shared, bool limit,
                  internal::Particle4* p) const;
  void AccumulateRun(const internal::SpringRun& run, bool shared, const Float3* x, const Float3* v,
                     Float3* forces) const;
  Status Collide(ClothState* state, const ClothColliders& colliders, const Substep& sub,
                 ClothStepStats* stats);
  void RestoreKinematic(ClothState* state);
  // The first particle with a non-finite position or velocity, or UINT32_MAX.
  uint32_t FirstNonFinite(const ClothState& state) const;
  // ORs the other colliders' flags into flags_ (when several ran) and counts the contacts; with
  // `check_finite`, also whether a position or velocity is not finite (*any_non_finite).
  uint32_t CountContacts(const ClothState& state, bool check_finite, bool* any_non_finite);
  void RestoreBackup(ClothState* state);
  // The stretch measure's figures: ClothStepStats::max_stretch and overstretched_springs.
  struct StretchFigures {
    float max_stretch = 0.f;
    uint32_t overstretched = 0;
  };
  StretchFigures MeasureStretch(const ClothState& state) const;

  const Cloth* cloth_ = nullptr;
  ClothSolverSettings settings_;
  // Scratch, sized by Init (particle_count unless noted).
  std::vector<Float3> backup_positions_, backup_velocities_;
  std::vector<Float3> forces_;  // explicit Euler spring forces, N
  std::vector<Float3> kinematic_positions_, kinematic_velocities_;  // kinematic_particles() sized
  std::vector<uint8_t> flags_, body_map_flags_, shape_flags_;
  // Skinned garments: targets and normals at the frame's start and end, for the particles in
  // skin_targets_ (the constrained ones and the kinematic skinned ones).
  std::vector<uint32_t> skin_targets_;
  uint32_t skin_kinematic_count_ = 0;  // the first ones of skin_targets_ are kinematic
  // Per particle: its tether's index in Cloth::tethers() and its index in skin_targets_ (the
  // constrained ones), or UINT32_MAX.
  std::vector<uint32_t> tether_of_, skin_target_of_;
  std::vector<Float3> skin_start_, skin_end_, skin_normal_start_, skin_normal_end_;
  // The spring solver's working copy of the positions (16-byte aligned particles for aligned SSE
  // loads; Verlet: written by Integrate and ApplyAttachments, read back after the springs) and the
  // springs in blocks of four, by group and colour (BuildSpringGroups).
  std::vector<internal::Particle4> solver_positions_;
  // The stretch springs MeasureStretch measures, ordered by their lower particle index: a chunk of
  // them reads the particles that the same worker's chunk of every per-particle stage wrote.
  struct MeasuredSpring {
    uint32_t a = 0, b = 0;
    float rest_length = 0.f;  // metres, > 0
  };                          // 12 bytes
  std::vector<MeasuredSpring> measured_springs_;
  std::vector<internal::SpringBlock> blocks_;
  std::vector<internal::SpringRun> runs_;
  std::vector<internal::SpringGroup> chunk_groups_, even_zones_, odd_zones_;
  internal::SpringGroup far_runs_;
  uint8_t merge_flags_ = 0;           // bit 0: OR body_map_flags_, bit 1: shape_flags_ into flags_
  bool restore_kinematic_ = false;    // Collide saved the kinematic particles
  bool positions_backed_up_ = false;  // this substep's backup holds the (carried) positions
};

}  // namespace drape

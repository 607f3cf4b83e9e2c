#include "drape/runtime/cloth_solver.h"

#include "cloth/cloth_solver_internal.h"
#include "cloth/spring_colouring.h"
#include "cloth/spring_kernels.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "drape/runtime/math.h"
#include "drape/runtime/shape_collider_set.h"

#include "tasks/parallel_for.h"

namespace drape {
namespace {

using internal::Particle4;
using internal::SpringBlock;
using internal::SpringGroup;
using internal::SpringRun;

using detail::AnyNonFinite;
using detail::Finite;
using detail::InvalidArgument;
using detail::kParticleGrain;
using detail::ParallelFor;
using detail::ParallelRanges;

constexpr uint32_t kMaxSubsteps = 256;
constexpr uint32_t kMaxIterations = 256;
// Blocks of four springs per chunk of a run shared among the workers (the far springs).
constexpr int64_t kBlockGrain = 256;

// Adds the time since the last lap to a stage's seconds, when on (measure_stages).
class StageClock {
 public:
  StageClock(bool on, ClothStageSeconds* out)
      : out_(on ? out : nullptr), last_(on ? Clock::now() : Clock::time_point{}) {}
  void Lap(double ClothStageSeconds::*stage) {
    if (out_ == nullptr) return;
    const Clock::time_point now = Clock::now();
    out_->*stage += std::chrono::duration<double>(now - last_).count();
    last_ = now;
  }

 private:
  using Clock = std::chrono::steady_clock;
  ClothStageSeconds* out_;
  Clock::time_point last_;
};

using detail::SpringSide;

SpringSide SideOf(SpringKind kind, bool buckling) {
  if (!buckling) return SpringSide::kBoth;
  return kind == SpringKind::kStretch ? SpringSide::kStretched : SpringSide::kCompressed;
}

// The length error a spring acts on: all of it, or under paper A's buckling model only a stretch
// (stretch springs) or only a compression (bend springs).
template <SpringSide side>
inline float ActiveError(float error) {
  if constexpr (side == SpringSide::kStretched) return error > 0.f ? error : 0.f;
  if constexpr (side == SpringSide::kCompressed) return error < 0.f ? error : 0.f;
  return error;
}

// One run's blocks, on the calling thread or shared among the workers (chunks of kBlockGrain
// blocks).
void CorrectRunSequential(const SpringBlock* blocks, const SpringRun& run, SpringSide side,
                          const detail::SpringCorrection& c, Particle4* p) {
  detail::CorrectBlocks(blocks, run.begin, run.end, side, c, p);
}

void CorrectRunShared(const SpringBlock* blocks, const SpringRun& run, SpringSide side,
                      const detail::SpringCorrection& c, Particle4* p) {
  const uint32_t first = run.begin;
  ParallelRanges(int64_t{run.end} - first, kBlockGrain, [&](int64_t begin, int64_t end) {
    detail::CorrectBlocks(blocks, first + static_cast<uint32_t>(begin),
                          first + static_cast<uint32_t>(end), side, c, p);
  });
}

// Appends `springs` (pairwise disjoint: one colour) as blocks of four, in order. The lanes of the
// last block left empty hold null springs (rest length 0, weights 0) on the group's own spare
// slots spare..spare + 3, which only this group writes: their correction is 0 and they touch no
// particle.
void PackBlocks(const std::vector<ClothSpring>& springs, uint32_t spare,
                std::vector<SpringBlock>* blocks) {
  for (size_t k = 0; k < springs.size(); k += 4) {
    SpringBlock& block = blocks->emplace_back();
    for (uint32_t lane = 0; lane < 4; ++lane) {
      if (k + lane < springs.size()) {
        const ClothSpring& spring = springs[k + lane];
        block.a[lane] = spring.a;
        block.b[lane] = spring.b;
        block.rest_length[lane] = spring.rest_length;
        block.weight_a[lane] = spring.weight_a;
        block.weight_b[lane] = spring.weight_b;
      } else {
        block.a[lane] = block.b[lane] = spare + lane;  // the rest stays 0
      }
    }
  }
}

// Paper A's spring force on lane k of a block: F_a = (k (L - R) + c (v_b - v_a).u) u, F_b = -F_a,
// or nothing while the buckling model keeps the spring inactive.
template <SpringSide side>
inline void AccumulateSpring(const SpringBlock& block, uint32_t k, float stiffness, float damping,
                             const Float3* x, const Float3* v, Float3* forces) {
  const uint32_t a = block.a[k], b = block.b[k];
  if (a == b) return;  // a null lane: its spare slot is not a particle
  const Float3 d = x[b] - x[a];
  const float length = std::sqrt(Dot(d, d));
  const float error = length - block.rest_length[k];
  if (ActiveError<side>(error) == 0.f || !(length > 1e-20f)) return;
  const Float3 u = d * (1.f / length);
  const Float3 f = u * (stiffness * error + damping * Dot(v[b] - v[a], u));
  forces[a] += f;
  forces[b] -= f;
}

template <SpringSide side>
void AccumulateRunLanes(const SpringBlock* blocks, const SpringRun& run, bool shared,
                        float stiffness, float damping, const Float3* x, const Float3* v,
                        Float3* forces) {
  const int64_t begin = run.begin, end = run.end;
  const auto block_forces = [&](int64_t k) {
    for (uint32_t lane = 0; lane < 4; ++lane)
      AccumulateSpring<side>(blocks[begin + k], lane, stiffness, damping, x, v, forces);
  };
  if (shared) {
    ParallelFor(end - begin, kBlockGrain, block_forces);
  } else {
    for (int64_t k = 0; k < end - begin; ++k) block_forces(k);
  }
}

// Runs group_fn on every spring group but the far runs, in two parallel phases. The chunk pairs
// (chunks 2k and 2k + 1, then the even zone 2k between them) are split into runs of consecutive
// pairs, one task per worker; a task then does the odd zones between its own pairs. The odd
// zones between two tasks follow, in a second phase. Any two springs that share a particle keep
// the order of the chunks, the even zones and the odd zones (a zone's springs join only its two
// chunks), so the bits are those of three phases whatever the runs' length, and the task count
// may follow the workers without changing a result. One task per worker leaves the second phase
// one zone on two workers, which the caller does alone instead of handing 15 zones of 0.8 us
// around (measured on the 10 100-particle skirt: 0.320 ms per frame on 2 workers instead of
// 0.334; two tasks per worker 0.328, four 0.334).
template <class GroupFn>
void ForEachGroupInPhases(const std::vector<SpringGroup>& chunks,
                          const std::vector<SpringGroup>& even_zones,
                          const std::vector<SpringGroup>& odd_zones, const GroupFn& group_fn) {
  const size_t pairs = (chunks.size() + 1) / 2;
  const size_t tasks =
      std::clamp<size_t>(GetTaskSystem().WorkerCount(), 1, std::max<size_t>(pairs, 1));
  const auto first_pair = [&](size_t task) { return task * pairs / tasks; };
  ParallelFor(static_cast<int64_t>(tasks), 1, [&](int64_t t) {
    const size_t begin = first_pair(static_cast<size_t>(t));
    const size_t end = first_pair(static_cast<size_t>(t) + 1);
    for (size_t k = begin; k < end; ++k) {
      group_fn(chunks[2 * k]);
      if (2 * k + 1 < chunks.size()) group_fn(chunks[2 * k + 1]);
      if (k < even_zones.size()) group_fn(even_zones[k]);
    }
    // Odd zone k lies between pairs k and k + 1.
    for (size_t k = begin; k + 1 < end && k < odd_zones.size(); ++k) group_fn(odd_zones[k]);
  });
  ParallelFor(static_cast<int64_t>(tasks - 1), 1, [&](int64_t t) {
    const size_t k = first_pair(static_cast<size_t>(t) + 1) - 1;
    if (k < odd_zones.size()) group_fn(odd_zones[k]);
  });
}

}  // namespace

ClothSolverSettings ClothSolverSettings::PaperA(uint32_t substeps) {
  ClothSolverSettings s;
  s.integrator = ClothIntegrator::kExplicitEuler;
  s.substeps = substeps;
  s.buckling = true;
  s.tethers = false;
  s.max_stretch = std::numeric_limits<float>::infinity();
  return s;
}

ClothSolverSettings ClothSolverSettings::PaperB() {
  ClothSolverSettings s;
  s.integrator = ClothIntegrator::kVerlet;
  s.iterations = 3;
  s.buckling = false;
  s.tethers = false;
  s.max_stretch = std::numeric_limits<float>::infinity();
  return s;
}

uint32_t RecommendedEulerSubsteps(const Cloth& cloth, float dt, float damping, float safety) {
  const float h_max = cloth.MaxStableEulerStep(damping) * std::clamp(safety, 1e-3f, 1.f);
  if (!(dt > 0.f) || !std::isfinite(h_max)) return 1;
  const double count = std::ceil(static_cast<double>(dt) / h_max);
  return static_cast<uint32_t>(std::clamp(count, 1.0, static_cast<double>(kMaxSubsteps)));
}

Status ClothSolver::SetSettings(const ClothSolverSettings& s) {
  if (s.substeps < 1 || s.substeps > kMaxSubsteps)
    return InvalidArgument("substeps = " + std::to_string(s.substeps) + ": must be in [1, 256]");
  if (s.iterations < 1 || s.iterations > kMaxIterations)
    return InvalidArgument("iterations = " + std::to_string(s.iterations) +
                           ": must be in [1, 256]");
  if (!IsFinite(s.gravity)) return InvalidArgument("gravity is not finite");
  if (!IsFinite(s.wind)) return InvalidArgument("wind is not finite");
  if (!std::isfinite(s.damping) || s.damping < 0.f)
    return InvalidArgument("damping = " + std::to_string(s.damping) +
                           " 1/s: must be finite and >= 0");
  if (!std::isfinite(s.drag) || s.drag < 0.f)
    return InvalidArgument("drag = " + std::to_string(s.drag) + ": must be finite and >= 0");
  if (s.root_joint < -1)
    return InvalidArgument("root_joint = " + std::to_string(s.root_joint) + ": must be >= -1");
  if (!IsFinite(s.root_bind_position)) return InvalidArgument("root_bind_position is not finite");
  for (const auto& [value, name] : {std::pair{s.linear_inertia, "linear_inertia"},
                                    std::pair{s.angular_inertia, "angular_inertia"},
                                    std::pair{s.centrifugal_inertia, "centrifugal_inertia"}}) {
    if (!(value >= 0.f && value <= 1.f))
      return InvalidArgument(std::string(name) + " = " + std::to_string(value) +
                             ": must be in [0, 1]");
  }
  if ((s.linear_inertia < 1.f || s.angular_inertia < 1.f) && s.root_joint < 0)
    return InvalidArgument("linear_inertia or angular_inertia below 1 needs a root_joint");
  if (!(s.max_stretch >= 0.f))
    return InvalidArgument("max_stretch = " + std::to_string(s.max_stretch) +
                           ": must be >= 0 (+inf: no strain limit)");
  if (s.integrator != ClothIntegrator::kVerlet && s.integrator != ClothIntegrator::kExplicitEuler)
    return InvalidArgument("unknown integrator");
  settings_ = s;
  return Status::Ok();
}

// The spring layout. Particles are split into `chunks` index ranges of equal size (a number that
// depends on the mesh only, never on the thread count). A spring between two particles of one
// chunk belongs to that chunk; one between neighbouring chunks c and c + 1 to zone c; any other
// is "far". Each group's springs are coloured (first fit, stretch then bend, in (a, b) order) and
// each colour is one run of blocks of four: the blocks of a run are independent, so the CPU
// overlaps their square roots and divisions. SolveSprings then runs per iteration: the chunks
// and even zones in parallel, the odd zones in parallel (zone c touches chunks c and c + 1 only,
// so zones two apart share no particle; ForEachGroupInPhases), then the far runs one by one,
// each shared among the workers. Meshes numbered row by row (every generated garment, most
// scanned meshes) have no far springs: two ParallelFors per iteration.
void ClothSolver::BuildSpringGroups(const Cloth& cloth) {
  const uint32_t n = cloth.particle_count();
  // Chunks of at least 256 particles and longer than 99 % of the springs' index spans |a - b| (so
  // that those cross at most one chunk boundary), a multiple of 8 of them (even shares for 2, 4
  // and 8 threads), at most 64. A cloth of 2048 particles or more gets at least 8 chunks (its
  // longer springs are then far springs); a smaller one is a single chunk.
  std::vector<uint32_t> spans;
  spans.reserve(cloth.springs().size());
  for (const ClothSpring& spring : cloth.springs())
    spans.push_back(std::max(spring.a, spring.b) - std::min(spring.a, spring.b));
  uint32_t span = 0;
  if (!spans.empty()) {
    const size_t rank = spans.size() * 99 / 100;
    std::nth_element(spans.begin(), spans.begin() + static_cast<std::ptrdiff_t>(rank), spans.end());
    span = spans[rank];
  }
  uint32_t chunks = n / std::max(256u, span + 1);
  if (chunks < 8) chunks = n >= 2048 ? 8 : 1;
  chunks = chunks >= 8 ? std::min(64u, chunks / 8 * 8) : 1;
  const auto chunk_of = [&](uint32_t i) { return static_cast<uint32_t>(uint64_t{i} * chunks / n); };
  const uint32_t zones = chunks - 1;
  const uint32_t far = chunks + zones;                // group index of the far springs
  std::vector<std::vector<ClothSpring>> by_group[2];  // [kind][group]: chunks, zones, far
  for (auto& g : by_group) g.resize(far + 1);
  for (const SpringColour& colour : cloth.colours()) {
    for (uint32_t k = colour.begin; k < colour.end; ++k) {
      const ClothSpring& spring = cloth.springs()[k];
      const uint32_t ca = chunk_of(std::min(spring.a, spring.b));
      const uint32_t cb = chunk_of(std::max(spring.a, spring.b));
      const uint32_t group = ca == cb ? ca : (cb == ca + 1 ? chunks + ca : far);
      by_group[static_cast<int>(colour.kind)][group].push_back(spring);
    }
  }
  // Spare slots after the particles: four per group, written only by that group's null lanes.
  solver_positions_.assign(n + 4 * (far + 1), Particle4{});
  blocks_.clear();
  runs_.clear();
  chunk_groups_.clear();
  even_zones_.clear();
  odd_zones_.clear();
  const auto by_index = [](const ClothSpring& x, const ClothSpring& y) {
    return x.a != y.a ? x.a < y.a : x.b < y.b;
  };
  std::vector<std::vector<uint64_t>> used(n);
  std::vector<uint32_t> colour_of;
  std::vector<std::vector<ClothSpring>> by_colour;
  // One run per colour of the group's springs of one kind; runs of one group share its spares
  // (they are solved one after the other, by one thread or with a barrier between them).
  const auto add_runs = [&](std::vector<ClothSpring>& springs, SpringKind kind, uint32_t group) {
    std::sort(springs.begin(), springs.end(), by_index);
    by_colour.assign(detail::FirstFitColours(springs, &used, &colour_of), {});
    for (size_t k = 0; k < springs.size(); ++k) by_colour[colour_of[k]].push_back(springs[k]);
    for (const std::vector<ClothSpring>& colour : by_colour) {
      SpringRun run;
      run.begin = static_cast<uint32_t>(blocks_.size());
      run.kind = kind;
      PackBlocks(colour, n + 4 * group, &blocks_);
      run.end = static_cast<uint32_t>(blocks_.size());
      runs_.push_back(run);
    }
  };
  for (uint32_t g = 0; g <= far; ++g) {
    SpringGroup group;
    group.run_begin = static_cast<uint32_t>(runs_.size());
    add_runs(by_group[0][g], SpringKind::kStretch, g);
    add_runs(by_group[1][g], SpringKind::kBend, g);
    group.run_end = static_cast<uint32_t>(runs_.size());
    if (g < chunks) {
      chunk_groups_.push_back(group);
    } else if (g < far) {
      ((g - chunks) % 2 == 0 ? even_zones_ : odd_zones_).push_back(group);
    } else {
      far_runs_ = group;
    }
  }
}

Status ClothSolver::Init(const Cloth& cloth, const ClothSolverSettings& settings) {
  if (cloth.empty()) return InvalidArgument("Init: the cloth is empty (not built)");
  if (Status s = SetSettings(settings); !s.ok()) return s;
  cloth_ = &cloth;
  const size_t n = cloth.particle_count();
  const size_t k = cloth.kinematic_particles().size();
  backup_positions_.assign(n, Float3{});
  backup_velocities_.assign(n, Float3{});
  forces_.assign(n, Float3{});
  kinematic_positions_.assign(k, Float3{});
  kinematic_velocities_.assign(k, Float3{});
  flags_.assign(n, 0);
  body_map_flags_.assign(n, 0);
  shape_flags_.assign(n, 0);
  // Skinned kinematic particles first (ApplyAttachments places them), then the constrained ones.
  skin_targets_.clear();
  skin_kinematic_count_ = 0;
  if (cloth.skinned()) {
    std::vector<uint8_t> attached(n, 0);
    for (const ClothAttachment& a : cloth.attachments()) attached[a.particle] = 1;
    for (const uint32_t i : cloth.kinematic_particles())
      if (!attached[i] && cloth.max_distances()[i] == 0.f) skin_targets_.push_back(i);
    skin_kinematic_count_ = static_cast<uint32_t>(skin_targets_.size());
    const std::span<const uint32_t> constrained = cloth.constrained_particles();
    skin_targets_.insert(skin_targets_.end(), constrained.begin(), constrained.end());
  }
  const size_t targets = skin_targets_.size();
  skin_start_.assign(targets, Float3{});
  skin_end_.assign(targets, Float3{});
  skin_normal_start_.assign(targets, Float3{});
  skin_normal_end_.assign(targets, Float3{});
  BuildSpringGroups(cloth);
  IndexConstraints();
  // The stretch springs are the first spring_count(kStretch) springs (Cloth::springs()).
  measured_springs_.clear();
  for (uint32_t j = 0; j < cloth.spring_count(SpringKind::kStretch); ++j) {
    const ClothSpring& spring = cloth.springs()[j];
    measured_springs_.push_back(
        {std::min(spring.a, spring.b), std::max(spring.a, spring.b), spring.rest_length});
  }
  std::sort(measured_springs_.begin(), measured_springs_.end(),
            [](const MeasuredSpring& x, const MeasuredSpring& y) {
              return x.a != y.a ? x.a < y.a : x.b < y.b;
            });
  return Status::Ok();
}

// ---- Step: the recipe --------------------------------------------------------------------------

Status ClothSolver::Step(ClothState* state, const ClothColliders& colliders,
                         const ClothFrame& frame, ClothStepStats* stats) {
  ClothStepStats local_stats;
  ClothStepStats& st = stats != nullptr ? *stats : local_stats;
  st = ClothStepStats{};
  StageClock setup_clock(settings_.measure_stages, &st.stage_seconds);
  if (Status s = ValidateFrame(*state, colliders, frame); !s.ok()) return s;
  const RootMotion root = ComputeRootMotion(frame);
  ComputeSkinnedTargets(frame);
  setup_clock.Lap(&ClothStageSeconds::constraints);

  const uint32_t count = settings_.substeps;
  const bool verlet = settings_.integrator == ClothIntegrator::kVerlet;
  for (uint32_t k = 0; k < count; ++k) {
    Substep sub;
    sub.s0 = static_cast<float>(k) / static_cast<float>(count);
    sub.s1 = static_cast<float>(k + 1) / static_cast<float>(count);  // exactly 1 at the end
    sub.h = frame.dt / static_cast<float>(count);

    // Each stage hands its chunks to the task system and returns when they are done.
    StageClock clock(settings_.measure_stages, &st.stage_seconds);
    if (k == 0) {
      // The input state is checked in the backup's pass, then the hulls posed, and only then
      // does anything change the state: an error leaves it (and the colliders) as they were.
      if (!CheckInputAndBackUp(state, root.carry)) {
        const uint32_t bad = FirstNonFinite(*state);
        return Status(StatusCode::kInvalidState,
                      "ClothSolver::Step: input state of particle " + std::to_string(bad) +
                          " is not finite (position or velocity); nothing was simulated");
      }
      clock.Lap(&ClothStageSeconds::bookkeeping);
      if (colliders.hulls != nullptr) {
        if (Status s = colliders.hulls->SetPose(frame.skinning_start, frame.skinning_end); !s.ok())
          return s;
      }
      clock.Lap(&ClothStageSeconds::collide);
    }
    BeginSubstep(state, root, sub, /*back_up=*/k > 0 && settings_.guard_blowups);
    clock.Lap(&ClothStageSeconds::integrate);
    if (!verlet) AccumulateSpringForces(*state);
    clock.Lap(&ClothStageSeconds::springs);
    Integrate(state, sub, root);
    ApplyAttachments(state, frame, sub);
    clock.Lap(&ClothStageSeconds::integrate);
    if (verlet) SolveSprings();
    clock.Lap(&ClothStageSeconds::springs);
    ConstrainAndUpdateVelocities(state, sub);
    clock.Lap(&ClothStageSeconds::constraints);
    if (Status s = Collide(state, colliders, sub, &st); !s.ok()) {
      if (settings_.guard_blowups) RestoreBackup(state);
      return s;
    }
    RestoreKinematic(state);
    clock.Lap(&ClothStageSeconds::collide);
    bool blew_up = false;
    st.contacts = CountContacts(*state, settings_.guard_blowups, &blew_up);
    if (blew_up) {
      const uint32_t bad = FirstNonFinite(*state);
      RestoreBackup(state);
      st.contacts = 0;
      const StretchFigures stretch = MeasureStretch(*state);
      st.max_stretch = stretch.max_stretch;
      st.overstretched_springs = stretch.overstretched;
      return Status(StatusCode::kInvalidState,
                    "ClothSolver::Step: particle " + std::to_string(bad) +
                        " became non-finite in substep " + std::to_string(k) +
                        " (a blow-up: for explicit Euler use more substeps); the state is left "
                        "at the end of the last valid substep");
    }
    ++st.substeps;
    clock.Lap(&ClothStageSeconds::bookkeeping);
  }
  StageClock clock(settings_.measure_stages, &st.stage_seconds);
  if (settings_.measure_stretch) {
    const StretchFigures stretch = MeasureStretch(*state);
    st.max_stretch = stretch.max_stretch;
    st.overstretched_springs = stretch.overstretched;
  }
  clock.Lap(&ClothStageSeconds::bookkeeping);
  return Status::Ok();
}

Status ClothSolver::ValidateFrame(const ClothState& state, const ClothColliders& colliders,
                                  const ClothFrame& frame) const {
  if (cloth_ == nullptr) return InvalidArgument("Step: Init was not called");
  if (!state.Matches(*cloth_))
    return InvalidArgument("Step: the state's arrays do not have the cloth's " +
                           std::to_string(cloth_->particle_count()) +
                           " particles (call ClothState::Reset)");
  if (!std::isfinite(frame.dt) || !(frame.dt > 0.f))
    return InvalidArgument("Step: dt = " + std::to_string(frame.dt) + " s: must be finite and > 0");
  size_t joints = cloth_->required_joint_count();
  if (settings_.root_joint >= 0) joints = std::max(joints, size_t(settings_.root_joint) + 1);
  if (frame.skinning_start.size() < joints || frame.skinning_end.size() < joints)
    return InvalidArgument("Step: " + std::to_string(joints) +
                           " skinning matrices are needed (attachments, root joint) at the start "
                           "and end of the frame; got " +
                           std::to_string(frame.skinning_start.size()) + " and " +
                           std::to_string(frame.skinning_end.size()));
  for (size_t j = 0; j < joints; ++j) {
    if (!Finite(frame.skinning_start[j]) || !Finite(frame.skinning_end[j]))
      return InvalidArgument("Step: skinning matrix of joint " + std::to_string(j) +
                             " is not finite");
  }
  if (!ValidResponse(colliders.response))
    return InvalidArgument(
        "Step: response friction in [0, 1], static_friction in [0, 4], restitution in [0, 1], "
        "separation finite and >= 0");
  if (colliders.body_map != nullptr && colliders.body_map->empty())
    return InvalidArgument("Step: the body map collider is empty (not built)");
  return Status::Ok();
}

// ---- Stages ------------------------------------------------------------------------------------
// Each stage is one or more ParallelFors (tasks/parallel_for.h): per-particle stages in chunks of
// kParticleGrain particles, the springs by group. A ParallelFor returns when all its chunks are
// done, so a stage sees every write of the stages before it.

// The first substep's backup in one pass with the check that the input state is finite; false
// (and the state untouched: only the backup is written) when it is not. The positions need a copy
// only when the root's motion carries them: otherwise Integrate's previous positions are the
// substep's start.
bool ClothSolver::CheckInputAndBackUp(ClothState* state, bool carry) {
  const Float3* x = state->positions.data();
  const Float3* v = state->velocities.data();
  const bool backup = settings_.guard_blowups;
  positions_backed_up_ = backup && carry;
  detail::ChunkSum bad_chunks;
  ParallelRanges(static_cast<int64_t>(state->positions.size()), kParticleGrain,
                 [&](int64_t begin, int64_t end) {
                   if (AnyNonFinite(x, v, begin, end)) bad_chunks.Add(1);
                   if (backup) BackUpRange(*state, carry, begin, end);
                 });
  return bad_chunks.total() == 0;
}

void ClothSolver::BackUpRange(const ClothState& state, bool positions, int64_t begin, int64_t end) {
  for (int64_t i = begin; positions && i < end; ++i) backup_positions_[i] = state.positions[i];
  for (int64_t i = begin; i < end; ++i) backup_velocities_[i] = state.velocities[i];
}

// The state's backup (restored if the substep fails; see CheckInputAndBackUp), then the carried
// share of the root's motion, in one pass over the particles.
void ClothSolver::BeginSubstep(ClothState* state, const RootMotion& root, const Substep& sub,
                               bool back_up) {
  const bool carry = root.carry;
  if (back_up) positions_backed_up_ = carry;
  if (!carry && !back_up) return;
  Float3* x = state->positions.data();
  Float3* v = state->velocities.data();
  const Mat34 carried = carry ? CarriedMotion(root, sub) : Mat34{};
  ParallelRanges(static_cast<int64_t>(state->positions.size()), kParticleGrain,
                 [&](int64_t begin, int64_t end) {
                   if (back_up) BackUpRange(*state, carry, begin, end);
                   if (!carry) return;
                   for (int64_t i = begin; i < end; ++i) {
                     x[i] = TransformPoint(carried, x[i]);
                     v[i] = TransformVector(carried, v[i]);
                   }
                 });
}

// The same traversal as SolveSprings (chunks, even zones, odd zones, far runs): every spring
// adds to its two particles' forces from one thread, in a fixed order.
void ClothSolver::AccumulateSpringForces(const ClothState& state) {
  const Float3* x = state.positions.data();
  const Float3* v = state.velocities.data();
  Float3* forces = forces_.data();
  const int64_t n = static_cast<int64_t>(forces_.size());
  ParallelFor(n, kParticleGrain, [&](int64_t i) { forces[i] = Float3{}; });
  const auto group_forces = [&](const SpringGroup& group) {
    for (uint32_t r = group.run_begin; r < group.run_end; ++r)
      AccumulateRun(runs_[r], false, x, v, forces);
  };
  ForEachGroupInPhases(chunk_groups_, even_zones_, odd_zones_, group_forces);
  for (uint32_t r = far_runs_.run_begin; r < far_runs_.run_end; ++r)
    AccumulateRun(runs_[r], true, x, v, forces);
}

void ClothSolver::AccumulateRun(const SpringRun& run, bool shared, const Float3* x, const Float3* v,
                                Float3* forces) const {
  const SpringBlock* blocks = blocks_.data();
  const SpringMaterial& m = cloth_->material(run.kind);
  switch (SideOf(run.kind, settings_.buckling)) {
    case SpringSide::kBoth:
      AccumulateRunLanes<SpringSide::kBoth>(blocks, run, shared, m.stiffness, m.damping, x, v,
                                            forces);
      break;
    case SpringSide::kStretched:
      AccumulateRunLanes<SpringSide::kStretched>(blocks, run, shared, m.stiffness, m.damping, x, v,
                                                 forces);
      break;
    case SpringSide::kCompressed:
      AccumulateRunLanes<SpringSide::kCompressed>(blocks, run, shared, m.stiffness, m.damping, x, v,
                                                  forces);
      break;
  }
}

// External forces: gravity, plus damping and fluid drag treated implicitly (a per-particle rate
// r = damping + drag * area / m, v' = (v + h (g + a_spring + r_drag * wind)) / (1 + h r)), which
// is unconditionally stable for any rate; the spring forces of explicit Euler stay explicit
// (paper A eq. 1).
// A carried rotation adds the centrifugal acceleration w x (r x w) (r from the root's position;
// scaled by the carried share and centrifugal_inertia).
void ClothSolver::Integrate(ClothState* state, const Substep& sub, const RootMotion& root) {
  const Cloth& cloth = *cloth_;
  const float* inverse_mass = cloth.inverse_masses().data();
  const float* area = cloth.areas().data();
  Float3* x = state->positions.data();
  Float3* x_start = state->previous_positions.data();
  Float3* v = state->velocities.data();
  const Float3* forces = forces_.data();
  const bool verlet = settings_.integrator == ClothIntegrator::kVerlet;
  const Float3 g = settings_.gravity;
  const Float3 wind = settings_.wind;
  const float h = sub.h;
  const float damping = settings_.damping;
  const float drag = settings_.drag;
  const bool centrifugal = root.centrifugal;
  const Float3 omega = root.omega;
  const Float3 pivot = Lerp(root.pivot0, root.pivot1, sub.s0);
  const float centrifugal_scale = (1.f - settings_.angular_inertia) * settings_.centrifugal_inertia;
  const int64_t n = static_cast<int64_t>(state->positions.size());
  // Verlet: the spring solver's copy too (SolveSprings works on it), in the same pass.
  Particle4* p = verlet ? solver_positions_.data() : nullptr;
  // Without drag (the rate is +0 for every particle: areas and inverse masses are >= 0) nor
  // centrifugal term, a particle's acceleration and damping factor are the same for all: computed
  // once, with the same operations (the same bits).
  const bool uniform = verlet && drag == 0.f && !centrifugal;
  const Float3 uniform_step = (g + wind * 0.f) * h;
  const float uniform_factor = 1.f / (1.f + h * (damping + 0.f));
  ParallelFor(n, kParticleGrain, [&](int64_t i) {
    const Float3 xi = x[i];
    x_start[i] = xi;
    const float w = inverse_mass[i];
    if (w == 0.f) {  // pinned or attached: moved by the caller or ApplyAttachments
      if (p != nullptr) p[i] = Particle4{xi.x, xi.y, xi.z, 0.f};
      return;
    }
    if (uniform) {
      const Float3 moved = xi + ((v[i] + uniform_step) * uniform_factor) * h;
      x[i] = moved;
      p[i] = Particle4{moved.x, moved.y, moved.z, 0.f};
      return;
    }
    const float drag_rate = drag * area[i] * w;  // 1/s
    const float rate = damping + drag_rate;
    Float3 a = g + wind * drag_rate;
    if (!verlet) a += forces[i] * w;
    if (centrifugal) a += Cross(Cross(omega, xi - pivot), omega) * centrifugal_scale;
    const Float3 v_new = (v[i] + a * h) * (1.f / (1.f + h * rate));
    // Verlet (paper B eq. 4): x + (x - x_prev) + h^2 a, with x - x_prev = h v; the velocity is
    // re-estimated from positions after the spring correction. Euler: v' and x + h v'.
    if (!verlet) v[i] = v_new;
    const Float3 moved = xi + v_new * h;
    x[i] = moved;
    if (p != nullptr) p[i] = Particle4{moved.x, moved.y, moved.z, 0.f};
  });
}

void ClothSolver::ApplyAttachments(ClothState* state, const ClothFrame& frame, const Substep& sub) {
  const float s = sub.s1;
  Float3* x = state->positions.data();
  Particle4* p =
      settings_.integrator == ClothIntegrator::kVerlet ? solver_positions_.data() : nullptr;
  const auto place = [x, p](uint32_t i, Float3 position) {
    x[i] = position;
    if (p != nullptr) p[i] = Particle4{position.x, position.y, position.z, 0.f};
  };
  const ClothAttachment* attachments = cloth_->attachments().data();
  const int64_t count = static_cast<int64_t>(cloth_->attachments().size());
  ParallelFor(count, kParticleGrain, [&](int64_t k) {
    const ClothAttachment& a = attachments[k];
    const size_t j = static_cast<size_t>(a.joint);
    const Float3 start = TransformPoint(frame.skinning_start[j], a.bind_position);
    const Float3 end = TransformPoint(frame.skinning_end[j], a.bind_position);
    place(a.particle, start * (1.f - s) + end * s);  // exactly `end` at s = 1
  });
  ParallelFor(skin_kinematic_count_, kParticleGrain, [&](int64_t k) {
    place(skin_targets_[k], skin_start_[k] * (1.f - s) + skin_end_[k] * s);
  });
}

// Works on the solver's copy of the positions (16-byte aligned particles for the SSE loads),
// which Integrate and ApplyAttachments write and ConstrainAndUpdateVelocities reads back. Spring
// order: see BuildSpringGroups.
void ClothSolver::SolveSprings() {
  Particle4* p = solver_positions_.data();
  // The iterations, then the strain limit's pass over the stretch springs.
  const bool limit_stretch = settings_.max_stretch < std::numeric_limits<float>::infinity();
  const uint32_t passes = settings_.iterations + (limit_stretch ? 1 : 0);
  for (uint32_t it = 0; it < passes; ++it) {
    const bool limit = it == settings_.iterations;
    ForEachGroupInPhases(chunk_groups_, even_zones_, odd_zones_,
                         [&](const SpringGroup& group) { CorrectGroup(group, limit, p); });
    for (uint32_t r = far_runs_.run_begin; r < far_runs_.run_end; ++r)
      CorrectRun(runs_[r], true, limit, p);
  }
}

void ClothSolver::CorrectGroup(const SpringGroup& group, bool limit, Particle4* p) const {
  for (uint32_t r = group.run_begin; r < group.run_end; ++r) CorrectRun(runs_[r], false, limit, p);
}

// One run of springs of one kind: sequentially on the calling thread, or shared among the
// workers.
void ClothSolver::CorrectRun(const SpringRun& run, bool shared, bool limit, Particle4* p) const {
  const SpringBlock* blocks = blocks_.data();
  detail::SpringCorrection c;
  c.set = UsableInstructionSet(settings_.instruction_set);
  SpringSide side = SideOf(run.kind, settings_.buckling);
  if (limit) {
    if (run.kind != SpringKind::kStretch) return;
    c.rest_scale = 1.f + settings_.max_stretch;  // only the stretch beyond it, removed whole
    side = SpringSide::kStretched;
  } else {
    c.fraction = cloth_->material(run.kind).correction;
  }
  shared ? CorrectRunShared(blocks, run, side, c, p)
         : CorrectRunSequential(blocks, run, side, c, p);
}

Status ClothSolver::Collide(ClothState* state, const ClothColliders& colliders, const Substep& sub,
                            ClothStepStats* stats) {
  merge_flags_ = 0;
  if (colliders.hulls == nullptr && colliders.body_map == nullptr && colliders.shapes == nullptr) {
    std::memset(flags_.data(), 0, flags_.size());
    return Status::Ok();
  }
  // Colliders see every particle; RestoreKinematic undoes what they do to kinematic ones.
  const std::span<const uint32_t> kinematic = cloth_->kinematic_particles();
  for (size_t k = 0; k < kinematic.size(); ++k) {
    kinematic_positions_[k] = state->positions[kinematic[k]];
    kinematic_velocities_[k] = state->velocities[kinematic[k]];
  }
  restore_kinematic_ = true;
  const std::span<const Float3> x_start = state->previous_positions;
  // The first collider that runs writes flags_, the others their own flags (merged after).
  bool first = true;
  if (colliders.hulls != nullptr) {
    if (Status s = colliders.hulls->SelectSubstep(sub.s0, sub.s1); !s.ok()) return s;
    uint32_t contacts = 0;
    if (Status s =
            colliders.hulls->CollideBatch(x_start, state->positions, state->velocities, flags_,
                                          colliders.response, sub.s0, sub.s1, &contacts);
        !s.ok())
      return s;
    stats->hull_contacts += contacts;
    first = false;
  }
  if (colliders.body_map != nullptr) {
    if (!first) merge_flags_ |= 1;
    uint32_t contacts = 0;
    if (Status s = colliders.body_map->CollideBatch(x_start, state->positions, state->velocities,
                                                    first ? flags_ : body_map_flags_,
                                                    colliders.response, &contacts);
        !s.ok())
      return s;
    stats->body_map_contacts += contacts;
    first = false;
  }
  if (colliders.shapes != nullptr) {
    if (!first) merge_flags_ |= 2;
    uint32_t contacts = 0;
    if (Status s = colliders.shapes->CollideBatch(x_start, state->positions, state->velocities,
                                                  first ? flags_ : shape_flags_, colliders.response,
                                                  sub.s0, sub.s1, sub.h, &contacts);
        !s.ok())
      return s;
    stats->shape_contacts += contacts;
  }
  return Status::Ok();
}

}  // namespace drape

// ClothSolver: resting contact with both integrators, attachments, relative simulation, long runs
// against a moving collider, body maps and hulls together, NaN handling, rejected settings, and
// determinism across thread counts and kernels.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "cloth_fixtures.h"
#include "drape/formats/body_map_data.h"
#include "drape/formats/hull_collider_data.h"
#include "drape/runtime/body_map_collider.h"
#include "drape/runtime/cloth.h"
#include "drape/runtime/cloth_solver.h"
#include "drape/runtime/garments.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"
#include "workers.h"

namespace drape {
namespace {

// Seconds at the start of frame `step`.
float Time(int step, float dt) { return static_cast<float>(step) * dt; }

// Rotation about +y by `angle` radians, then translation t.
Mat34 RotationY(float angle, Float3 t) {
  Mat34 m = TranslationMatrix(t);
  const float c = std::cos(angle), s = std::sin(angle);
  m.m[0] = c;
  m.m[2] = s;
  m.m[8] = -s;
  m.m[10] = c;
  return m;
}

// One joint sphere on joint 0: with skinning = TranslationMatrix(t) its centre is center + t.
void BuildSphere(Float3 center, float radius, HullColliderSet* set) {
  JointSphereData sphere;
  sphere.joint = 0;
  sphere.center = center;
  sphere.radius = radius;
  ASSERT_TRUE(set->Build({}, std::span<const JointSphereData>(&sphere, 1), 1).ok());
}

double KineticEnergy(const Cloth& cloth, const ClothState& state) {
  double energy = 0.0;
  for (uint32_t i = 0; i < cloth.particle_count(); ++i) {
    if (cloth.inverse_masses()[i] == 0.f) continue;
    const Float3 v = state.velocities[i];
    energy += 0.5 * cloth.masses()[i] * (double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
  }
  return energy;
}

// Deepest penetration (metres, <= 0 when every particle is outside) of the dynamic particles.
float MaxPenetration(const Cloth& cloth, const ClothState& state, Float3 center, float radius) {
  float deepest = -std::numeric_limits<float>::infinity();
  for (uint32_t i = 0; i < cloth.particle_count(); ++i) {
    if (cloth.inverse_masses()[i] == 0.f) continue;
    deepest = std::max(deepest, radius - Length(state.positions[i] - center));
  }
  return deepest;
}

bool AllFinite(const ClothState& state) {
  for (size_t i = 0; i < state.positions.size(); ++i)
    if (!IsFinite(state.positions[i]) || !IsFinite(state.velocities[i])) return false;
  return true;
}

// max over stretch springs of L / R - 1, every spring evaluated.
float MaxStretch(const Cloth& cloth, const ClothState& state) {
  float worst = -1.f;
  for (const SpringColour& colour : cloth.colours()) {
    if (colour.kind != SpringKind::kStretch) continue;
    for (uint32_t k = colour.begin; k < colour.end; ++k) {
      const ClothSpring& s = cloth.springs()[k];
      const Float3 d = state.positions[s.b] - state.positions[s.a];
      worst = std::max(worst, std::sqrt(Dot(d, d)) / s.rest_length - 1.f);
    }
  }
  return worst;
}

using test::SheetDescription;

// The physics tests run on one OpenMP thread: the small cloths here gain nothing from a second
// one, and on a loaded 2-core CI machine spinning OpenMP barriers would dominate the run time.
// ThreadCountDoesNotChangeResults sets the thread count itself.
class SingleThreadEnvironment : public ::testing::Environment {
 public:
  void SetUp() override { test::UseWorkers(1); }
};
[[maybe_unused]] const ::testing::Environment* const kSingleThread =
    ::testing::AddGlobalTestEnvironment(new SingleThreadEnvironment);

// Skinning matrices of a one-joint skeleton for one frame.
struct OneJointFrame {
  Mat34 start, end;
  ClothFrame Frame(float dt) const {
    ClothFrame f;
    f.dt = dt;
    f.skinning_start = std::span<const Mat34>(&start, 1);
    f.skinning_end = std::span<const Mat34>(&end, 1);
    return f;
  }
};

// ---- Resting contact -------------------------------------------------------------------------

struct IntegratorCase {
  const char* name;
  ClothIntegrator integrator;
};

class SheetOnSphere : public ::testing::TestWithParam<IntegratorCase> {};

// A 30x30 sheet (1 m, 0.15 kg) dropped from 0.15 m above a 0.3 m sphere drapes over it and comes
// to rest: after 5 s its kinetic energy is below 1e-4 of the potential energy of the drop
// (m g 0.15 m = 0.22 J; measured: about 1e-5 of it for Euler, 1e-6 for Verlet), and no particle
// is inside the sphere by more than 1 mm after any step.
// Separation is 0 here: with a separation s > 0 every contact lifts a particle by s against the
// cloth's tension, which then pulls it back: a chatter of amplitude s (0.1 mm by default) whose
// kinetic energy (about 5e-5 J here) would hide whether the cloth itself has come to rest.
// Friction is 1 and damping 2/s: paper A's friction only scales the tangential velocity at a
// contact, it has no static part, so with less the cloth keeps creeping on the slope and the
// buckling model's wrinkles keep snapping through (kinetic energy spikes near 1e-4 J). Even with
// friction 1 Verlet creeps: each substep's spring correction moves contact particles
// tangentially and nothing undoes the displacement (about 2 mm/s here, hence the 3 cm bound on
// the middle particle's horizontal position).
TEST_P(SheetOnSphere, ComesToRest) {
  const Float3 center{0.f, 0.f, 0.f};
  const float radius = 0.3f;
  HullColliderSet hulls;
  BuildSphere(center, radius, &hulls);
  Cloth cloth;
  ASSERT_TRUE(BuildCloth(SheetDescription(30, 1.f, {0.f, 0.45f, 0.f}), &cloth).ok());
  const float dt = 1.f / 60.f;
  ClothSolverSettings settings = ClothSolverSettings::PaperB();
  settings.substeps = 4;
  if (GetParam().integrator == ClothIntegrator::kExplicitEuler) {
    settings = ClothSolverSettings::PaperA(RecommendedEulerSubsteps(cloth, dt, 2.f));
    EXPECT_GT(settings.substeps, 10u);  // 200 N/m springs on 0.16 g particles
  }
  settings.damping = 2.f;
  ClothSolver solver;
  ASSERT_TRUE(solver.Init(cloth, settings).ok());
  ClothState state;
  state.Reset(cloth);
  ClothColliders colliders;
  colliders.hulls = &hulls;
  colliders.response.friction = 1.f;
  colliders.response.separation = 0.f;
  const OneJointFrame joint;
  float deepest = -1.f;
  ClothStepStats stats;
  for (int step = 0; step < 300; ++step) {
    ASSERT_TRUE(solver.Step(&state, colliders, joint.Frame(dt), &stats).ok()) << "step " << step;
    deepest = std::max(deepest, MaxPenetration(cloth, state, center, radius));
  }
  const double drop_energy = cloth.total_mass() * 9.81 * 0.15;
  EXPECT_LT(KineticEnergy(cloth, state), 1e-4 * drop_energy);
  EXPECT_LE(deepest, 1e-3f);
  EXPECT_GT(stats.contacts, 100u);  // the cap over the sphere's top
  EXPECT_EQ(stats.substeps, settings.substeps);
  EXPECT_GT(stats.hull_contacts, 100u * settings.substeps);
  EXPECT_LT(stats.max_stretch, 0.15f);
  EXPECT_EQ(stats.max_stretch, MaxStretch(cloth, state));  // the same formula, all springs
  // The middle particle sits on the top of the sphere; the corners hang below its centre.
  const Float3 middle = state.positions[15 * 31 + 15];
  EXPECT_NEAR(middle.y, radius, 1e-3f);
  EXPECT_NEAR(middle.x, 0.f, 3e-2f);
  EXPECT_NEAR(middle.z, 0.f, 3e-2f);
  EXPECT_LT(state.positions[0].y, 0.f);
  EXPECT_LT(state.positions[30 * 31 + 30].y, 0.f);
}

INSTANTIATE_TEST_SUITE_P(Integrators, SheetOnSphere,
                         ::testing::Values(IntegratorCase{"verlet", ClothIntegrator::kVerlet},
                                           IntegratorCase{"euler",
                                                          ClothIntegrator::kExplicitEuler}),
                         [](const auto& param_info) { return std::string(param_info.param.name); });

// ---- Attachments -----------------------------------------------------------------------------

// A cape whose top row is attached to joint 0 while the joint swings about y and travels.
// Attached particles are exactly at skinning_end * bind_position after every step, even the ones
// inside a collider (a neck sphere on the same joint encloses the middle of the top row). The
// rest of the cape trails: no particle is farther from its column's attached particle than its
// rest distance plus the measured stretch bound, and after the joint stops the cape hangs under
// its attachment.
TEST(ClothSolver, CapeFollowsMovingJoint) {
  CapeShape shape;
  shape.top_center = {0.f, 1.5f, -0.15f};
  shape.top_width = 0.4f;
  shape.bottom_width = 0.6f;
  shape.length = 0.8f;
  shape.columns = 16;
  shape.rows = 24;
  GarmentMesh mesh;
  ASSERT_TRUE(MakeCape(shape, &mesh).ok());
  ClothDescription d = DescribeAttachedGarment(mesh, 0);
  Cloth cloth;
  ASSERT_TRUE(BuildCloth(d, &cloth).ok());
  EXPECT_EQ(cloth.kinematic_particles().size(), 17u);
  EXPECT_EQ(cloth.required_joint_count(), 1u);

  HullColliderSet hulls;
  const Float3 neck{0.f, 1.5f, -0.15f};
  const float neck_radius = 0.06f;
  BuildSphere(neck, neck_radius, &hulls);
  uint32_t attached_inside = 0;
  for (const uint32_t p : mesh.held)
    attached_inside += Length(mesh.positions[p] - neck) < neck_radius;
  ASSERT_GE(attached_inside, 3u);

  ClothSolverSettings settings = ClothSolverSettings::PaperB();
  settings.substeps = 4;
  settings.damping = 0.5f;
  ClothSolver solver;
  ASSERT_TRUE(solver.Init(cloth, settings).ok());
  ClothState state;
  state.Reset(cloth);
  ClothColliders colliders;
  colliders.hulls = &hulls;
  // Paper A's friction: the cape slides off the neck sphere to hang straight (Coulomb's static
  // friction may hold it a few cm aside).
  colliders.response.friction_model = FrictionModel::kPaperA;

  const float dt = 1.f / 60.f;
  const auto pose = [](float t) {
    const float moving = std::min(t, 2.f);  // the joint stops at t = 2 s
    const float angle = 0.6f * std::sin(2.f * std::numbers::pi_v<float> * 0.5f * moving);
    return RotationY(angle,
                     {0.3f * std::sin(2.f * std::numbers::pi_v<float> * 0.7f * moving),
                      0.1f * std::sin(2.f * std::numbers::pi_v<float> * moving), 0.5f * moving});
  };
  const uint32_t stride = shape.columns + 1;
  // Distance to the column's attached particle / rest distance, after allowing for the neck
  // sphere, which can push a particle up to its radius off the straight line.
  float worst_ratio = 0.f;
  for (int step = 0; step < 300; ++step) {
    OneJointFrame joint{pose(Time(step, dt)), pose(Time(step + 1, dt))};
    ASSERT_TRUE(solver.Step(&state, colliders, joint.Frame(dt)).ok()) << "step " << step;
    for (const ClothAttachment& a : cloth.attachments()) {
      const Float3 target = TransformPoint(joint.end, a.bind_position);
      ASSERT_EQ(std::memcmp(&state.positions[a.particle], &target, sizeof(Float3)), 0)
          << "attached particle " << a.particle << " step " << step;
    }
    for (uint32_t j = 1; j <= shape.rows; ++j) {
      for (uint32_t i = 0; i < stride; ++i) {
        const uint32_t p = j * stride + i;
        const float rest = Length(mesh.positions[p] - mesh.positions[i]);
        const float distance = Length(state.positions[p] - state.positions[i]);
        worst_ratio = std::max(worst_ratio, (distance - neck_radius) / rest);
      }
    }
  }
  // Verlet with 3 iterations and 4 substeps stretches the 24-spring columns under the joint's
  // accelerations (up to about 5 m/s^2 here) by about 3 %; 10 % is the bound.
  EXPECT_LT(worst_ratio, 1.1f);
  // Three seconds after the joint stopped, the bottom-middle particle hangs below the top-middle
  // one (the frame is rotated by the final angle; the cape hangs along -y).
  const Float3 top = state.positions[shape.columns / 2];
  const Float3 bottom = state.positions[shape.rows * stride + shape.columns / 2];
  EXPECT_NEAR(bottom.x, top.x, 0.03f);
  EXPECT_NEAR(bottom.z, top.z, 0.03f);
  EXPECT_LT(bottom.y, top.y - 0.75f);
}

// Relative simulation: a cape attached to the root joint, which runs at 3 m/s along +z against
// still air (drag 1 kg/(m^2 s)). Without relative simulation the air blows the cape back (the
// drag force 3 N/m^2 is twice its weight 1.5 N/m^2: a trailing angle near 60 degrees); with it
// the root's translation is invisible to the cloth, which hangs straight down.
TEST(ClothSolver, RelativeSimulationRemovesRootTranslation) {
  CapeShape shape;
  shape.top_center = {0.f, 1.5f, -0.15f};
  shape.columns = 8;
  shape.rows = 12;
  shape.length = 0.6f;
  GarmentMesh mesh;
  ASSERT_TRUE(MakeCape(shape, &mesh).ok());
  ClothDescription d = DescribeAttachedGarment(mesh, 0);
  Cloth cloth;
  ASSERT_TRUE(BuildCloth(d, &cloth).ok());
  const float dt = 1.f / 60.f;
  float offsets[2] = {0.f, 0.f};
  for (int relative = 0; relative < 2; ++relative) {
    ClothSolverSettings settings = ClothSolverSettings::PaperB();
    settings.substeps = 2;
    settings.drag = 1.f;
    settings.root_joint = relative ? 0 : -1;
    settings.root_bind_position = {0.f, 1.f, 0.f};
    settings.linear_inertia = relative ? 0.f : 1.f;
    ClothSolver solver;
    ASSERT_TRUE(solver.Init(cloth, settings).ok());
    ClothState state;
    state.Reset(cloth);
    for (int step = 0; step < 120; ++step) {
      OneJointFrame joint{TranslationMatrix({0.f, 0.f, 3.f * Time(step, dt)}),
                          TranslationMatrix({0.f, 0.f, 3.f * Time(step + 1, dt)})};
      ASSERT_TRUE(solver.Step(&state, ClothColliders{}, joint.Frame(dt)).ok());
    }
    const Float3 top = state.positions[shape.columns / 2];
    const Float3 bottom = state.positions[shape.rows * (shape.columns + 1) + shape.columns / 2];
    offsets[relative] = bottom.z - top.z;
    EXPECT_NEAR(top.z, 6.f - 0.15f, 1e-4f);
  }
  EXPECT_LT(offsets[0], -0.3f) << "the cape should trail without relative simulation";
  EXPECT_NEAR(offsets[1], 0.f, 0.005f) << "the cape should hang straight with it";
}

// ---- Long runs -------------------------------------------------------------------------------

class MovingSphereLongRun : public ::testing::TestWithParam<float> {};

// A hanging sheet pinned along its top edge and a 0.2 m sphere sweeping back and forth through
// its plane (peak speed 1.13 m/s) for 10 s at the given frame length, paper B's settings (one
// substep, three iterations): every step succeeds, stays finite, leaves no particle more than
// 1 mm inside the sphere at the end of the step, keeps every particle within 2 m, and keeps the
// kinetic energy below that of the whole cloth moving at twice the sphere's peak speed (the
// measured peak is about half that bound at 1/30 s, a quarter at 1/60 s).
TEST_P(MovingSphereLongRun, StaysBounded) {
  const float dt = GetParam();
  SheetShape shape;
  shape.center = {0.f, 1.f, 0.f};
  shape.axis_v = {0.f, 1.f, 0.f};
  shape.columns = shape.rows = 24;
  GarmentMesh mesh;
  ASSERT_TRUE(MakeSheet(shape, &mesh).ok());
  ClothDescription d;
  d.positions = mesh.positions;
  d.triangles = mesh.triangles;
  d.pinned = mesh.held;
  Cloth cloth;
  ASSERT_TRUE(BuildCloth(d, &cloth).ok());
  const Float3 center{0.f, 0.9f, 0.f};
  const float radius = 0.2f;
  HullColliderSet hulls;
  BuildSphere(center, radius, &hulls);
  ClothSolver solver;
  ASSERT_TRUE(solver.Init(cloth, ClothSolverSettings::PaperB()).ok());
  ClothState state;
  state.Reset(cloth);
  ClothColliders colliders;
  colliders.hulls = &hulls;
  const float omega = 2.f * std::numbers::pi_v<float> * 0.4f;
  const float amplitude = 0.45f;
  const auto offset = [&](float t) { return Float3{0.f, 0.f, amplitude * std::sin(omega * t)}; };
  const double energy_bound = 0.5 * cloth.total_mass() * std::pow(2.0 * amplitude * omega, 2.0);
  double max_energy = 0.0;
  float deepest = -1.f;
  uint32_t contact_steps = 0;
  const int steps = static_cast<int>(std::lround(10.f / dt));
  for (int step = 0; step < steps; ++step) {
    OneJointFrame joint{TranslationMatrix(offset(Time(step, dt))),
                        TranslationMatrix(offset(Time(step + 1, dt)))};
    ClothStepStats stats;
    ASSERT_TRUE(solver.Step(&state, colliders, joint.Frame(dt), &stats).ok()) << "step " << step;
    ASSERT_TRUE(AllFinite(state)) << "step " << step;
    const Float3 c = center + offset(Time(step + 1, dt));
    deepest = std::max(deepest, MaxPenetration(cloth, state, c, radius));
    max_energy = std::max(max_energy, KineticEnergy(cloth, state));
    contact_steps += stats.contacts > 0;
    for (const Float3& p : state.positions) ASSERT_LT(Length(p - shape.center), 2.f);
  }
  EXPECT_LE(deepest, 1e-3f);
  EXPECT_LT(max_energy, energy_bound);
  EXPECT_GT(contact_steps, static_cast<uint32_t>(steps / 4));  // the sphere does push the sheet
}

INSTANTIATE_TEST_SUITE_P(FrameLengths, MovingSphereLongRun,
                         ::testing::Values(1.f / 60.f, 1.f / 30.f), [](const auto& param_info) {
                           return param_info.param < 0.02f ? std::string("dt_1_60")
                                                           : std::string("dt_1_30");
                         });

// ---- Body maps -------------------------------------------------------------------------------

// A 0.6 x 0.6 x 0.1 m slab as paper A's front and back maps (64 x 64 texels over [-0.5, 0.5]^2),
// with a joint sphere beside it: a sheet falling along -z (the maps' view axis) lands on the slab
// and on the sphere. Both colliders report contacts and no particle ends a step more than 1 mm
// inside either. (The depth is measured in the box of the covered texels: a particle that slid
// off the slab's edge can be left on a texel side wall, which IsInside counts as inside.)
TEST(ClothSolver, BodyMapAndHullsTogether) {
  BodyMapPose pose;
  pose.width = pose.height = 64;
  pose.origin_x = pose.origin_y = -0.5f;
  pose.texel_size = 1.f / 64.f;
  pose.front_z = 0.5f;
  pose.depth_range = 1.f;
  const size_t texels = 64 * 64;
  for (int view = 0; view < 2; ++view) {
    pose.depth_f32[view].assign(texels, 2.f);  // background
    pose.normal_f32[view].assign(texels * 3, 0.f);
  }
  for (uint32_t j = 0; j < 64; ++j) {
    for (uint32_t i = 0; i < 64; ++i) {
      const float x = pose.origin_x + (static_cast<float>(i) + 0.5f) * pose.texel_size;
      const float y = pose.origin_y + (static_cast<float>(j) + 0.5f) * pose.texel_size;
      if (std::fabs(x) > 0.3f || std::fabs(y) > 0.3f) continue;
      const size_t t = j * 64 + i;
      pose.depth_f32[0][t] = pose.front_z - 0.05f;                        // top at z = 0.05
      pose.depth_f32[1][t] = -0.05f - (pose.front_z - pose.depth_range);  // bottom at z = -0.05
      pose.normal_f32[0][3 * t + 2] = 1.f;
      pose.normal_f32[1][3 * t + 2] = -1.f;
    }
  }
  BodyMapCollider body_map;
  ASSERT_TRUE(body_map.Build(pose).ok());
  const float kSlabHalf = 0.5f - 13.f / 64.f;  // texel edges of the covered texels
  HullColliderSet hulls;
  const Float3 sphere_center{0.45f, 0.45f, -0.05f};
  BuildSphere(sphere_center, 0.1f, &hulls);

  SheetShape shape;
  shape.center = {0.f, 0.f, 0.2f};
  shape.axis_v = {0.f, 1.f, 0.f};
  shape.width = shape.height = 1.2f;
  shape.columns = shape.rows = 24;
  GarmentMesh mesh;
  ASSERT_TRUE(MakeSheet(shape, &mesh).ok());
  ClothDescription d;
  d.positions = mesh.positions;
  d.triangles = mesh.triangles;
  Cloth cloth;
  ASSERT_TRUE(BuildCloth(d, &cloth).ok());
  ClothSolverSettings settings = ClothSolverSettings::PaperB();
  settings.substeps = 2;
  settings.gravity = {0.f, 0.f, -9.81f};
  ClothSolver solver;
  ASSERT_TRUE(solver.Init(cloth, settings).ok());
  ClothState state;
  state.Reset(cloth);
  ClothColliders colliders;
  colliders.hulls = &hulls;
  colliders.body_map = &body_map;
  const OneJointFrame joint;
  uint32_t hull_contacts = 0, map_contacts = 0;
  for (int step = 0; step < 90; ++step) {
    ClothStepStats stats;
    ASSERT_TRUE(solver.Step(&state, colliders, joint.Frame(1.f / 60.f), &stats).ok());
    hull_contacts += stats.hull_contacts;
    map_contacts += stats.body_map_contacts;
    for (uint32_t i = 0; i < cloth.particle_count(); ++i) {
      // Depth inside the box the maps hold: texels 13..50 in x and y, z in [-0.05, 0.05].
      const Float3 p = state.positions[i];
      const float depth = std::min({p.x + kSlabHalf, kSlabHalf - p.x, p.y + kSlabHalf,
                                    kSlabHalf - p.y, p.z + 0.05f, 0.05f - p.z});
      ASSERT_LE(depth, 1e-3f) << "particle " << i << " step " << step;
      ASSERT_GE(Length(state.positions[i] - sphere_center), 0.1f - 1e-3f);
    }
  }
  EXPECT_GT(hull_contacts, 0u);
  EXPECT_GT(map_contacts, 0u);
  // The merged flags of the last substep mark particles on the slab.
  const uint32_t middle = 12 * 25 + 12;
  EXPECT_NE(solver.contact_flags()[middle] & kCollisionContact, 0);
  EXPECT_NEAR(state.positions[middle].z, 0.05f, 2e-3f);
}

// ---- Invalid states --------------------------------------------------------------------------

// Settings that carry the particles with a moving root (inertia below 1) or not, and a joint
// that moves 5 cm along x over each frame: the state's backup must then hold the positions before
// the carry.
ClothSolverSettings Carried(ClothSolverSettings s, bool carry) {
  if (carry) {
    s.root_joint = 0;
    s.linear_inertia = 0.5f;
  }
  return s;
}
OneJointFrame MovingJoint() {
  OneJointFrame joint;
  joint.end.m[3] = 0.05f;
  return joint;
}

// A 21 x 21 sheet's solver, carried by the root or not, and its state at rest.
struct CarriedSheet {
  Cloth cloth;
  ClothSolver solver;
  ClothState state;
  explicit CarriedSheet(bool carry) {
    EXPECT_TRUE(BuildCloth(SheetDescription(20, 1.f, {0.f, 0.f, 0.f}), &cloth).ok());
    EXPECT_TRUE(solver.Init(cloth, Carried(ClothSolverSettings::PaperB(), carry)).ok());
    state.Reset(cloth);
  }
};

// Positions, velocities and previous positions, bit for bit.
void ExpectSameState(const ClothState& actual, const ClothState& expected) {
  const size_t bytes = expected.positions.size() * sizeof(Float3);
  EXPECT_EQ(std::memcmp(actual.positions.data(), expected.positions.data(), bytes), 0);
  EXPECT_EQ(std::memcmp(actual.velocities.data(), expected.velocities.data(), bytes), 0);
  EXPECT_EQ(
      std::memcmp(actual.previous_positions.data(), expected.previous_positions.data(), bytes), 0);
}

// Colliders whose skeleton the frame does not cover (a hull set of three joints, one matrix): the
// step fails before anything moves, with the particles carried by the root too.
TEST(ClothSolver, CollidersThatTheFrameCannotPoseLeaveTheStateAlone) {
  for (const bool carry : {false, true}) {
    SCOPED_TRACE(carry ? "carried by the root" : "world");
    CarriedSheet sheet(carry);
    sheet.state.velocities[7] = {0.f, 0.5f, 0.f};
    JointSphereData sphere;
    sphere.joint = 2;
    sphere.radius = 0.1f;
    HullColliderSet hulls;
    ASSERT_TRUE(hulls.Build({}, std::span<const JointSphereData>(&sphere, 1), 3).ok());
    ClothColliders colliders;
    colliders.hulls = &hulls;
    const ClothState before = sheet.state;
    const Status status =
        sheet.solver.Step(&sheet.state, colliders, MovingJoint().Frame(1.f / 60.f));
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << status.message();
    ExpectSameState(sheet.state, before);
  }
}

// A NaN in the input state is reported (kInvalidState, naming the particle) and nothing moves.
TEST(ClothSolver, NanInputIsReportedAndNotPropagated) {
  for (const bool carry : {false, true}) {
    SCOPED_TRACE(carry ? "carried by the root" : "world");
    CarriedSheet sheet(carry);
    ClothSolver& solver = sheet.solver;
    ClothState& state = sheet.state;
    const OneJointFrame joint = MovingJoint();
    for (int step = 0; step < 5; ++step)
      ASSERT_TRUE(solver.Step(&state, ClothColliders{}, joint.Frame(1.f / 60.f)).ok());

    for (int which = 0; which < 2; ++which) {
      ClothState bad = state;
      const uint32_t particle = which == 0 ? 123 : 45;
      if (which == 0) {
        bad.positions[particle].y = std::numeric_limits<float>::quiet_NaN();
      } else {
        bad.velocities[particle].z = std::numeric_limits<float>::infinity();
      }
      const ClothState before = bad;
      const Status status = solver.Step(&bad, ClothColliders{}, joint.Frame(1.f / 60.f));
      EXPECT_EQ(status.code(), StatusCode::kInvalidState);
      EXPECT_NE(status.message().find("particle " + std::to_string(particle)), std::string::npos)
          << status.message();
      ExpectSameState(bad, before);
    }
  }
}

// Explicit Euler far beyond its stability bound (1e4 N/m springs, one substep at 60 Hz against
// a bound near 0.1 ms) blows up. The blow-up is reported as kInvalidState naming a particle, and
// the state is the one before the failing step (the last valid substep), finite.
TEST(ClothSolver, BlowUpIsReportedAndStateKept) {
  for (const bool carry : {false, true}) {
    SCOPED_TRACE(carry ? "carried by the root" : "world");
    ClothDescription d = SheetDescription(10, 1.f, {0.f, 0.f, 0.f});
    d.stretch.stiffness = 1e4f;
    d.pinned = {0};
    Cloth cloth;
    ASSERT_TRUE(BuildCloth(d, &cloth).ok());
    EXPECT_LT(cloth.MaxStableEulerStep(), 1e-3f);
    ClothSolver solver;
    ASSERT_TRUE(solver.Init(cloth, Carried(ClothSolverSettings::PaperA(1), carry)).ok());
    ClothState state;
    state.Reset(cloth);
    state.velocities[60] = {0.f, 1.f, 0.f};  // a kick to start the unstable modes
    const OneJointFrame joint = MovingJoint();
    Status status;
    int step = 0;
    ClothState before;
    for (; step < 200; ++step) {
      before = state;
      status = solver.Step(&state, ClothColliders{}, joint.Frame(1.f / 60.f));
      if (!status.ok()) break;
    }
    ASSERT_LT(step, 200) << "explicit Euler was expected to blow up";
    EXPECT_EQ(status.code(), StatusCode::kInvalidState);
    EXPECT_NE(status.message().find("particle "), std::string::npos) << status.message();
    EXPECT_TRUE(AllFinite(state));
    const size_t bytes = state.positions.size() * sizeof(Float3);
    EXPECT_EQ(std::memcmp(state.positions.data(), before.positions.data(), bytes), 0);
    EXPECT_EQ(std::memcmp(state.velocities.data(), before.velocities.data(), bytes), 0);
    EXPECT_EQ(std::memcmp(state.previous_positions.data(), state.positions.data(), bytes), 0);
  }
}

TEST(ClothSolver, RejectsBadFramesAndSettings) {
  ClothDescription d = SheetDescription(4, 1.f, {0.f, 0.f, 0.f});
  d.attachments.push_back({0, 2, d.positions[0]});  // joint 2: needs three matrices
  Cloth cloth;
  ASSERT_TRUE(BuildCloth(d, &cloth).ok());
  EXPECT_EQ(cloth.required_joint_count(), 3u);
  ClothSolver solver;
  ClothState state;
  state.Reset(cloth);
  const OneJointFrame joint;
  EXPECT_EQ(solver.Step(&state, ClothColliders{}, joint.Frame(0.01f)).code(),
            StatusCode::kInvalidArgument);  // not initialised
  ClothSolverSettings bad = ClothSolverSettings::PaperB();
  bad.substeps = 0;
  EXPECT_EQ(solver.Init(cloth, bad).code(), StatusCode::kInvalidArgument);
  bad = ClothSolverSettings::PaperB();
  bad.damping = -1.f;
  EXPECT_EQ(solver.Init(cloth, bad).code(), StatusCode::kInvalidArgument);
  ASSERT_TRUE(solver.Init(cloth, ClothSolverSettings::PaperB()).ok());
  EXPECT_EQ(solver.Step(&state, ClothColliders{}, joint.Frame(0.01f)).code(),
            StatusCode::kInvalidArgument);  // one matrix for joint 2
  const Mat34 three[3];
  ClothFrame frame;
  frame.skinning_start = three;
  frame.skinning_end = three;
  frame.dt = 0.f;
  EXPECT_EQ(solver.Step(&state, ClothColliders{}, frame).code(), StatusCode::kInvalidArgument);
  frame.dt = 0.01f;
  ClothColliders colliders;
  colliders.response.friction = 2.f;
  EXPECT_EQ(solver.Step(&state, colliders, frame).code(), StatusCode::kInvalidArgument);
  ClothState wrong_size = state;
  wrong_size.velocities.pop_back();
  EXPECT_EQ(solver.Step(&wrong_size, ClothColliders{}, frame).code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(solver.Step(&state, ClothColliders{}, frame).ok());
}

// ---- Determinism -----------------------------------------------------------------------------

// Runs `frames` frames of a 72 x 72 sheet (5184 particles, above every parallel threshold of the
// solver) falling onto a sphere that rises, with wind and drag, under the given task system.
ClothState RunSheetScene(const Cloth& cloth, const ClothSolverSettings& settings,
                         const test::TaskSystemCase& tasks, int frames,
                         uint32_t* contacts = nullptr) {
  tasks.Use();
  HullColliderSet hulls;
  BuildSphere({0.f, 0.f, 0.f}, 0.3f, &hulls);
  ClothSolver solver;
  EXPECT_TRUE(solver.Init(cloth, settings).ok());
  ClothState state;
  state.Reset(cloth);
  ClothColliders colliders;
  colliders.hulls = &hulls;
  for (int step = 0; step < frames; ++step) {
    OneJointFrame joint{TranslationMatrix({0.f, Time(step, 0.002f), 0.f}),
                        TranslationMatrix({0.f, Time(step + 1, 0.002f), 0.f})};
    ClothStepStats stats;
    const Status s = solver.Step(&state, colliders, joint.Frame(1.f / 60.f), &stats);
    EXPECT_TRUE(s.ok()) << s.message();
    if (contacts != nullptr) *contacts += stats.hull_contacts;
  }
  test::UseWorkers(1);
  return state;
}

void ExpectBitwiseEqual(const ClothState& a, const ClothState& b) {
  ASSERT_EQ(a.positions.size(), b.positions.size());
  const size_t bytes = a.positions.size() * sizeof(Float3);
  EXPECT_EQ(std::memcmp(a.positions.data(), b.positions.data(), bytes), 0);
  EXPECT_EQ(std::memcmp(a.velocities.data(), b.velocities.data(), bytes), 0);
  EXPECT_EQ(std::memcmp(a.previous_positions.data(), b.previous_positions.data(), bytes), 0);
}

// The same scene serially, on the std::thread pool at 2 and 4 workers and on OpenMP's team
// gives bitwise identical states, for both integrators (explicit Euler on a heavier sheet so that
// few substeps are stable).
TEST(ClothSolver, TaskSystemDoesNotChangeResults) {
  const std::vector<test::TaskSystemCase> systems = test::AllTaskSystems();
  const test::TaskSystemCase& serial = systems.front();
  const auto expect_same_under_every_system = [&](const Cloth& c, const ClothSolverSettings& s,
                                                  int frames, const ClothState& reference) {
    for (size_t k = 1; k < systems.size(); ++k) {
      SCOPED_TRACE(systems[k].name);
      ExpectBitwiseEqual(reference, RunSheetScene(c, s, systems[k], frames));
    }
  };
  ClothDescription d = SheetDescription(71, 1.2f, {0.f, 0.33f, 0.f});
  Cloth cloth;
  ASSERT_TRUE(BuildCloth(d, &cloth).ok());
  ASSERT_GT(cloth.particle_count(), 4096u);
  ClothSolverSettings verlet = ClothSolverSettings::PaperB();
  verlet.substeps = 2;
  verlet.drag = 0.5f;
  verlet.wind = {1.f, 0.f, 0.f};
  uint32_t contacts = 0;
  const ClothState one = RunSheetScene(cloth, verlet, serial, 6, &contacts);
  EXPECT_GT(contacts, 100u);  // the sheet reached the sphere
  expect_same_under_every_system(cloth, verlet, 6, one);

  // The same sheet with its particles numbered in a shuffled order (a fixed permutation): most
  // springs are then "far" (between distant index chunks) and take the coloured path.
  ClothDescription shuffled = d;
  std::vector<uint32_t> order(d.positions.size());
  for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  uint64_t random = 12345;
  for (size_t i = order.size() - 1; i > 0; --i) {
    random = random * 6364136223846793005ull + 1442695040888963407ull;
    std::swap(order[i], order[(random >> 33) % (i + 1)]);
  }
  for (uint32_t i = 0; i < order.size(); ++i) shuffled.positions[order[i]] = d.positions[i];
  for (uint32_t& t : shuffled.triangles) t = order[t];
  Cloth shuffled_cloth;
  ASSERT_TRUE(BuildCloth(shuffled, &shuffled_cloth).ok());
  contacts = 0;
  const ClothState shuffled_one = RunSheetScene(shuffled_cloth, verlet, serial, 6, &contacts);
  EXPECT_GT(contacts, 100u);
  expect_same_under_every_system(shuffled_cloth, verlet, 6, shuffled_one);

  d = SheetDescription(71, 1.2f, {0.f, 0.305f, 0.f});
  d.density = 3.f;
  d.stretch.stiffness = 50.f;
  Cloth heavy;
  ASSERT_TRUE(BuildCloth(d, &heavy).ok());
  ClothSolverSettings euler =
      ClothSolverSettings::PaperA(RecommendedEulerSubsteps(heavy, 1.f / 60.f, 0.1f));
  EXPECT_LE(euler.substeps, 32u);
  euler.drag = 0.5f;
  euler.wind = {1.f, 0.f, 0.f};
  contacts = 0;
  const ClothState euler_one = RunSheetScene(heavy, euler, serial, 2, &contacts);
  EXPECT_GT(contacts, 100u);
  expect_same_under_every_system(heavy, euler, 2, euler_one);
}

// The spring kernel in SSE2 and in the scalar reference pack gives the same bits, with and without
// the buckling model.
TEST(ClothSolver, SimdAndScalarKernelsAgree) {
  Cloth cloth;
  ASSERT_TRUE(BuildCloth(SheetDescription(71, 1.2f, {0.f, 0.45f, 0.f}), &cloth).ok());
  ClothSolverSettings buckling = ClothSolverSettings::PaperB();
  buckling.buckling = true;
  // Paper B, its buckling variant (stretch-only and compress-only sides) and the engine defaults
  // (the strain limit's pass); AVX2 (where the CPU has it: two blocks at a time) and SSE2.
  for (ClothSolverSettings settings :
       {ClothSolverSettings::PaperB(), buckling, ClothSolverSettings{}}) {
    settings.instruction_set = InstructionSet::kScalar;
    const ClothState scalar = RunSheetScene(cloth, settings, test::AllTaskSystems().front(), 20);
    for (const InstructionSet set : {InstructionSet::kAvx2, InstructionSet::kSse2}) {
      SCOPED_TRACE(static_cast<int>(set));
      settings.instruction_set = set;
      ExpectBitwiseEqual(scalar,
                         RunSheetScene(cloth, settings, test::AllTaskSystems().front(), 20));
    }
  }
}

// The stretch measure, the stage timing and the blow-up guard (backup and finite check) change
// no result: off or on, the same bits.
TEST(ClothSolver, MeasuresAndGuardsAreOptionalAndChangeNothing) {
  ClothDescription hung = SheetDescription(71, 1.2f, {0.f, 0.45f, 0.f});
  hung.pinned = {0};  // held by a corner: the sheet stretches as it falls
  Cloth cloth;
  ASSERT_TRUE(BuildCloth(hung, &cloth).ok());
  ClothSolverSettings measured;
  measured.measure_stages = true;
  ClothSolverSettings unmeasured;
  unmeasured.measure_stretch = false;
  unmeasured.guard_blowups = false;
  const test::TaskSystemCase serial = test::AllTaskSystems().front();
  ExpectBitwiseEqual(RunSheetScene(cloth, measured, serial, 5),
                     RunSheetScene(cloth, unmeasured, serial, 5));
  ClothSolver solver;
  ASSERT_TRUE(solver.Init(cloth, unmeasured).ok());
  ClothState state;
  state.Reset(cloth);
  ClothFrame frame;
  ClothStepStats stats;
  ASSERT_TRUE(solver.Step(&state, ClothColliders{}, frame, &stats).ok());
  EXPECT_EQ(stats.max_stretch, 0.f);
  EXPECT_EQ(stats.stage_seconds.springs, 0.0);
  ASSERT_TRUE(solver.SetSettings(measured).ok());
  ASSERT_TRUE(solver.Step(&state, ClothColliders{}, frame, &stats).ok());
  EXPECT_GT(stats.max_stretch, 0.f);  // a falling sheet stretches a little
  EXPECT_GT(stats.stage_seconds.springs, 0.0);
  EXPECT_GE(stats.stage_seconds.integrate, 0.0);
}

}  // namespace
}  // namespace drape

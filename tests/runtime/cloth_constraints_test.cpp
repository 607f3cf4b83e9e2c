// What an engine's cloth is expected to do beyond the papers: long-range tethers and a strain
// limit, skinned garments with max distance and backstop, teleport, reset and inertia relative to
// the character's root, and a Step that allocates nothing with all of it on.

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>
#include <numbers>
#include <vector>

#include "cloth_fixtures.h"
#include "walking_legs.h"
#include "workers.h"

#include "drape/runtime/cloth.h"
#include "drape/runtime/cloth_solver.h"
#include "drape/runtime/garments.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"
#include "drape/runtime/shape_collider_set.h"

// Every allocation of the program is counted, so a test can assert that a call makes none. (GCC
// sees free() on memory from the replaced operator new and warns; the pair is malloc/free.)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
namespace {
std::atomic<uint64_t> g_allocations{0};
}  // namespace
void* operator new(size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }

namespace drape {
namespace {

using test::kJoints;
using test::WalkPose;
constexpr float kFrame = 1.f / 60.f;
float At(int frame) { return static_cast<float>(frame) * kFrame; }  // seconds

// The 0.8 m skirt on the walking legs, its waistband attached to the hips.
struct WalkingScene {
  test::WalkingLegs legs = test::MakeWalkingLegs();
  HullColliderSet hulls;
  Cloth cloth;

  WalkingScene() {
    EXPECT_TRUE(hulls.Build(legs.boxes, legs.spheres, kJoints).ok());
    GarmentMesh mesh;
    EXPECT_TRUE(MakeSkirt(test::WalkingSkirt(0.8f, 48, 40), &mesh).ok());
    EXPECT_TRUE(BuildCloth(DescribeAttachedGarment(mesh, 0), &cloth).ok());
  }
};

// Runs `frames` walking frames from frame `first`; returns the worst stretch over them.
float Walk(ClothSolver* solver, ClothState* state, ClothColliders colliders, int first, int frames,
           const Mat34& place = Mat34{}) {
  Mat34 start[kJoints], end[kJoints];
  ClothFrame frame;
  frame.dt = kFrame;
  frame.skinning_start = start;
  frame.skinning_end = end;
  float worst = 0.f;
  for (int f = first; f < first + frames; ++f) {
    WalkPose(static_cast<float>(f) * kFrame, start);
    WalkPose(static_cast<float>(f + 1) * kFrame, end);
    for (int j = 0; j < kJoints; ++j) {
      start[j] = Multiply(place, start[j]);
      end[j] = Multiply(place, end[j]);
    }
    ClothStepStats stats;
    const Status s = solver->Step(state, colliders, frame, &stats);
    EXPECT_TRUE(s.ok()) << s.message();
    worst = std::max(worst, stats.max_stretch);
  }
  return worst;
}

TEST(Tethers, AreGeodesicToTheNearestHeldParticle) {
  // A 1 m sheet held by its top row: a particle's tether runs to the held particle straight
  // above it (the shortest path over the grid's edges), its length the rows between them.
  ClothDescription d = test::SheetDescription(10, 1.f, {0.f, 0.f, 0.f});
  for (uint32_t c = 0; c <= 10; ++c) d.pinned.push_back(c);  // row 0 (z = -0.5)
  d.tether_stretch = 0.05f;
  Cloth cloth;
  ASSERT_TRUE(BuildCloth(d, &cloth).ok());
  EXPECT_EQ(cloth.tethers().size(), 110u);
  EXPECT_EQ(cloth.build_report().untethered_particles, 0u);
  for (const ClothTether& t : cloth.tethers()) {
    const Float3 p = d.positions[t.particle], a = d.positions[t.anchor];
    EXPECT_LT(t.anchor, 11u);
    EXPECT_FLOAT_EQ(a.x, p.x) << "particle " << t.particle;
    EXPECT_NEAR(t.length, std::abs(p.z - a.z) * 1.05f, 1e-5f);
  }
  // Without a held particle nothing is tethered; a piece with no path is counted.
  d.pinned.clear();
  d.attachments.clear();
  d.masses.clear();
  ASSERT_TRUE(BuildCloth(d, &cloth).ok());
  EXPECT_TRUE(cloth.tethers().empty());
  EXPECT_EQ(cloth.build_report().untethered_particles, 121u);
  d.tether_stretch = -1.f;
  EXPECT_FALSE(BuildCloth(d, &cloth).ok());
}

TEST(Tethers, HoldTheWalkingSkirtNearItsRestLengthAtOneSubstep) {
  // 1 substep x 5 iterations, the solver alone (what tethers and the strain limit act on): paper
  // B's solver lets the 0.8 m skirt's springs stretch several times their length (the waistband
  // holds 40 rings that 5 Gauss-Seidel passes cannot reach); with tethers and the strain limit
  // the worst spring stays below 50 % over two seconds of walking and no particle is ever
  // farther from its anchor than its tether.
  ClothSolverSettings settings;  // the engine defaults: tethers and a 10 % strain limit
  settings.iterations = 5;
  settings.substeps = 1;
  settings.damping = 0.2f;
  ClothSolverSettings papers = settings;
  papers.tethers = false;
  papers.max_stretch = std::numeric_limits<float>::infinity();
  WalkingScene scene;
  {
    ClothSolver solver;
    ASSERT_TRUE(solver.Init(scene.cloth, papers).ok());
    ClothState state;
    state.Reset(scene.cloth);
    EXPECT_GT(Walk(&solver, &state, {}, 0, 120), 2.f);
  }
  ClothSolver solver;
  ASSERT_TRUE(solver.Init(scene.cloth, settings).ok());
  ClothState state;
  state.Reset(scene.cloth);
  float worst = 0.f, beyond_tether = 0.f;
  for (int f = 0; f < 120; ++f) {
    worst = std::max(worst, Walk(&solver, &state, {}, f, 1));
    for (const ClothTether& t : scene.cloth.tethers())
      beyond_tether =
          std::max(beyond_tether,
                   Length(state.positions[t.particle] - state.positions[t.anchor]) - t.length);
  }
  EXPECT_LT(worst, 0.5f);
  EXPECT_LE(beyond_tether, 1e-5f);
}

// Stretch springs longer than `allowed` times their rest length.
uint32_t CountLongerThan(const Cloth& cloth, const ClothState& state, float allowed) {
  uint32_t count = 0;
  for (uint32_t k = 0; k < cloth.spring_count(SpringKind::kStretch); ++k) {
    const ClothSpring& s = cloth.springs()[k];
    count += Length(state.positions[s.b] - state.positions[s.a]) > allowed * s.rest_length;
  }
  return count;
}

TEST(StretchMeasure, CountsTheSpringsBeyondTheStrainLimit) {
  // The walking skirt on the legs, where the colliders hold springs beyond the limit: the step's
  // count is the springs longer than R (1 + max_stretch), to within the rounding margin, or
  // beyond 10 % under paper B (no limit); nothing when the measure is off.
  WalkingScene scene;
  ClothColliders colliders;
  colliders.hulls = &scene.hulls;
  for (const float limit : {0.1f, 0.25f, std::numeric_limits<float>::infinity()}) {
    ClothSolverSettings settings;
    settings.max_stretch = limit;
    ClothSolver solver;
    ASSERT_TRUE(solver.Init(scene.cloth, settings).ok());
    ClothState state;
    state.Reset(scene.cloth);
    Walk(&solver, &state, colliders, 0, 30);
    Mat34 start[kJoints], end[kJoints];
    WalkPose(At(30), start);
    WalkPose(At(31), end);
    ClothStepStats stats;
    ASSERT_TRUE(solver.Step(&state, colliders, {kFrame, start, end}, &stats).ok());
    const float allowed = 1.f + (std::isinf(limit) ? 0.1f : limit);
    EXPECT_GT(stats.overstretched_springs, 0u) << "limit " << limit;
    EXPECT_LE(stats.overstretched_springs, CountLongerThan(scene.cloth, state, allowed));
    EXPECT_GE(stats.overstretched_springs,
              CountLongerThan(scene.cloth, state, allowed * (1.f + 1e-4f)));
    settings.measure_stretch = false;
    ASSERT_TRUE(solver.SetSettings(settings).ok());
    ASSERT_TRUE(solver.Step(&state, colliders, {kFrame, start, end}, &stats).ok());
    EXPECT_EQ(stats.overstretched_springs, 0u);
    EXPECT_EQ(stats.max_stretch, 0.f);
  }
}

// A 1 m horizontal sheet skinned to joint 0 (weight 1), its winding facing up; the joint swings.
struct SkinnedSheet {
  ClothDescription description = test::SheetDescription(16, 1.f, {0.f, 1.f, 0.f});
  Cloth cloth;
  SkinnedSheet(float max_distance, float backstop) {
    ClothDescription& d = description;
    d.skin.assign(d.positions.size(), ClothSkinWeights{});
    for (ClothSkinWeights& w : d.skin) w.weights[0] = 1.f;
    d.max_distance.assign(d.positions.size(), max_distance);
    d.backstop.assign(d.positions.size(), backstop);
    for (uint32_t c = 0; c <= 16; ++c) d.max_distance[c] = 0.f;  // the held row: kinematic
    // Face the triangles up (+y) whatever the fixture's winding.
    for (size_t t = 0; t < d.triangles.size(); t += 3) {
      const Float3 a = d.positions[d.triangles[t]], b = d.positions[d.triangles[t + 1]],
                   c = d.positions[d.triangles[t + 2]];
      if (Cross(b - a, c - a).y < 0.f) std::swap(d.triangles[t + 1], d.triangles[t + 2]);
    }
  }
};

Mat34 Swing(float t) {
  const float angle = 0.6f * std::sin(2.f * std::numbers::pi_v<float> * t);
  Mat34 m = test::RotateXAbout(angle, {0.f, 1.f, -0.5f});
  m.m[3] += 0.3f * t;
  return m;
}

// Frame f of the swing of joint 0 (holds the matrices the frame points to).
struct SwingFrame {
  Mat34 start[1], end[1];
  ClothFrame frame;
  explicit SwingFrame(int f) : start{Swing(At(f))}, end{Swing(At(f + 1))} {
    frame.skinning_start = start;
    frame.skinning_end = end;
  }
};

TEST(SkinnedGarment, StaysWithinMaxDistanceAndOutsideItsBackstop) {
  SkinnedSheet sheet(0.05f, 0.01f);
  ASSERT_TRUE(BuildCloth(sheet.description, &sheet.cloth).ok());
  EXPECT_TRUE(sheet.cloth.skinned());
  EXPECT_EQ(sheet.cloth.constrained_particles().size(), 17u * 16u);
  ClothSolver solver;
  ASSERT_TRUE(solver.Init(sheet.cloth, ClothSolverSettings{}).ok());
  ClothState state;
  state.Reset(sheet.cloth);
  const std::span<const Float3> rest = sheet.cloth.rest_positions();
  float worst_distance = 0.f, worst_behind = 0.f;
  for (int f = 0; f < 120; ++f) {
    const SwingFrame swing(f);
    const Mat34* end = swing.end;
    ASSERT_TRUE(solver.Step(&state, {}, swing.frame).ok());
    const Float3 normal = TransformVector(end[0], {0.f, 1.f, 0.f});
    for (size_t i = 17; i < rest.size(); ++i) {
      const Float3 skinned = TransformPoint(end[0], rest[i]);
      worst_distance = std::max(worst_distance, Length(state.positions[i] - skinned));
      worst_behind = std::max(worst_behind, -Dot(state.positions[i] - skinned, normal));
    }
    for (uint32_t c = 0; c <= 16; ++c)  // max distance 0: exactly the skinned position
      ASSERT_EQ(Length(state.positions[c] - TransformPoint(end[0], rest[c])), 0.f);
  }
  EXPECT_LE(worst_distance, 0.05f + 1e-5f);
  EXPECT_LE(worst_behind, 0.01f + 1e-5f);
  EXPECT_GT(worst_behind, 0.009f);  // gravity pushed it onto the backstop: the bound was active
}

TEST(SkinnedGarment, MaxDistanceZeroIsAnAttachment) {
  // The held row skinned with max distance 0 and the same row attached to joint 0: the same bits.
  SkinnedSheet skinned(std::numeric_limits<float>::infinity(),
                       std::numeric_limits<float>::infinity());
  ClothDescription attached = test::SheetDescription(16, 1.f, {0.f, 1.f, 0.f});
  attached.triangles = skinned.description.triangles;
  for (uint32_t c = 0; c <= 16; ++c) attached.attachments.push_back({c, 0, attached.positions[c]});
  Cloth a, b;
  ASSERT_TRUE(BuildCloth(attached, &a).ok());
  ASSERT_TRUE(BuildCloth(skinned.description, &b).ok());
  ClothSolver sa, sb;
  ASSERT_TRUE(sa.Init(a, ClothSolverSettings{}).ok());
  ASSERT_TRUE(sb.Init(b, ClothSolverSettings{}).ok());
  ClothState xa, xb;
  xa.Reset(a);
  xb.Reset(b);
  for (int f = 0; f < 60; ++f) {
    const SwingFrame swing(f);
    ASSERT_TRUE(sa.Step(&xa, {}, swing.frame).ok());
    ASSERT_TRUE(sb.Step(&xb, {}, swing.frame).ok());
  }
  for (size_t i = 0; i < xa.positions.size(); ++i) {
    ASSERT_EQ(xa.positions[i].x, xb.positions[i].x) << i;
    ASSERT_EQ(xa.positions[i].y, xb.positions[i].y) << i;
    ASSERT_EQ(xa.positions[i].z, xb.positions[i].z) << i;
  }
}

TEST(SkinnedGarment, RejectsBadWeightsAndDistances) {
  SkinnedSheet sheet(0.05f, 0.01f);
  Cloth cloth;
  ClothDescription d = sheet.description;
  d.skin[3].weights[0] = 0.f;
  EXPECT_NE(BuildCloth(d, &cloth).message().find("skin[3]"), std::string::npos);
  d = sheet.description;
  d.max_distance[5] = std::nanf("");
  EXPECT_NE(BuildCloth(d, &cloth).message().find("max_distance[5]"), std::string::npos);
  d = sheet.description;
  d.backstop.pop_back();
  EXPECT_NE(BuildCloth(d, &cloth).message().find("backstop"), std::string::npos);
  d = sheet.description;
  d.skin.clear();
  EXPECT_NE(BuildCloth(d, &cloth).message().find("need skin weights"), std::string::npos);
}

// A rigid place: a turn of `degrees` about +y and a translation.
Mat34 Place(float degrees, Float3 offset) {
  const float a = degrees * std::numbers::pi_v<float> / 180.f;
  Mat34 m;
  const float c = degrees == 90.f ? 0.f : std::cos(a), s = degrees == 90.f ? 1.f : std::sin(a);
  m.m[0] = c;
  m.m[2] = s;
  m.m[8] = -s;
  m.m[10] = c;
  m.m[3] = offset.x;
  m.m[7] = offset.y;
  m.m[11] = offset.z;
  return m;
}

// The worst distance, in the character's frame, between a walk and the same walk teleported by
// `place` after `before` frames, `after` frames later.
float TeleportError(const Mat34& place, bool with_colliders, int before, int after) {
  ClothSolverSettings settings;
  settings.iterations = 5;
  WalkingScene scene_a, scene_b;
  ClothSolver a, b;
  EXPECT_TRUE(a.Init(scene_a.cloth, settings).ok());
  EXPECT_TRUE(b.Init(scene_b.cloth, settings).ok());
  ClothState xa, xb;
  xa.Reset(scene_a.cloth);
  xb.Reset(scene_b.cloth);
  ClothColliders ca, cb;
  if (with_colliders) {
    ca.hulls = &scene_a.hulls;
    cb.hulls = &scene_b.hulls;
  }
  Walk(&a, &xa, ca, 0, before);
  Walk(&b, &xb, cb, 0, before);
  EXPECT_TRUE(b.Teleport(&xb, place).ok());
  Walk(&a, &xa, ca, before, after);
  Walk(&b, &xb, cb, before, after, place);
  const Mat34 back = InverseRigid(place);
  float worst = 0.f;
  for (size_t i = 0; i < xa.positions.size(); ++i)
    worst = std::max(worst, Length(TransformPoint(back, xb.positions[i]) - xa.positions[i]));
  return worst;
}

TEST(Teleport, GivesTheSameStateInTheCharactersFrame) {
  // The character (and the cloth) jump 100 m and turn 90 degrees after half a second of walking.
  const Mat34 place = Place(90.f, {100.f, 0.f, -100.f});
  // At the jump the state is the same within the float spacing at 100 m (7.6 um); a frame later
  // within 30 of them. (From there the two runs' different rounding grows like any two runs'
  // of a skirt in contact: ~0.1 m after 30 frames; see the inertia test.)
  EXPECT_LE(TeleportError(place, true, 30, 0), 1e-5f);
  EXPECT_LE(TeleportError(place, true, 30, 1), 2e-4f);
  EXPECT_LE(TeleportError(place, false, 30, 1), 1e-4f);
  ClothSolver solver;
  WalkingScene scene;
  ASSERT_TRUE(solver.Init(scene.cloth, ClothSolverSettings{}).ok());
  ClothState state;
  state.Reset(scene.cloth);
  Mat34 scaled = place;
  scaled.m[0] = 2.f;
  EXPECT_FALSE(solver.Teleport(&state, scaled).ok());
}

TEST(Reset, PutsTheSkirtOnTheBodyWithNoParticleInside) {
  // Mid-stride the legs cut through the rest-shaped skirt; Reset places it and pushes it out.
  WalkingScene scene;
  ClothSolverSettings settings;
  settings.root_joint = 0;
  ClothSolver solver;
  ASSERT_TRUE(solver.Init(scene.cloth, settings).ok());
  Mat34 pose[kJoints];
  WalkPose(0.25f, pose);  // the thighs at their widest swing
  ClothState state;
  state.Reset(scene.cloth);
  ASSERT_GT(test::MeasurePenetration(scene.legs, pose, state.positions).inside, 0u);
  ClothColliders colliders;
  colliders.hulls = &scene.hulls;
  ASSERT_TRUE(solver.Reset(&state, colliders, pose).ok());
  const test::Penetration after = test::MeasurePenetration(scene.legs, pose, state.positions);
  EXPECT_EQ(after.inside, 0u) << "deepest " << after.max_depth;
  for (const Float3& v : state.velocities) ASSERT_EQ(Length(v), 0.f);
}

// The skirt hanging from a root that runs along +z at 3 m/s and turns about +y.
struct RootRun {
  ClothDescription description;
  Cloth cloth;
  RootRun() {
    GarmentMesh mesh;
    EXPECT_TRUE(MakeSkirt(test::WalkingSkirt(0.6f, 32, 16), &mesh).ok());
    description = DescribeAttachedGarment(mesh, 0);
    EXPECT_TRUE(BuildCloth(description, &cloth).ok());
  }
  // Positions in the root's frame after `frames` frames.
  std::vector<Float3> Run(ClothSolverSettings settings, float speed, float turn_rate,
                          int frames) const {
    settings.root_joint = 0;
    settings.root_bind_position = {0.f, test::kHipY, 0.f};
    ClothSolver solver;
    EXPECT_TRUE(solver.Init(cloth, settings).ok());
    ClothState state;
    state.Reset(cloth);
    const auto root = [&](int f) {
      const float t = static_cast<float>(f) * kFrame;
      Mat34 m = Place(turn_rate * t, {0.f, 0.f, speed * t});
      return m;
    };
    for (int f = 0; f < frames; ++f) {
      Mat34 start[1] = {root(f)}, end[1] = {root(f + 1)};
      ClothFrame frame;
      frame.skinning_start = start;
      frame.skinning_end = end;
      EXPECT_TRUE(solver.Step(&state, {}, frame).ok());
    }
    const Mat34 back = InverseRigid(root(frames));
    std::vector<Float3> local;
    for (const Float3& p : state.positions) local.push_back(TransformPoint(back, p));
    return local;
  }
};

float WorstDifference(const std::vector<Float3>& a, const std::vector<Float3>& b) {
  float worst = 0.f;
  for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, Length(a[i] - b[i]));
  return worst;
}

// Mean distance of the hem (the last ring) from the skirt's axis.
float HemRadius(const std::vector<Float3>& local, uint32_t segments) {
  float sum = 0.f;
  for (size_t i = local.size() - segments; i < local.size(); ++i)
    sum += std::hypot(local[i].x, local[i].z);
  return sum / static_cast<float>(segments);
}

TEST(Inertia, ZeroCarriesTheClothWithTheRootAndOneIsTheWorld) {
  RootRun run;
  ClothSolverSettings world;
  const std::vector<Float3> still = run.Run(world, 0.f, 0.f, 60);
  // Inertia 1 with a root is the world simulation, bit for bit.
  ClothSolverSettings rooted = world;
  ClothSolver plain, with_root;
  ASSERT_TRUE(plain.Init(run.cloth, world).ok());
  rooted.root_joint = 0;
  ASSERT_TRUE(with_root.Init(run.cloth, rooted).ok());
  ClothState xa, xb;
  xa.Reset(run.cloth);
  xb.Reset(run.cloth);
  for (int f = 0; f < 30; ++f) {
    Mat34 start[1] = {Place(40.f * At(f), {0.f, 0.f, 2.f * At(f)})};
    Mat34 end[1] = {Place(40.f * At(f + 1), {0.f, 0.f, 2.f * At(f + 1)})};
    ClothFrame frame;
    frame.skinning_start = start;
    frame.skinning_end = end;
    ASSERT_TRUE(plain.Step(&xa, {}, frame).ok());
    ASSERT_TRUE(with_root.Step(&xb, {}, frame).ok());
  }
  EXPECT_EQ(WorstDifference(xa.positions, xb.positions), 0.f);
  // Running at 3 m/s in the world the skirt trails; with linear inertia 0 it hangs as if still.
  // (Compared over 5 frames: the skirt's folds amplify float rounding ~e-fold every 7 frames, so
  // two runs of any different rounding drift apart by a millimetre after a second.)
  const std::vector<Float3> still5 = run.Run(world, 0.f, 0.f, 5);
  ClothSolverSettings carried = world;
  carried.linear_inertia = 0.f;
  EXPECT_GT(WorstDifference(run.Run(world, 3.f, 0.f, 5), still5), 1e-3f);
  EXPECT_LT(WorstDifference(run.Run(carried, 3.f, 0.f, 5), still5), 1e-5f);
  // Turning at 180 degrees/s, carried with angular inertia 0: without the centrifugal push the
  // skirt hangs as if still; with it the hem flares out.
  carried.angular_inertia = 0.f;
  carried.centrifugal_inertia = 0.f;
  EXPECT_GT(WorstDifference(run.Run(world, 3.f, 180.f, 5), still5), 1e-3f);
  EXPECT_LT(WorstDifference(run.Run(carried, 3.f, 180.f, 5), still5), 1e-5f);
  carried.centrifugal_inertia = 1.f;
  EXPECT_GT(HemRadius(run.Run(carried, 3.f, 180.f, 60), 32), HemRadius(still, 32) + 0.02f);
  // Inertia below 1 needs a root; out of range is rejected.
  ClothSolver solver;
  ClothSolverSettings bad = world;
  bad.linear_inertia = 0.5f;
  EXPECT_FALSE(solver.Init(run.cloth, bad).ok());
  bad.root_joint = 0;
  bad.angular_inertia = 1.5f;
  EXPECT_FALSE(solver.Init(run.cloth, bad).ok());
}

TEST(ClothSolverAllocations, StepAllocatesNothingWithEveryFeatureOn) {
  WalkingScene scene;
  SkinnedSheet sheet(0.05f, 0.01f);
  ASSERT_TRUE(BuildCloth(sheet.description, &sheet.cloth).ok());
  ClothSolverSettings settings;
  settings.root_joint = 0;
  settings.linear_inertia = 0.5f;
  settings.angular_inertia = 0.5f;
  settings.substeps = 2;
  ClothSolver skirt, skinned;
  ASSERT_TRUE(skirt.Init(scene.cloth, settings).ok());
  ASSERT_TRUE(skinned.Init(sheet.cloth, settings).ok());
  ClothState xs, xk;
  xs.Reset(scene.cloth);
  xk.Reset(sheet.cloth);
  ClothColliders colliders;
  colliders.hulls = &scene.hulls;
  ShapeColliderSet shapes;  // a floor and a capsule the engine moves, re-posed every frame
  shapes.Reserve(2, 0);
  colliders.shapes = &shapes;
  Mat34 start[kJoints], end[kJoints];
  ClothFrame frame;
  frame.skinning_start = start;
  frame.skinning_end = end;
  const auto step = [&](int f) {
    WalkPose(At(f), start);
    WalkPose(At(f + 1), end);
    shapes.Clear();
    ASSERT_TRUE(shapes.AddPlane(Mat34{}, Mat34{}).ok());
    ASSERT_TRUE(shapes
                    .AddCapsule(Place(0.f, {0.f, 0.5f, At(f)}), Place(0.f, {0.f, 0.5f, At(f + 1)}),
                                0.2f, 0.05f, 0.03f)
                    .ok());
    ASSERT_TRUE(skirt.Step(&xs, colliders, frame).ok());
    ASSERT_TRUE(skinned.Step(&xk, colliders, frame).ok());
  };
  for (int threads : {1, 2}) {
    test::UseWorkers(threads);
    step(0);  // the thread pool starts
    const uint64_t before = g_allocations.load();
    for (int f = 1; f < 10; ++f) step(f);
    EXPECT_EQ(g_allocations.load(), before) << threads << " threads";
  }
}

// A plane through the origin tilted by `degrees` about +z (its normal turned from +y towards -x).
Mat34 Slope(float degrees) {
  const float a = degrees * std::numbers::pi_v<float> / 180.f;
  Mat34 m;
  m.m[0] = std::cos(a);
  m.m[1] = -std::sin(a);
  m.m[4] = std::sin(a);
  m.m[5] = std::cos(a);
  return m;
}

// A free 0.5 m sheet (no held particle) dropped from 5 cm onto a plane tilted by `degrees`;
// returns the mean speed (m/s) of the particles along the slope over the last second of four.
float SheetOnSlope(float degrees, float static_friction, float friction, float* lowest,
                   FrictionModel model = FrictionModel::kCoulomb) {
  ClothDescription d = test::SheetDescription(20, 0.5f, {0.f, 0.f, 0.f});
  const Mat34 slope = Slope(degrees);
  for (Float3& p : d.positions) p = TransformPoint(slope, p + Float3{0.f, 0.05f, 0.f});
  Cloth cloth;
  EXPECT_TRUE(BuildCloth(d, &cloth).ok());
  ClothSolver solver;
  EXPECT_TRUE(solver.Init(cloth, ClothSolverSettings{}).ok());
  ClothState state;
  state.Reset(cloth);
  ShapeColliderSet shapes;
  shapes.Reserve(1, 0);
  EXPECT_TRUE(shapes.AddPlane(slope, slope).ok());
  ClothColliders colliders;
  colliders.shapes = &shapes;
  colliders.response.static_friction = static_friction;
  colliders.response.friction = friction;
  colliders.response.friction_model = model;
  const Float3 normal = TransformVector(slope, {0.f, 1.f, 0.f});
  *lowest = std::numeric_limits<float>::infinity();
  Float3 centre_at_3s;
  for (int f = 0; f < 240; ++f) {
    ClothFrame frame;
    EXPECT_TRUE(solver.Step(&state, colliders, frame).ok());
    for (const Float3& p : state.positions) *lowest = std::min(*lowest, Dot(p, normal));
    if (f == 179) {
      for (const Float3& p : state.positions) centre_at_3s += p;
    }
  }
  Float3 centre;
  for (const Float3& p : state.positions) centre += p;
  const float n = static_cast<float>(state.positions.size());
  return Length(centre * (1.f / n) - centre_at_3s * (1.f / n));  // metres over the last second
}

TEST(EngineShapes, SheetRestsOnAFloorAndStaysOnAGentleSlope) {
  float lowest = 0.f;
  // Flat floor: no particle below it after any step.
  SheetOnSlope(0.f, 0.5f, 0.3f, &lowest);
  EXPECT_GE(lowest, 0.f);
  // 20 degrees, static friction 0.5 (tan 20 = 0.36 < 0.5): it stays (creeps < 0.1 mm/s).
  EXPECT_LT(SheetOnSlope(20.f, 0.5f, 0.3f, &lowest), 1e-4f);
  EXPECT_GE(lowest, 0.f);
  // Static friction 0.2 (< 0.36): it slides; paper A's kinetic-only friction creeps.
  EXPECT_GT(SheetOnSlope(20.f, 0.2f, 0.1f, &lowest), 0.05f);
  EXPECT_GT(SheetOnSlope(20.f, 0.f, 0.3f, &lowest, FrictionModel::kPaperA), 1e-4f);
}

}  // namespace
}  // namespace drape

// drape::ShapeColliderSet: the engine's spheres, tapered capsules, planes, boxes and convexes.
// Each kind: resting contact, tunnelling, sweeping by a moving shape, push-out from inside,
// friction on a slope, the round cone's distance against a brute-force reference, hostile
// inputs, argument validation, thread-count independence and no allocation on re-adding. The
// bake's capsules posed from a skeleton (AddCapsuleColliders) follow their bone.

#include "rigid_poses.h"
#include "workers.h"

#include "drape/runtime/capsule_colliders.h"
#include "drape/runtime/shape_collider_set.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <new>
#include <random>
#include <string>
#include <vector>

#include "drape/runtime/math.h"
#include "shapes/shape_distance.h"

// Counts the global allocations of this test program (the re-adding test reads it). (GCC sees
// free() on memory from the replaced operator new and warns; the pair is malloc/free.)
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
namespace {
std::atomic<uint64_t> g_allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace drape {
namespace {

constexpr float kFrame = 1.f / 60.f;  // seconds
const Float3 kGravity{0.f, -9.81f, 0.f};

double Distance3(Float3 a, Float3 b) {
  const double dx = double(a.x) - b.x, dy = double(a.y) - b.y, dz = double(a.z) - b.z;
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

using test::Pose;

// The shape's signed distance at world point p, the shape posed by `pose`.
double WorldDistance(const detail::LocalShape& shape, const Mat34& pose, Float3 p) {
  return detail::Distance(shape, detail::ToD(TransformPoint(InverseRigid(pose), p))).value;
}

struct Particle {
  Float3 x, v;
  uint8_t flags = 0;
};

Particle CollideOne(const ShapeColliderSet& set, Float3 p0, Float3 p1, Float3 v = {},
                    const ResponseParams& params = {}, float s0 = 0.f, float s1 = 1.f,
                    float seconds = kFrame) {
  Float3 x = p1;
  uint8_t flags = 0xff;
  const Status status = set.CollideBatch(std::span<const Float3>(&p0, 1), std::span<Float3>(&x, 1),
                                         std::span<Float3>(&v, 1), std::span<uint8_t>(&flags, 1),
                                         params, s0, s1, seconds);
  EXPECT_TRUE(status.ok()) << status.message();
  return {x, v, flags};
}

// A convex: the box |x| <= e with one corner chamfered (7 planes, an extra face).
std::vector<Plane> ChamferedBox(Float3 e) {
  std::vector<Plane> planes = {
      {{1, 0, 0}, e.x},  {{-1, 0, 0}, e.x}, {{0, 1, 0}, e.y},
      {{0, -1, 0}, e.y}, {{0, 0, 1}, e.z},  {{0, 0, -1}, e.z},
  };
  const float k = 1.f / std::sqrt(3.f);
  planes.push_back({{k, -k, k}, 0.8f * (e.x + e.y + e.z) * k});
  return planes;
}

// One shape of each kind, the same geometry added to a set and described locally.
struct ShapeCase {
  const char* name;
  std::function<Status(ShapeColliderSet*, const Mat34&, const Mat34&)> add;
  detail::LocalShape local;
};

std::vector<ShapeCase> Cases(const std::vector<Plane>& convex_planes) {
  const Float3 box{0.3f, 0.1f, 0.2f};
  return {
      {"sphere",
       [](ShapeColliderSet* s, const Mat34& a, const Mat34& b) { return s->AddSphere(a, b, 0.2f); },
       detail::SphereShape(0.2f)},
      {"capsule",
       [](ShapeColliderSet* s, const Mat34& a, const Mat34& b) {
         return s->AddCapsule(a, b, 0.25f, 0.12f, 0.07f);
       },
       detail::CapsuleShape(0.25f, 0.12f, 0.07f)},
      {"plane",
       [](ShapeColliderSet* s, const Mat34& a, const Mat34& b) { return s->AddPlane(a, b); },
       detail::PlaneShape()},
      {"box",
       [box](ShapeColliderSet* s, const Mat34& a, const Mat34& b) { return s->AddBox(a, b, box); },
       detail::BoxShape(detail::ToD(box))},
      {"convex",
       [&convex_planes](ShapeColliderSet* s, const Mat34& a, const Mat34& b) {
         return s->AddConvex(a, b, convex_planes);
       },
       detail::ConvexShape(convex_planes.data(), static_cast<uint32_t>(convex_planes.size()), 1.0)},
  };
}

// Frames of gravity integration (x += v h + g h^2, v += g h), then CollideBatch over the frame.
void Simulate(const ShapeColliderSet& set, const ResponseParams& params, int frames,
              std::vector<Float3>* x, std::vector<Float3>* v) {
  std::vector<Float3> previous(x->size());
  std::vector<uint8_t> flags(x->size());
  for (int f = 0; f < frames; ++f) {
    previous = *x;
    for (size_t i = 0; i < x->size(); ++i) {
      (*x)[i] = (*x)[i] + (*v)[i] * kFrame + kGravity * (kFrame * kFrame);
      (*v)[i] = (*v)[i] + kGravity * kFrame;
    }
    ASSERT_TRUE(set.CollideBatch(previous, *x, *v, flags, params, 0.f, 1.f, kFrame).ok());
  }
}

// ---- Tests ----------------------------------------------------------------------------------

TEST(ShapeColliderSetTest, FallingParticleRestsOnEachKind) {
  const std::vector<Plane> convex = ChamferedBox({0.3f, 0.1f, 0.2f});
  const Mat34 pose = Pose({0.1f, 0.2f, -0.1f}, {0.f, 1.f, 0.f}, 30.0);
  const ResponseParams params;
  for (const ShapeCase& c : Cases(convex)) {
    ShapeColliderSet set;
    ASSERT_TRUE(c.add(&set, pose, pose).ok()) << c.name;
    // Above the local origin, 0.6 m over the shape's centre (every top is below 0.25 m).
    std::vector<Float3> x = {TransformPoint(pose, {0.f, 0.6f, 0.f})}, v(1);
    Simulate(set, params, 90, &x, &v);
    const double d = WorldDistance(c.local, pose, x[0]);
    EXPECT_GE(d, params.separation - 1e-6) << c.name;
    EXPECT_LE(d, params.separation + 1e-5) << c.name;
    EXPECT_LT(Length(v[0]), 1e-3f) << c.name;
  }
}

TEST(ShapeColliderSetTest, FastSegmentsThroughThinShapesAreCaught) {
  // 1 m in one substep through 5 mm of box, convex slab, plane, a 1 cm sphere and an 8 mm capsule.
  const Float3 thin{0.2f, 0.0025f, 0.2f};
  const std::vector<Plane> slab = {{{1, 0, 0}, 0.2f},     {{-1, 0, 0}, 0.2f}, {{0, 1, 0}, 0.0025f},
                                   {{0, -1, 0}, 0.0025f}, {{0, 0, 1}, 0.2f},  {{0, 0, -1}, 0.2f}};
  struct Thin {
    const char* name;
    std::function<Status(ShapeColliderSet*)> add;
    detail::LocalShape local;
  };
  const Mat34 id;
  const std::vector<Thin> shapes = {
      {"box", [&](ShapeColliderSet* s) { return s->AddBox(id, id, thin); },
       detail::BoxShape(detail::ToD(thin))},
      {"convex", [&](ShapeColliderSet* s) { return s->AddConvex(id, id, slab); },
       detail::ConvexShape(slab.data(), 6, 1.0)},
      {"plane", [&](ShapeColliderSet* s) { return s->AddPlane(id, id); }, detail::PlaneShape()},
      {"sphere", [&](ShapeColliderSet* s) { return s->AddSphere(id, id, 0.01f); },
       detail::SphereShape(0.01f)},
      {"capsule", [&](ShapeColliderSet* s) { return s->AddCapsule(id, id, 0.1f, 0.004f, 0.004f); },
       detail::CapsuleShape(0.1f, 0.004f, 0.004f)},
      {"tapered capsule",
       [&](ShapeColliderSet* s) { return s->AddCapsule(id, id, 0.1f, 0.006f, 0.002f); },
       detail::CapsuleShape(0.1f, 0.006f, 0.002f)},
  };
  // Straight down, and slanted (both ends outside every shape: the search for the minimum).
  const Float3 starts[2] = {{0.003f, 0.5f, 0.001f}, {-0.2f, 0.45f, 0.0015f}};
  const Float3 ends[2] = {{0.003f, -0.5f, 0.001f}, {0.2f, -0.45f, 0.0005f}};
  for (const Thin& t : shapes) {
    ShapeColliderSet set;
    ASSERT_TRUE(t.add(&set).ok()) << t.name;
    for (int k = 0; k < 2; ++k) {
      const ContactQuery q = set.Query(starts[k], ends[k], 0.f, 1.f);
      EXPECT_TRUE(q.contact) << t.name << " " << k;
      EXPECT_EQ(q.inside_end, std::string(t.name) == "plane") << t.name << " " << k;
      EXPECT_NEAR(q.t, 0.5f, 0.02f) << t.name << " " << k;
      const Particle p = CollideOne(set, starts[k], ends[k]);
      EXPECT_TRUE(p.flags & kCollisionContact) << t.name << " " << k;
      // Moved along the supporting plane at the entry: the resolved motion stays outside.
      EXPECT_FALSE(set.Query(starts[k], p.x, 0.f, 1.f).contact) << t.name << " " << k;
      EXPECT_GE(WorldDistance(t.local, id, p.x), 1e-4 - 1e-6) << t.name << " " << k;
    }
  }
}

TEST(ShapeColliderSetTest, MovingShapesSweepRestingParticles) {
  const ResponseParams params;
  {  // A sphere moving 0.5 m along x in one substep through a particle at rest at the origin.
    ShapeColliderSet set;
    ASSERT_TRUE(set.AddSphere(Pose({-0.3f, 0.f, 0.f}), Pose({0.2f, 0.f, 0.f}), 0.1f).ok());
    const Particle p = CollideOne(set, {}, {}, {}, params);
    EXPECT_TRUE(p.flags & kCollisionContact);
    EXPECT_FALSE(p.flags & kCollisionStartedInside);
    EXPECT_NEAR(p.x.x, 0.3f + params.separation, 1e-6f);
    EXPECT_NEAR(p.v.x, 0.5f / kFrame, 1e-3f);  // carried at the surface's speed
  }
  {  // A tapered capsule moving 0.5 m across its axis, over the second half of the frame.
    ShapeColliderSet set;
    const Mat34 a = Pose({0.f, 0.f, -0.3f}, {0.f, 1.f, 0.f}, 10.0);
    const Mat34 b = Pose({0.f, 0.f, 0.2f}, {0.f, 1.f, 0.f}, 10.0);
    ASSERT_TRUE(set.AddCapsule(a, b, 0.2f, 0.1f, 0.06f).ok());
    const Float3 rest{0.05f, 0.01f, 0.f};
    const Particle p = CollideOne(set, rest, rest, {}, params, 0.f, 0.5f, 0.5f * kFrame);
    EXPECT_TRUE(p.flags & kCollisionContact);
    EXPECT_FALSE(p.flags & kCollisionStartedInside);
    const detail::LocalShape local = detail::CapsuleShape(0.2f, 0.1f, 0.06f);
    EXPECT_GE(WorldDistance(local, set.WorldTransform(0, 0.5f), p.x), params.separation - 1e-6);
    EXPECT_GT(p.v.z, 0.f);
  }
  {  // A slab turning 90 degrees about its centre within the substep.
    ShapeColliderSet set;
    const Float3 e{0.3f, 0.02f, 0.05f};
    const Mat34 b = Pose({}, {0.f, 1.f, 0.f}, 90.0);
    ASSERT_TRUE(set.AddBox(Pose({}), b, e).ok());
    const Float3 rest{0.f, 0.f, 0.2f};
    const Particle p = CollideOne(set, rest, rest, {}, params);
    EXPECT_TRUE(p.flags & kCollisionContact);
    EXPECT_GE(WorldDistance(detail::BoxShape(detail::ToD(e)), b, p.x), params.separation - 1e-6);
  }
}

TEST(ShapeColliderSetTest, ParticlesInsideArePushedToTheNearestSurface) {
  const std::vector<Plane> convex = ChamferedBox({0.3f, 0.1f, 0.2f});
  const Mat34 pose = Pose({0.1f, 0.2f, -0.1f}, {0.3f, 0.8f, 0.52f}, 40.0);
  // Local points inside each case (same order as Cases).
  const Float3 inside[5] = {{0.05f, 0.1f, 0.f},
                            {0.1f, 0.02f, 0.01f},
                            {0.3f, -0.05f, 0.1f},
                            {0.25f, 0.f, 0.05f},
                            {0.f, 0.05f, -0.1f}};
  const ResponseParams params;
  const std::vector<ShapeCase> cases = Cases(convex);
  for (size_t k = 0; k < cases.size(); ++k) {
    ShapeColliderSet set;
    ASSERT_TRUE(cases[k].add(&set, pose, pose).ok());
    const Float3 p = TransformPoint(pose, inside[k]);
    const double depth = -WorldDistance(cases[k].local, pose, p);
    ASSERT_GT(depth, 0.01) << cases[k].name;
    const Particle r = CollideOne(set, p, p, {}, params);
    EXPECT_EQ(r.flags, kCollisionContact | kCollisionStartedInside) << cases[k].name;
    EXPECT_NEAR(WorldDistance(cases[k].local, pose, r.x), params.separation, 1e-6) << cases[k].name;
    EXPECT_NEAR(Distance3(r.x, p), depth + params.separation, 1e-6) << cases[k].name;
    const ContactQuery q = set.Query(p, p, 0.f, 1.f);
    EXPECT_TRUE(q.contact && q.inside_end) << cases[k].name;
    EXPECT_NEAR(q.depth, depth, 1e-6) << cases[k].name;
  }
}

TEST(ShapeColliderSetTest, SheetOnASlopeSticksOrSlides) {
  // A 5 x 5 sheet (free particles) resting on a 20 degree slope.
  const Mat34 slope = Pose({}, {0.f, 0.f, 1.f}, 20.0);
  ShapeColliderSet set;
  ASSERT_TRUE(set.AddPlane(slope, slope).ok());
  const auto run = [&](float static_friction, float friction, FrictionModel model, double* speed) {
    ResponseParams params;
    params.static_friction = static_friction;
    params.friction = friction;
    params.friction_model = model;
    std::vector<Float3> x, v;
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j)
        x.push_back(TransformPoint(slope, {0.05f * float(i), params.separation, 0.05f * float(j)}));
    v.resize(x.size());
    Simulate(set, params, 60, &x, &v);  // settle for 1 s
    const std::vector<Float3> at_one_second = x;
    Simulate(set, params, 180, &x, &v);  // then 3 s
    *speed = 0.0;
    for (size_t i = 0; i < x.size(); ++i)
      *speed = std::max(*speed, Distance3(x[i], at_one_second[i]) / 3.0);
  };
  double speed = 0.0;
  run(0.5f, 0.4f, FrictionModel::kCoulomb, &speed);  // tan(20 deg) = 0.36 < 0.5: sticks
  EXPECT_LT(speed, 1e-4);
  run(0.1f, 0.1f, FrictionModel::kCoulomb, &speed);  // slides: g (sin 20 - 0.1 cos 20) = 2.4 m/s^2
  EXPECT_GT(speed, 1.0);
  run(0.5f, 0.4f, FrictionModel::kPaperA, &speed);  // paper A: only (1 - friction) of the speed
  EXPECT_GT(speed, 1e-2);
}

// The round cone's signed distance by its support function, h(d) = max over the two spheres of
// c . d + r, in the plane through the axis: sd(p) = max over unit d of (d . p - h(d)), for any
// convex set and any point inside or outside.
// Sampled over the direction's angle, then refined by golden section around the best sample
// (the maximum can sit on the support function's kink, where sampling alone is only linear).
double RoundConeReference(double h, double r0, double r1, double x, double rho) {
  const auto value = [&](double theta) {
    const double dx = std::cos(theta), dr = std::sin(theta);
    return dx * x + dr * rho - std::max(-h * dx + r0, h * dx + r1);
  };
  const int samples = 20000;
  const double step = 3.14159265358979323846 / samples;
  int best = 0;
  for (int i = 1; i <= samples; ++i)
    if (value(step * i) > value(step * best)) best = i;
  double a = step * (best - 1), b = step * (best + 1);
  for (int i = 0; i < 200; ++i) {
    const double x1 = b - 0.618034 * (b - a), x2 = a + 0.618034 * (b - a);
    if (value(x1) < value(x2)) {
      a = x1;
    } else {
      b = x2;
    }
  }
  return std::max(value(0.5 * (a + b)), value(step * best));
}

TEST(ShapeColliderSetTest, RoundConeDistanceMatchesReference) {
  struct Cone {
    double h, r0, r1;
  };
  const Cone cones[] = {{0.25, 0.12, 0.07},
                        {0.1, 0.02, 0.09},
                        {0.2, 0.05, 0.05},
                        {0.0, 0.1, 0.1},
                        {0.05, 0.2, 0.08}};  // the last: one holds the other
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.45, 0.45);
  for (const Cone& c : cones) {
    const detail::LocalShape s = detail::CapsuleShape(c.h, c.r0, c.r1);
    for (int i = 0; i < 40; ++i) {
      const detail::Vec3D p{u(rng), u(rng) * 0.6, u(rng) * 0.6};
      const double rho = std::sqrt(p.y * p.y + p.z * p.z);
      const detail::SignedDistance d = detail::Distance(s, p);
      EXPECT_NEAR(d.value, RoundConeReference(c.h, c.r0, c.r1, p.x, rho), 1e-8)
          << c.h << " " << c.r0 << " " << c.r1 << " at " << p.x << " " << p.y << " " << p.z;
      // The gradient: unit, and the distance's central difference.
      EXPECT_NEAR(detail::LengthD(d.gradient), 1.0, 1e-12);
      const double eps = 1e-6;
      const detail::Vec3D fd{(detail::Distance(s, {p.x + eps, p.y, p.z}).value -
                              detail::Distance(s, {p.x - eps, p.y, p.z}).value) /
                                 (2 * eps),
                             (detail::Distance(s, {p.x, p.y + eps, p.z}).value -
                              detail::Distance(s, {p.x, p.y - eps, p.z}).value) /
                                 (2 * eps),
                             (detail::Distance(s, {p.x, p.y, p.z + eps}).value -
                              detail::Distance(s, {p.x, p.y, p.z - eps}).value) /
                                 (2 * eps)};
      EXPECT_NEAR(detail::LengthD(fd - d.gradient), 0.0, 1e-4);
    }
  }
  // Known points: beyond the small end on the axis; beside a cylinder's middle.
  EXPECT_NEAR(detail::Distance(detail::CapsuleShape(0.25, 0.12, 0.07), {0.42, 0, 0}).value, 0.1,
              1e-12);
  EXPECT_NEAR(detail::Distance(detail::CapsuleShape(0.2, 0.05, 0.05), {0.1, 0, 0.3}).value, 0.25,
              1e-12);
  EXPECT_NEAR(detail::Distance(detail::CapsuleShape(0.2, 0.05, 0.05), {0.1, 0.01, 0}).value, -0.04,
              1e-12);
}

TEST(ShapeColliderSetTest, HostileInputsGiveFiniteBoundedResults) {
  const std::vector<Plane> convex = ChamferedBox({0.3f, 0.1f, 0.2f});
  const Mat34 pose = Pose({0.1f, 0.2f, -0.1f}, {0.3f, 0.8f, 0.52f}, 40.0);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> near(-1.f, 1.f), unit(0.f, 1.f);
  const auto far = [&]() { return (unit(rng) < 0.5f ? -1e30f : 1e30f) * (0.5f + unit(rng)); };
  const auto point = [&](int mode) {
    return mode == 0 ? Float3{near(rng), near(rng), near(rng)} : Float3{far(), far(), far()};
  };
  const ResponseParams params;
  ShapeColliderSet all;
  for (const ShapeCase& c : Cases(convex)) {
    ASSERT_TRUE(c.add(&all, pose, pose).ok());
    ShapeColliderSet set;
    ASSERT_TRUE(c.add(&set, pose, pose).ok());
    std::vector<Float3> x0, x1, v;
    for (int i = 0; i < 3000; ++i) {
      const int kind = i % 4;  // near pairs, 20 m segments, one far end, both far
      Float3 a = point(kind == 3 ? 1 : 0), b;
      if (kind == 1) {
        const Float3 dir = NormalizeOr({near(rng), near(rng), near(rng)}, {1.f, 0.f, 0.f});
        b = a + dir * 10.f;
        a = a - dir * 10.f;
      } else {
        b = point(kind >= 2 ? 1 : 0);
      }
      x0.push_back(a);
      x1.push_back(b);
      v.push_back({near(rng), near(rng), near(rng)});
    }
    // Non-finite particles are flagged and left alone.
    x0.push_back({NAN, 0.f, 0.f});
    x1.push_back({0.f, 0.f, 0.f});
    v.push_back({});
    x0.push_back({0.f, 0.f, 0.f});
    x1.push_back({0.f, INFINITY, 0.f});
    v.push_back({});
    x0.push_back({0.f, 0.f, 0.f});
    x1.push_back({0.f, 0.f, 0.f});
    v.push_back({0.f, 0.f, NAN});
    const std::vector<Float3> before = x1, v_before = v;
    std::vector<uint8_t> flags(x1.size());
    ASSERT_TRUE(set.CollideBatch(x0, x1, v, flags, params, 0.f, 1.f, kFrame).ok());
    const size_t n = x1.size();
    for (size_t i = n - 3; i < n; ++i) {
      EXPECT_EQ(flags[i], kCollisionInvalidInput) << c.name;
      EXPECT_EQ(std::memcmp(&x1[i], &before[i], sizeof(Float3)), 0) << c.name;
      EXPECT_EQ(std::memcmp(&v[i], &v_before[i], sizeof(Float3)), 0) << c.name;
    }
    for (size_t i = 0; i + 3 < n; ++i) {
      ASSERT_TRUE(IsFinite(x1[i]) && IsFinite(v[i])) << c.name << " " << i;
      const double depth = std::max(0.0, -WorldDistance(c.local, pose, before[i]));
      const double scale =
          std::max({1.0, double(std::fabs(before[i].x)), double(std::fabs(before[i].y)),
                    double(std::fabs(before[i].z))});
      EXPECT_LE(Distance3(x1[i], before[i]),
                Distance3(before[i], x0[i]) + depth + params.separation + 1e-6 * scale)
          << c.name << " " << i;
    }
  }
  // All kinds at once (several contacts per particle): finite.
  std::vector<Float3> x0(2000), x1(2000), v(2000);
  for (size_t i = 0; i < x0.size(); ++i) {
    x0[i] = point(i % 3 == 0 ? 1 : 0);
    x1[i] = point(i % 2);
  }
  std::vector<uint8_t> flags(x0.size());
  ASSERT_TRUE(all.CollideBatch(x0, x1, v, flags, params, 0.f, 1.f, kFrame).ok());
  for (size_t i = 0; i < x1.size(); ++i) EXPECT_TRUE(IsFinite(x1[i]) && IsFinite(v[i])) << i;
}

TEST(ShapeColliderSetTest, InvalidArgumentsAreRejectedNamingTheShape) {
  ShapeColliderSet set;
  const Mat34 id;
  const auto expect_error = [&](const Status& s, const std::string& shape,
                                const std::string& field) {
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << field;
    EXPECT_NE(s.message().find(shape), std::string::npos) << s.message();
    EXPECT_NE(s.message().find(field), std::string::npos) << s.message();
  };
  expect_error(set.AddSphere(id, id, 0.f), "shape 0", "radius");
  expect_error(set.AddSphere(id, id, -1.f), "shape 0", "radius");
  expect_error(set.AddSphere(id, id, NAN), "shape 0", "radius");
  ASSERT_TRUE(set.AddSphere(id, id, 0.1f).ok());
  Mat34 scaled = id;
  scaled.m[0] = 2.f;
  expect_error(set.AddSphere(scaled, id, 0.1f), "shape 1", "start is not rigid");
  Mat34 sheared = id;
  sheared.m[1] = 0.1f;
  expect_error(set.AddBox(id, sheared, {1, 1, 1}), "shape 1", "end is not rigid");
  Mat34 mirrored = id;
  mirrored.m[10] = -1.f;
  expect_error(set.AddPlane(mirrored, id), "shape 1", "start is not rigid");
  Mat34 nan = id;
  nan.m[7] = NAN;
  expect_error(set.AddPlane(id, nan), "shape 1", "end is not finite");
  expect_error(set.AddCapsule(id, id, -0.1f, 0.1f, 0.1f), "shape 1", "half_length");
  expect_error(set.AddCapsule(id, id, 0.1f, 0.1f, 0.f), "shape 1", "radius1");
  expect_error(set.AddBox(id, id, {0.1f, 0.f, 0.1f}), "shape 1", "half_extents.y");
  std::vector<Plane> planes = ChamferedBox({0.1f, 0.1f, 0.1f});
  expect_error(set.AddConvex(id, id, std::span<const Plane>(planes.data(), 3)), "shape 1",
               "planes count 3");
  // A pyramid without its base: unbounded below.
  const float k = 1.f / std::sqrt(2.f);
  const std::vector<Plane> open = {
      {{k, k, 0}, 0.1f}, {{-k, k, 0}, 0.1f}, {{0, k, k}, 0.1f}, {{0, k, -k}, 0.1f}};
  expect_error(set.AddConvex(id, id, open), "shape 1", "planes are not bounded");
  std::vector<Plane> empty = planes;
  empty[0] = {{1, 0, 0}, -0.2f};  // x <= -0.2 against -x <= 0.1
  expect_error(set.AddConvex(id, id, empty), "shape 1", "planes enclose nothing");
  std::vector<Plane> bad = planes;
  bad[2].normal.y = 1.1f;
  expect_error(set.AddConvex(id, id, bad), "shape 1", "planes[2].normal");
  bad = planes;
  bad[1].offset = NAN;
  expect_error(set.AddConvex(id, id, bad), "shape 1", "planes[1]");
  EXPECT_EQ(set.size(), 1u);
  EXPECT_EQ(set.plane_count(), 0u);
  ASSERT_TRUE(set.AddConvex(id, id, planes).ok());
  EXPECT_EQ(set.plane_count(), 7u);

  std::vector<Float3> x0(4), x1(4), v(4);
  std::vector<uint8_t> flags(4);
  const ResponseParams params;
  const auto batch = [&](float s0, float s1, float h) {
    return set.CollideBatch(x0, x1, v, flags, params, s0, s1, h).code();
  };
  EXPECT_EQ(batch(0.f, 1.f, kFrame), StatusCode::kOk);
  EXPECT_EQ(batch(0.6f, 0.5f, kFrame), StatusCode::kInvalidArgument);
  EXPECT_EQ(batch(0.f, 1.5f, kFrame), StatusCode::kInvalidArgument);
  EXPECT_EQ(batch(NAN, 1.f, kFrame), StatusCode::kInvalidArgument);
  EXPECT_EQ(batch(0.f, 1.f, 0.f), StatusCode::kInvalidArgument);
  EXPECT_EQ(batch(0.f, 1.f, -kFrame), StatusCode::kInvalidArgument);
  EXPECT_EQ(batch(0.f, 1.f, NAN), StatusCode::kInvalidArgument);
  std::vector<uint8_t> short_flags(3);
  EXPECT_EQ(set.CollideBatch(x0, x1, v, short_flags, params, 0.f, 1.f, kFrame).code(),
            StatusCode::kInvalidArgument);
  ResponseParams bad_params;
  bad_params.friction = 2.f;
  EXPECT_EQ(set.CollideBatch(x0, x1, v, flags, bad_params, 0.f, 1.f, kFrame).code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(set.Query({}, {}, 0.7f, 0.2f).flags, kCollisionInvalidInput);
}

// A scene with every kind, moving over the frame, and particles around it.
void BuildMovingScene(ShapeColliderSet* set, const std::vector<Plane>& convex) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  const auto pose = [&](float lift) {
    return Pose({u(rng), 0.3f + u(rng) + lift, u(rng)},
                NormalizeOr({u(rng), u(rng), u(rng)}, {0, 1, 0}), 60.0 * u(rng));
  };
  for (int i = 0; i < 6; ++i) {
    const Mat34 a = pose(0.f), b = pose(0.f);
    ASSERT_TRUE(set->AddSphere(a, b, 0.1f + 0.1f * std::fabs(u(rng))).ok());
    ASSERT_TRUE(set->AddCapsule(a, pose(0.f), 0.2f, 0.08f, 0.05f).ok());
  }
  ASSERT_TRUE(
      set->AddPlane(Pose({0.f, -0.2f, 0.f}), Pose({0.f, -0.18f, 0.f}, {1, 0, 0}, 3.0)).ok());
  ASSERT_TRUE(set->AddBox(pose(0.f), pose(0.f), {0.2f, 0.05f, 0.1f}).ok());
  ASSERT_TRUE(set->AddConvex(pose(0.f), pose(0.f), convex).ok());
}

TEST(ShapeColliderSetTest, SameBitsAtOneAndTwoThreads) {
  const std::vector<Plane> convex = ChamferedBox({0.15f, 0.1f, 0.1f});
  ShapeColliderSet set;
  BuildMovingScene(&set, convex);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-0.8f, 0.8f), step(-0.03f, 0.03f);
  const size_t n = 10000;
  std::vector<Float3> x0(n), x1(n), v(n);
  for (size_t i = 0; i < n; ++i) {
    x0[i] = {u(rng), 0.3f + u(rng), u(rng)};
    x1[i] = x0[i] + Float3{step(rng), step(rng), step(rng)};
    v[i] = {step(rng) * 60.f, step(rng) * 60.f, step(rng) * 60.f};
  }
  std::vector<Float3> results_x[2], results_v[2];
  std::vector<uint8_t> results_flags[2];
  uint32_t contacts[2] = {0, 0};
  for (int threads = 1; threads <= 2; ++threads) {
    test::UseWorkers(threads);
    std::vector<Float3> x = x1, vel = v;
    std::vector<uint8_t> flags(n);
    ASSERT_TRUE(set.CollideBatch(x0, x, vel, flags, ResponseParams{}, 0.25f, 0.5f, 0.25f * kFrame,
                                 &contacts[threads - 1])
                    .ok());
    results_x[threads - 1] = x;
    results_v[threads - 1] = vel;
    results_flags[threads - 1] = flags;
  }
  test::UseDefaultWorkers();
  EXPECT_GT(contacts[0], n / 20);
  EXPECT_EQ(contacts[0], contacts[1]);
  EXPECT_EQ(std::memcmp(results_x[0].data(), results_x[1].data(), n * sizeof(Float3)), 0);
  EXPECT_EQ(std::memcmp(results_v[0].data(), results_v[1].data(), n * sizeof(Float3)), 0);
  EXPECT_EQ(results_flags[0], results_flags[1]);
}

TEST(ShapeColliderSetTest, ReAddingAfterClearAllocatesNothing) {
  const std::vector<Plane> convex = ChamferedBox({0.15f, 0.1f, 0.1f});
  ShapeColliderSet set;
  set.Reserve(16, 16);
  BuildMovingScene(&set, convex);
  const uint32_t shape_capacity = set.shape_capacity(), plane_capacity = set.plane_capacity();
  const size_t n = 3000;  // above the batch's threading threshold
  std::vector<Float3> x0(n), x1(n), v(n);
  for (size_t i = 0; i < n; ++i) x0[i] = x1[i] = {0.001f * float(i % 100), 0.f, 0.f};
  std::vector<uint8_t> flags(n);
  set.Clear();
  const uint64_t before = g_allocations.load();
  BuildMovingScene(&set, convex);
  const Status status = set.CollideBatch(x0, x1, v, flags, ResponseParams{}, 0.f, 1.f, kFrame);
  const uint64_t after = g_allocations.load();
  ASSERT_TRUE(status.ok());
  EXPECT_EQ(after, before);
  EXPECT_EQ(set.shape_capacity(), shape_capacity);
  EXPECT_EQ(set.plane_capacity(), plane_capacity);
  EXPECT_EQ(set.size(), 15u);
}

TEST(ShapeColliderSetTest, ManyShapesAndTheFirstContact) {
  // 40 spheres (more than one posing chunk): a particle falls onto the 38th.
  ShapeColliderSet set;
  for (int i = 0; i < 40; ++i)
    ASSERT_TRUE(
        set.AddSphere(Pose({0.5f * float(i), 0.f, 0.f}), Pose({0.5f * float(i), 0.f, 0.f}), 0.1f)
            .ok());
  std::vector<Float3> x = {{0.5f * 37.f, 0.5f, 0.f}}, v(1);
  Simulate(set, ResponseParams{}, 60, &x, &v);
  EXPECT_NEAR(x[0].y, 0.1f + 1e-4f, 1e-5f);
  // The segment meets sphere 38 before sphere 37: the first contact is 38's.
  const ContactQuery q = set.Query({19.3f, 0.f, 0.f}, {18.2f, 0.f, 0.f}, 0.f, 1.f);
  ASSERT_TRUE(q.contact);
  EXPECT_NEAR(q.t, 0.2f / 1.1f, 1e-5f);
  EXPECT_NEAR(Distance3(q.point, {19.1f, 0.f, 0.f}), 0.0, 1e-6);
}

TEST(ShapeColliderSetTest, SecondPassResolvesAParticlePushedBackIn) {
  // A box (shape 0, top face y = 0) and a sphere (shape 1) poking out of it: the sphere's push
  // sends the particle into the box; the second pass takes it out again.
  ShapeColliderSet set;
  ASSERT_TRUE(set.AddBox(Pose({0.f, -0.5f, 0.f}), Pose({0.f, -0.5f, 0.f}), {1.f, 0.5f, 1.f}).ok());
  ASSERT_TRUE(set.AddSphere(Pose({0.f, 0.05f, 0.f}), Pose({0.f, 0.05f, 0.f}), 0.1f).ok());
  const Float3 p{0.f, -0.01f, 0.05f};
  ResponseParams frictionless;
  frictionless.friction = frictionless.static_friction = 0.f;
  const Particle r = CollideOne(set, p, p, {}, frictionless);
  EXPECT_EQ(r.flags, kCollisionContact | kCollisionStartedInside);
  // One pass leaves it 2.1 cm inside the box; the second 0.8 cm (a pinch converges slowly).
  EXPECT_GT(r.x.y, -0.01f);
  EXPECT_LT(r.x.y, -0.005f);
}

// A baked capsule on joint 1 posed from the skeleton: its end spheres' centres are the bone's
// skinning of `from` and `to` at both ends of the frame, a segment through its middle at the end
// pose is caught and the particle ends outside; a capsule whose ends coincide is a sphere; a
// joint without a matrix is refused naming the capsule.
TEST(ShapeColliderSetTest, BakedCapsulesFollowTheirBone) {
  const CapsuleColliderData capsule{1, {0.f, 0.f, 0.f}, {0.f, 0.4f, 0.f}, 0.06f, 0.04f};
  const std::vector<Mat34> start = {Mat34{}, Pose({1.f, 0.f, 0.f}, {0.f, 0.f, 1.f}, 90.0)};
  const std::vector<Mat34> end = {Mat34{}, Pose({1.f, 0.1f, 0.f}, {0.3f, 0.f, 1.f}, 110.0)};
  ShapeColliderSet shapes;
  ASSERT_TRUE(AddCapsuleColliders(std::span(&capsule, 1), start, end, &shapes).ok());
  ASSERT_EQ(shapes.size(), 1u);
  EXPECT_EQ(shapes.kind(0), ShapeKind::kCapsule);
  const float half = 0.2f;
  for (const auto& [s, skinning] : {std::pair{0.f, start[1]}, std::pair{1.f, end[1]}}) {
    const Mat34 frame = shapes.WorldTransform(0, s);
    EXPECT_LT(
        Distance3(TransformPoint(frame, {-half, 0.f, 0.f}), TransformPoint(skinning, capsule.from)),
        1e-5);
    EXPECT_LT(
        Distance3(TransformPoint(frame, {half, 0.f, 0.f}), TransformPoint(skinning, capsule.to)),
        1e-5);
  }
  const Float3 middle = TransformPoint(end[1], {0.f, 0.2f, 0.f});
  const Float3 across = TransformVector(end[1], {0.f, 0.f, 1.f});  // normal to the axis
  std::vector<Float3> previous = {middle + across * 0.2f}, positions = {middle - across * 0.2f},
                      velocities = {Float3{}};
  std::vector<uint8_t> flags(1);
  ResponseParams params;
  ShapeColliderSet still;  // held at the end pose, so the particle's exit is exact
  ASSERT_TRUE(AddCapsuleColliders(std::span(&capsule, 1), end, end, &still).ok());
  const ContactQuery q = still.Query(middle + across * 0.2f, middle - across * 0.2f, 0.f, 1.f);
  EXPECT_TRUE(q.contact);
  EXPECT_NEAR(Distance3(q.point, middle), 0.05, 1e-4);  // the radius halfway: (0.06 + 0.04) / 2
  ASSERT_TRUE(
      still.CollideBatch(previous, positions, velocities, flags, params, 0.f, 1.f, kFrame).ok());
  EXPECT_GE(Distance3(positions[0], middle), 0.05 - 1e-5);
  EXPECT_LT(Distance3(positions[0], middle), 0.05 + 0.005);

  // A capsule a hair off its bone's y axis (the bone's y column nearly along the capsule): its
  // frame stays rigid (the cancellation once left it 1e-3 off orthogonal on a posed mannequin).
  CapsuleColliderData skewed = capsule;
  for (float off : {2e-5f, 4e-6f, 1.5e-6f, 8e-7f}) {
    skewed.to = {off, 0.4f, off};
    for (double degrees : {0.0, 33.0, 90.0, 147.0}) {
      const std::vector<Mat34> posed = {Mat34{},
                                        Pose({0.3f, 1.f, 0.f}, {0.2f, 0.5f, 1.f}, degrees)};
      ShapeColliderSet one;
      const Status s = AddCapsuleColliders(std::span(&skewed, 1), posed, posed, &one);
      EXPECT_TRUE(s.ok()) << off << " " << degrees << ": " << s.message();
    }
  }

  CapsuleColliderData ball = capsule;
  ball.to = ball.from;
  float half_length = 1.f;
  const Mat34 frame = CapsuleFrame(ball, start[1], &half_length);
  EXPECT_EQ(half_length, 0.f);
  EXPECT_LT(Distance3(TransformPoint(frame, {}), TransformPoint(start[1], ball.from)), 1e-6);
  CapsuleColliderData stray = capsule;
  stray.joint = 5;
  const Status s = AddCapsuleColliders(std::span(&stray, 1), start, end, &shapes);
  EXPECT_EQ(s.message(), "capsule 0: joint 5 has no skinning matrix");
}

}  // namespace
}  // namespace drape

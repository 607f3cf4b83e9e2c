// Runtime-only tests of drape::HullColliderSet (no bake headers: builds with
// -DDRAPE_BUILD_BAKE=OFF). The hull data is made by hand here: a box and a tessellated ellipsoid,
// planes with offsets rounded outward in the runtime's float arithmetic. Kirkpatrick-mode and
// map-table builder tests live in tests/bake (they need the builders).

#include "drape/runtime/hull_collider.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <array>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "drape/runtime/math.h"

namespace drape {
namespace {

constexpr double kPi = 3.14159265358979323846;

// ---- Hand-made convex hulls -------------------------------------------------------------------

// Orients every face outward (against the vertex centroid), merges exactly coplanar faces into one
// plane and rounds each offset outward: every vertex is inside in the runtime's arithmetic.
HullColliderData MakeHull(const std::vector<Float3>& vertices,
                          std::vector<std::array<uint32_t, 3>> faces, const Obb& obb) {
  HullColliderData h;
  h.joint = 0;
  h.vertices = vertices;
  h.obb = obb;
  double cx = 0, cy = 0, cz = 0;
  for (const Float3& v : vertices) cx += v.x, cy += v.y, cz += v.z;
  cx /= double(vertices.size()), cy /= double(vertices.size()), cz /= double(vertices.size());
  for (auto& f : faces) {
    const Float3 a = vertices[f[0]], b = vertices[f[1]], c = vertices[f[2]];
    const double ux = double(b.x) - a.x, uy = double(b.y) - a.y, uz = double(b.z) - a.z;
    const double vx = double(c.x) - a.x, vy = double(c.y) - a.y, vz = double(c.z) - a.z;
    double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    const double mx = (double(a.x) + b.x + c.x) / 3 - cx, my = (double(a.y) + b.y + c.y) / 3 - cy,
                 mz = (double(a.z) + b.z + c.z) / 3 - cz;
    if (nx * mx + ny * my + nz * mz < 0) {
      std::swap(f[1], f[2]);
      nx = -nx, ny = -ny, nz = -nz;
    }
    const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
    const Float3 n{float(nx / len), float(ny / len), float(nz / len)};
    const double offset = (double(n.x) * a.x + double(n.y) * a.y + double(n.z) * a.z);
    int32_t plane = -1;
    for (size_t p = 0; p < h.planes.size(); ++p) {
      const Float3 q = h.planes[p].normal;
      if (std::fabs(q.x - n.x) + std::fabs(q.y - n.y) + std::fabs(q.z - n.z) < 1e-6f &&
          std::fabs(double(q.x) * a.x + double(q.y) * a.y + double(q.z) * a.z - offset) < 1e-6)
        plane = int32_t(p);
    }
    if (plane < 0) {
      plane = int32_t(h.planes.size());
      h.planes.push_back({n, 0.f});
    }
    h.triangles.insert(h.triangles.end(), {f[0], f[1], f[2]});
    h.triangle_planes.push_back(uint32_t(plane));
  }
  // As bake/hull_builder.h does: the max over the vertices of n.x plus the worst-case rounding
  // of a float dot product (3 ulps of sum |n_i x_i|), rounded up to float, plus one more ulp.
  for (Plane& p : h.planes) {
    double worst = -std::numeric_limits<double>::infinity();
    for (const Float3& v : vertices) {
      const double nx = double(p.normal.x) * v.x, ny = double(p.normal.y) * v.y,
                   nz = double(p.normal.z) * v.z;
      worst = std::max(worst, nx + ny + nz +
                                  3.0 * std::numeric_limits<float>::epsilon() *
                                      (std::fabs(nx) + std::fabs(ny) + std::fabs(nz)));
    }
    float d = static_cast<float>(worst);
    if (double(d) < worst) d = std::nextafter(d, std::numeric_limits<float>::infinity());
    p.offset = std::nextafter(d, std::numeric_limits<float>::infinity());
  }
  return h;
}

Float3 Rotate(const Float3 axes[3], Float3 local) {
  return axes[0] * local.x + axes[1] * local.y + axes[2] * local.z;
}

// Box with half extents he, rotated to `axes`, centred at `center` (collider frame).
HullColliderData MakeBox(Float3 he, Float3 center = {}, const Float3* axes = nullptr) {
  const Float3 identity[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  if (axes == nullptr) axes = identity;
  std::vector<Float3> v;
  for (int i = 0; i < 8; ++i) {
    const Float3 local{(i & 1) ? he.x : -he.x, (i & 2) ? he.y : -he.y, (i & 4) ? he.z : -he.z};
    v.push_back(center + Rotate(axes, local));
  }
  const std::vector<std::array<uint32_t, 3>> faces = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                                      {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                                      {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  Obb obb;
  obb.center = center;
  for (int k = 0; k < 3; ++k) obb.axes[k] = axes[k];
  obb.half_extents = he;
  return MakeHull(v, faces, obb);
}

// Icosphere subdivided `levels` times, scaled to semi-axes `r`, rotated and centred. All its
// vertices lie on the ellipsoid, so every face is a convex-hull face.
HullColliderData MakeEllipsoid(Float3 r, int levels, Float3 center, const Float3 axes[3]) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<std::array<double, 3>> p = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                          {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                          {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<uint32_t, 3>> f = {
      {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& q : p) {
    const double l = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    for (double& x : q) x /= l;
  }
  for (int level = 0; level < levels; ++level) {
    std::vector<std::array<uint32_t, 3>> next;
    std::vector<std::pair<uint64_t, uint32_t>> cache;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      const uint64_t key = (uint64_t(std::min(a, b)) << 32) | std::max(a, b);
      for (auto& [k, v] : cache)
        if (k == key) return v;
      std::array<double, 3> m = {p[a][0] + p[b][0], p[a][1] + p[b][1], p[a][2] + p[b][2]};
      const double l = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
      for (double& x : m) x /= l;
      p.push_back(m);
      cache.push_back({key, uint32_t(p.size() - 1)});
      return uint32_t(p.size() - 1);
    };
    for (const auto& tri : f) {
      const uint32_t a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]),
                     c = midpoint(tri[2], tri[0]);
      next.push_back({tri[0], a, c});
      next.push_back({tri[1], b, a});
      next.push_back({tri[2], c, b});
      next.push_back({a, b, c});
    }
    f = next;
  }
  std::vector<Float3> v;
  for (const auto& q : p)
    v.push_back(center +
                Rotate(axes, Float3{float(q[0] * r.x), float(q[1] * r.y), float(q[2] * r.z)}));
  Obb obb;
  obb.center = center;
  for (int k = 0; k < 3; ++k) obb.axes[k] = axes[k];
  obb.half_extents = r;
  return MakeHull(v, f, obb);
}

void RotatedAxes(double angle_deg, Float3 axis, Float3 out[3]) {
  const double a = angle_deg * kPi / 180.0;
  const double l =
      std::sqrt(double(axis.x) * axis.x + double(axis.y) * axis.y + double(axis.z) * axis.z);
  const double x = axis.x / l, y = axis.y / l, z = axis.z / l, c = std::cos(a), s = std::sin(a);
  const double m[3][3] = {{c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s},
                          {y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s},
                          {z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)}};
  for (int k = 0; k < 3; ++k) out[k] = {float(m[0][k]), float(m[1][k]), float(m[2][k])};
}

// Rigid matrix rotating by angle about `axis` through `pivot`.
Mat34 RotationAbout(double angle_deg, Float3 axis, Float3 pivot) {
  Float3 cols[3];
  RotatedAxes(angle_deg, axis, cols);
  Mat34 m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m.m[4 * r + c] = (&cols[c].x)[r];
  const Float3 rp = TransformVector(m, pivot);
  m.m[3] = pivot.x - rp.x;
  m.m[7] = pivot.y - rp.y;
  m.m[11] = pivot.z - rp.z;
  return m;
}

float MaxPlane(const HullColliderData& h, Float3 p) {
  float m = -std::numeric_limits<float>::infinity();
  for (const Plane& pl : h.planes) m = std::max(m, PlaneSignedDistance(pl, p));
  return m;
}

Float3 RandomIn(std::mt19937& rng, Float3 lo, Float3 hi) {
  std::uniform_real_distribution<float> u(0.f, 1.f);
  return {lo.x + (hi.x - lo.x) * u(rng), lo.y + (hi.y - lo.y) * u(rng),
          lo.z + (hi.z - lo.z) * u(rng)};
}

HullColliderSet BuildSet(const std::vector<HullColliderData>& hulls,
                         const std::vector<JointSphereData>& spheres, uint32_t joints,
                         const HullColliderOptions& options = {}) {
  HullColliderSet set;
  const Status s = set.Build(hulls, spheres, joints, options);
  EXPECT_TRUE(s.ok()) << s.message();
  return set;
}

// ---- Tests ----------------------------------------------------------------------------------

TEST(HullColliderTest, HandMadeHullsAreConvexAndContainTheirVertices) {
  Float3 axes[3];
  RotatedAxes(33.0, {1, 2, 3}, axes);
  for (const HullColliderData& h :
       {MakeBox({0.1f, 0.2f, 0.05f}),
        MakeEllipsoid({0.05f, 0.12f, 0.07f}, 1, {0.1f, 0.2f, 0.3f}, axes)}) {
    for (const Float3& v : h.vertices) EXPECT_LE(MaxPlane(h, v), 0.f);
    // Every plane has a vertex within float rounding of it (a real face, not a loose plane).
    for (const Plane& p : h.planes) {
      float best = -1e30f;
      for (const Float3& v : h.vertices) best = std::max(best, PlaneSignedDistance(p, v));
      EXPECT_GT(best, -1e-6f);
    }
  }
  EXPECT_EQ(MakeBox({0.1f, 0.2f, 0.05f}).planes.size(), 6u);
  EXPECT_EQ(MakeEllipsoid({0.05f, 0.12f, 0.07f}, 1, {}, axes).planes.size(), 80u);
}

TEST(HullColliderTest, ValidationRejectsBadData) {
  const HullColliderData good = MakeBox({0.1f, 0.1f, 0.1f});
  HullColliderSet set;
  ASSERT_TRUE(set.Build(std::vector<HullColliderData>{good}, {}, 1).ok());
  auto expect_rejected = [&](const HullColliderData& h, const char* what) {
    HullColliderSet s;
    const Status status = s.Build(std::vector<HullColliderData>{h}, {}, 1);
    EXPECT_FALSE(status.ok()) << what;
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << what;
    EXPECT_TRUE(s.empty()) << what;
  };
  HullColliderData h = good;
  h.triangles[4] = 8;
  expect_rejected(h, "triangle index out of range");
  h = good;
  h.triangle_planes[3] = 6;
  expect_rejected(h, "triangle plane out of range");
  h = good;
  h.joint = 1;
  expect_rejected(h, "joint out of range");
  h = good;
  h.planes[0].normal = {0.f, 0.f, 2.f};
  expect_rejected(h, "non-unit normal");
  h = good;
  h.planes[0].offset = std::nanf("");
  expect_rejected(h, "NaN offset");
  h = good;
  h.planes.clear();
  expect_rejected(h, "no planes");
  h = good;
  h.obb.axes[1] = {1.f, 0.f, 0.f};
  expect_rejected(h, "OBB axes not orthogonal");
  // Map table: offsets and indices.
  h = good;
  h.map.rows = 1;
  h.map.cols = 2;
  h.map.axis = {0, 0, 1};
  h.map.reference = {1, 0, 0};
  h.map.cell_offsets = {0, 1, 2};
  h.map.cell_triangles = {0, 12};
  expect_rejected(h, "map triangle out of range");
  h.map.cell_triangles = {0, 1};
  h.map.cell_offsets = {0, 2, 1};
  expect_rejected(h, "map offsets decreasing / wrong end");
  h.map.cell_offsets = {0, 1, 2};
  {
    HullColliderSet s;
    EXPECT_TRUE(s.Build(std::vector<HullColliderData>{h}, {}, 1).ok());
  }
  // Kirkpatrick hierarchy: a child index not below its parent, a vertex index out of range.
  h = good;
  h.projection_axis = {0, 0, 1};
  h.projection_u = {1, 0, 0};
  h.projection_v = {0, 1, 0};
  for (KirkpatrickHierarchy* k : {&h.upper, &h.lower}) {
    // The box's vertices projected along z (origin = OBB centre 0): (+-0.1, +-0.1).
    k->vertices_uv = {-0.1f, -0.1f, 0.1f, -0.1f, -0.1f, 0.1f, 0.1f, 0.1f};
    k->node_triangles = {0, 1, 2, 1, 3, 2, 0, 1, 2};
    k->child_offsets = {0, 0, 0, 2};
    k->children = {0, 1};
    k->leaf_planes = {0, 1, -1};
    k->root_begin = 2;
    k->root_end = 3;
  }
  {
    HullColliderSet s;
    EXPECT_TRUE(s.Build(std::vector<HullColliderData>{h}, {}, 1).ok());
  }
  HullColliderData bad = h;
  bad.upper.children = {0, 2};
  expect_rejected(bad, "child not below its parent");
  bad = h;
  bad.lower.node_triangles[4] = 4;
  expect_rejected(bad, "hierarchy vertex index out of range");
  bad = h;
  bad.upper.leaf_planes[0] = 6;
  expect_rejected(bad, "leaf plane out of range");
  bad = h;
  bad.upper.node_triangles = {0, 2, 1, 1, 3, 2, 0, 1, 2};
  expect_rejected(bad, "clockwise node");
  bad = h;
  bad.lower = KirkpatrickHierarchy{};
  expect_rejected(bad, "only one hierarchy");
  bad = h;
  bad.obb.center = {0.01f, 0.f, 0.f};  // the projection changed after the bake
  expect_rejected(bad, "stale hierarchy");
  // Options that need missing data.
  {
    HullColliderSet s;
    HullColliderOptions o;
    o.inside_test = InsideTest::kKirkpatrick;
    EXPECT_FALSE(s.Build(std::vector<HullColliderData>{good}, {}, 1, o).ok());
    o = HullColliderOptions{};
    o.response = HullResponse::kMapTableRay;
    EXPECT_FALSE(s.Build(std::vector<HullColliderData>{good}, {}, 1, o).ok());
    o = HullColliderOptions{};
    o.gauss_seidel_passes = 0;
    EXPECT_FALSE(s.Build(std::vector<HullColliderData>{good}, {}, 1, o).ok());
  }
  // Spheres.
  {
    HullColliderSet s;
    EXPECT_FALSE(s.Build({}, std::vector<JointSphereData>{{0, -1, {0, 0, 0}, 0.f}}, 1).ok());
    EXPECT_FALSE(s.Build({}, std::vector<JointSphereData>{{3, -1, {0, 0, 0}, 0.1f}}, 1).ok());
    EXPECT_TRUE(s.Build({}, std::vector<JointSphereData>{{0, -1, {0, 0, 0}, 0.1f}}, 1).ok());
  }
  // Poses.
  std::vector<Mat34> one(1);
  EXPECT_FALSE(set.SetPose({}, one).ok());
  one[0].m[5] = std::nanf("");
  EXPECT_FALSE(set.SetPose(one, one).ok());
  EXPECT_FALSE(set.SelectSubstep(0.6f, 0.5f).ok());
}

TEST(HullColliderTest, ObbRejectionIsConservative) {
  Float3 axes[3];
  RotatedAxes(40.0, {0.3f, -1.f, 0.5f}, axes);
  const HullColliderData h = MakeEllipsoid({0.06f, 0.15f, 0.04f}, 2, {0.02f, -0.1f, 0.3f}, axes);
  HullColliderSet set = BuildSet({h}, {}, 1);
  std::mt19937 rng(7);
  uint32_t inside = 0, rejected = 0;
  for (int i = 0; i < 200000; ++i) {
    const Float3 p = RandomIn(rng, {-0.2f, -0.35f, 0.1f}, {0.25f, 0.15f, 0.5f});
    const bool in = set.InsideLocal(0, p, InsideTest::kPlanes);
    const bool may = set.ObbMayContainLocal(0, p);
    if (in) {
      ++inside;
      EXPECT_TRUE(may);
    }
    if (!may) ++rejected;
  }
  EXPECT_GT(inside, 1000u);
  EXPECT_GT(rejected, 100000u);
  for (const Float3& v : h.vertices) EXPECT_TRUE(set.ObbMayContainLocal(0, v));
}

TEST(HullColliderTest, PushOutIsOnTheSurfaceAndMinimalForABox) {
  const Float3 he{0.1f, 0.2f, 0.05f};
  const HullColliderData box = MakeBox(he);
  HullColliderSet set = BuildSet({box}, {}, 1);
  std::mt19937 rng(1);
  for (int i = 0; i < 20000; ++i) {
    const Float3 p = RandomIn(rng, -he * 0.999f, he * 0.999f);
    const ContactQuery c = set.QueryHullLocal(0, p, p);
    ASSERT_TRUE(c.contact);
    EXPECT_TRUE(c.inside_end);
    EXPECT_TRUE(c.flags & kCollisionStartedInside);
    // On or outside the hull in the runtime's arithmetic.
    EXPECT_GE(set.MaxPlaneDistanceLocal(0, c.point), 0.f);
    // Minimal: the distance to the box boundary.
    const double exact = std::min({he.x - std::fabs(double(p.x)), he.y - std::fabs(double(p.y)),
                                   he.z - std::fabs(double(p.z))});
    const Float3 d = c.point - p;
    EXPECT_NEAR(Length(d), exact, 1e-6) << i;
    EXPECT_NEAR(c.depth, exact, 1e-6);
    // Along the normal.
    EXPECT_NEAR(Dot(d, c.normal), Length(d), 1e-6);
  }
}

TEST(HullColliderTest, PushOutOfARotatedEllipsoidIsOnTheFaceOfTheMaxPlane) {
  Float3 axes[3];
  RotatedAxes(71.0, {1.f, 0.2f, -0.4f}, axes);
  const HullColliderData h = MakeEllipsoid({0.08f, 0.05f, 0.2f}, 2, {0.3f, 1.1f, -0.2f}, axes);
  HullColliderSet set = BuildSet({h}, {}, 1);
  std::mt19937 rng(3);
  int tested = 0;
  for (int i = 0; i < 1000000 && tested < 10000; ++i) {
    const Float3 p = RandomIn(rng, {0.1f, 0.9f, -0.45f}, {0.5f, 1.3f, 0.05f});
    uint32_t plane;
    const float m = set.MaxPlaneDistanceLocal(0, p, &plane);
    if (m > 0.f) continue;
    ++tested;
    const ContactQuery c = set.QueryHullLocal(0, p, p);
    ASSERT_TRUE(c.contact);
    EXPECT_GE(set.MaxPlaneDistanceLocal(0, c.point), 0.f);
    // The projection lands on the face: every other plane still holds (up to rounding) and the
    // displacement equals the max-plane depth (the exact distance to the polytope's boundary).
    EXPECT_LE(set.MaxPlaneDistanceLocal(0, c.point), 2e-6f);
    EXPECT_NEAR(Length(c.point - p), -m, 2e-6f);
    EXPECT_NEAR(c.depth, -m, 1e-7f);
    EXPECT_EQ(c.normal.x, h.planes[plane].normal.x);
  }
  EXPECT_EQ(tested, 10000);
}

TEST(HullColliderTest, FastParticleCrossingAThinBoxIsCaught) {
  const HullColliderData thin = MakeBox({0.2f, 0.2f, 0.001f});
  for (EntryResponse entry : {EntryResponse::kProjectEnd, EntryResponse::kEntryPoint}) {
    HullColliderOptions options;
    options.entry_response = entry;
    HullColliderSet set = BuildSet({thin}, {}, 1, options);
    std::vector<Float3> previous = {
        {0.01f, 0.02f, 0.1f}, {-0.05f, 0.0f, -0.08f}, {0.3f, 0.f, 0.1f}};
    std::vector<Float3> positions = {
        {0.03f, 0.02f, -0.1f}, {-0.05f, 0.01f, 0.07f}, {0.3f, 0.f, -0.1f}};
    std::vector<Float3> velocities = {{0.2f, 0.f, -2.f}, {0.f, 0.1f, 1.5f}, {0.f, 0.f, -2.f}};
    std::vector<uint8_t> flags(3);
    ResponseParams params;
    params.friction = 0.f;
    params.separation = 1e-4f;
    uint32_t contacts = 0;
    ASSERT_TRUE(
        set.CollideBatch(previous, positions, velocities, flags, params, 0.f, 1.f, &contacts).ok());
    EXPECT_EQ(contacts, 2u);
    // Particle 0 came from above: it stays above the top face (z = 0.001), tangential motion kept
    // (kProjectEnd) or stopped at the entry point (kEntryPoint).
    EXPECT_NEAR(positions[0].z, 0.001f + 1e-4f, 2e-6f);
    EXPECT_NEAR(positions[0].x,
                entry == EntryResponse::kProjectEnd ? 0.03f : 0.01f + 0.02f * (0.099f / 0.2f),
                1e-5f);
    EXPECT_FLOAT_EQ(velocities[0].z, 0.f);  // restitution 0
    EXPECT_FLOAT_EQ(velocities[0].x, 0.2f);
    // Particle 1 came from below.
    EXPECT_NEAR(positions[1].z, -0.001f - 1e-4f, 2e-6f);
    // Particle 2 missed the box (x = 0.3 > 0.2).
    EXPECT_EQ(flags[2], kCollisionNone);
    EXPECT_FLOAT_EQ(positions[2].z, -0.1f);
    // The query reports the entry parameter.
    const ContactQuery q = set.Query({0.01f, 0.02f, 0.1f}, {0.03f, 0.02f, -0.1f});
    EXPECT_TRUE(q.contact);
    EXPECT_FALSE(q.inside_end);
    EXPECT_NEAR(q.t, 0.099f / 0.2f, 1e-5f);
    EXPECT_NEAR(q.normal.z, 1.f, 1e-6f);
  }
  // Without the continuous test the particle tunnels (paper B's endpoint test).
  HullColliderOptions discrete;
  discrete.continuous = false;
  HullColliderSet set = BuildSet({thin}, {}, 1, discrete);
  EXPECT_FALSE(set.Query({0.01f, 0.02f, 0.1f}, {0.03f, 0.02f, -0.1f}).contact);
}

TEST(HullColliderTest, BoneTurning90DegreesInOneStepLeavesNoParticleInside) {
  // A forearm-like box on joint 0 whose joint sits at the origin; the bone turns 90 degrees about
  // z within one step. Particles at rest in the swept region must all end outside the end pose.
  HullColliderData arm = MakeBox({0.15f, 0.04f, 0.04f}, {0.2f, 0.f, 0.f});
  HullColliderSet set = BuildSet({arm}, {}, 1);
  const std::vector<Mat34> start = {Mat34{}};
  const std::vector<Mat34> end = {RotationAbout(90.0, {0, 0, 1}, {0, 0, 0})};
  ASSERT_TRUE(set.SetPose(start, end).ok());
  // Screw interpolation pivots about the joint: the mid-step transform is the 45 degree rotation.
  const Mat34 mid = set.HullWorldTransform(0, 0.5f);
  const Mat34 expect_mid = RotationAbout(45.0, {0, 0, 1}, {0, 0, 0});
  for (int i = 0; i < 12; ++i) EXPECT_NEAR(mid.m[i], expect_mid.m[i], 1e-5f) << i;
  std::mt19937 rng(11);
  std::vector<Float3> previous, positions, velocities;
  for (int i = 0; i < 20000; ++i) {
    const Float3 p = RandomIn(rng, {-0.1f, -0.1f, -0.06f}, {0.4f, 0.4f, 0.06f});
    previous.push_back(p);
    positions.push_back(p);
    velocities.push_back({0.f, 0.f, 0.f});
  }
  std::vector<uint8_t> flags(previous.size());
  ResponseParams params;
  params.separation = 1e-5f;
  uint32_t contacts = 0;
  ASSERT_TRUE(
      set.CollideBatch(previous, positions, velocities, flags, params, 0.f, 1.f, &contacts).ok());
  EXPECT_GT(contacts, 1000u);
  const Mat34 to_local = InverseRigid(end[0]);
  uint32_t inside_before = 0;
  for (size_t i = 0; i < positions.size(); ++i) {
    const Float3 before = TransformPoint(to_local, previous[i]);
    if (MaxPlane(arm, before) <= 0.f) ++inside_before;
    EXPECT_GT(MaxPlane(arm, TransformPoint(to_local, positions[i])), 0.f) << i;
  }
  EXPECT_GT(inside_before, 500u);
}

TEST(HullColliderTest, JointSpherePushOutAndContinuousSegment) {
  const JointSphereData sphere{0, -1, {0.f, 1.f, 0.f}, 0.1f};
  HullColliderSet set = BuildSet({}, {sphere}, 1);
  ResponseParams params;
  params.separation = 1e-4f;
  params.friction = 0.f;
  // Resting particle inside: radial push-out.
  std::vector<Float3> previous = {{0.03f, 1.04f, 0.f}}, positions = previous,
                      velocities = {{0, 0, 0}};
  std::vector<uint8_t> flags(1);
  ASSERT_TRUE(set.CollideBatch(previous, positions, velocities, flags, params).ok());
  EXPECT_TRUE(flags[0] & kCollisionContact);
  EXPECT_TRUE(flags[0] & kCollisionStartedInside);
  const Float3 d = positions[0] - sphere.center;
  EXPECT_NEAR(Length(d), 0.1f + 1e-4f, 1e-6f);
  EXPECT_NEAR(d.x / Length(d), 0.6f, 1e-5f);
  EXPECT_NEAR(d.y / Length(d), 0.8f, 1e-5f);
  // A fast particle crossing the whole sphere is caught at the entry side.
  previous = {{-0.5f, 1.01f, 0.f}};
  positions = {{0.5f, 1.01f, 0.f}};
  velocities = {{10.f, 0.f, 0.f}};
  ASSERT_TRUE(set.CollideBatch(previous, positions, velocities, flags, params).ok());
  EXPECT_TRUE(flags[0] & kCollisionContact);
  EXPECT_LT(positions[0].x, -0.09f);
  EXPECT_GE(Length(positions[0] - sphere.center), 0.1f);
  // The normal part of the velocity is removed: N at the entry point (-sqrt(0.0099), 0.01)/0.1.
  const Float3 n{-std::sqrt(0.0099f) / 0.1f, 0.1f, 0.f};
  EXPECT_NEAR(Dot(velocities[0], n), 0.f, 1e-3f);
  EXPECT_NEAR(velocities[0].x, 10.f - 10.f * n.x * n.x, 1e-3f);
  // The sphere follows its joint: moved by +0.5 in x at the end of the step.
  std::vector<Mat34> start(1), end(1);
  end[0].m[3] = 0.5f;
  ASSERT_TRUE(set.SetPose(start, end).ok());
  const ContactQuery q = set.Query({0.52f, 1.f, 0.f}, {0.52f, 1.f, 0.f});
  EXPECT_TRUE(q.inside_end);
  EXPECT_NEAR(q.depth, 0.08f, 1e-6f);
  EXPECT_NEAR(set.SphereCenter(0, 0.5f).x, 0.25f, 1e-6f);
}

TEST(HullColliderTest, GaussSeidelLeavesParticlesOutsideTwoOverlappingBoxes) {
  // A = [-0.2, 0.2] x [-0.05, 0.05]^2 and B = A shifted by +0.3 in x: overlap x in [0.1, 0.2].
  const HullColliderData a = MakeBox({0.2f, 0.05f, 0.05f});
  const HullColliderData b = MakeBox({0.2f, 0.05f, 0.05f}, {0.3f, 0.f, 0.f});
  HullColliderSet set = BuildSet({a, b}, {}, 1);
  std::mt19937 rng(5);
  std::vector<Float3> previous, positions, velocities;
  for (int i = 0; i < 5000; ++i) {
    const Float3 p = RandomIn(rng, {0.1f, -0.049f, -0.049f}, {0.2f, 0.049f, 0.049f});
    previous.push_back(p);
    positions.push_back(p);
    velocities.push_back({0, 0, 0});
  }
  std::vector<uint8_t> flags(positions.size());
  ResponseParams params;
  params.separation = 1e-5f;
  ASSERT_TRUE(set.CollideBatch(previous, positions, velocities, flags, params).ok());
  for (size_t i = 0; i < positions.size(); ++i) {
    EXPECT_GT(MaxPlane(a, positions[i]), 0.f) << i;
    EXPECT_GT(MaxPlane(b, positions[i]), 0.f) << i;
    // Pushed out through the shared side (y or z), never farther than needed.
    EXPECT_LE(Length(positions[i] - previous[i]), 0.05f + 1e-3f);
  }
}

std::vector<HullColliderData> SceneHulls() {
  std::vector<HullColliderData> hulls;
  for (int i = 0; i < 6; ++i) {
    Float3 axes[3];
    RotatedAxes(20.0 * i, {1.f, float(i), 0.5f}, axes);
    HullColliderData h = MakeEllipsoid({0.05f, 0.12f + 0.01f * float(i), 0.06f}, 1,
                                       {0.12f * float(i), 0.f, 0.f}, axes);
    h.joint = i % 3;
    hulls.push_back(h);
  }
  hulls.push_back(MakeBox({0.1f, 0.1f, 0.02f}, {0.3f, 0.1f, 0.f}));
  return hulls;
}

TEST(HullColliderTest, BatchIsBitwiseIdenticalAtOneAndTwoThreads) {
  const std::vector<HullColliderData> hulls = SceneHulls();
  const std::vector<JointSphereData> spheres = {{1, 0, {0.2f, 0.05f, 0.f}, 0.06f},
                                                {2, 1, {0.5f, -0.05f, 0.f}, 0.05f}};
  HullColliderSet set = BuildSet(hulls, spheres, 3);
  const std::vector<Mat34> start = {Mat34{}, RotationAbout(-10, {0, 1, 0}, {0.2f, 0, 0}), Mat34{}};
  const std::vector<Mat34> end = {RotationAbout(15, {0, 0, 1}, {0, 0, 0}),
                                  RotationAbout(20, {0, 1, 0}, {0.2f, 0, 0}),
                                  RotationAbout(-30, {1, 0, 0}, {0.5f, 0, 0})};
  ASSERT_TRUE(set.SetPose(start, end).ok());
  std::mt19937 rng(9);
  std::vector<Float3> previous, positions, velocities;
  for (int i = 0; i < 30000; ++i) {
    const Float3 p = RandomIn(rng, {-0.15f, -0.2f, -0.15f}, {0.75f, 0.25f, 0.15f});
    previous.push_back(p);
    positions.push_back(p + RandomIn(rng, {-0.02f, -0.02f, -0.02f}, {0.02f, 0.02f, 0.02f}));
    velocities.push_back(RandomIn(rng, {-1, -1, -1}, {1, 1, 1}));
  }
  positions[17].x = std::nanf("");
  ResponseParams params;
  for (float s0 : {0.f, 0.25f}) {
    const float s1 = s0 == 0.f ? 1.f : 0.5f;
    std::vector<Float3> p1 = positions, v1 = velocities, p2 = positions, v2 = velocities;
    std::vector<uint8_t> f1(positions.size()), f2(positions.size());
    uint32_t c1 = 0, c2 = 0;
    omp_set_num_threads(1);
    ASSERT_TRUE(set.CollideBatch(previous, p1, v1, f1, params, s0, s1, &c1).ok());
    omp_set_num_threads(2);
    ASSERT_TRUE(set.CollideBatch(previous, p2, v2, f2, params, s0, s1, &c2).ok());
    EXPECT_EQ(c1, c2);
    EXPECT_GT(c1, 1000u);
    EXPECT_EQ(std::memcmp(p1.data(), p2.data(), p1.size() * sizeof(Float3)), 0);
    EXPECT_EQ(std::memcmp(v1.data(), v2.data(), v1.size() * sizeof(Float3)), 0);
    EXPECT_EQ(f1, f2);
    // The substep fast path (SelectSubstep) gives the same bits as the per-pair interpolation.
    ASSERT_TRUE(set.SelectSubstep(s0, s1).ok());
    std::vector<Float3> p3 = positions, v3 = velocities;
    std::vector<uint8_t> f3(positions.size());
    ASSERT_TRUE(set.CollideBatch(previous, p3, v3, f3, params, s0, s1).ok());
    EXPECT_EQ(std::memcmp(p1.data(), p3.data(), p1.size() * sizeof(Float3)), 0);
    EXPECT_EQ(f1, f3);
    ASSERT_TRUE(set.SelectSubstep(0.f, 1.f).ok());
    // 4-wide (SSE2) plane loops give the same bits as 8-wide (AVX2, when the CPU has it).
    HullColliderOptions narrow;
    narrow.allow_avx2 = false;
    ASSERT_TRUE(set.SetOptions(narrow).ok());
    std::vector<Float3> p4 = positions, v4 = velocities;
    std::vector<uint8_t> f4(positions.size());
    ASSERT_TRUE(set.CollideBatch(previous, p4, v4, f4, params, s0, s1).ok());
    EXPECT_EQ(std::memcmp(p1.data(), p4.data(), p1.size() * sizeof(Float3)), 0);
    EXPECT_EQ(std::memcmp(v1.data(), v4.data(), v1.size() * sizeof(Float3)), 0);
    EXPECT_EQ(f1, f4);
    ASSERT_TRUE(set.SetOptions(HullColliderOptions{}).ok());
  }
}

TEST(HullColliderTest, InvalidInputIsFlaggedAndLeftUntouched) {
  HullColliderSet set = BuildSet({MakeBox({0.1f, 0.1f, 0.1f})}, {}, 1);
  const float nan = std::nanf(""), inf = std::numeric_limits<float>::infinity();
  std::vector<Float3> previous = {{0, 0, 0}, {nan, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  std::vector<Float3> positions = {{0, 0, inf}, {0.01f, 0, 0}, {0.f, 0.f, 0.f}, {0.02f, 0, 0}};
  std::vector<Float3> velocities = {{0, 0, 0}, {0, 0, 0}, {0, nan, 0}, {0, 0, 0}};
  const std::vector<Float3> positions_before = positions;
  std::vector<uint8_t> flags(4);
  uint32_t contacts = 0;
  ASSERT_TRUE(set.CollideBatch(previous, positions, velocities, flags, ResponseParams{}, 0.f, 1.f,
                               &contacts)
                  .ok());
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(flags[i], kCollisionInvalidInput);
    EXPECT_EQ(std::memcmp(&positions[i], &positions_before[i], sizeof(Float3)), 0);
  }
  EXPECT_TRUE(flags[3] & kCollisionContact);
  EXPECT_EQ(contacts, 1u);
  EXPECT_EQ(set.Query({nan, 0, 0}, {0, 0, 0}).flags, kCollisionInvalidInput);
  // Argument errors.
  std::vector<uint8_t> short_flags(3);
  EXPECT_FALSE(
      set.CollideBatch(previous, positions, velocities, short_flags, ResponseParams{}).ok());
  ResponseParams bad;
  bad.friction = 2.f;
  EXPECT_FALSE(set.CollideBatch(previous, positions, velocities, flags, bad).ok());
  EXPECT_FALSE(
      set.CollideBatch(previous, positions, velocities, flags, ResponseParams{}, 0.5f, 0.2f).ok());
}

TEST(HullColliderTest, ResponseAppliesFrictionAndRestitutionOnlyWhenApproaching) {
  HullColliderSet set = BuildSet({MakeBox({0.1f, 0.1f, 0.1f})}, {}, 1);
  ResponseParams params;
  params.friction = 0.25f;
  params.restitution = 0.5f;
  params.separation = 0.f;
  std::vector<Float3> previous = {{0.f, 0.2f, 0.f}, {0.05f, 0.05f, 0.f}};
  std::vector<Float3> positions = {{0.02f, 0.09f, 0.f}, {0.05f, 0.09f, 0.f}};
  std::vector<Float3> velocities = {{1.f, -2.f, 0.f}, {1.f, 2.f, 0.f}};  // approaching, separating
  std::vector<uint8_t> flags(2);
  ASSERT_TRUE(set.CollideBatch(previous, positions, velocities, flags, params).ok());
  EXPECT_NEAR(positions[0].y, 0.1f, 1e-6f);
  EXPECT_NEAR(positions[0].x, 0.02f, 1e-6f);  // projected end: tangential motion kept
  EXPECT_NEAR(velocities[0].x, 0.75f, 1e-6f);
  EXPECT_NEAR(velocities[0].y, 1.f, 1e-6f);  // -(-2) * 0.5
  EXPECT_TRUE(flags[1] & kCollisionStartedInside);
  EXPECT_NEAR(positions[1].y, 0.1f, 1e-6f);  // pushed out through the nearest face (y)
  EXPECT_FLOAT_EQ(velocities[1].x, 1.f);     // separating: unchanged
  EXPECT_FLOAT_EQ(velocities[1].y, 2.f);
}

TEST(HullColliderTest, MapTableRayResponseAndFallback) {
  HullColliderData box = MakeBox({0.1f, 0.2f, 0.05f});
  // A trivially conservative one-cell table: every triangle listed.
  box.map.kind = MapTableKind::kSphere;
  box.map.rows = 1;
  box.map.cols = 1;
  box.map.origin = {0.01f, 0.02f, 0.f};
  box.map.axis = {0, 0, 1};
  box.map.reference = {1, 0, 0};
  box.map.cell_offsets = {0, 12};
  for (uint32_t t = 0; t < 12; ++t) box.map.cell_triangles.push_back(t);
  HullColliderOptions options;
  options.response = HullResponse::kMapTableRay;
  HullColliderSet set = BuildSet({box}, {}, 1, options);
  std::mt19937 rng(2);
  for (int i = 0; i < 5000; ++i) {
    const Float3 p = RandomIn(rng, {-0.099f, -0.199f, -0.049f}, {0.099f, 0.199f, 0.049f});
    const ContactQuery c = set.QueryHullLocal(0, p, p);
    ASSERT_TRUE(c.contact);
    EXPECT_FALSE(c.flags & kCollisionFallback) << i;
    EXPECT_GE(set.MaxPlaneDistanceLocal(0, c.point), 0.f);
    EXPECT_LE(set.MaxPlaneDistanceLocal(0, c.point), 1e-6f);
    // On the ray from the source through p, beyond p.
    const Float3 d = p - box.map.origin, e = c.point - box.map.origin;
    EXPECT_LE(Length(Cross(d, e)), 1e-6f * Length(e));
    EXPECT_GE(Dot(d, e), Dot(d, d));
  }
  // An empty table: every response falls back to the push-out and says so.
  box.map.cell_offsets = {0, 0};
  box.map.cell_triangles.clear();
  HullColliderSet empty = BuildSet({box}, {}, 1, options);
  const ContactQuery c = empty.QueryHullLocal(0, {0.f, 0.f, 0.04f}, {0.f, 0.f, 0.04f});
  EXPECT_TRUE(c.contact);
  EXPECT_TRUE(c.flags & kCollisionFallback);
  EXPECT_NEAR(c.point.z, 0.05f, 1e-6f);
}

TEST(HullColliderTest, QueryReportsInsideDepthAndKinds) {
  HullColliderSet set =
      BuildSet({MakeBox({0.1f, 0.1f, 0.1f})}, {{0, -1, {1.f, 0.f, 0.f}, 0.2f}}, 1);
  ContactQuery q = set.Query({0.f, 0.f, 0.07f}, {0.f, 0.f, 0.07f});
  EXPECT_TRUE(q.inside_end);
  EXPECT_TRUE(q.contact);
  EXPECT_NEAR(q.depth, 0.03f, 1e-6f);
  EXPECT_NEAR(q.point.z, 0.1f, 1e-6f);
  EXPECT_FALSE(set.Query({0.f, 0.f, 0.07f}, {0.f, 0.f, 0.07f}, kColliderSpheres).contact);
  q = set.Query({1.f, 0.1f, 0.f}, {1.f, 0.1f, 0.f}, kColliderSpheres);
  EXPECT_TRUE(q.inside_end);
  EXPECT_NEAR(q.depth, 0.1f, 1e-6f);
  EXPECT_FALSE(set.Query({0.5f, 0.5f, 0.5f}, {0.5f, 0.5f, 0.5f}).contact);
  EXPECT_GT(set.memory_bytes(), 0u);
}

TEST(HullColliderTest, BindFrameAndSkinningPlaceTheCollider) {
  // Collider frame -> asset at bind: translate by (1, 0, 0); skinning rotates 90 degrees about y
  // through the origin: the box centre goes to (0, 0, -1).
  HullColliderData box = MakeBox({0.1f, 0.1f, 0.1f});
  box.bind_frame.m[3] = 1.f;
  HullColliderSet set = BuildSet({box}, {}, 1);
  const std::vector<Mat34> pose = {RotationAbout(90.0, {0, 1, 0}, {0, 0, 0})};
  ASSERT_TRUE(set.SetPose(pose, pose).ok());
  EXPECT_TRUE(set.Query({0.f, 0.f, -1.05f}, {0.f, 0.f, -1.05f}).inside_end);
  EXPECT_FALSE(set.Query({1.f, 0.f, 0.f}, {1.f, 0.f, 0.f}).inside_end);
}

}  // namespace
}  // namespace drape

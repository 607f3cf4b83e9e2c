// Checks of the benchmark peers: FCL's distance against analytic answers and brute force, from
// two threads at once; Bullet's cloth held by a box, deterministic, refusing bad setups. The cost
// of one FCL query is bench/gbench/fcl_mesh_peer_bench.cpp's.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <thread>
#include <utility>
#include <vector>

#include "bullet_cloth_peer.h"
#include "drape/runtime/math.h"
#include "fcl_mesh_peer.h"

namespace drape::peers {
namespace {

struct Mesh {
  std::vector<Float3> positions;
  std::vector<uint32_t> triangles;
};

// The box [-h, h] (12 triangles).
Mesh Box(Float3 h) {
  Mesh m;
  for (int k = 0; k < 8; ++k)
    m.positions.push_back({(k & 1) ? h.x : -h.x, (k & 2) ? h.y : -h.y, (k & 4) ? h.z : -h.z});
  const uint32_t quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& q : quads)
    m.triangles.insert(m.triangles.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  return m;
}

// Unsigned distance from p to the surface of the box [-h, h], and the closest surface point.
double BoxDistance(const double p[3], const double h[3], double closest[3]) {
  bool inside = true;
  for (int a = 0; a < 3; ++a) inside = inside && std::abs(p[a]) <= h[a];
  if (!inside) {
    double sq = 0.0;
    for (int a = 0; a < 3; ++a) {
      closest[a] = std::clamp(p[a], -h[a], h[a]);
      sq += (p[a] - closest[a]) * (p[a] - closest[a]);
    }
    return std::sqrt(sq);
  }
  int axis = 0;
  double best = h[0] - std::abs(p[0]);
  for (int a = 1; a < 3; ++a)
    if (h[a] - std::abs(p[a]) < best) best = h[a] - std::abs(p[a]), axis = a;
  for (int a = 0; a < 3; ++a) closest[a] = p[a];
  closest[axis] = p[axis] < 0.0 ? -h[axis] : h[axis];
  return best;
}

// An icosphere of `radius`: 20 * 4^levels triangles.
Mesh Icosphere(float radius, int levels) {
  Mesh m;
  const float t = (1.f + std::sqrt(5.f)) / 2.f;
  const Float3 base[12] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                           {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                           {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (const Float3& v : base) m.positions.push_back(v * (radius / Length(v)));
  m.triangles = {0, 11, 5,  0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
                 4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3,  4,  2, 3, 2, 6, 3,
                 6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6,  2, 10, 8,  6, 7, 9, 8, 1};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;
    const auto midpoint = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto found = midpoints.find(key);
      if (found != midpoints.end()) return found->second;
      const Float3 mid = (m.positions[a] + m.positions[b]) * 0.5f;
      m.positions.push_back(mid * (radius / Length(mid)));
      const uint32_t index = static_cast<uint32_t>(m.positions.size() - 1);
      midpoints.emplace(key, index);
      return index;
    };
    std::vector<uint32_t> next;
    for (size_t f = 0; f < m.triangles.size(); f += 3) {
      const uint32_t a = m.triangles[f], b = m.triangles[f + 1], c = m.triangles[f + 2];
      const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    m.triangles = std::move(next);
  }
  return m;
}

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5), in double.
void ClosestOnTriangle(const double p[3], const double a[3], const double b[3], const double c[3],
                       double out[3]) {
  const auto sub = [](const double* u, const double* v, double* r) {
    for (int i = 0; i < 3; ++i) r[i] = u[i] - v[i];
  };
  const auto dot = [](const double* u, const double* v) {
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
  };
  const auto set = [&](double s, double t) {  // a + s (b - a) + t (c - a)
    for (int i = 0; i < 3; ++i) out[i] = a[i] + s * (b[i] - a[i]) + t * (c[i] - a[i]);
  };
  double ab[3], ac[3], ap[3], bp[3], cp[3];
  sub(b, a, ab);
  sub(c, a, ac);
  sub(p, a, ap);
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return set(0, 0);
  sub(p, b, bp);
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return set(1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return set(d1 / (d1 - d3), 0);
  sub(p, c, cp);
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return set(0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return set(0, d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return set(1 - w, w);
  }
  const double denom = 1.0 / (va + vb + vc);
  return set(vb * denom, vc * denom);
}

double BruteForceDistance(const Mesh& m, Float3 q) {
  const double p[3] = {q.x, q.y, q.z};
  double best = INFINITY;
  for (size_t f = 0; f < m.triangles.size(); f += 3) {
    double v[3][3], c[3];
    for (int k = 0; k < 3; ++k) {
      const Float3 x = m.positions[m.triangles[f + static_cast<size_t>(k)]];
      v[k][0] = x.x, v[k][1] = x.y, v[k][2] = x.z;
    }
    ClosestOnTriangle(p, v[0], v[1], v[2], c);
    best = std::min(best, std::sqrt((p[0] - c[0]) * (p[0] - c[0]) + (p[1] - c[1]) * (p[1] - c[1]) +
                                    (p[2] - c[2]) * (p[2] - c[2])));
  }
  return best;
}

TEST(FclMeshPeer, BoxDistanceMatchesAnalytic) {
  // Dyadic half extents and sample points: every input is exact in float, so the only error is
  // FCL's double arithmetic.
  const Float3 half{0.25f, 0.5f, 0.125f};
  const Mesh box = Box(half);
  const FclMeshPeer peer(box.positions, box.triangles);
  ASSERT_EQ(peer.triangle_count(), 12u);
  EXPECT_GT(peer.memory_bytes(), 0u);
  const double h[3] = {half.x, half.y, half.z};
  std::mt19937_64 rng(20240605);
  std::uniform_real_distribution<float> coordinate(-1.f, 1.f);
  int inside = 0;
  for (int i = 0; i < 4000; ++i) {
    const Float3 p{coordinate(rng), coordinate(rng), coordinate(rng)};
    const double pd[3] = {p.x, p.y, p.z};
    double expected_closest[3];
    const double expected = BoxDistance(pd, h, expected_closest);
    if (expected < 1e-4) continue;  // on the surface FCL's zero-radius sphere test is undefined
    inside += std::abs(p.x) < h[0] && std::abs(p.y) < h[1] && std::abs(p.z) < h[2];
    Float3 closest;
    const double distance = peer.Distance(p, &closest);
    ASSERT_NEAR(distance, expected, 1e-6) << "point " << p.x << " " << p.y << " " << p.z;
    EXPECT_NEAR(closest.x, expected_closest[0], 1e-6);
    EXPECT_NEAR(closest.y, expected_closest[1], 1e-6);
    EXPECT_NEAR(closest.z, expected_closest[2], 1e-6);
    EXPECT_NEAR(peer.Distance(p, nullptr), expected, 1e-6);
  }
  EXPECT_GT(inside, 20);  // the interior (unsigned distance to the nearest face) was sampled
}

TEST(FclMeshPeer, MalformedMeshGivesInfinity) {
  const std::vector<Float3> positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<uint32_t> out_of_range = {0, 1, 3};
  EXPECT_TRUE(std::isinf(FclMeshPeer(positions, out_of_range).Distance({0, 0, 1}, nullptr)));
  EXPECT_TRUE(std::isinf(FclMeshPeer(positions, {}).Distance({0, 0, 1}, nullptr)));
}

// Distance is const and keeps no scratch: two threads querying at once get the serial answers.
TEST(FclMeshPeer, ConcurrentQueriesMatchSerial) {
  const Mesh sphere = Icosphere(0.5f, 3);
  const FclMeshPeer peer(sphere.positions, sphere.triangles);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<float> coordinate(-0.8f, 0.8f);
  std::vector<Float3> points(4000);
  for (Float3& p : points) p = {coordinate(rng), coordinate(rng), coordinate(rng)};
  std::vector<double> serial(points.size()), parallel(points.size());
  for (size_t i = 0; i < points.size(); ++i) serial[i] = peer.Distance(points[i], nullptr);
  const auto run = [&](size_t begin) {
    for (size_t i = begin; i < points.size(); i += 2)
      parallel[i] = peer.Distance(points[i], nullptr);
  };
  std::thread other(run, size_t{1});
  run(0);
  other.join();
  EXPECT_EQ(serial, parallel);
}

TEST(FclMeshPeer, IcosphereDistanceNearTheSurfaceMatchesBruteForce) {
  const Mesh sphere = Icosphere(0.5f, 5);  // 20480 triangles, 10242 vertices
  ASSERT_EQ(sphere.triangles.size(), 3u * 20480u);
  const FclMeshPeer peer(sphere.positions, sphere.triangles);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> unit(-1.f, 1.f);
  // Points at radius 0.5 +- band: inside and outside, near the surface (as cloth particles are).
  const auto sample = [&](float band) {
    std::uniform_real_distribution<float> radius(0.5f - band, 0.5f + band);
    std::vector<Float3> points;
    while (points.size() < 20000) {
      const Float3 d{unit(rng), unit(rng), unit(rng)};
      const float len = Length(d);
      if (len < 0.1f || len > 1.f) continue;
      points.push_back(d * (radius(rng) / len));
    }
    return points;
  };
  for (const float band : {0.01f, 0.15f}) {
    const std::vector<Float3> points = sample(band);
    for (size_t i = 0; i < points.size(); i += 200)
      ASSERT_NEAR(peer.Distance(points[i], nullptr), BruteForceDistance(sphere, points[i]), 1e-6);
  }
}

// A 0.6 m sheet of 21 x 21 particles at y = 0.2 m, 10 g per particle, its first corner attached.
BulletClothSetup Sheet() {
  BulletClothSetup setup;
  const int cells = 20;
  const float size = 0.6f;
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i)
      setup.positions.push_back({-size / 2 + size * static_cast<float>(i) / cells, 0.2f,
                                 -size / 2 + size * static_cast<float>(j) / cells});
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i) {
      const uint32_t a = static_cast<uint32_t>(j * (cells + 1) + i);
      const uint32_t b = a + 1, c = a + static_cast<uint32_t>(cells + 1), d = c + 1;
      setup.triangles.insert(setup.triangles.end(), {a, b, d, a, d, c});
    }
  setup.inverse_masses.assign(setup.positions.size(), 100.f);
  setup.inverse_masses[0] = 0.f;  // one attached corner
  return setup;
}

// A sheet dropped onto a box: Bullet's cloth builds, keeps its attached corner on target and is
// held by the box.
TEST(BulletClothPeer, SheetOnBoxIsHeld) {
  const BulletClothSetup setup = Sheet();
  BulletHullShape box;
  const Mesh box_mesh = Box({0.1f, 0.1f, 0.1f});
  box.local_vertices = box_mesh.positions;
  const std::vector<BulletHullShape> hulls = {box};
  const std::vector<float> radii = {0.05f};
  BulletClothPeer peer;
  ASSERT_TRUE(peer.Build(setup, hulls, radii).ok());
  ASSERT_EQ(peer.particle_count(), setup.positions.size());
  ASSERT_EQ(peer.attached_count(), 1u);
  const std::vector<Mat34> hull_pose(1);
  const std::vector<Float3> sphere_centre = {{0.2f, 0.f, 0.2f}};
  ASSERT_TRUE(peer.SetInitialPose(hull_pose, sphere_centre).ok());
  const std::vector<Float3> target = {setup.positions[0]};
  for (int frame = 0; frame < 60; ++frame)
    ASSERT_TRUE(peer.Step(hull_pose, sphere_centre, target, 1.f / 60.f).ok());
  std::vector<Float3> x(peer.particle_count());
  peer.CopyPositions(x);
  EXPECT_EQ(x[0].x, target[0].x);
  EXPECT_EQ(x[0].y, target[0].y);
  float max_depth = 0.f;
  size_t on_top = 0;
  for (const Float3& p : x) {
    const float depth =
        std::min({0.1f - std::abs(p.x), 0.1f - std::abs(p.y), 0.1f - std::abs(p.z)});
    max_depth = std::max(max_depth, depth);
    on_top += std::abs(p.x) < 0.09f && std::abs(p.z) < 0.09f && p.y > 0.09f && p.y < 0.13f;
  }
  // Bullet's contacts are found once per step and its links are solved after them, so where the
  // sheet wraps the box's edges nodes end up to about 2 cm inside (2.1 cm measured: under one
  // 3 cm cell). Bullet's default kinematic hardness (kKHR 0.1) lets the sheet fall through.
  EXPECT_LT(max_depth, 0.03f) << on_top << " particles resting on top";
  EXPECT_GT(on_top, 20u) << "max depth " << max_depth << " m";
  // Wrong counts are refused.
  EXPECT_FALSE(peer.Step(hull_pose, {}, target, 1.f / 60.f).ok());
  EXPECT_FALSE(peer.Step(hull_pose, sphere_centre, {}, 1.f / 60.f).ok());
}

// Two runs of the same scene give bitwise the same positions (Bullet single-threaded, its link
// shuffle a fixed sequence).
TEST(BulletClothPeer, Deterministic) {
  const BulletClothSetup setup = Sheet();
  BulletHullShape box;
  box.local_vertices = Box({0.1f, 0.1f, 0.1f}).positions;
  const std::vector<BulletHullShape> hulls = {box};
  const std::vector<float> radii = {0.05f};
  std::vector<Float3> runs[2];
  for (std::vector<Float3>& x : runs) {
    BulletClothPeer peer;
    ASSERT_TRUE(peer.Build(setup, hulls, radii).ok());
    for (int frame = 0; frame < 30; ++frame) {
      // The box turns about y and rises: kinematic motion with rotation.
      Mat34 pose;
      const float angle = 0.05f * static_cast<float>(frame), c = std::cos(angle),
                  s = std::sin(angle);
      pose.m[0] = c, pose.m[2] = s, pose.m[8] = -s, pose.m[10] = c;
      pose.m[7] = 0.002f * static_cast<float>(frame);
      const std::vector<Mat34> hull_pose = {pose};
      const std::vector<Float3> centre = {{0.2f, 0.f, 0.2f}}, target = {setup.positions[0]};
      ASSERT_TRUE(peer.Step(hull_pose, centre, target, 1.f / 60.f).ok());
    }
    x.resize(peer.particle_count());
    peer.CopyPositions(x);
  }
  for (size_t i = 0; i < runs[0].size(); ++i) {
    ASSERT_EQ(runs[0][i].x, runs[1][i].x) << i;
    ASSERT_EQ(runs[0][i].y, runs[1][i].y) << i;
    ASSERT_EQ(runs[0][i].z, runs[1][i].z) << i;
  }
}

TEST(BulletClothPeer, RejectsBadSetups) {
  BulletClothPeer peer;
  BulletClothSetup setup = Sheet();
  setup.triangles.push_back(0);
  EXPECT_EQ(peer.Build(setup, {}, {}).code(), StatusCode::kInvalidArgument);
  setup = Sheet();
  setup.triangles[5] = 9999;
  EXPECT_EQ(peer.Build(setup, {}, {}).code(), StatusCode::kInvalidArgument);
  setup = Sheet();
  setup.inverse_masses.pop_back();
  EXPECT_EQ(peer.Build(setup, {}, {}).code(), StatusCode::kInvalidArgument);
  setup = Sheet();
  setup.positions.push_back({0.f, 0.f, 0.f});  // in no triangle
  setup.inverse_masses.push_back(1.f);
  EXPECT_EQ(peer.Build(setup, {}, {}).code(), StatusCode::kInvalidArgument);
  const std::vector<BulletHullShape> flat = {BulletHullShape{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}};
  EXPECT_EQ(peer.Build(Sheet(), flat, {}).code(), StatusCode::kInvalidArgument);
  const std::vector<float> bad_radius = {0.f};
  EXPECT_EQ(peer.Build(Sheet(), {}, bad_radius).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(peer.Step({}, {}, {}, 1.f / 60.f).code(), StatusCode::kInvalidState);
  ASSERT_TRUE(peer.Build(Sheet(), {}, {}).ok());
  const std::vector<Float3> target = {{0.f, 0.f, 0.f}};
  EXPECT_EQ(peer.Step({}, {}, target, 0.f).code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(peer.Step({}, {}, target, 1.f / 60.f).ok());
}

}  // namespace
}  // namespace drape::peers

// Tests of paper A's body map bake (drape/bake/body_map_baker.h) against analytic shapes: depth
// at texel centres, normals, coverage, the un-mirrored back map, encodings, the OSMesa path
// against the CPU reference, degenerate input, determinism, the PNG previews, and the row-span
// layout against the dense one (same maps, same runtime answers, the mannequin's bytes).

#include "drape/bake/body_map_baker.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "drape/bake/bake_config.h"
#include "drape/bake/bake_pipeline.h"
#include "drape/runtime/body_map_collider.h"
#include "octahedron_sphere.h"
#include "test_support.h"

namespace drape::bake {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180.0;

struct Mesh {
  std::vector<Float3> positions;
  std::vector<uint32_t> triangles;
};

struct Vec3d {
  double x = 0, y = 0, z = 0;
};
Vec3d ToD(Float3 p) { return {p.x, p.y, p.z}; }
Vec3d Sub(Vec3d a, Vec3d b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3d Add(Vec3d a, Vec3d b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec3d Scale(Vec3d a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double Dot(Vec3d a, Vec3d b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3d Cross(Vec3d a, Vec3d b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double Len(Vec3d a) { return std::sqrt(Dot(a, a)); }
double AngleDeg(Vec3d a, Vec3d b) {
  const double c = Dot(a, b) / (Len(a) * Len(b));
  return std::acos(std::clamp(c, -1.0, 1.0)) / kDegree;
}

// Appends a triangle wound counter-clockwise seen from outside, where "outside" is the direction
// `outward` (the shapes here are convex, so centroid minus an interior point works).
void AddOutwardTriangle(Mesh* m, uint32_t a, uint32_t b, uint32_t c, Vec3d outward) {
  const Vec3d pa = ToD(m->positions[a]), pb = ToD(m->positions[b]), pc = ToD(m->positions[c]);
  const Vec3d n = Cross(Sub(pb, pa), Sub(pc, pa));
  if (Dot(n, outward) >= 0.0) {
    m->triangles.insert(m->triangles.end(), {a, b, c});
  } else {
    m->triangles.insert(m->triangles.end(), {a, c, b});
  }
}

// A UV capsule around the y axis through `centre`: hemispheres of radius r joined by a cylinder
// of half-length `half_length` (0 gives a UV sphere). `stacks` (even) rings from pole to pole,
// `slices` around. Triangles: 2 * slices * (stacks - 1) for the sphere, + 2 * slices for the
// cylinder band.
Mesh MakeCapsule(Vec3d centre, double r, double half_length, int stacks, int slices) {
  Mesh m;
  std::vector<double> ring_theta, ring_shift;
  for (int k = 1; k < stacks; ++k) {
    const double theta = kPi * k / stacks;
    if (half_length > 0.0 && 2 * k == stacks) {
      ring_theta.insert(ring_theta.end(), {theta, theta});
      ring_shift.insert(ring_shift.end(), {half_length, -half_length});
    } else {
      ring_theta.push_back(theta);
      ring_shift.push_back(2 * k < stacks ? half_length : -half_length);
    }
  }
  auto add = [&](double x, double y, double z) {
    m.positions.push_back({static_cast<float>(centre.x + x), static_cast<float>(centre.y + y),
                           static_cast<float>(centre.z + z)});
  };
  add(0, r + half_length, 0);  // top pole
  for (size_t k = 0; k < ring_theta.size(); ++k) {
    for (int s = 0; s < slices; ++s) {
      const double phi = 2 * kPi * s / slices;
      add(r * std::sin(ring_theta[k]) * std::cos(phi), r * std::cos(ring_theta[k]) + ring_shift[k],
          r * std::sin(ring_theta[k]) * std::sin(phi));
    }
  }
  add(0, -r - half_length, 0);  // bottom pole
  const uint32_t rings = static_cast<uint32_t>(ring_theta.size());
  const uint32_t bottom = 1 + rings * static_cast<uint32_t>(slices);
  auto ring_vertex = [&](uint32_t k, int s) {
    return 1 + k * static_cast<uint32_t>(slices) + static_cast<uint32_t>(s % slices);
  };
  // Outward direction: from the closest point of the axis segment to the triangle centroid.
  auto outward = [&](uint32_t a, uint32_t b, uint32_t c) {
    const Vec3d g =
        Scale(Add(Add(ToD(m.positions[a]), ToD(m.positions[b])), ToD(m.positions[c])), 1.0 / 3.0);
    const double axis_y = std::clamp(g.y - centre.y, -half_length, half_length) + centre.y;
    return Sub(g, Vec3d{centre.x, axis_y, centre.z});
  };
  auto tri = [&](uint32_t a, uint32_t b, uint32_t c) {
    AddOutwardTriangle(&m, a, b, c, outward(a, b, c));
  };
  for (int s = 0; s < slices; ++s) tri(0, ring_vertex(0, s), ring_vertex(0, s + 1));
  for (uint32_t k = 0; k + 1 < rings; ++k) {
    for (int s = 0; s < slices; ++s) {
      tri(ring_vertex(k, s), ring_vertex(k + 1, s), ring_vertex(k + 1, s + 1));
      tri(ring_vertex(k, s), ring_vertex(k + 1, s + 1), ring_vertex(k, s + 1));
    }
  }
  for (int s = 0; s < slices; ++s)
    tri(bottom, ring_vertex(rings - 1, s + 1), ring_vertex(rings - 1, s));
  return m;
}

Mesh MakeSphere(Vec3d centre, double r, int stacks, int slices) {
  return MakeCapsule(centre, r, 0.0, stacks, slices);
}

// An axis-aligned box with separate vertices per face (24 vertices, 12 triangles), so every
// vertex normal is exactly its face normal and the epsilon offset moves each face by epsilon.
void AddSplitBox(Mesh* m, Vec3d lo, Vec3d hi) {
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      const uint32_t base = static_cast<uint32_t>(m->positions.size());
      for (int corner = 0; corner < 4; ++corner) {
        double c[3];
        const double l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
        c[axis] = side ? h[axis] : l[axis];
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        c[u] = (corner == 1 || corner == 2) ? h[u] : l[u];
        c[v] = (corner >= 2) ? h[v] : l[v];
        m->positions.push_back(
            {static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2])});
      }
      Vec3d out;
      (axis == 0 ? out.x : axis == 1 ? out.y : out.z) = side ? 1.0 : -1.0;
      AddOutwardTriangle(m, base, base + 1, base + 2, out);
      AddOutwardTriangle(m, base, base + 2, base + 3, out);
    }
  }
}

// The epsilon-offset vertices, computed as body_map_baker.h specifies (area-weighted normals).
std::vector<Vec3d> OffsetVertices(const Mesh& m, double epsilon, std::vector<Vec3d>* normals) {
  std::vector<Vec3d> n(m.positions.size());
  for (size_t t = 0; t < m.triangles.size(); t += 3) {
    const Vec3d a = ToD(m.positions[m.triangles[t]]), b = ToD(m.positions[m.triangles[t + 1]]),
                c = ToD(m.positions[m.triangles[t + 2]]);
    const Vec3d f = Cross(Sub(b, a), Sub(c, a));
    for (int k = 0; k < 3; ++k) n[m.triangles[t + k]] = Add(n[m.triangles[t + k]], f);
  }
  std::vector<Vec3d> q(m.positions.size());
  for (size_t v = 0; v < n.size(); ++v) {
    const double l = Len(n[v]);
    n[v] = l > 0 ? Scale(n[v], 1.0 / l) : Vec3d{};
    q[v] = Add(ToD(m.positions[v]), Scale(n[v], epsilon));
  }
  if (normals != nullptr) *normals = n;
  return q;
}

// Distance from point p to triangle abc (Ericson, Real-Time Collision Detection 5.1.5).
double PointTriangleDistance(Vec3d p, Vec3d a, Vec3d b, Vec3d c) {
  const Vec3d ab = Sub(b, a), ac = Sub(c, a), ap = Sub(p, a);
  const double d1 = Dot(ab, ap), d2 = Dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return Len(ap);
  const Vec3d bp = Sub(p, b);
  const double d3 = Dot(ab, bp), d4 = Dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return Len(bp);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return Len(Sub(p, Add(a, Scale(ab, d1 / (d1 - d3)))));
  const Vec3d cp = Sub(p, c);
  const double d5 = Dot(ab, cp), d6 = Dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return Len(cp);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return Len(Sub(p, Add(a, Scale(ac, d2 / (d2 - d6)))));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    return Len(Sub(p, Add(b, Scale(Sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))))));
  }
  const double denom = 1.0 / (va + vb + vc);
  return Len(Sub(p, Add(a, Add(Scale(ab, vb * denom), Scale(ac, vc * denom)))));
}

// Sag of the offset sphere mesh below the sphere of radius r_outer: r_outer minus the smallest
// distance from the centre to any offset triangle.
double SphereSag(const Mesh& m, const std::vector<Vec3d>& q, Vec3d centre, double r_outer) {
  double min_distance = std::numeric_limits<double>::infinity();
  for (size_t t = 0; t < m.triangles.size(); t += 3) {
    min_distance =
        std::min(min_distance, PointTriangleDistance(centre, q[m.triangles[t]],
                                                     q[m.triangles[t + 1]], q[m.triangles[t + 2]]));
  }
  return r_outer - min_distance;
}

// Largest angle between a vertex normal and the analytic normal at that (offset) vertex,
// degrees. `axis_point` maps a point to the centre of its osculating sphere or cylinder.
template <typename AxisPoint>
double MaxVertexNormalDeviationDeg(const std::vector<Vec3d>& q, const std::vector<Vec3d>& normals,
                                   AxisPoint axis_point) {
  double deviation = 0.0;
  for (size_t v = 0; v < q.size(); ++v) {
    deviation = std::max(deviation, AngleDeg(normals[v], Sub(q[v], axis_point(q[v]))));
  }
  return deviation;
}

// Why the normal tolerance is what it is: when every vertex normal is radial, the interpolated
// normal sum(lambda_k n_k) is parallel to p_tri - centre, the radial direction of the rasterized
// point p_tri itself. The analytic normal is taken at the outer surface point above the same
// texel, which differs from p_tri only along z, by at most z_outer - z_inner: an angle of at most
// (z_outer - z_inner) / r_inner as seen from the centre. Non-radial vertex normals add at most
// their deviation. So: tolerance = deviation + (z_outer - z_inner) / r_inner + float rounding.
double NormalToleranceDeg(double vertex_deviation_deg, double z_outer, double z_inner,
                          double r_inner) {
  return vertex_deviation_deg + (z_outer - z_inner) / r_inner / kDegree + 0.01;
}

Vec3d TexelCentre(const BodyMapPose& pose, uint32_t i, uint32_t j) {
  return {pose.origin_x + (i + 0.5) * double(pose.texel_size),
          pose.origin_y + (j + 0.5) * double(pose.texel_size), 0.0};
}
Vec3d ToD3(Float3 n) { return {n.x, n.y, n.z}; }

BodyMapOptions FloatOptions(uint32_t resolution) {
  BodyMapOptions o;
  o.resolution = resolution;
  o.depth_encoding = DepthEncoding::kFloat32;
  o.normal_encoding = NormalEncoding::kFloat32;
  return o;
}

// Float32 options (or unorm16 depth and `compact_normals` when `compact`) in the dense layout with
// `layers` depth layers: the gap tests read texels by their dense index.
BodyMapOptions DenseGapOptions(uint32_t resolution, uint8_t layers, bool compact = false,
                               NormalEncoding compact_normals = NormalEncoding::kOct16) {
  BodyMapOptions o = FloatOptions(resolution);
  if (compact) {
    o.depth_encoding = DepthEncoding::kUnorm16;
    o.normal_encoding = compact_normals;
  }
  o.layout = BodyMapLayout::kDense;
  o.layers = layers;
  return o;
}

BodyMapPose BakeOrDie(const Mesh& m, const BodyMapOptions& o, BodyMapPoseStats* stats = nullptr) {
  BodyMapPose pose;
  const Status status = BakeBodyMapPose(m.positions, m.triangles, o, &pose, stats);
  EXPECT_TRUE(status.ok()) << status.message();
  return pose;
}

// Bit patterns: the two layouts must give the very same floats, not merely close ones.
uint32_t Bits(float v) { return std::bit_cast<uint32_t>(v); }
bool SameBits(Float3 a, Float3 b) {
  return Bits(a.x) == Bits(b.x) && Bits(a.y) == Bits(b.y) && Bits(a.z) == Bits(b.z);
}
bool SameBits(const ContactQuery& a, const ContactQuery& b) {
  return a.inside_end == b.inside_end && a.contact == b.contact && Bits(a.t) == Bits(b.t) &&
         SameBits(a.point, b.point) && SameBits(a.normal, b.normal) &&
         Bits(a.depth) == Bits(b.depth) && a.flags == b.flags;
}

// Bytes of the row-span table (BodyMapPoseStats::bytes counts them).
size_t SpanTableBytes(const BodyMapPose& p) {
  return p.row_span_offsets.size() * 4 + p.span_begin.size() * 2 + p.span_texel_offsets.size() * 4;
}

// ---------------------------------------------------------------------------------------------

TEST(BodyMapBaker, SphereDepthCoverageAndNormalsMatchAnalytic) {
  const Vec3d c{0.05, 1.0, -0.02};
  const double r = 0.3;
  const Mesh sphere = MakeSphere(c, r, 50, 50);  // 4900 triangles
  ASSERT_EQ(sphere.triangles.size() / 3, 4900u);
  BodyMapOptions o = FloatOptions(512);
  BodyMapPoseStats stats;
  const BodyMapPose pose = BakeOrDie(sphere, o, &stats);
  ASSERT_GT(pose.width, 0u);

  std::vector<Vec3d> normals;
  const std::vector<Vec3d> q = OffsetVertices(sphere, o.epsilon, &normals);
  const double r_outer = r + o.epsilon;
  const double sag = SphereSag(sphere, q, c, r_outer);
  const double vertex_deviation_deg =
      MaxVertexNormalDeviationDeg(q, normals, [&](Vec3d) { return c; });
  ASSERT_GT(sag, 0.0);
  ASSERT_LT(sag, 2e-3);  // the tessellation is what we think it is
  const double r_inner = r_outer - sag;
  const double back_z = double(pose.front_z) - double(pose.depth_range);
  const double t = pose.texel_size;

  // The square window of paper A: side = 2 r' + 2 margin, N texels.
  EXPECT_NEAR(t, (2 * r_outer + 2 * o.margin) / o.resolution, 1e-4 * t);
  EXPECT_EQ(stats.window_width, o.resolution);
  EXPECT_EQ(stats.window_height, o.resolution);
  EXPECT_EQ(stats.silhouette_conflicts, 0u);  // one rasterizer, same texel centres: no conflict

  size_t checked_depth = 0, checked_normals = 0, valid = 0;
  double max_central_depth_error = 0.0, max_normal_error_deg = 0.0;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      const Vec3d p = TexelCentre(pose, i, j);
      const double rho = std::hypot(p.x - c.x, p.y - c.y);
      const BodyMapTexel front = ReadBodyMapTexel(pose, 0, i, j);
      const BodyMapTexel back = ReadBodyMapTexel(pose, 1, i, j);
      ASSERT_EQ(front.valid, back.valid) << i << "," << j;
      valid += front.valid ? 1 : 0;
      // Coverage: the inner ball always projects under the mesh, nothing lies beyond r'.
      if (rho < r_inner - 1e-6) {
        EXPECT_TRUE(front.valid) << i << "," << j << " rho " << rho;
      }
      if (rho > r_outer + 1e-6) {
        EXPECT_FALSE(front.valid) << i << "," << j << " rho " << rho;
      }
      if (!front.valid || rho >= r_inner - 1e-6) continue;
      // The visible surface lies between the inner and the outer sphere along z.
      const double z_outer = std::sqrt(r_outer * r_outer - rho * rho);
      const double z_inner = std::sqrt(r_inner * r_inner - rho * rho);
      const double front_lo = double(pose.front_z) - (c.z + z_outer);
      const double front_hi = double(pose.front_z) - (c.z + z_inner);
      const double back_lo = (c.z - z_outer) - back_z;
      const double back_hi = (c.z - z_inner) - back_z;
      constexpr double kRounding = 2e-6;  // float storage of metres-scale values and origins
      EXPECT_GE(front.depth, front_lo - kRounding) << i << "," << j;
      EXPECT_LE(front.depth, front_hi + kRounding) << i << "," << j;
      EXPECT_GE(back.depth, back_lo - kRounding) << i << "," << j;
      EXPECT_LE(back.depth, back_hi + kRounding) << i << "," << j;
      if (z_outer >= 0.9 * r_outer) {
        max_central_depth_error =
            std::max(max_central_depth_error, std::fabs(front.depth - front_lo));
      }
      ++checked_depth;
      // Normals: the analytic outward normal at the analytic surface point above the texel.
      const Vec3d n_front{p.x - c.x, p.y - c.y, z_outer};
      const Vec3d n_back{p.x - c.x, p.y - c.y, -z_outer};
      if (n_front.z / r_outer >= 0.3) {
        const double tolerance_deg =
            NormalToleranceDeg(vertex_deviation_deg, z_outer, z_inner, r_inner);
        const double front_error = AngleDeg(ToD3(front.normal), n_front);
        const double back_error = AngleDeg(ToD3(back.normal), n_back);
        EXPECT_LE(front_error, tolerance_deg) << i << "," << j;
        EXPECT_LE(back_error, tolerance_deg) << i << "," << j;
        max_normal_error_deg = std::max({max_normal_error_deg, front_error, back_error});
        EXPECT_NEAR(Len(ToD3(front.normal)), 1.0, 1e-6);
        ++checked_normals;
      }
    }
  }
  // The covered area is between the inner and the outer disc (plus a texel of outline).
  const double area_texels = double(valid) * t * t;
  EXPECT_GE(area_texels, kPi * r_inner * r_inner - 2 * kPi * r_inner * t);
  EXPECT_LE(area_texels, kPi * r_outer * r_outer + 2 * kPi * r_outer * t);
  EXPECT_NEAR(stats.coverage, double(valid) / (double(o.resolution) * o.resolution), 1e-6);
  EXPECT_EQ(stats.valid_texels, valid);
  EXPECT_GT(checked_depth, 0.8 * kPi * r * r / (t * t));
  EXPECT_GT(checked_normals, 0.5 * kPi * r * r / (t * t));
  // Near the view axis (n.z >= 0.9) the depth is within sag / 0.9 of the analytic sphere.
  EXPECT_LE(max_central_depth_error, sag / 0.9 + 2e-6);
  EXPECT_LT(max_normal_error_deg, 2.0);  // "within a few degrees" (measured about 0.6)
  std::printf(
      "[ sphere 4.9k N=512 ] sag %.3g m, vertex normal deviation %.3f deg, max normal "
      "error %.3f deg, max central depth error %.3g m\n",
      sag, vertex_deviation_deg, max_normal_error_deg, max_central_depth_error);
}

TEST(BodyMapBaker, NothingIsClippedAndThePlanesEncloseTheOffsetSurface) {
  const Vec3d c{0.0, 0.0, 0.4};
  const double r = 0.3;
  const Mesh sphere = MakeSphere(c, r, 50, 50);
  BodyMapOptions o = FloatOptions(256);
  o.epsilon = 0.02f;  // a large offset makes clipping visible if the box were not enlarged
  const BodyMapPose pose = BakeOrDie(sphere, o);
  const std::vector<Vec3d> q = OffsetVertices(sphere, o.epsilon, nullptr);
  double z_min = 1e9, z_max = -1e9;
  for (const Vec3d& p : q) {
    z_min = std::min(z_min, p.z);
    z_max = std::max(z_max, p.z);
  }
  // The planes sit margin beyond the offset surface, rounded outward to float.
  EXPECT_GE(double(pose.front_z), z_max + o.margin);
  EXPECT_LE(double(pose.front_z), z_max + o.margin + 1e-6);
  const double back_z = double(pose.front_z) - double(pose.depth_range);
  EXPECT_LE(back_z, z_min - o.margin);
  EXPECT_GE(back_z, z_min - o.margin - 2e-6);
  float min_front = 1e9f, min_back = 1e9f, max_depth = 0.f;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      for (int view = 0; view < 2; ++view) {
        const BodyMapTexel texel = ReadBodyMapTexel(pose, view, i, j);
        if (!texel.valid) continue;
        (view == 0 ? min_front : min_back) =
            std::min(view == 0 ? min_front : min_back, texel.depth);
        max_depth = std::max(max_depth, texel.depth);
      }
    }
  }
  // The extreme points of the offset sphere are in the maps, a margin away from each plane.
  const double sag = SphereSag(sphere, q, c, r + o.epsilon);
  EXPECT_GE(min_front, o.margin - 1e-6);
  EXPECT_LE(min_front, o.margin + sag + 1e-5);
  EXPECT_GE(min_back, o.margin - 1e-6);
  EXPECT_LE(min_back, o.margin + sag + 1e-5);
  EXPECT_LT(max_depth, pose.depth_range);
  // One texel of background border all around the stored rectangle, and covered texels next to it.
  bool border_valid = false, inner_row_valid = false;
  for (uint32_t i = 0; i < pose.width; ++i) {
    border_valid |= ReadBodyMapTexel(pose, 0, i, 0).valid;
    border_valid |= ReadBodyMapTexel(pose, 0, i, pose.height - 1).valid;
    inner_row_valid |= ReadBodyMapTexel(pose, 0, i, 1).valid;
  }
  for (uint32_t j = 0; j < pose.height; ++j) {
    border_valid |= ReadBodyMapTexel(pose, 0, 0, j).valid;
    border_valid |= ReadBodyMapTexel(pose, 0, pose.width - 1, j).valid;
  }
  EXPECT_FALSE(border_valid);
  EXPECT_TRUE(inner_row_valid);
}

TEST(BodyMapBaker, SplitBoxGivesExactDepthNormalsAndCoverage) {
  Mesh box;
  const Vec3d lo{-0.2013, -0.3107, 0.1031}, hi{0.1517, 0.4291, 0.3543};
  AddSplitBox(&box, lo, hi);
  BodyMapOptions o = FloatOptions(300);
  BodyMapPoseStats stats;
  const BodyMapPose pose = BakeOrDie(box, o, &stats);
  const double eps = o.epsilon;
  double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9, z0 = 1e9, z1 = -1e9;
  for (Float3 p : box.positions) {
    x0 = std::min(x0, double(p.x));
    x1 = std::max(x1, double(p.x));
    y0 = std::min(y0, double(p.y));
    y1 = std::max(y1, double(p.y));
    z0 = std::min(z0, double(p.z));
    z1 = std::max(z1, double(p.z));
  }
  // Window: square, side max(L', H') with L' = L + 2 eps + 2 margin.
  const double side = std::max(x1 - x0, y1 - y0) + 2 * eps + 2 * o.margin;
  EXPECT_NEAR(pose.texel_size, side / o.resolution, 1e-6 * side / o.resolution);
  const double t = pose.texel_size;
  const double back_z = double(pose.front_z) - double(pose.depth_range);
  size_t valid = 0;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      const Vec3d p = TexelCentre(pose, i, j);
      const BodyMapTexel front = ReadBodyMapTexel(pose, 0, i, j);
      const BodyMapTexel back = ReadBodyMapTexel(pose, 1, i, j);
      // The side faces are edge-on: exactly the texel centres over the x,y rectangle are covered.
      const double inset = std::min({p.x - x0, x1 - p.x, p.y - y0, y1 - p.y});
      if (std::fabs(inset) < 1e-4 * t) continue;  // centre on the outline: either answer is fine
      ASSERT_EQ(front.valid, inset > 0) << i << "," << j;
      ASSERT_EQ(back.valid, inset > 0) << i << "," << j;
      if (!front.valid) continue;
      ++valid;
      EXPECT_NEAR(front.depth, double(pose.front_z) - (z1 + eps), 1e-6);
      EXPECT_NEAR(back.depth, (z0 - eps) - back_z, 1e-6);
      EXPECT_NEAR(front.normal.z, 1.0, 1e-6);
      EXPECT_NEAR(back.normal.z, -1.0, 1e-6);
    }
  }
  const double expected = (x1 - x0) * (y1 - y0) / (t * t);
  EXPECT_NEAR(double(valid), expected, 2 * ((x1 - x0) + (y1 - y0)) / t + 4);
  EXPECT_EQ(stats.valid_texels, valid);
  // Row spans (the default): exactly the valid texels are stored, plus the span table.
  ASSERT_EQ(pose.layout, BodyMapLayout::kRowSpans);
  EXPECT_EQ(stats.stored_texels, stats.valid_texels);
  EXPECT_EQ(stats.bytes, 2 * stats.stored_texels * (4 + 12) + SpanTableBytes(pose));
}

TEST(BodyMapBaker, BackMapIsNotMirrored) {
  // Two boxes, the small one off to +x, nearer the front and deeper than the big one.
  Mesh mesh;
  const Vec3d big_lo{-0.3, -0.4, -0.1}, big_hi{-0.05, 0.4, 0.1};
  const Vec3d small_lo{0.1, 0.2, 0.0}, small_hi{0.2, 0.3, 0.3};
  AddSplitBox(&mesh, big_lo, big_hi);
  AddSplitBox(&mesh, small_lo, small_hi);
  const BodyMapOptions o = FloatOptions(256);
  const BodyMapPose pose = BakeOrDie(mesh, o);
  const double t = pose.texel_size, eps = o.epsilon;
  const double back_z = double(pose.front_z) - double(pose.depth_range);
  auto texel_at = [&](double x, double y, uint32_t* i, uint32_t* j) {
    *i = static_cast<uint32_t>(std::floor((x - pose.origin_x) / t));
    *j = static_cast<uint32_t>(std::floor((y - pose.origin_y) / t));
  };
  uint32_t i = 0, j = 0;
  texel_at(0.15, 0.25, &i, &j);  // over the small box
  BodyMapTexel front = ReadBodyMapTexel(pose, 0, i, j), back = ReadBodyMapTexel(pose, 1, i, j);
  ASSERT_TRUE(front.valid && back.valid);
  EXPECT_NEAR(front.depth, double(pose.front_z) - (0.3 + eps), 2e-6);
  EXPECT_NEAR(back.depth, (0.0 - eps) - back_z, 2e-6);
  EXPECT_LT(back.normal.z, -0.999f);
  texel_at(-0.2, -0.3, &i, &j);  // over the big box
  front = ReadBodyMapTexel(pose, 0, i, j);
  back = ReadBodyMapTexel(pose, 1, i, j);
  ASSERT_TRUE(front.valid && back.valid);
  EXPECT_NEAR(front.depth, double(pose.front_z) - (0.1 + eps), 2e-6);
  EXPECT_NEAR(back.depth, (-0.1 - eps) - back_z, 2e-6);
  // A back map mirrored about the box centre (x -> 2 c_x - x, c_x = -0.05) would show the small
  // box at x = -0.25; un-mirrored, that texel shows the big box's back face.
  texel_at(-0.25, 0.25, &i, &j);
  back = ReadBodyMapTexel(pose, 1, i, j);
  ASSERT_TRUE(back.valid);
  EXPECT_NEAR(back.depth, (-0.1 - eps) - back_z, 2e-6);
  // Every texel is valid in both maps or in neither.
  for (uint32_t jj = 0; jj < pose.height; ++jj) {
    for (uint32_t ii = 0; ii < pose.width; ++ii) {
      ASSERT_EQ(ReadBodyMapTexel(pose, 0, ii, jj).valid, ReadBodyMapTexel(pose, 1, ii, jj).valid);
    }
  }
  // The gap between the boxes at y = 0.25 is background in both maps.
  texel_at(0.025, 0.25, &i, &j);
  EXPECT_FALSE(ReadBodyMapTexel(pose, 0, i, j).valid);
  EXPECT_FALSE(ReadBodyMapTexel(pose, 1, i, j).valid);
}

TEST(BodyMapBaker, CapsuleDepthAndNormalsMatchAnalytic) {
  const Vec3d c{0.0, 0.9, 0.05};
  const double r = 0.12, half = 0.35;
  const Mesh capsule = MakeCapsule(c, r, half, 32, 64);
  BodyMapOptions o = FloatOptions(512);
  o.fitted_window = true;
  BodyMapPoseStats stats;
  const BodyMapPose pose = BakeOrDie(capsule, o, &stats);
  std::vector<Vec3d> normals;
  const std::vector<Vec3d> q = OffsetVertices(capsule, o.epsilon, &normals);
  const double r_outer = r + o.epsilon;
  // Sag: r' minus the smallest distance of any offset triangle to the axis segment (sampled).
  double min_axis_distance = 1e9;
  for (size_t tri = 0; tri < capsule.triangles.size(); tri += 3) {
    const Vec3d a = q[capsule.triangles[tri]], b = q[capsule.triangles[tri + 1]],
                cc = q[capsule.triangles[tri + 2]];
    for (int u = 0; u <= 16; ++u) {
      for (int v = 0; u + v <= 16; ++v) {
        const Vec3d p = Add(a, Add(Scale(Sub(b, a), u / 16.0), Scale(Sub(cc, a), v / 16.0)));
        const Vec3d axis{c.x, std::clamp(p.y - c.y, -half, half) + c.y, c.z};
        min_axis_distance = std::min(min_axis_distance, Len(Sub(p, axis)));
      }
    }
  }
  const double sag = (r_outer - min_axis_distance) * 1.1 + 1e-6;  // sampling slack
  const double r_inner = r_outer - sag;
  const double vertex_deviation_deg = MaxVertexNormalDeviationDeg(q, normals, [&](Vec3d p) {
    return Vec3d{c.x, std::clamp(p.y - c.y, -half, half) + c.y, c.z};
  });
  double max_normal_error_deg = 0.0;
  const double back_z = double(pose.front_z) - double(pose.depth_range);

  // Fitted window: the same texel budget as N x N, smaller texels than the square window.
  const double box_l = 2 * r_outer + 2 * o.margin, box_h = 2 * (r_outer + half) + 2 * o.margin;
  EXPECT_NEAR(pose.texel_size, std::sqrt(box_l * box_h) / o.resolution, 1e-6);
  EXPECT_LT(pose.texel_size, std::max(box_l, box_h) / o.resolution);
  EXPECT_LE(double(stats.window_width) * stats.window_height,
            double(o.resolution) * o.resolution + stats.window_width + stats.window_height + 1);

  size_t checked = 0;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      const Vec3d p = TexelCentre(pose, i, j);
      const double axis_y = std::clamp(p.y - c.y, -half, half) + c.y;
      const double rho = std::hypot(p.x - c.x, p.y - axis_y);
      const BodyMapTexel front = ReadBodyMapTexel(pose, 0, i, j);
      const BodyMapTexel back = ReadBodyMapTexel(pose, 1, i, j);
      ASSERT_EQ(front.valid, back.valid);
      if (rho < r_inner - 1e-6) {
        EXPECT_TRUE(front.valid) << i << "," << j;
      }
      if (rho > r_outer + 1e-6) {
        EXPECT_FALSE(front.valid) << i << "," << j;
      }
      if (!front.valid || rho >= r_inner - 1e-6) continue;
      const double z_outer = std::sqrt(r_outer * r_outer - rho * rho);
      const double z_inner = std::sqrt(r_inner * r_inner - rho * rho);
      EXPECT_GE(front.depth, double(pose.front_z) - (c.z + z_outer) - 2e-6);
      EXPECT_LE(front.depth, double(pose.front_z) - (c.z + z_inner) + 2e-6);
      EXPECT_GE(back.depth, (c.z - z_outer) - back_z - 2e-6);
      EXPECT_LE(back.depth, (c.z - z_inner) - back_z + 2e-6);
      if (z_outer / r_outer >= 0.3) {
        const Vec3d n_front{p.x - c.x, p.y - axis_y, z_outer};
        const Vec3d n_back{p.x - c.x, p.y - axis_y, -z_outer};
        const double tolerance_deg =
            NormalToleranceDeg(vertex_deviation_deg, z_outer, z_inner, r_inner);
        const double front_error = AngleDeg(ToD3(front.normal), n_front);
        const double back_error = AngleDeg(ToD3(back.normal), n_back);
        EXPECT_LE(front_error, tolerance_deg) << i << "," << j;
        EXPECT_LE(back_error, tolerance_deg) << i << "," << j;
        max_normal_error_deg = std::max({max_normal_error_deg, front_error, back_error});
        ++checked;
      }
    }
  }
  EXPECT_LT(max_normal_error_deg, 3.0);  // "within a few degrees"
  std::printf(
      "[ capsule N=512 fitted ] sag %.3g m, vertex normal deviation %.3f deg, max normal "
      "error %.3f deg\n",
      sag, vertex_deviation_deg, max_normal_error_deg);
  EXPECT_GT(checked, 1000u);
}

TEST(BodyMapBaker, FittedWindowGivesSmallerTexelsForTheSameBudget) {
  const Mesh capsule = MakeCapsule({0.0, 0.9, 0.0}, 0.15, 0.6, 16, 32);
  BodyMapOptions square = FloatOptions(256), fitted = FloatOptions(256);
  fitted.fitted_window = true;
  BodyMapPoseStats square_stats, fitted_stats;
  const BodyMapPose a = BakeOrDie(capsule, square, &square_stats);
  const BodyMapPose b = BakeOrDie(capsule, fitted, &fitted_stats);
  EXPECT_LT(b.texel_size, 0.7f * a.texel_size);  // box 0.33 x 1.53 m: sqrt(0.33/1.53) = 0.46
  EXPECT_GT(fitted_stats.coverage, 1.5f * square_stats.coverage);
  EXPECT_GT(fitted_stats.valid_texels, 3 * square_stats.valid_texels);
}

// Compares two bakes of the same window texel by texel over the union of their rectangles.
struct MapDifference {
  size_t window_texels = 0, coverage_mismatch = 0, both_valid = 0;
  double max_depth_diff = 0.0, p999_depth_diff = 0.0, max_normal_deg = 0.0;
  size_t depth_over_1um = 0;
  // Largest depth difference relative to the surface slope: diff / (texel * tan(theta)), theta
  // the angle between the normal (of bake a) and the view axis. Vertex snapping moves a triangle
  // by a fraction of a texel; the depth then changes by that fraction times the slope.
  double max_diff_per_slope_texel = 0.0;
  double max_cos_over_1um = 0.0;  // max |n.z| over texels whose depth differs by > 1e-6 m
};
MapDifference Compare(const BodyMapPose& a, const BodyMapPose& b, size_t window_texels) {
  MapDifference d;
  d.window_texels = window_texels;
  const double t = a.texel_size;
  const long di = std::lround((double(b.origin_x) - a.origin_x) / t);
  const long dj = std::lround((double(b.origin_y) - a.origin_y) / t);
  const long i_lo = std::min(0L, di), j_lo = std::min(0L, dj);
  const long i_hi = std::max<long>(a.width, di + long(b.width));
  const long j_hi = std::max<long>(a.height, dj + long(b.height));
  std::vector<double> diffs;
  for (long j = j_lo; j < j_hi; ++j) {
    for (long i = i_lo; i < i_hi; ++i) {
      for (int view = 0; view < 2; ++view) {
        const bool in_a = i >= 0 && j >= 0 && i < long(a.width) && j < long(a.height);
        const bool in_b =
            i - di >= 0 && j - dj >= 0 && i - di < long(b.width) && j - dj < long(b.height);
        const BodyMapTexel ta =
            in_a ? ReadBodyMapTexel(a, view, uint32_t(i), uint32_t(j)) : BodyMapTexel{};
        const BodyMapTexel tb =
            in_b ? ReadBodyMapTexel(b, view, uint32_t(i - di), uint32_t(j - dj)) : BodyMapTexel{};
        if (ta.valid != tb.valid) {
          if (view == 0) ++d.coverage_mismatch;
          continue;
        }
        if (!ta.valid) continue;
        if (view == 0) ++d.both_valid;
        const double diff = std::fabs(double(ta.depth) - tb.depth);
        diffs.push_back(diff);
        d.max_depth_diff = std::max(d.max_depth_diff, diff);
        const double nz = std::min(1.0, std::fabs(double(ta.normal.z)));
        const double tan_theta = std::sqrt(std::max(0.0, 1.0 - nz * nz)) / std::max(nz, 1e-9);
        if (diff > 1e-6) {
          ++d.depth_over_1um;
          d.max_cos_over_1um = std::max(d.max_cos_over_1um, nz);
          d.max_diff_per_slope_texel =
              std::max(d.max_diff_per_slope_texel, (diff - 1e-6) / (t * tan_theta));
        }
        d.max_normal_deg = std::max(d.max_normal_deg, AngleDeg(ToD3(ta.normal), ToD3(tb.normal)));
      }
    }
  }
  if (!diffs.empty()) {
    std::sort(diffs.begin(), diffs.end());
    d.p999_depth_diff = diffs[std::min(diffs.size() - 1, size_t(0.999 * double(diffs.size())))];
  }
  return d;
}

void ExpectOsMesaMatchesCpu(const Mesh& mesh, uint32_t resolution, const char* label) {
  if (!OsMesaRendererAvailable()) GTEST_SKIP() << "OSMesa renderer not available in this build";
  BodyMapOptions cpu = FloatOptions(resolution), gl = FloatOptions(resolution);
  gl.renderer = MapRenderer::kOsMesa;
  BodyMapPoseStats cpu_stats, gl_stats;
  const BodyMapPose a = BakeOrDie(mesh, cpu, &cpu_stats);
  const BodyMapPose b = BakeOrDie(mesh, gl, &gl_stats);
  ASSERT_EQ(a.texel_size, b.texel_size);
  ASSERT_EQ(a.front_z, b.front_z);
  ASSERT_EQ(a.depth_range, b.depth_range);
  const MapDifference d = Compare(a, b, size_t(resolution) * resolution);
  const double mismatch_fraction = double(d.coverage_mismatch) / double(d.window_texels);
  const double over_fraction = double(d.depth_over_1um) / double(2 * d.both_valid);
  std::printf(
      "[ osmesa vs cpu ] %s N=%u: renderer '%s', coverage mismatch %zu texels (%.5f %%), "
      "silhouette conflicts %u, both valid %zu, depth |diff| max %.3g m, p99.9 %.3g m, "
      "> 1e-6 m on %zu texel-views (%.4f %%, all with |n.z| <= %.3f), max (diff - 1e-6) / "
      "(texel * tan theta) %.4f, normal max %.3f deg\n",
      label, resolution, gl_stats.renderer, d.coverage_mismatch, 100.0 * mismatch_fraction,
      gl_stats.silhouette_conflicts, d.both_valid, d.max_depth_diff, d.p999_depth_diff,
      d.depth_over_1um, 100.0 * over_fraction, d.max_cos_over_1um, d.max_diff_per_slope_texel,
      d.max_normal_deg);
  EXPECT_LE(mismatch_fraction, 1e-4);  // 0.01 % of the window's texels
  // Depth: within 1e-6 m on texels valid in both, except on steep texels next to the outline,
  // where llvmpipe's vertex snapping (8 sub-pixel bits: a vertex moves by <= 1/512 texel per
  // axis) shifts a triangle whose depth changes by tan(theta) per unit of x,y. There the bound
  // is 1e-6 m + texel * tan(theta) / 256. Measured (printed above): p99.9 under 1e-6 m, the
  // larger differences all at |n.z| < 0.14, and at most 0.0008 texel * tan(theta).
  EXPECT_LE(d.p999_depth_diff, 1e-6);
  EXPECT_LE(over_fraction, 1e-3);
  EXPECT_LE(d.max_diff_per_slope_texel, 1.0 / 256.0);
  EXPECT_LE(d.max_normal_deg, 0.1);
}

TEST(BodyMapBaker, OsMesaAgreesWithCpuOnSphere) {
  ExpectOsMesaMatchesCpu(MakeSphere({0.05, 1.0, -0.02}, 0.3, 50, 50), 1024, "sphere 4.9k");
}

TEST(BodyMapBaker, OsMesaAgreesWithCpuOn80kTriangles) {
  ExpectOsMesaMatchesCpu(MakeSphere({0.0, 0.0, 0.0}, 0.3, 200, 200), 1024, "sphere 79.6k");
}

TEST(BodyMapBaker, OsMesaIsUnavailableOrDeterministic) {
  const Mesh sphere = MakeSphere({0.0, 0.0, 0.0}, 0.3, 30, 30);
  BodyMapOptions o = FloatOptions(256);
  o.renderer = MapRenderer::kOsMesa;
  BodyMapPose a, b;
  const Status status = BakeBodyMapPose(sphere.positions, sphere.triangles, o, &a);
  if (!OsMesaRendererAvailable()) {
    EXPECT_EQ(status.code(), StatusCode::kInvalidState);
    EXPECT_NE(status.message().find("OSMesa renderer not available"), std::string::npos);
    return;
  }
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_TRUE(BakeBodyMapPose(sphere.positions, sphere.triangles, o, &b).ok());
  EXPECT_EQ(a.depth_f32[0], b.depth_f32[0]);
  EXPECT_EQ(a.depth_f32[1], b.depth_f32[1]);
  EXPECT_EQ(a.normal_f32[0], b.normal_f32[0]);
}

TEST(BodyMapBaker, OsMesaTilesAgreeWithCpuOnATallFittedWindow) {
  // 0.33 m x 1.53 m: at N = 2048 the fitted window is about 950 x 4400 texels, so the OSMesa
  // path renders it in several 2048-texel tiles; the seams must not show.
  const Mesh capsule = MakeCapsule({0.0, 0.9, 0.0}, 0.15, 0.6, 32, 64);
  if (!OsMesaRendererAvailable()) GTEST_SKIP() << "OSMesa renderer not available in this build";
  BodyMapOptions cpu = FloatOptions(2048), gl = FloatOptions(2048);
  cpu.fitted_window = gl.fitted_window = true;
  gl.renderer = MapRenderer::kOsMesa;
  BodyMapPoseStats stats;
  const BodyMapPose a = BakeOrDie(capsule, cpu, &stats);
  const BodyMapPose b = BakeOrDie(capsule, gl);
  ASSERT_GT(stats.window_height, 4096u);
  const MapDifference d = Compare(a, b, size_t(stats.window_width) * size_t(stats.window_height));
  std::printf(
      "[ osmesa vs cpu ] tall capsule, fitted %u x %u: coverage mismatch %zu, depth max "
      "%.3g m, p99.9 %.3g m, max (diff - 1e-6) / (texel * tan theta) %.4f\n",
      stats.window_width, stats.window_height, d.coverage_mismatch, d.max_depth_diff,
      d.p999_depth_diff, d.max_diff_per_slope_texel);
  EXPECT_LE(double(d.coverage_mismatch) / double(d.window_texels), 1e-4);
  EXPECT_LE(d.p999_depth_diff, 1e-6);
  EXPECT_LE(d.max_diff_per_slope_texel, 1.0 / 256.0);
}

TEST(BodyMapBaker, SharedEdgesLeaveNoCracks) {
  // A flat, jittered 40 x 40 grid of quads (3200 triangles sharing edges, mixed orientations):
  // every texel centre inside the outer square is covered, none outside. A crack in the
  // rasterizer's edge rule would leave background texels inside.
  Mesh grid;
  constexpr int kCells = 40;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  const double cell = 0.02;
  for (int y = 0; y <= kCells; ++y) {
    for (int x = 0; x <= kCells; ++x) {
      const bool interior = x > 0 && y > 0 && x < kCells && y < kCells;
      const double px = (x + (interior ? jitter(rng) : 0.0)) * cell;
      const double py = (y + (interior ? jitter(rng) : 0.0)) * cell;
      grid.positions.push_back({static_cast<float>(px), static_cast<float>(py), 0.25f});
    }
  }
  for (int y = 0; y < kCells; ++y) {
    for (int x = 0; x < kCells; ++x) {
      const uint32_t a = uint32_t(y * (kCells + 1) + x), b = a + 1, c = a + kCells + 1, e = c + 1;
      if ((x + y) % 2 == 0) {
        grid.triangles.insert(grid.triangles.end(), {a, b, e, a, e, c});
      } else {
        grid.triangles.insert(grid.triangles.end(), {a, c, b, b, c, e});  // clockwise ones too
      }
    }
  }
  BodyMapOptions o = FloatOptions(997);  // an odd N puts texel centres at arbitrary offsets
  o.epsilon = 0.f;                       // keep the grid flat (the normals are all +z anyway)
  BodyMapPoseStats stats;
  const BodyMapPose pose = BakeOrDie(grid, o, &stats);
  const double t = pose.texel_size, side = kCells * cell;
  const double lo_x = double(grid.positions.front().x), hi_x = double(grid.positions.back().x);
  const double lo_y = double(grid.positions.front().y), hi_y = double(grid.positions.back().y);
  ASSERT_NEAR(hi_x - lo_x, side, 1e-6);
  size_t inside = 0;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      const Vec3d p = TexelCentre(pose, i, j);
      const double inset = std::min({p.x - lo_x, hi_x - p.x, p.y - lo_y, hi_y - p.y});
      if (std::fabs(inset) < 1e-4 * t) continue;
      const BodyMapTexel texel = ReadBodyMapTexel(pose, 0, i, j);
      ASSERT_EQ(texel.valid, inset > 0) << i << "," << j;
      inside += inset > 0 ? 1 : 0;
      if (texel.valid) {
        ASSERT_NEAR(texel.depth, double(pose.front_z) - 0.25, 1e-6);
      }
    }
  }
  EXPECT_GT(inside, size_t(0.9 * side * side / (t * t)));
  EXPECT_EQ(stats.silhouette_conflicts, 0u);
}

TEST(BodyMapBaker, CodecsRoundTripWithinTheirDocumentedErrors) {
  std::mt19937 rng(12345);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<Vec3d> directions = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},   {0, -1, 0},       {0, 0, 1},
                                   {0, 0, -1}, {1, 1, 1},  {-1, 1, -1}, {0.3, -0.2, -0.9}};
  for (int k = 0; k < 20000; ++k) directions.push_back({gauss(rng), gauss(rng), gauss(rng)});
  double max_oct = 0.0, max_rgb = 0.0;
  for (const Vec3d& d : directions) {
    const Vec3d n = Scale(d, 1.0 / Len(d));
    const Float3 nf{float(n.x), float(n.y), float(n.z)};
    max_oct = std::max(max_oct, AngleDeg(ToD3(DecodeNormalOct16(EncodeNormalOct16(nf))), n));
    uint8_t rgb[3];
    EncodeNormalRgb8(nf, rgb);
    max_rgb = std::max(max_rgb, AngleDeg(ToD3(DecodeNormalRgb8(rgb)), n));
  }
  EXPECT_LE(max_oct, 0.01);
  EXPECT_LE(max_rgb, 0.5);
  // The rgb8 formula is paper A's: round((n * 0.5 + 0.5) * 255).
  uint8_t rgb[3];
  EncodeNormalRgb8({0.f, -1.f, 0.6f}, rgb);
  EXPECT_EQ(rgb[0], 128);
  EXPECT_EQ(rgb[1], 0);
  EXPECT_EQ(rgb[2], 204);
  // Depth: unorm16 error <= depth_range / 65535, 65535 reserved for background.
  const float range = 0.73f;
  for (int k = 0; k <= 1000; ++k) {
    const float depth = range * float(k) / 1000.f * 0.99999f;
    const uint16_t code = EncodeDepthUnorm16(depth, range);
    EXPECT_LE(code, 65534);
    EXPECT_LE(std::fabs(DecodeDepthUnorm16(code, range) - depth), range / 65535.0);
  }
  EXPECT_EQ(EncodeDepthUnorm16(range, range), 65534);
}

TEST(BodyMapBaker, EncodedBakesMatchTheFloatBake) {
  const Mesh sphere = MakeSphere({0.0, 0.0, 0.0}, 0.3, 40, 40);
  const BodyMapPose reference = BakeOrDie(sphere, FloatOptions(256));
  BodyMapOptions compact = FloatOptions(256), paper = FloatOptions(256);
  compact.depth_encoding = DepthEncoding::kUnorm16;
  compact.normal_encoding = NormalEncoding::kOct16;
  paper.normal_encoding = NormalEncoding::kRgb8;
  // Dense, so the arrays can be indexed by j * width + i below (row spans read the same through
  // ReadBodyMapTexel: RowSpansHoldTheSameMapsAsDenseOnASphere).
  compact.layout = paper.layout = BodyMapLayout::kDense;
  BodyMapOptions dense_reference = FloatOptions(256);
  dense_reference.layout = BodyMapLayout::kDense;
  const BodyMapPose reference_dense = BakeOrDie(sphere, dense_reference);
  BodyMapPoseStats compact_stats;
  const BodyMapPose a = BakeOrDie(sphere, compact, &compact_stats);
  const BodyMapPose b = BakeOrDie(sphere, paper);
  ASSERT_EQ(a.width, reference.width);
  ASSERT_EQ(a.height, reference.height);
  EXPECT_TRUE(a.depth_f32[0].empty() && a.normal_f32[0].empty() && a.normal_rgb8[0].empty());
  EXPECT_EQ(a.depth_u16[1].size(), size_t(a.width) * a.height);
  EXPECT_EQ(a.normal_oct16[1].size(), 2 * size_t(a.width) * a.height);
  EXPECT_EQ(compact_stats.bytes, 2 * size_t(a.width) * a.height * (2 + 4));
  double max_depth = 0.0, max_oct = 0.0, max_rgb = 0.0;
  size_t valid = 0;
  for (uint32_t j = 0; j < a.height; ++j) {
    for (uint32_t i = 0; i < a.width; ++i) {
      for (int view = 0; view < 2; ++view) {
        const BodyMapTexel r = ReadBodyMapTexel(reference, view, i, j);
        const BodyMapTexel ta = ReadBodyMapTexel(a, view, i, j);
        const BodyMapTexel tb = ReadBodyMapTexel(b, view, i, j);
        ASSERT_EQ(r.valid, ta.valid);
        ASSERT_EQ(r.valid, tb.valid);
        if (!r.valid) {
          EXPECT_EQ(a.depth_u16[view][size_t(j) * a.width + i], 65535);
          EXPECT_EQ(reference_dense.depth_f32[view][size_t(j) * a.width + i],
                    reference.depth_range);
          continue;
        }
        ++valid;
        max_depth = std::max(max_depth, std::fabs(double(ta.depth) - r.depth));
        max_oct = std::max(max_oct, AngleDeg(ToD3(ta.normal), ToD3(r.normal)));
        max_rgb = std::max(max_rgb, AngleDeg(ToD3(tb.normal), ToD3(r.normal)));
      }
    }
  }
  EXPECT_GT(valid, 1000u);
  EXPECT_LE(max_depth, double(reference.depth_range) / 65535.0);
  EXPECT_LE(max_oct, 0.01);
  EXPECT_LE(max_rgb, 0.5);
}

TEST(BodyMapBaker, CpuBakesAreByteIdentical) {
  const Mesh sphere = MakeSphere({0.01, 0.02, 0.03}, 0.3, 50, 50);
  BodyMapOptions o;  // defaults: float depth, oct16 normals, N = 1024
  o.resolution = 512;
  const BodyMapPose a = BakeOrDie(sphere, o), b = BakeOrDie(sphere, o);
  for (int view = 0; view < 2; ++view) {
    ASSERT_EQ(a.depth_f32[view].size(), b.depth_f32[view].size());
    EXPECT_EQ(0, std::memcmp(a.depth_f32[view].data(), b.depth_f32[view].data(),
                             a.depth_f32[view].size() * sizeof(float)));
    EXPECT_EQ(a.normal_oct16[view], b.normal_oct16[view]);
  }
  EXPECT_EQ(a.row_span_offsets, b.row_span_offsets);
  EXPECT_EQ(a.span_begin, b.span_begin);
  EXPECT_EQ(a.span_texel_offsets, b.span_texel_offsets);
  EXPECT_EQ(0, std::memcmp(&a.origin_x, &b.origin_x, sizeof(float)));
  EXPECT_EQ(0, std::memcmp(&a.front_z, &b.front_z, sizeof(float)));
}

// --- Layouts: row spans hold the same maps as the dense rectangle, in a fraction of the bytes ---

// The two layouts of one bake: the same arrays once expanded, the same texels read, and the
// runtime colliders built from them answer every texel and `segments` random queries bit for bit.
// `spans` expanded to the dense layout holds exactly `dense`'s arrays and gap list.
void ExpandsToTheSameArrays(const BodyMapPose& spans, const BodyMapPose& dense) {
  BodyMapPose expanded;
  const Status status = ConvertBodyMapLayout(spans, BodyMapLayout::kDense, &expanded);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(expanded.gap_texels, dense.gap_texels);
  for (int view = 0; view < 2; ++view) {
    EXPECT_EQ(expanded.depth_f32[view], dense.depth_f32[view]);
    EXPECT_EQ(expanded.depth_u16[view], dense.depth_u16[view]);
    EXPECT_EQ(expanded.normal_f32[view], dense.normal_f32[view]);
    EXPECT_EQ(expanded.normal_oct16[view], dense.normal_oct16[view]);
    EXPECT_EQ(expanded.normal_rgb8[view], dense.normal_rgb8[view]);
  }
}

void ExpectLayoutsEquivalent(const BodyMapPose& dense, const BodyMapPose& spans, int segments) {
  ASSERT_EQ(dense.layout, BodyMapLayout::kDense);
  ASSERT_EQ(spans.layout, BodyMapLayout::kRowSpans);
  ASSERT_EQ(spans.width, dense.width);
  ASSERT_EQ(spans.height, dense.height);
  EXPECT_EQ(Bits(spans.origin_x), Bits(dense.origin_x));
  EXPECT_EQ(Bits(spans.origin_y), Bits(dense.origin_y));
  EXPECT_EQ(Bits(spans.front_z), Bits(dense.front_z));
  EXPECT_EQ(Bits(spans.depth_range), Bits(dense.depth_range));
  ExpandsToTheSameArrays(spans, dense);
  size_t texel_mismatches = 0;
  for (uint32_t j = 0; j < dense.height; ++j) {
    for (uint32_t i = 0; i < dense.width; ++i) {
      for (int view = 0; view < 2; ++view) {
        const BodyMapTexel a = ReadBodyMapTexel(dense, view, i, j);
        const BodyMapTexel b = ReadBodyMapTexel(spans, view, i, j);
        texel_mismatches +=
            a.valid != b.valid || Bits(a.depth) != Bits(b.depth) || !SameBits(a.normal, b.normal);
      }
    }
  }
  EXPECT_EQ(texel_mismatches, 0u);

  for (DepthSampling sampling : {DepthSampling::kNearest, DepthSampling::kBilinear}) {
    BodyMapCollider a, b;
    ASSERT_TRUE(a.Build(dense, sampling).ok());
    ASSERT_TRUE(b.Build(spans, sampling).ok());
    ASSERT_EQ(a.width(), b.width());
    ASSERT_EQ(a.height(), b.height());
    EXPECT_EQ(a.stats().valid_texels, b.stats().valid_texels);
    EXPECT_EQ(a.stats().bilinear_blocks, b.stats().bilinear_blocks);
    EXPECT_TRUE(SameBits(a.bounds_min(), b.bounds_min()));
    EXPECT_TRUE(SameBits(a.bounds_max(), b.bounds_max()));
    size_t slab_mismatches = 0;
    for (uint32_t j = 0; j < a.height(); ++j) {
      for (uint32_t i = 0; i < a.width(); ++i) {
        float at = 0.f, ab = 0.f, bt = 0.f, bb = 0.f;
        const bool av = a.TexelSlab(i, j, &at, &ab), bv = b.TexelSlab(i, j, &bt, &bb);
        slab_mismatches += av != bv || Bits(at) != Bits(bt) || Bits(ab) != Bits(bb) ||
                           !SameBits(a.TexelNormal(i, j, false), b.TexelNormal(i, j, false)) ||
                           !SameBits(a.TexelNormal(i, j, true), b.TexelNormal(i, j, true));
      }
    }
    EXPECT_EQ(slab_mismatches, 0u);
    // Segments between points of the valid box widened by 5 % of its size: long ones across
    // the body and short ones of a few texels near it.
    const Float3 lo = a.bounds_min(), hi = a.bounds_max();
    const Float3 pad = (hi - lo) * 0.05f;
    std::mt19937_64 rng(0x5EA5);
    std::uniform_real_distribution<float> unit(0.f, 1.f);
    const auto point = [&] {
      return Float3{lo.x - pad.x + unit(rng) * (hi.x - lo.x + 2.f * pad.x),
                    lo.y - pad.y + unit(rng) * (hi.y - lo.y + 2.f * pad.y),
                    lo.z - pad.z + unit(rng) * (hi.z - lo.z + 2.f * pad.z)};
    };
    int query_mismatches = 0, contacts = 0;
    for (int k = 0; k < segments; ++k) {
      const Float3 p0 = point();
      const Float3 p1 = k % 2 == 0 ? point() : p0 + (point() - p0) * (4.f * a.texel_size());
      const ContactQuery qa = a.Query(p0, p1), qb = b.Query(p0, p1);
      query_mismatches += !SameBits(qa, qb) || a.IsInside(p1) != b.IsInside(p1);
      contacts += qa.contact;
    }
    EXPECT_EQ(query_mismatches, 0);
    EXPECT_GT(contacts, segments / 20) << "the segments must exercise contacts";
  }
}

TEST(BodyMapBaker, RowSpansHoldTheSameMapsAsDenseOnASphere) {
  const Mesh sphere = MakeSphere({0.01, 0.02, 0.03}, 0.3, 40, 40);
  for (const bool compact : {false, true}) {
    BodyMapOptions o = FloatOptions(256);
    if (compact) {
      o.depth_encoding = DepthEncoding::kUnorm16;
      o.normal_encoding = NormalEncoding::kOct16;
    }
    o.layout = BodyMapLayout::kDense;
    BodyMapPoseStats dense_stats, spans_stats;
    const BodyMapPose dense = BakeOrDie(sphere, o, &dense_stats);
    o.layout = BodyMapLayout::kRowSpans;
    const BodyMapPose spans = BakeOrDie(sphere, o, &spans_stats);
    SCOPED_TRACE(compact ? "unorm16 + oct16" : "float32");
    ExpectLayoutsEquivalent(dense, spans, 4000);
    // The stored texels are exactly the valid ones (both views agree after the bake's
    // consistency step), and the bytes are what the arrays and the span table hold.
    const size_t per_texel = compact ? 2 * (2 + 4) : 2 * (4 + 12);
    EXPECT_EQ(spans_stats.stored_texels, spans_stats.valid_texels);
    EXPECT_EQ(spans_stats.valid_texels, dense_stats.valid_texels);
    EXPECT_EQ(dense_stats.stored_texels, size_t(dense.width) * dense.height);
    EXPECT_EQ(dense_stats.bytes, per_texel * dense.width * dense.height);
    EXPECT_EQ(spans_stats.bytes, per_texel * spans_stats.stored_texels + SpanTableBytes(spans));
    // A disc in its square: pi/4 of the rectangle plus the border.
    EXPECT_LT(spans_stats.bytes, dense_stats.bytes * 4 / 5);
  }
}

// The built-in mannequin at N = 512 in the compact encodings (issue #3): measured 581,232 bytes
// in row spans (47,770 texels of the 424 x 508 rectangle, 18.2 % of the window) against
// 2,584,704 bytes dense.
TEST(BodyMapBaker, MannequinAt512CompactIsUnderTwoMegabytesInRowSpans) {
  BakeConfig config;
  config.hulls_enabled = false;
  config.spheres_enabled = false;
  config.maps.resolution = 512;
  config.maps.depth_encoding = DepthEncoding::kUnorm16;
  config.maps.normal_encoding = NormalEncoding::kOct16;
  BakeResult spans, dense;
  ASSERT_EQ(config.maps.layout, BodyMapLayout::kRowSpans) << "row spans are the default";
  Status status = BakeCharacter(test::MannequinPath(), config, &spans);
  ASSERT_TRUE(status.ok()) << status.message();
  config.maps.layout = BodyMapLayout::kDense;
  status = BakeCharacter(test::MannequinPath(), config, &dense);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(spans.asset.body_maps.poses.size(), 1u);
  ASSERT_EQ(dense.asset.body_maps.poses.size(), 1u);
  const BodyMapPose& s = spans.asset.body_maps.poses[0];
  const BodyMapPose& d = dense.asset.body_maps.poses[0];
  const nlohmann::json& spans_report = spans.report["body_maps"]["poses"][0];
  const nlohmann::json& dense_report = dense.report["body_maps"]["poses"][0];
  const size_t spans_bytes = spans_report["bytes"].get<size_t>();
  const size_t dense_bytes = dense_report["bytes"].get<size_t>();
  EXPECT_EQ(spans_report["layout"], "spans");
  EXPECT_EQ(dense_report["layout"], "dense");
  EXPECT_EQ(spans_bytes, 12 * BodyMapStoredTexels(s) + SpanTableBytes(s));
  EXPECT_EQ(dense_bytes, 12 * size_t(d.width) * d.height);
  // The bound, and the measured figure with a 10 % margin (so a real regression shows).
  EXPECT_LT(spans_bytes, 2'000'000u);
  EXPECT_LT(spans_bytes, 640'000u) << "measured 581,232 bytes";
  EXPECT_GT(dense_bytes, 2'500'000u) << "measured 2,584,704 bytes (424 x 508 texels)";
  ExpectLayoutsEquivalent(d, s, 4000);
}

TEST(BodyMapBaker, DegenerateInputReturnsAnErrorAndLeavesThePoseUnchanged) {
  const Mesh sphere = MakeSphere({0.0, 0.0, 0.0}, 0.3, 8, 8);
  BodyMapPose pose;
  pose.clip = 7;
  pose.width = 42;
  auto expect_error = [&](std::span<const Float3> positions, std::span<const uint32_t> tris,
                          const BodyMapOptions& o, const char* fragment) {
    const Status status = BakeBodyMapPose(positions, tris, o, &pose);
    EXPECT_FALSE(status.ok()) << fragment;
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << status.message();
    EXPECT_NE(status.message().find(fragment), std::string::npos) << status.message();
    EXPECT_EQ(pose.width, 42u);
    EXPECT_EQ(pose.clip, 7);
  };
  const BodyMapOptions o;
  expect_error(sphere.positions, {}, o, "no triangles");
  const std::vector<uint32_t> two = {0, 1};
  expect_error(sphere.positions, two, o, "multiple of 3");
  const std::vector<uint32_t> out_of_range = {0, 1, 9999};
  expect_error(sphere.positions, out_of_range, o, "vertex 9999");
  Mesh nan_mesh = sphere;
  nan_mesh.positions[5].y = std::numeric_limits<float>::quiet_NaN();
  expect_error(nan_mesh.positions, nan_mesh.triangles, o, "vertex 5");
  nan_mesh.positions[5].y = std::numeric_limits<float>::infinity();
  expect_error(nan_mesh.positions, nan_mesh.triangles, o, "non-finite");
  BodyMapOptions bad = o;
  bad.resolution = 8;
  expect_error(sphere.positions, sphere.triangles, bad, "resolution");
  bad.resolution = 9000;
  expect_error(sphere.positions, sphere.triangles, bad, "resolution");
  bad = o;
  bad.epsilon = -0.001f;
  expect_error(sphere.positions, sphere.triangles, bad, "epsilon");
  bad.epsilon = std::numeric_limits<float>::quiet_NaN();
  expect_error(sphere.positions, sphere.triangles, bad, "epsilon");
  bad = o;
  bad.margin = -1.f;
  expect_error(sphere.positions, sphere.triangles, bad, "margin");
  bad = o;
  bad.normal_encoding = static_cast<NormalEncoding>(9);
  expect_error(sphere.positions, sphere.triangles, bad, "normal encoding");
  // All triangles degenerate (collinear points): nothing is covered.
  const std::vector<Float3> line = {{0, 0, 0}, {0.1f, 0.1f, 0.1f}, {0.2f, 0.2f, 0.2f}};
  const std::vector<uint32_t> line_tri = {0, 1, 2, 2, 1, 0};
  expect_error(line, line_tri, o, "covers no texel");
  // A flat mesh with no offset and no margin has no depth range.
  const std::vector<Float3> flat = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<uint32_t> flat_tri = {0, 1, 2};
  BodyMapOptions zero = o;
  zero.epsilon = 0.f;
  zero.margin = 0.f;
  expect_error(flat, flat_tri, zero, "depth_range");
  // ... but with a margin it bakes (a single triangle), both views valid on the same texels.
  zero.margin = 0.01f;
  zero.resolution = 64;
  BodyMapPoseStats stats;
  const Status ok = BakeBodyMapPose(flat, flat_tri, zero, &pose, &stats);
  ASSERT_TRUE(ok.ok()) << ok.message();
  EXPECT_NEAR(stats.coverage, 0.5 * (1.0 / 1.02) * (1.0 / 1.02), 0.02);
  EXPECT_EQ(pose.clip, 7);  // clip and time are the caller's
  EXPECT_EQ(BakeBodyMapPose(flat, flat_tri, zero, nullptr).code(), StatusCode::kInvalidArgument);
}

// `dir` holds exactly the named files (no other), each larger than `min_bytes`.
void ExpectExactlyTheseFiles(const std::filesystem::path& dir,
                             std::initializer_list<const char*> names, uintmax_t min_bytes) {
  for (const char* name : names) {
    const std::filesystem::path file = dir / name;
    ASSERT_TRUE(std::filesystem::exists(file)) << file;
    EXPECT_GT(std::filesystem::file_size(file), min_bytes) << file;
  }
  size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    files += entry.is_regular_file();
  EXPECT_EQ(files, names.size());
}

TEST(BodyMapBaker, PreviewWritesFourPngs) {
  const Mesh capsule = MakeCapsule({0.0, 0.0, 0.0}, 0.2, 0.3, 16, 32);
  BodyMapOptions o;
  o.resolution = 128;
  o.normal_encoding = NormalEncoding::kOct16;
  o.depth_encoding = DepthEncoding::kUnorm16;
  const BodyMapPose pose = BakeOrDie(capsule, o);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("drape_body_map_preview_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const Status status = WriteBodyMapPreview(pose, dir.string(), "capsule");
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectExactlyTheseFiles(dir,
                          {"capsule_front_depth.png", "capsule_back_depth.png",
                           "capsule_front_normal.png", "capsule_back_normal.png"},
                          100);
  std::filesystem::remove_all(dir);
  // A directory that does not exist is an I/O error, not a crash.
  EXPECT_EQ(WriteBodyMapPreview(pose, (dir / "missing" / "deeper").string(), "x").code(),
            StatusCode::kIoError);
}

// --- Gap layers (body_map_baker.h step 8) ---

// Appends an axis-aligned closed box to `m` with separate vertices per face, counter-clockwise
// seen from outside, without the faces `skip` names (bit 2*axis + side: bit 4 is the z-low face),
// so an open box can be built too. Same geometry as AddSplitBox; kept separate because the hash
// constants of GapLayersLeaveTheSlabByteIdentical were recorded with exactly this vertex order.
void AddPortableBox(Mesh* m, double x0, double y0, double z0, double x1, double y1, double z1,
                    unsigned skip = 0) {
  const double lo[3] = {x0, y0, z0}, hi[3] = {x1, y1, z1};
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      if (skip & (1u << (2 * axis + side))) continue;
      const uint32_t base = static_cast<uint32_t>(m->positions.size());
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int corner = 0; corner < 4; ++corner) {
        double c[3];
        c[axis] = side ? hi[axis] : lo[axis];
        c[u] = (corner == 1 || corner == 2) ? hi[u] : lo[u];
        c[v] = (corner >= 2) ? hi[v] : lo[v];
        m->positions.push_back(
            {static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2])});
      }
      // Corners 0..3 go counter-clockwise around +axis: reversed on the low side.
      if (side) {
        m->triangles.insert(m->triangles.end(),
                            {base, base + 1, base + 2, base, base + 2, base + 3});
      } else {
        m->triangles.insert(m->triangles.end(),
                            {base, base + 2, base + 1, base, base + 3, base + 2});
      }
    }
  }
}

// A sphere from a 4^levels-subdivided octahedron on radius r (square roots only, so the same
// positions on every IEEE machine), counter-clockwise seen from outside, shared vertices.
void AddOctaSphere(Mesh* m, double cx, double cy, double cz, double r, int levels) {
  const test::UnitSphereMesh sphere = test::OctahedronSphere(levels);
  const uint32_t base = static_cast<uint32_t>(m->positions.size());
  for (const auto& q : sphere.positions) {
    m->positions.push_back({static_cast<float>(cx + r * q[0]), static_cast<float>(cy + r * q[1]),
                            static_cast<float>(cz + r * q[2])});
  }
  for (const auto& f : sphere.triangles) {
    m->triangles.insert(m->triangles.end(), {base + f[0], base + f[1], base + f[2]});
  }
}

// A single quad at height z over [x0, x1] x [y0, y1], facing +z (up) or -z: an open surface.
void AddQuad(Mesh* m, double x0, double y0, double x1, double y1, double z, bool up) {
  const uint32_t base = static_cast<uint32_t>(m->positions.size());
  for (const auto& [x, y] : {std::pair{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}) {
    m->positions.push_back({static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
  }
  if (up) {
    m->triangles.insert(m->triangles.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  } else {
    m->triangles.insert(m->triangles.end(), {base, base + 2, base + 1, base, base + 3, base + 2});
  }
}

// A thin closed sheet over [x0, x1] x [y0, y1] whose bottom is z = z0 + slope * (x - x0) and whose
// top is `thickness` above it (vertical sides; separate vertices per face).
void AddSlantedSheet(Mesh* m, double x0, double y0, double x1, double y1, double z0, double slope,
                     double thickness) {
  const auto bottom = [&](double x) { return z0 + slope * (x - x0); };
  const Vec3d corner[8] = {{x0, y0, bottom(x0)},
                           {x1, y0, bottom(x1)},
                           {x1, y1, bottom(x1)},
                           {x0, y1, bottom(x0)},
                           {x0, y0, bottom(x0) + thickness},
                           {x1, y0, bottom(x1) + thickness},
                           {x1, y1, bottom(x1) + thickness},
                           {x0, y1, bottom(x0) + thickness}};
  const int faces[6][4] = {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 1, 5, 4},
                           {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  const Vec3d centre = Scale(Add(corner[0], corner[6]), 0.5);
  for (const auto& face : faces) {
    const uint32_t base = static_cast<uint32_t>(m->positions.size());
    Vec3d face_centre;
    for (int k : face) {
      m->positions.push_back({static_cast<float>(corner[k].x), static_cast<float>(corner[k].y),
                              static_cast<float>(corner[k].z)});
      face_centre = Add(face_centre, Scale(corner[k], 0.25));
    }
    const Vec3d outward = Sub(face_centre, centre);
    AddOutwardTriangle(m, base, base + 1, base + 2, outward);
    AddOutwardTriangle(m, base, base + 2, base + 3, outward);
  }
}

// FNV-1a 64 over the bytes of everything a bake writes (header floats, span table, arrays).
uint64_t Fnv(uint64_t h, const void* data, size_t bytes) {
  const unsigned char* b = static_cast<const unsigned char*>(data);
  for (size_t k = 0; k < bytes; ++k) {
    h ^= b[k];
    h *= 1099511628211ull;
  }
  return h;
}
template <class T>
uint64_t FnvVector(uint64_t h, const std::vector<T>& v) {
  const uint64_t n = v.size();
  h = Fnv(h, &n, sizeof(n));
  return Fnv(h, v.data(), v.size() * sizeof(T));
}
uint64_t PoseHash(const BodyMapPose& p) {
  uint64_t h = 14695981039346656037ull;
  for (const void* field :
       {static_cast<const void*>(&p.width), static_cast<const void*>(&p.height),
        static_cast<const void*>(&p.origin_x), static_cast<const void*>(&p.origin_y),
        static_cast<const void*>(&p.texel_size), static_cast<const void*>(&p.front_z),
        static_cast<const void*>(&p.depth_range)}) {
    h = Fnv(h, field, 4);
  }
  h = FnvVector(h, p.row_span_offsets);
  h = FnvVector(h, p.span_begin);
  h = FnvVector(h, p.span_texel_offsets);
  for (int view = 0; view < 2; ++view) {
    h = FnvVector(h, p.depth_f32[view]);
    h = FnvVector(h, p.depth_u16[view]);
    h = FnvVector(h, p.normal_f32[view]);
    h = FnvVector(h, p.normal_oct16[view]);
    h = FnvVector(h, p.normal_rgb8[view]);
  }
  return h;
}

// A block, a plate in front of it, a sphere further in front and one beside it: flat and curved
// surfaces, shared and split vertices, air between them along z.
Mesh GapScene() {
  Mesh m;
  AddPortableBox(&m, -0.20, -0.30, -0.10, 0.20, 0.30, 0.05);  // block
  AddPortableBox(&m, -0.10, -0.12, 0.12, 0.14, 0.08, 0.15);   // plate in front of it
  AddOctaSphere(&m, 0.05, 0.20, 0.30, 0.07, 4);               // sphere further in front
  AddOctaSphere(&m, -0.25, -0.05, -0.02, 0.09, 3);            // sphere overlapping the side
  return m;
}

// The array entry of `layer` at texel (i, j) (body_map_baker.h, encodings), or -1 where the
// texel is not stored (layer 0) or not in the gap list (layers >= 1).
int64_t LayerEntry(const BodyMapPose& pose, uint32_t i, uint32_t j, uint32_t layer) {
  const int64_t index = BodyMapTexelIndex(pose, i, j);
  if (index < 0 || layer == 0) return index;
  const auto& list = pose.gap_texels;
  const auto found = std::lower_bound(list.begin(), list.end(), static_cast<uint32_t>(index));
  if (found == list.end() || *found != index) return -1;
  return static_cast<int64_t>(BodyMapStoredTexels(pose) + (layer - 1) * list.size() +
                              static_cast<size_t>(found - list.begin()));
}

// The raw depth code of `layer` at texel (i, j) decoded as a float reader would (unorm16:
// code / 65535 * depth_range in float), or NaN on background.
float FloatReaderDepth(const BodyMapPose& pose, int view, uint32_t i, uint32_t j, uint32_t layer) {
  const int64_t index = LayerEntry(pose, i, j, layer);
  if (index < 0) return std::numeric_limits<float>::quiet_NaN();
  const size_t entry = static_cast<size_t>(index);
  if (pose.depth_encoding == DepthEncoding::kFloat32) {
    const float d = pose.depth_f32[view][entry];
    return d < pose.depth_range ? d : std::numeric_limits<float>::quiet_NaN();
  }
  const uint16_t code = pose.depth_u16[view][entry];
  if (code == 65535) return std::numeric_limits<float>::quiet_NaN();
  return static_cast<float>(code) / 65535.f * pose.depth_range;
}

// Every texel's layers as body_map_data.h requires: a gap has both boundaries or neither, layers
// are filled in order, and top > upper_1 > lower_1 > upper_2 > ... > bottom in asset z, with the
// documented decoder in double and with a float reader's arithmetic. Returns the texels checked
// that hold at least one gap.
size_t ExpectStrictlyNested(const BodyMapPose& pose) {
  const double back_z = double(pose.front_z) - double(pose.depth_range);
  const float back_zf = pose.front_z - pose.depth_range;
  size_t with_gaps = 0, violations = 0;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      const BodyMapTexel top = ReadBodyMapTexel(pose, 0, i, j),
                         bottom = ReadBodyMapTexel(pose, 1, i, j);
      double ceiling = double(pose.front_z) - top.depth;
      float ceiling_f = pose.front_z - FloatReaderDepth(pose, 0, i, j, 0);
      const double floor = back_z + bottom.depth;
      const float floor_f = back_zf + FloatReaderDepth(pose, 1, i, j, 0);
      bool absent = !top.valid;
      for (uint32_t layer = 1; layer < pose.layers; ++layer) {
        const BodyMapTexel upper = ReadBodyMapTexel(pose, 0, i, j, layer);
        const BodyMapTexel lower = ReadBodyMapTexel(pose, 1, i, j, layer);
        if (!upper.valid && !lower.valid) {
          absent = true;
          continue;
        }
        with_gaps += layer == 1;
        const double upper_z = double(pose.front_z) - upper.depth;
        const double lower_z = back_z + lower.depth;
        const float upper_f = pose.front_z - FloatReaderDepth(pose, 0, i, j, layer);
        const float lower_f = back_zf + FloatReaderDepth(pose, 1, i, j, layer);
        const bool ok = !absent && upper.valid && lower.valid && ceiling > upper_z &&
                        upper_z > lower_z && lower_z > floor && ceiling_f > upper_f &&
                        upper_f > lower_f && lower_f > floor_f;
        if (!ok && violations++ < 5) {
          ADD_FAILURE() << "texel " << i << "," << j << " layer " << layer << ": ceiling "
                        << ceiling << " upper " << upper_z << " lower " << lower_z << " floor "
                        << floor;
        }
        ceiling = lower_z;
        ceiling_f = lower_f;
      }
    }
  }
  EXPECT_EQ(violations, 0u);
  // The gap list: strictly increasing, exactly the texels with a gap.
  EXPECT_EQ(with_gaps, pose.gap_texels.size());
  EXPECT_TRUE(std::adjacent_find(pose.gap_texels.begin(), pose.gap_texels.end(),
                                 std::greater_equal<uint32_t>()) == pose.gap_texels.end());
  if (pose.layers == 1) {
    EXPECT_TRUE(pose.gap_texels.empty());
  }
  return with_gaps;
}

// The gaps a texel centre should hold: (upper z, lower z) front to back.
using ExpectedGaps = std::vector<std::pair<double, double>>;

struct GapCheck {
  size_t texels_with_gaps = 0;  // texels checked that hold a gap
  size_t skipped = 0;           // texel centres within 1e-4 texel of an outline
};

// Compares every texel's gap layers with `expected` (positions within `tolerance` metres, the
// upper normal (0,0,-1) and the lower (0,0,+1) within `normal_tolerance`); texel centres within
// 1e-4 texel of one of the x = `outline_x` or y = `outline_y` lines are skipped.
template <class Expected>
GapCheck ExpectGaps(const BodyMapPose& pose, Expected expected,
                    const std::vector<double>& outline_x, const std::vector<double>& outline_y,
                    double tolerance, double normal_tolerance) {
  GapCheck check;
  const double t = pose.texel_size;
  const double back_z = double(pose.front_z) - double(pose.depth_range);
  size_t failures = 0;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      const Vec3d p = TexelCentre(pose, i, j);
      bool on_outline = false;
      for (double x : outline_x) on_outline |= std::fabs(p.x - x) < 1e-4 * t;
      for (double y : outline_y) on_outline |= std::fabs(p.y - y) < 1e-4 * t;
      if (on_outline) {
        ++check.skipped;
        continue;
      }
      const ExpectedGaps gaps = expected(p);
      for (uint32_t layer = 1; layer < pose.layers; ++layer) {
        const BodyMapTexel upper = ReadBodyMapTexel(pose, 0, i, j, layer);
        const BodyMapTexel lower = ReadBodyMapTexel(pose, 1, i, j, layer);
        const bool want = layer <= gaps.size();
        bool ok = upper.valid == want && lower.valid == want;
        if (ok && want) {
          const auto [upper_z, lower_z] = gaps[layer - 1];
          ok = std::fabs(double(pose.front_z) - upper.depth - upper_z) <= tolerance &&
               std::fabs(back_z + lower.depth - lower_z) <= tolerance &&
               std::fabs(upper.normal.z + 1.0) <= normal_tolerance &&
               std::fabs(lower.normal.z - 1.0) <= normal_tolerance;
        }
        if (!ok && failures++ < 5) {
          ADD_FAILURE() << "texel " << i << "," << j << " (" << p.x << ", " << p.y << ") layer "
                        << layer << ": expected " << (want ? "a gap" : "none") << ", read "
                        << (upper.valid ? "upper " + std::to_string(pose.front_z - upper.depth)
                                        : std::string("no upper"))
                        << " / "
                        << (lower.valid ? "lower " + std::to_string(back_z + lower.depth)
                                        : std::string("no lower"));
        }
      }
      check.texels_with_gaps += !gaps.empty();
    }
  }
  EXPECT_EQ(failures, 0u);
  return check;
}

bool Inside(Vec3d p, double x0, double y0, double x1, double y1) {
  return p.x > x0 && p.x < x1 && p.y > y0 && p.y < y1;
}

TEST(BodyMapBaker, GapLayerHoldsTheAirBetweenAPlateAndABlock) {
  Mesh mesh;
  const Vec3d block_lo{-0.20, -0.30, -0.10}, block_hi{0.20, 0.30, 0.05};
  const Vec3d plate_lo{-0.10, -0.12, 0.12}, plate_hi{0.14, 0.08, 0.15};
  AddSplitBox(&mesh, block_lo, block_hi);
  AddSplitBox(&mesh, plate_lo, plate_hi);
  for (const bool compact : {false, true}) {
    SCOPED_TRACE(compact ? "unorm16 + oct16" : "float32");
    BodyMapOptions o = DenseGapOptions(200, 3, compact);
    BodyMapPoseStats stats;
    const BodyMapPose pose = BakeOrDie(mesh, o, &stats);
    ASSERT_EQ(pose.layers, 3);
    // The split boxes' faces move by exactly epsilon along their normals: the gap is the plate's
    // back face lowered by epsilon down to the block's front face raised by epsilon, over the
    // plate's own x,y rectangle (its side faces are edge-on).
    const double eps = o.epsilon;
    const double tolerance = compact ? double(pose.depth_range) / 65535.0 + 1e-6 : 1e-6;
    const GapCheck check = ExpectGaps(
        pose,
        [&](Vec3d p) {
          return Inside(p, plate_lo.x, plate_lo.y, plate_hi.x, plate_hi.y)
                     ? ExpectedGaps{{plate_lo.z - eps, block_hi.z + eps}}
                     : ExpectedGaps{};
        },
        {plate_lo.x, plate_hi.x}, {plate_lo.y, plate_hi.y}, tolerance, compact ? 1e-3 : 1e-6);
    const double t = pose.texel_size;
    const double area = (plate_hi.x - plate_lo.x) * (plate_hi.y - plate_lo.y) / (t * t);
    EXPECT_NEAR(double(check.texels_with_gaps), area,
                2 * ((plate_hi.x - plate_lo.x) + (plate_hi.y - plate_lo.y)) / t + 4);
    EXPECT_GT(check.texels_with_gaps, 1000u);
    EXPECT_NEAR(double(stats.gap_texels), double(check.texels_with_gaps), double(check.skipped));
    EXPECT_EQ(stats.layers, 3);
    EXPECT_EQ(stats.dropped_gaps, 0u);
    EXPECT_GT(stats.gap_ms, 0.0);
    // Layer 0 for every texel of the rectangle, the two gap layers and the list for the texels
    // with a gap.
    const size_t per_texel = compact ? 2 * (2 + 4) : 2 * (4 + 12);
    const size_t listed = pose.gap_texels.size();
    EXPECT_EQ(listed, stats.gap_texels);
    EXPECT_EQ(stats.bytes,
              per_texel * (size_t(pose.width) * pose.height + 2 * listed) + 4 * listed);
    // Layer 0 is still the slab: the plate's front face to the block's back face.
    const uint32_t ci = pose.width / 2, cj = pose.height / 2;
    ASSERT_TRUE(Inside(TexelCentre(pose, ci, cj), plate_lo.x, plate_lo.y, plate_hi.x, plate_hi.y));
    EXPECT_NEAR(pose.front_z - ReadBodyMapTexel(pose, 0, ci, cj).depth, plate_hi.z + eps,
                tolerance);
    EXPECT_NEAR(pose.front_z - pose.depth_range + ReadBodyMapTexel(pose, 1, ci, cj).depth,
                block_lo.z - eps, tolerance);
    EXPECT_GT(ExpectStrictlyNested(pose), 1000u);
  }
}

TEST(BodyMapBaker, GapLayersKeepTheThickestGapsInDepthOrder) {
  // Plate B in front of plate A in front of a block; B covers x < 0.05, A covers x > -0.05.
  // Where both are: the gap B -> A (20 mm) and, deeper but thicker, A -> block (60 mm).
  Mesh mesh;
  const double eps = 0.005;
  AddSplitBox(&mesh, {-0.20, -0.20, -0.10}, {0.20, 0.20, 0.00});  // block
  AddSplitBox(&mesh, {-0.05, -0.10, 0.07}, {0.10, 0.10, 0.09});   // A
  AddSplitBox(&mesh, {-0.10, -0.10, 0.12}, {0.05, 0.10, 0.14});   // B
  const std::pair<double, double> b_to_a{0.12 - eps, 0.09 + eps}, a_to_block{0.07 - eps, eps},
      b_to_block{0.12 - eps, eps};
  const std::vector<double> outline_x = {-0.10, -0.05, 0.05, 0.10}, outline_y = {-0.10, 0.10};
  const auto in_y = [](Vec3d p) { return p.y > -0.10 && p.y < 0.10; };
  for (const int layers : {2, 3, 4}) {
    SCOPED_TRACE(testing::Message() << "layers " << int(layers));
    BodyMapOptions o = DenseGapOptions(160, static_cast<uint8_t>(layers));
    o.epsilon = static_cast<float>(eps);
    BodyMapPoseStats stats;
    const BodyMapPose pose = BakeOrDie(mesh, o, &stats);
    size_t both = 0;
    const GapCheck check = ExpectGaps(
        pose,
        [&](Vec3d p) {
          if (!in_y(p) || p.x <= -0.10 || p.x >= 0.10) return ExpectedGaps{};
          if (p.x < -0.05) return ExpectedGaps{b_to_block};
          if (p.x > 0.05) return ExpectedGaps{a_to_block};
          ++both;
          // layers = 2 keeps one: the thicker, although it is the deeper.
          return layers == 2 ? ExpectedGaps{a_to_block} : ExpectedGaps{b_to_a, a_to_block};
        },
        outline_x, outline_y, 1e-6, 1e-6);
    EXPECT_GT(both, 500u);
    EXPECT_GT(check.texels_with_gaps, both + 500);  // and texels under one plate only
    EXPECT_NEAR(double(stats.gap_texels), double(check.texels_with_gaps), double(check.skipped));
    EXPECT_NEAR(double(stats.dropped_gaps), layers == 2 ? double(both) : 0.0,
                double(check.skipped));
    ExpectStrictlyNested(pose);
  }
}

TEST(BodyMapBaker, OpenOrInconsistentSurfacesGiveNoGap) {
  // Six things in front of a block, each over its own cell (columns x in [-0.15, -0.02] and
  // [0.02, 0.15], rows y in [-0.18, -0.07], [-0.05, 0.05], [0.07, 0.18]); no epsilon, so that
  // the lone quads stay flat.
  Mesh mesh;
  AddPortableBox(&mesh, -0.20, -0.20, -0.10, 0.20, 0.20, 0.00);
  // Closed: a plate (a gap from 0.05 down to the block), and a plate over a flattened box of
  // zero thickness at z = 0.03, whose faces enter and leave at the same depth: entering sorts
  // first, so the count stays >= 0 and the texel keeps its thicker gap, plate -> sheet (the
  // sheet -> block one is beyond layers - 1 = 1).
  AddPortableBox(&mesh, 0.02, 0.07, 0.05, 0.15, 0.18, 0.08);
  AddPortableBox(&mesh, 0.02, -0.05, 0.12, 0.15, 0.05, 0.14);
  AddPortableBox(&mesh, 0.02, -0.05, 0.03, 0.15, 0.05, 0.03);
  // Open: a box without its back face under a closed plate (the count reaches 0 between them but
  // ends at 1), a lone quad facing +z (it ends at 1), a lone quad facing -z (it goes negative at
  // once), and a plate wound inside out (-1, +1, then the block's +1, -1: it ends at 0 but went
  // negative first).
  AddPortableBox(&mesh, -0.15, 0.07, 0.10, -0.02, 0.18, 0.12);
  AddPortableBox(&mesh, -0.15, 0.07, 0.05, -0.02, 0.18, 0.08, 1u << 4);
  AddQuad(&mesh, -0.15, -0.05, -0.02, 0.05, 0.06, /*up=*/true);
  AddQuad(&mesh, -0.15, -0.18, -0.02, -0.07, 0.06, /*up=*/false);
  AddPortableBox(&mesh, 0.02, -0.18, 0.05, 0.15, -0.07, 0.08);
  for (size_t t = mesh.triangles.size() - 36; t < mesh.triangles.size(); t += 3) {
    std::swap(mesh.triangles[t + 1], mesh.triangles[t + 2]);
  }
  BodyMapOptions o = DenseGapOptions(160, 2);
  o.epsilon = 0.f;
  BodyMapPoseStats stats;
  const BodyMapPose pose = BakeOrDie(mesh, o, &stats);
  size_t plate = 0, sheet = 0;
  const GapCheck check = ExpectGaps(
      pose,
      [&](Vec3d p) {
        if (Inside(p, 0.02, 0.07, 0.15, 0.18)) return ++plate, ExpectedGaps{{0.05, 0.0}};
        if (Inside(p, 0.02, -0.05, 0.15, 0.05)) return ++sheet, ExpectedGaps{{0.12, 0.03}};
        return ExpectedGaps{};
      },
      {-0.15, -0.02, 0.02, 0.15}, {-0.18, -0.07, -0.05, 0.05, 0.07, 0.18}, 1e-6, 1e-6);
  EXPECT_GT(plate, 1000u);
  EXPECT_GT(sheet, 1000u);
  EXPECT_EQ(check.texels_with_gaps, plate + sheet);
  EXPECT_NEAR(double(stats.dropped_gaps), double(sheet), double(check.skipped));
  EXPECT_NEAR(double(stats.gap_texels), double(check.texels_with_gaps), double(check.skipped));
  // The open surfaces are in layer 0 all the same: paper A's slab from them to the block's back.
  for (const auto& [x, y, top] : {std::tuple{-0.085, 0.125, 0.12},
                                  {-0.085, 0.0, 0.06},
                                  {-0.085, -0.125, 0.06},
                                  {0.085, -0.125, 0.08}}) {
    const uint32_t i = static_cast<uint32_t>((x - pose.origin_x) / pose.texel_size);
    const uint32_t j = static_cast<uint32_t>((y - pose.origin_y) / pose.texel_size);
    const BodyMapTexel front = ReadBodyMapTexel(pose, 0, i, j);
    ASSERT_TRUE(front.valid) << x << ", " << y;
    EXPECT_NEAR(pose.front_z - front.depth, top, 1e-6) << x << ", " << y;
    EXPECT_FALSE(ReadBodyMapTexel(pose, 0, i, j, 1).valid) << x << ", " << y;
  }
}

TEST(BodyMapBaker, GapsThinnerThanTheMinimumAreNotStored) {
  // Two plates above a block, no epsilon: 0.05 mm of air under the first (below kMinBodyMapGap,
  // 0.1 mm), 0.2 mm under the second.
  ASSERT_EQ(kMinBodyMapGap, 1e-4);
  Mesh mesh;
  AddPortableBox(&mesh, -0.20, -0.20, -0.10, 0.20, 0.20, 0.00);
  AddPortableBox(&mesh, -0.15, -0.15, 0.00005, -0.02, 0.15, 0.02);
  AddPortableBox(&mesh, 0.02, -0.15, 0.0002, 0.15, 0.15, 0.02);
  BodyMapOptions o = DenseGapOptions(160, 2);
  o.epsilon = 0.f;
  BodyMapPoseStats stats;
  const BodyMapPose pose = BakeOrDie(mesh, o, &stats);
  const GapCheck check = ExpectGaps(
      pose,
      [](Vec3d p) {
        return Inside(p, 0.02, -0.15, 0.15, 0.15) ? ExpectedGaps{{0.0002, 0.0}} : ExpectedGaps{};
      },
      {-0.15, -0.02, 0.02, 0.15}, {-0.15, 0.15}, 1e-6, 1e-6);
  EXPECT_GT(check.texels_with_gaps, 1000u);
  EXPECT_EQ(stats.dropped_gaps, 0u);
}

TEST(BodyMapBaker, GapLayersLeaveTheSlabByteIdentical) {
  const Mesh scene = GapScene();
  // Hashes of layers = 1 bakes recorded before gap layers existed (the same meshes and options):
  // asking for no gap must not change a byte. FNV-1a over every field the bake writes.
  struct Case {
    DepthEncoding depth;
    NormalEncoding normal;
    BodyMapLayout layout;
    uint32_t resolution;
    uint64_t hash;
  };
  const Case cases[] = {{DepthEncoding::kFloat32, NormalEncoding::kFloat32, BodyMapLayout::kDense,
                         200, 0x25a4ba18ef37c2b9ull},
                        {DepthEncoding::kUnorm16, NormalEncoding::kOct16, BodyMapLayout::kRowSpans,
                         256, 0xd90cb6c4340bd0f2ull},
                        {DepthEncoding::kUnorm16, NormalEncoding::kRgb8, BodyMapLayout::kDense, 160,
                         0x8160848a5c820c99ull}};
  for (const Case& c : cases) {
    BodyMapOptions o;
    o.resolution = c.resolution;
    o.depth_encoding = c.depth;
    o.normal_encoding = c.normal;
    o.layout = c.layout;
    ASSERT_EQ(o.layers, 1) << "paper A's slab alone is the default";
    BodyMapPoseStats stats;
    const BodyMapPose one = BakeOrDie(scene, o, &stats);
    EXPECT_EQ(PoseHash(one), c.hash) << "resolution " << c.resolution;
    EXPECT_EQ(one.layers, 1);
    EXPECT_EQ(stats.gap_texels, 0u);
    EXPECT_EQ(stats.gap_ms, 0.0);
    // Layer 0 of a bake with gaps is the same bytes, followed by the gap layers.
    if (c.layout != BodyMapLayout::kDense) continue;
    o.layers = 3;
    const BodyMapPose three = BakeOrDie(scene, o, &stats);
    EXPECT_GT(stats.gap_texels, 1000u);
    const size_t texels = size_t(one.width) * one.height;
    const size_t gap_entries = 2 * three.gap_texels.size();
    EXPECT_EQ(three.gap_texels.size(), stats.gap_texels);
    EXPECT_TRUE(one.gap_texels.empty());
    for (int view = 0; view < 2; ++view) {
      const auto same_prefix = [&](const auto& a, const auto& b, size_t per_texel) {
        ASSERT_EQ(a.size(), per_texel * texels);
        ASSERT_EQ(b.size(), per_texel * (texels + gap_entries));
        if (!a.empty()) {
          EXPECT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])));
        }
      };
      same_prefix(one.depth_f32[view], three.depth_f32[view], c.depth == DepthEncoding::kFloat32);
      same_prefix(one.depth_u16[view], three.depth_u16[view], c.depth == DepthEncoding::kUnorm16);
      same_prefix(one.normal_f32[view], three.normal_f32[view],
                  c.normal == NormalEncoding::kFloat32 ? 3 : 0);
      same_prefix(one.normal_oct16[view], three.normal_oct16[view],
                  c.normal == NormalEncoding::kOct16 ? 2 : 0);
      same_prefix(one.normal_rgb8[view], three.normal_rgb8[view],
                  c.normal == NormalEncoding::kRgb8 ? 3 : 0);
    }
  }
}

TEST(BodyMapBaker, Unorm16GapsAreStrictlyNestedAfterQuantisation) {
  // A slanted sheet 1 um thick (less than a unorm16 step, ~2.9 um here) between a slanted slab
  // and a block, no epsilon: the lower boundary of the first gap (the sheet's top, from the
  // back) and the upper boundary of the second (the sheet's bottom, from the front) quantise on
  // different grids and often swap. Such a gap must be dropped, the texel keeping the first.
  Mesh mesh;
  AddPortableBox(&mesh, -0.20, -0.20, -0.10, 0.20, 0.20, 0.00);
  AddSlantedSheet(&mesh, -0.15, -0.15, 0.15, 0.15, 0.030, 0.01, 1e-6);
  AddSlantedSheet(&mesh, -0.15, -0.15, 0.15, 0.15, 0.060, 0.01, 0.01);
  BodyMapOptions o;
  o.resolution = 200;
  o.epsilon = 0.f;
  o.depth_encoding = DepthEncoding::kUnorm16;
  o.normal_encoding = NormalEncoding::kOct16;
  o.layout = BodyMapLayout::kDense;
  o.layers = 3;
  BodyMapPoseStats stats;
  const BodyMapPose pose = BakeOrDie(mesh, o, &stats);
  EXPECT_GT(ExpectStrictlyNested(pose), 10000u);
  size_t two = 0, one = 0;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      if (!Inside(TexelCentre(pose, i, j), -0.149, -0.149, 0.149, 0.149)) continue;
      const bool first = ReadBodyMapTexel(pose, 0, i, j, 1).valid;
      const bool second = ReadBodyMapTexel(pose, 0, i, j, 2).valid;
      two += first && second;
      one += first && !second;
    }
  }
  std::printf("[ unorm16 nesting ] %zu texels keep both gaps, %zu only the first; %zu dropped\n",
              two, one, stats.dropped_gaps);
  // Both outcomes occur, and every single-gap texel is a dropped one.
  EXPECT_GT(two, 1000u);
  EXPECT_GT(one, 1000u);
  EXPECT_GE(stats.dropped_gaps, one);
  // With float32 depth nothing needs dropping.
  o.depth_encoding = DepthEncoding::kFloat32;
  BodyMapPoseStats float_stats;
  const BodyMapPose exact = BakeOrDie(mesh, o, &float_stats);
  ExpectStrictlyNested(exact);
  EXPECT_EQ(float_stats.dropped_gaps, 0u);
  EXPECT_EQ(float_stats.gap_texels, stats.gap_texels);
}

TEST(BodyMapBaker, GapLayersOnCurvedClosedMeshesAreNested) {
  const Mesh scene = GapScene();
  for (const bool compact : {false, true}) {
    BodyMapOptions o = DenseGapOptions(256, 4, compact, NormalEncoding::kRgb8);
    BodyMapPoseStats stats;
    const BodyMapPose pose = BakeOrDie(scene, o, &stats);
    EXPECT_EQ(ExpectStrictlyNested(pose), stats.gap_texels);
    // Upper boundaries face into the gap (down), lower ones up: clearly so, except near a
    // sphere's silhouette, where the vertex normals of the equator ring have z = 0.
    size_t wrong_way = 0, clear = 0, gaps = 0;
    for (uint32_t j = 0; j < pose.height; ++j) {
      for (uint32_t i = 0; i < pose.width; ++i) {
        for (uint32_t layer = 1; layer < pose.layers; ++layer) {
          const BodyMapTexel upper = ReadBodyMapTexel(pose, 0, i, j, layer);
          if (!upper.valid) break;
          const BodyMapTexel lower = ReadBodyMapTexel(pose, 1, i, j, layer);
          ++gaps;
          wrong_way += upper.normal.z > 0.05f || lower.normal.z < -0.05f;
          clear += upper.normal.z < -0.5f && lower.normal.z > 0.5f;
        }
      }
    }
    EXPECT_GT(gaps, 5000u);
    EXPECT_EQ(wrong_way, 0u);
    EXPECT_GT(clear, gaps * 9 / 10);
  }
}

TEST(BodyMapBaker, RowSpansCarryEveryGapLayer) {
  const Mesh scene = GapScene();
  for (const bool compact : {false, true}) {
    SCOPED_TRACE(compact ? "unorm16 + oct16" : "float32");
    BodyMapOptions o = DenseGapOptions(256, 3, compact);
    BodyMapPoseStats dense_stats, spans_stats, slab_stats;
    const BodyMapPose dense = BakeOrDie(scene, o, &dense_stats);
    o.layout = BodyMapLayout::kRowSpans;
    const BodyMapPose spans = BakeOrDie(scene, o, &spans_stats);
    o.layers = 1;
    const BodyMapPose slab = BakeOrDie(scene, o, &slab_stats);
    ASSERT_EQ(spans.layers, 3);
    // Layer 0 decides the spans.
    EXPECT_EQ(spans.row_span_offsets, slab.row_span_offsets);
    EXPECT_EQ(spans.span_begin, slab.span_begin);
    EXPECT_EQ(spans.span_texel_offsets, slab.span_texel_offsets);
    EXPECT_EQ(spans_stats.gap_texels, dense_stats.gap_texels);
    EXPECT_EQ(spans_stats.stored_texels, slab_stats.stored_texels);
    const size_t per_texel = compact ? 2 * (2 + 4) : 2 * (4 + 12);
    const size_t listed = spans.gap_texels.size();
    EXPECT_EQ(listed, spans_stats.gap_texels);
    EXPECT_EQ(spans_stats.bytes, per_texel * (spans_stats.stored_texels + 2 * listed) +
                                     SpanTableBytes(spans) + 4 * listed);
    ExpandsToTheSameArrays(spans, dense);
    size_t mismatches = 0;
    for (uint32_t j = 0; j < dense.height; ++j) {
      for (uint32_t i = 0; i < dense.width; ++i) {
        for (uint32_t layer = 0; layer < 3; ++layer) {
          for (int view = 0; view < 2; ++view) {
            const BodyMapTexel a = ReadBodyMapTexel(dense, view, i, j, layer);
            const BodyMapTexel b = ReadBodyMapTexel(spans, view, i, j, layer);
            mismatches += a.valid != b.valid || Bits(a.depth) != Bits(b.depth) ||
                          !SameBits(a.normal, b.normal);
          }
        }
      }
    }
    EXPECT_EQ(mismatches, 0u);
  }
}

TEST(BodyMapBaker, OsMesaSlabGetsTheCpuGaps) {
  if (!OsMesaRendererAvailable()) GTEST_SKIP() << "OSMesa renderer not available in this build";
  const Mesh scene = GapScene();
  BodyMapOptions o = DenseGapOptions(256, 3);
  BodyMapPoseStats cpu_stats, gl_stats;
  const BodyMapPose cpu = BakeOrDie(scene, o, &cpu_stats);
  o.renderer = MapRenderer::kOsMesa;
  const BodyMapPose gl = BakeOrDie(scene, o, &gl_stats);
  ASSERT_EQ(gl.width, cpu.width);
  ASSERT_EQ(gl.height, cpu.height);
  EXPECT_EQ(ExpectStrictlyNested(gl), gl_stats.gap_texels);
  // The gaps come from the same CPU fragment pass: they differ only where OSMesa's slab does.
  size_t differ = 0;
  for (uint32_t j = 0; j < cpu.height; ++j) {
    for (uint32_t i = 0; i < cpu.width; ++i) {
      for (uint32_t layer = 1; layer < 3; ++layer) {
        const BodyMapTexel a = ReadBodyMapTexel(cpu, 0, i, j, layer);
        const BodyMapTexel b = ReadBodyMapTexel(gl, 0, i, j, layer);
        differ += a.valid != b.valid || (a.valid && Bits(a.depth) != Bits(b.depth));
      }
    }
  }
  std::printf("[ osmesa gaps ] %zu gap texels (cpu %zu), %zu texel-layers differ, %zu dropped\n",
              gl_stats.gap_texels, cpu_stats.gap_texels, differ, gl_stats.dropped_gaps);
  EXPECT_GT(cpu_stats.gap_texels, 1000u);
  EXPECT_LE(differ, cpu_stats.gap_texels / 100);
}

TEST(BodyMapBaker, BadLayerCountsAreRefused) {
  const Mesh scene = GapScene();
  BodyMapPose pose;
  pose.width = 42;
  for (const int layers : {0, 5, 255}) {
    BodyMapOptions o;
    o.resolution = 64;
    o.layers = static_cast<uint8_t>(layers);
    const Status status = BakeBodyMapPose(scene.positions, scene.triangles, o, &pose);
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << layers;
    EXPECT_NE(status.message().find("layers " + std::to_string(layers) + " is outside [1, 4]"),
              std::string::npos)
        << status.message();
    EXPECT_EQ(pose.width, 42u);
  }
}

TEST(BodyMapBaker, PreviewWritesGapLayerPngs) {
  const Mesh scene = GapScene();
  BodyMapOptions o;
  o.resolution = 128;
  o.depth_encoding = DepthEncoding::kUnorm16;
  o.layout = BodyMapLayout::kDense;
  o.layers = 3;
  const BodyMapPose pose = BakeOrDie(scene, o);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("drape_body_map_gap_preview_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const Status status = WriteBodyMapPreview(pose, dir.string(), "scene");
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectExactlyTheseFiles(
      dir,
      {"scene_front_depth.png", "scene_back_depth.png", "scene_front_normal.png",
       "scene_back_normal.png", "scene_gap1_front_depth.png", "scene_gap1_back_depth.png",
       "scene_gap2_front_depth.png", "scene_gap2_back_depth.png"},
      60);
  std::filesystem::remove_all(dir);
}

TEST(BodyMapBaker, BakeReportCarriesTheGapFields) {
  BakeConfig config;
  config.hulls_enabled = false;
  config.spheres_enabled = false;
  config.maps.resolution = 128;
  config.maps.layers = 2;
  BakeResult result;
  const Status status = BakeCharacter(test::MannequinPath(), config, &result);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(result.asset.body_maps.poses.size(), 1u);
  EXPECT_EQ(result.asset.body_maps.poses[0].layers, 2);
  const nlohmann::json& report = result.report["body_maps"]["poses"][0];
  EXPECT_EQ(report["layers"], 2);
  EXPECT_TRUE(report["gap_texels"].is_number_unsigned()) << report.dump();
  EXPECT_TRUE(report["dropped_gaps"].is_number_unsigned()) << report.dump();
  EXPECT_GT(report["gap_ms"].get<double>(), 0.0);
}

}  // namespace
}  // namespace drape::bake

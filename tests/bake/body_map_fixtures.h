#pragma once
// Meshes, options and comparisons shared by the body-map bake tests (drape/bake/body_map_baker.h):
// UV spheres and capsules, boxes with split faces, the epsilon-offset surface computed as the bake
// specifies, texel centres, and bit-for-bit comparisons of floats and contact answers.
// Header-only.

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "drape/bake/body_map_baker.h"
#include "drape/runtime/body_map_collider.h"

namespace drape::bake::body_map_fixtures {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kDegree = kPi / 180.0;

struct Mesh {
  std::vector<Float3> positions;
  std::vector<uint32_t> triangles;
};

struct Vec3d {
  double x = 0, y = 0, z = 0;
};
inline Vec3d ToD(Float3 p) { return {p.x, p.y, p.z}; }
inline Vec3d Sub(Vec3d a, Vec3d b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3d Add(Vec3d a, Vec3d b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3d Scale(Vec3d a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline double Dot(Vec3d a, Vec3d b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3d Cross(Vec3d a, Vec3d b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double Len(Vec3d a) { return std::sqrt(Dot(a, a)); }
inline double AngleDeg(Vec3d a, Vec3d b) {
  const double c = Dot(a, b) / (Len(a) * Len(b));
  return std::acos(std::clamp(c, -1.0, 1.0)) / kDegree;
}

// Appends a triangle wound counter-clockwise seen from outside, where "outside" is the direction
// `outward` (the shapes here are convex, so centroid minus an interior point works).
inline void AddOutwardTriangle(Mesh* m, uint32_t a, uint32_t b, uint32_t c, Vec3d outward) {
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
inline Mesh MakeCapsule(Vec3d centre, double r, double half_length, int stacks, int slices) {
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

inline Mesh MakeSphere(Vec3d centre, double r, int stacks, int slices) {
  return MakeCapsule(centre, r, 0.0, stacks, slices);
}

// An axis-aligned box with separate vertices per face (24 vertices, 12 triangles), so every
// vertex normal is exactly its face normal and the epsilon offset moves each face by epsilon.
inline void AddSplitBox(Mesh* m, Vec3d lo, Vec3d hi) {
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
inline std::vector<Vec3d> OffsetVertices(const Mesh& m, double epsilon,
                                         std::vector<Vec3d>* normals) {
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
inline double PointTriangleDistance(Vec3d p, Vec3d a, Vec3d b, Vec3d c) {
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
inline double SphereSag(const Mesh& m, const std::vector<Vec3d>& q, Vec3d centre, double r_outer) {
  double min_distance = std::numeric_limits<double>::infinity();
  for (size_t t = 0; t < m.triangles.size(); t += 3) {
    min_distance =
        std::min(min_distance, PointTriangleDistance(centre, q[m.triangles[t]],
                                                     q[m.triangles[t + 1]], q[m.triangles[t + 2]]));
  }
  return r_outer - min_distance;
}

inline Vec3d TexelCentre(const BodyMapPose& pose, uint32_t i, uint32_t j) {
  return {pose.origin_x + (i + 0.5) * double(pose.texel_size),
          pose.origin_y + (j + 0.5) * double(pose.texel_size), 0.0};
}
inline Vec3d ToD3(Float3 n) { return {n.x, n.y, n.z}; }

inline BodyMapOptions FloatOptions(uint32_t resolution) {
  BodyMapOptions o;
  o.resolution = resolution;
  o.depth_encoding = DepthEncoding::kFloat32;
  o.normal_encoding = NormalEncoding::kFloat32;
  return o;
}

// Float32 options (or unorm16 depth and `compact_normals` when `compact`) in the dense layout with
// `layers` depth layers: the gap tests read texels by their dense index.
inline BodyMapOptions DenseGapOptions(uint32_t resolution, uint8_t layers, bool compact = false,
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

inline BodyMapPose BakeOrDie(const Mesh& m, const BodyMapOptions& o,
                             BodyMapPoseStats* stats = nullptr) {
  BodyMapPose pose;
  const Status status = BakeBodyMapPose(m.positions, m.triangles, o, &pose, stats);
  EXPECT_TRUE(status.ok()) << status.message();
  return pose;
}

// Bit patterns: the two layouts must give the very same floats, not merely close ones.
inline uint32_t Bits(float v) { return std::bit_cast<uint32_t>(v); }
inline bool SameBits(Float3 a, Float3 b) {
  return Bits(a.x) == Bits(b.x) && Bits(a.y) == Bits(b.y) && Bits(a.z) == Bits(b.z);
}
inline bool SameBits(const ContactQuery& a, const ContactQuery& b) {
  return a.inside_end == b.inside_end && a.contact == b.contact && Bits(a.t) == Bits(b.t) &&
         SameBits(a.point, b.point) && SameBits(a.normal, b.normal) &&
         Bits(a.depth) == Bits(b.depth) && a.flags == b.flags;
}

// Bytes of the row-span table (BodyMapPoseStats::bytes counts them).
inline size_t SpanTableBytes(const BodyMapPose& p) {
  return p.row_span_offsets.size() * 4 + p.span_begin.size() * 2 + p.span_texel_offsets.size() * 4;
}

}  // namespace drape::bake::body_map_fixtures

#include "fit/collider_fit.h"

#include <algorithm>
#include <cmath>

#include "capsule/capsule_fit.h"
#include "drape/bake/mesh_queries.h"
#include "drape/bake/mesh_reference.h"
#include "drape/runtime/math.h"
#include "fit/surface_samples.h"

namespace drape::bake {
namespace {

// Seeds of the sample streams; hull h draws from kHullSeed + h.
constexpr uint64_t kHullSeed = 0x68756C6C00000000ull;
constexpr uint64_t kBodySeed = 0x626F647900000000ull;
constexpr uint64_t kCapsuleSeed = 0x6361707300000000ull;

// A hull at rest in the asset frame, in double. `placed` is false when its joint has no
// skinning matrix: it then has no geometry and no samples.
struct PlacedHull {
  bool placed = false;
  std::vector<double> vertices;  // 3 per vertex, metres
  std::vector<uint32_t> triangles;
  // 4 per plane of the hull (the runtime's inside test): unit outward normal n, offset d.
  std::vector<double> planes;
  double lo[3] = {INFINITY, INFINITY, INFINITY};
  double hi[3] = {-INFINITY, -INFINITY, -INFINITY};
};

struct PlacedSphere {
  bool placed = false;
  double centre[3] = {0, 0, 0};
  double radius = 0.0;
};

struct PlacedCapsule {
  bool placed = false;
  double a[3] = {0, 0, 0}, b[3] = {0, 0, 0};
  double radius_a = 0.0, radius_b = 0.0;
};

bool HasJoint(int32_t joint, size_t joint_count) {
  return joint >= 0 && static_cast<size_t>(joint) < joint_count;
}

// The hull where the runtime puts it at the rest pose: skinning(joint) * bind_frame, in float
// as the runtime computes it, then widened to double.
PlacedHull PlaceHull(const HullColliderData& hull, std::span<const Mat34> rest_skinning) {
  PlacedHull placed;
  if (!HasJoint(hull.joint, rest_skinning.size())) return placed;
  placed.placed = true;
  const Mat34 world = Multiply(rest_skinning[hull.joint], hull.bind_frame);
  for (const Float3& v : hull.vertices) {
    const Float3 p = TransformPoint(world, v);
    const double q[3] = {p.x, p.y, p.z};
    for (int k = 0; k < 3; ++k) {
      placed.vertices.push_back(q[k]);
      placed.lo[k] = std::min(placed.lo[k], q[k]);
      placed.hi[k] = std::max(placed.hi[k], q[k]);
    }
  }
  const size_t vertex_count = hull.vertices.size();
  for (size_t t = 0; t + 2 < hull.triangles.size(); t += 3) {
    const uint32_t* corner = &hull.triangles[t];
    if (corner[0] >= vertex_count || corner[1] >= vertex_count || corner[2] >= vertex_count)
      continue;
    placed.triangles.insert(placed.triangles.end(), corner, corner + 3);
  }
  // The baked planes, not planes through the triangles: a simplified hull's sliver triangles
  // give normals of any direction, and such a plane would call most of the hull outside.
  // Normals move by the inverse transpose (bind_frame may scale), a point of the plane by world.
  Mat34 to_local;
  if (!InverseAffine(world, &to_local)) return placed;
  for (const Plane& plane : hull.planes) {
    const Float3 n = plane.normal;
    double m[3] = {0, 0, 0};
    for (int r = 0; r < 3; ++r) {  // (to_local's 3x3)^T n
      m[r] = double(to_local.m[r]) * n.x + double(to_local.m[4 + r]) * n.y +
             double(to_local.m[8 + r]) * n.z;
    }
    const double length = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
    if (!(length > 0.0)) continue;
    for (double& x : m) x /= length;
    const Float3 on = TransformPoint(world, n * plane.offset);
    placed.planes.insert(placed.planes.end(),
                         {m[0], m[1], m[2], m[0] * on.x + m[1] * on.y + m[2] * on.z});
  }
  return placed;
}

PlacedSphere PlaceSphere(const JointSphereData& sphere, std::span<const Mat34> rest_skinning) {
  PlacedSphere placed;
  if (!HasJoint(sphere.joint, rest_skinning.size())) return placed;
  const Float3 c = TransformPoint(rest_skinning[sphere.joint], sphere.center);
  placed.placed = true;
  placed.centre[0] = c.x, placed.centre[1] = c.y, placed.centre[2] = c.z;
  placed.radius = sphere.radius;
  return placed;
}

PlacedCapsule PlaceCapsule(const CapsuleColliderData& c, std::span<const Mat34> rest_skinning) {
  PlacedCapsule placed;
  if (!HasJoint(c.joint, rest_skinning.size())) return placed;
  const Float3 a = TransformPoint(rest_skinning[c.joint], c.from);
  const Float3 b = TransformPoint(rest_skinning[c.joint], c.to);
  placed.placed = true;
  placed.a[0] = a.x, placed.a[1] = a.y, placed.a[2] = a.z;
  placed.b[0] = b.x, placed.b[1] = b.y, placed.b[2] = b.z;
  placed.radius_a = c.radius_from, placed.radius_b = c.radius_to;
  return placed;
}

// The placed colliders of one measure.
struct Placed {
  std::vector<PlacedHull> hulls;
  std::vector<PlacedSphere> spheres;
  std::vector<PlacedCapsule> capsules;
};

// How far p lies outside the hull, metres: 0 inside (behind every plane), else the distance to
// its surface. Beyond `limit` the answer may be any value above `limit` (the largest plane
// distance, a lower bound of the true one), which is all the coverage needs.
double HullOutsideDistance(const PlacedHull& hull, const double p[3], double limit) {
  double worst_plane = -INFINITY;
  for (size_t i = 0; i < hull.planes.size(); i += 4) {
    const double* plane = &hull.planes[i];
    worst_plane =
        std::max(worst_plane, plane[0] * p[0] + plane[1] * p[1] + plane[2] * p[2] - plane[3]);
  }
  if (worst_plane <= 0.0) return 0.0;
  if (worst_plane > limit) return worst_plane;
  double nearest = INFINITY;
  for (size_t t = 0; t < hull.triangles.size(); t += 3) {
    nearest =
        std::min(nearest, PointTriangleDistance(p, &hull.vertices[3 * size_t{hull.triangles[t]}],
                                                &hull.vertices[3 * size_t{hull.triangles[t + 1]}],
                                                &hull.vertices[3 * size_t{hull.triangles[t + 2]}]));
  }
  return nearest;
}

// Whether a point on the body is inside some collider or within its delta + tolerance of it.
bool Covered(const double p[3], const Placed& placed, const ColliderFitOptions& options) {
  for (const PlacedCapsule& c : placed.capsules) {
    if (c.placed &&
        RoundConeDistance(p, c.a, c.radius_a, c.b, c.radius_b) <= options.coverage_tolerance)
      return true;
  }
  const double sphere_limit = options.sphere_delta + options.coverage_tolerance;
  for (const PlacedSphere& s : placed.spheres) {
    if (!s.placed) continue;
    const double d[3] = {p[0] - s.centre[0], p[1] - s.centre[1], p[2] - s.centre[2]};
    if (std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) - s.radius <= sphere_limit) return true;
  }
  const double hull_limit = options.hull_delta + options.coverage_tolerance;
  for (const PlacedHull& h : placed.hulls) {
    if (!h.placed) continue;
    bool near_box = true;  // within hull_limit of the bounding box on every axis
    for (int k = 0; k < 3; ++k) {
      near_box = near_box && p[k] >= h.lo[k] - hull_limit && p[k] <= h.hi[k] + hull_limit;
    }
    if (near_box && HullOutsideDistance(h, p, hull_limit) <= hull_limit) return true;
  }
  return false;
}

// The nearest-rank 99th percentile of the values (sorted in place).
double Percentile99(std::vector<double>& values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const size_t rank = static_cast<size_t>(std::ceil(0.99 * static_cast<double>(values.size())));
  return values[std::max<size_t>(rank, 1) - 1];
}

// Every collider's bloat samples, flattened: collider c owns points [begin[c], end[c]), of which
// [begin[c], area_end[c]) are spread over its area (the rest are a hull's vertices).
struct BloatSamples {
  std::vector<double> points;  // 3 per sample, metres
  std::vector<double> delta;   // per sample: its collider's delta, metres
  std::vector<size_t> begin, area_end, end;

  size_t count() const { return points.size() / 3; }
  void Close(double collider_delta) {
    end.push_back(count());
    delta.resize(count(), collider_delta);
  }
};

BloatSamples CollectBloatSamples(const Placed& placed, const ColliderFitOptions& options) {
  const std::vector<PlacedHull>& hulls = placed.hulls;
  BloatSamples s;
  for (size_t h = 0; h < hulls.size(); ++h) {
    s.begin.push_back(s.count());
    if (hulls[h].placed) {
      SampleTriangles(hulls[h].vertices, hulls[h].triangles, options.hull_samples, kHullSeed + h,
                      &s.points);
    }
    s.area_end.push_back(s.count());
    // The corners stick out farthest: the maximum includes them.
    s.points.insert(s.points.end(), hulls[h].vertices.begin(), hulls[h].vertices.end());
    s.Close(options.hull_delta);
  }
  for (const PlacedSphere& sphere : placed.spheres) {
    s.begin.push_back(s.count());
    if (sphere.placed)
      SampleSphere(sphere.centre, sphere.radius, options.sphere_samples, &s.points);
    s.area_end.push_back(s.count());
    s.Close(options.sphere_delta);
  }
  for (size_t c = 0; c < placed.capsules.size(); ++c) {
    const PlacedCapsule& capsule = placed.capsules[c];
    s.begin.push_back(s.count());
    if (capsule.placed) {
      std::vector<double> vertices;
      std::vector<uint32_t> triangles;
      RoundConeMesh(capsule.a, capsule.radius_a, capsule.b, capsule.radius_b, 32, 8, &vertices,
                    &triangles);
      SampleTriangles(vertices, triangles, options.capsule_samples, kCapsuleSeed + c, &s.points);
    }
    s.area_end.push_back(s.count());
    s.Close(0.0);
  }
  return s;
}

// Bloat of every sample, metres: how far outside the body beyond its collider's delta, >= 0.
// One sample per iteration into its own slot: the same values at any thread count.
std::vector<double> BloatOf(const BloatSamples& samples, const MeshReference& body) {
  std::vector<double> bloat(samples.count());
#pragma omp parallel for schedule(dynamic, 64)
  for (int64_t i = 0; i < static_cast<int64_t>(bloat.size()); ++i) {
    const double* q = &samples.points[3 * static_cast<size_t>(i)];
    // The distance first: a sample within its delta of the surface has no bloat inside or out,
    // so only the others need the winding number (the costlier query).
    const double distance = body.Distance(q);
    const bool beyond = distance > samples.delta[i] && !(body.WindingNumber(q) > 0.5);
    bloat[i] = beyond ? distance - samples.delta[i] : 0.0;
  }
  return bloat;
}

ColliderBloat Summarise(const std::vector<double>& bloat, size_t begin, size_t area_end,
                        size_t end) {
  ColliderBloat b;
  b.samples = static_cast<uint32_t>(end - begin);
  std::vector<double> area(bloat.begin() + begin, bloat.begin() + area_end);
  b.p99_mm = 1000.0 * Percentile99(area);
  for (size_t i = begin; i < end; ++i) b.max_mm = std::max(b.max_mm, 1000.0 * bloat[i]);
  return b;
}

// The fraction of area-weighted body samples that some collider covers.
double Coverage(std::span<const double> body_points, const Placed& placed,
                const ColliderFitOptions& options) {
  const size_t count = body_points.size() / 3;
  if (count == 0) return 0.0;
  std::vector<uint8_t> covered(count);
#pragma omp parallel for schedule(dynamic, 256)
  for (int64_t i = 0; i < static_cast<int64_t>(count); ++i) {
    covered[i] = Covered(&body_points[3 * static_cast<size_t>(i)], placed, options);
  }
  size_t inside = 0;
  for (uint8_t c : covered) inside += c;
  return static_cast<double>(inside) / static_cast<double>(count);
}

// Area-weighted points on the body (its triangles whose corners exist), 3 doubles each.
std::vector<double> BodySamples(std::span<const Float3> positions,
                                std::span<const uint32_t> triangles, uint32_t count) {
  std::vector<double> corners;
  corners.reserve(3 * positions.size());
  for (const Float3& p : positions) corners.insert(corners.end(), {p.x, p.y, p.z});
  std::vector<uint32_t> valid;
  for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
    if (triangles[t] < positions.size() && triangles[t + 1] < positions.size() &&
        triangles[t + 2] < positions.size()) {
      valid.insert(valid.end(), &triangles[t], &triangles[t] + 3);
    }
  }
  std::vector<double> points;
  SampleTriangles(corners, valid, count, kBodySeed, &points);
  return points;
}

}  // namespace

ColliderFit MeasureColliderFit(std::span<const Float3> rest_positions,
                               std::span<const uint32_t> triangles,
                               std::span<const HullColliderData> hulls,
                               std::span<const JointSphereData> spheres,
                               std::span<const CapsuleColliderData> capsules,
                               std::span<const Mat34> rest_skinning,
                               const ColliderFitOptions& options) {
  Placed placed;
  for (const HullColliderData& hull : hulls) placed.hulls.push_back(PlaceHull(hull, rest_skinning));
  for (const JointSphereData& s : spheres) placed.spheres.push_back(PlaceSphere(s, rest_skinning));
  for (const CapsuleColliderData& c : capsules)
    placed.capsules.push_back(PlaceCapsule(c, rest_skinning));

  WindingNumberOptions winding;
  winding.beta = options.winding_beta;
  const MeshReference body(rest_positions, triangles, winding);
  const BloatSamples samples = CollectBloatSamples(placed, options);
  const std::vector<double> bloat = BloatOf(samples, body);

  ColliderFit fit;
  std::vector<double> area_bloat;  // every collider's area-weighted samples, for the p99
  for (size_t c = 0; c < samples.begin.size(); ++c) {
    const ColliderBloat b = Summarise(bloat, samples.begin[c], samples.area_end[c], samples.end[c]);
    (c < hulls.size()                    ? fit.hulls
     : c < hulls.size() + spheres.size() ? fit.spheres
                                         : fit.capsules)
        .push_back(b);
    area_bloat.insert(area_bloat.end(), bloat.begin() + samples.begin[c],
                      bloat.begin() + samples.area_end[c]);
    fit.bloat_max_mm = std::max(fit.bloat_max_mm, b.max_mm);
  }
  fit.bloat_p99_mm = 1000.0 * Percentile99(area_bloat);
  fit.collider_samples = static_cast<uint32_t>(samples.count());

  const std::vector<double> body_points =
      BodySamples(rest_positions, triangles, options.body_samples);
  fit.body_samples = static_cast<uint32_t>(body_points.size() / 3);
  fit.coverage = Coverage(body_points, placed, options);
  return fit;
}

}  // namespace drape::bake

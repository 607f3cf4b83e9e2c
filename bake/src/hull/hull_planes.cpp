#include "hull/hull_planes.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hull/coplanar_faces.h"

namespace drape::bake::detail {

PlaneGroups BuildPlaneGroups(const Mesh& mesh, const std::vector<Vec3>* hint_normals,
                             const std::vector<double>* hint_offsets, double hint_tolerance) {
  PlaneGroups out;
  const uint32_t n = static_cast<uint32_t>(mesh.triangles.size());
  uint32_t count = 0;
  std::vector<uint32_t> parent;
  GroupCoplanar(mesh, &count, &parent);
  std::vector<uint32_t> hint_of(n, UINT32_MAX);
  if (hint_normals) {
    std::vector<uint32_t> first_with_hint(hint_normals->size(), UINT32_MAX);
    for (uint32_t t = 0; t < n; ++t) {
      const auto& tri = mesh.triangles[t];
      const Vec3 a = mesh.points[tri[0]], b = mesh.points[tri[1]], c = mesh.points[tri[2]];
      Vec3 normal = Cross(b - a, c - a);
      normal = normal * (1.0 / Norm(normal));
      double best = hint_tolerance;
      for (uint32_t j = 0; j < hint_normals->size(); ++j) {
        const Vec3 hn = (*hint_normals)[j];
        if (Dot(hn, normal) < 0.5) continue;
        const double dev = std::max({std::fabs(Dot(hn, a) - (*hint_offsets)[j]),
                                     std::fabs(Dot(hn, b) - (*hint_offsets)[j]),
                                     std::fabs(Dot(hn, c) - (*hint_offsets)[j])});
        if (dev <= best) {
          best = dev;
          hint_of[t] = j;
        }
      }
      if (hint_of[t] != UINT32_MAX) {
        uint32_t& first = first_with_hint[hint_of[t]];
        if (first == UINT32_MAX) {
          first = t;
        } else {
          Union(parent, first, t);
        }
      }
    }
  }
  out.triangle_group.resize(n);
  std::vector<uint32_t> root_group(n, UINT32_MAX);
  count = 0;
  for (uint32_t t = 0; t < n; ++t) {
    const uint32_t root = Find(parent, t);
    if (root_group[root] == UINT32_MAX) root_group[root] = count++;
    out.triangle_group[t] = root_group[root];
  }
  // Normal: area-weighted sum of the group's triangle normals (local origin for accuracy), or
  // the hint plane's normal.
  std::vector<Vec3> sums(count);
  std::vector<uint32_t> hint_of_group(count, UINT32_MAX);
  for (uint32_t t = 0; t < n; ++t) {
    const auto& tri = mesh.triangles[t];
    const Vec3 a = mesh.points[tri[0]];
    const uint32_t g = out.triangle_group[t];
    sums[g] = sums[g] + Cross(mesh.points[tri[1]] - a, mesh.points[tri[2]] - a);
    if (hint_of[t] != UINT32_MAX) hint_of_group[g] = hint_of[t];
  }
  out.normals.resize(count);
  for (uint32_t g = 0; g < count; ++g) {
    out.normals[g] = hint_of_group[g] != UINT32_MAX ? (*hint_normals)[hint_of_group[g]]
                                                    : sums[g] * (1.0 / Norm(sums[g]));
  }
  return out;
}

// Float plane offsets that contain, in the runtime's float arithmetic, every collider vertex
// and every float point within delta of an input point (header, step 5).
void FillPlanes(const Mesh& mesh, const PlaneGroups& groups, const std::vector<Vec3>& inputs,
                double delta, HullColliderData* collider) {
  collider->planes.clear();
  for (const Vec3& normal_double : groups.normals) {
    const Float3 nf = ToFloat3(normal_double);
    const Vec3 n = ToVec3(nf);
    const double n_len = Norm(n);
    double d = -std::numeric_limits<double>::infinity();
    for (const Vec3& v : mesh.points) d = std::max(d, Dot(n, v) + kFloatDot3Error * AbsDot(n, v));
    for (const Vec3& x : inputs) {
      const double ball = delta * n_len;
      d = std::max(d, Dot(n, x) + ball + kFloatDot3Error * (AbsDot(n, x) + std::sqrt(3.0) * ball));
    }
    Plane plane;
    plane.normal = nf;
    plane.offset = std::nextafter(RoundUpToFloat(d), std::numeric_limits<float>::infinity());
    collider->planes.push_back(plane);
  }
  collider->triangle_planes = groups.triangle_group;
}

}  // namespace drape::bake::detail

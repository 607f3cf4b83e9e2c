#include "regions/interior_points.h"

#include <algorithm>
#include <cmath>

#include "drape/bake/mesh_reference.h"
#include "drape/bake/regions.h"
#include "drape/runtime/math.h"

namespace drape::bake {

namespace {

bool DeepInside(const MeshReference& body, Float3 p, float delta) {
  const double q[3] = {p.x, p.y, p.z};
  return body.Distance(q) > delta && body.Inside(q);  // the cheaper query first
}

}  // namespace

std::vector<std::vector<Float3>> BoneInteriorPoints(const Regions& regions,
                                                    std::span<const int32_t> parents,
                                                    const MeshReference& body, float delta) {
  constexpr int kSamples = 8;  // per bone segment, joint included, child excluded
  const size_t joints = regions.collider_frames.size();
  const auto position = [&](size_t j) {
    const Mat34& m = regions.collider_frames[j];
    return Float3{m.m[3], m.m[7], m.m[11]};
  };
  std::vector<std::vector<Float3>> interior(joints);
  for (size_t j = 0; j < joints; ++j) {
    if (DeepInside(body, position(j), delta)) interior[j].push_back(position(j));
  }
  for (size_t c = 0; c < joints && c < parents.size(); ++c) {
    const int32_t j = parents[c];
    if (j < 0 || static_cast<size_t>(j) >= joints) continue;
    const Float3 from = position(static_cast<size_t>(j)), to = position(c);
    for (int k = 1; k < kSamples; ++k) {
      const Float3 p = from + (to - from) * (static_cast<float>(k) / kSamples);
      if (DeepInside(body, p, delta)) interior[static_cast<size_t>(j)].push_back(p);
    }
  }
  return interior;
}

std::vector<std::vector<Float3>> BodyInteriorPoints(std::span<const Float3> rest_positions,
                                                    std::span<const int32_t> triangle_bones,
                                                    uint32_t joints, const MeshReference& body,
                                                    float delta) {
  std::vector<std::vector<Float3>> interior(joints);
  if (rest_positions.empty() || joints == 0) return interior;
  Float3 lo = rest_positions[0], hi = rest_positions[0];
  for (const Float3& p : rest_positions) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const Float3 size = hi - lo;
  const float cell = std::max({size.x, size.y, size.z}) / static_cast<float>(kInteriorGridCells);
  if (!(cell > 0.f) || !std::isfinite(cell)) return interior;
  const auto cells = [&](float extent) {
    return std::max<uint32_t>(1, static_cast<uint32_t>(std::ceil(extent / cell)));
  };
  const uint32_t nx = cells(size.x), ny = cells(size.y), nz = cells(size.z);
  // Cell centres, each judged into its own slot in parallel, then gathered in grid order:
  // identical at any thread count.
  const int64_t total = int64_t{nx} * ny * nz;
  const auto centre = [&](int64_t i) {
    const int64_t x = i % nx, y = i / nx % ny, z = i / (int64_t{nx} * ny);
    return lo + Float3{(static_cast<float>(x) + 0.5f) * cell, (static_cast<float>(y) + 0.5f) * cell,
                       (static_cast<float>(z) + 0.5f) * cell};
  };
  std::vector<int32_t> owner(static_cast<size_t>(total), -1);
#pragma omp parallel for schedule(dynamic, 64)
  for (int64_t i = 0; i < total; ++i) {
    const Float3 p = centre(i);
    if (!DeepInside(body, p, delta)) continue;
    const double q[3] = {p.x, p.y, p.z};
    uint32_t triangle = kNoTriangle;
    body.ClosestPoint(q, nullptr, &triangle, nullptr);
    if (triangle < triangle_bones.size()) owner[static_cast<size_t>(i)] = triangle_bones[triangle];
  }
  for (int64_t i = 0; i < total; ++i) {
    const int32_t j = owner[static_cast<size_t>(i)];
    if (j < 0 || static_cast<uint32_t>(j) >= joints) continue;
    interior[static_cast<size_t>(j)].push_back(centre(i));
  }
  return interior;
}

}  // namespace drape::bake

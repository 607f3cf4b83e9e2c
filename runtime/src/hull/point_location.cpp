// Paper B's inside test: the point's projection located in the upper and the lower Kirkpatrick
// hierarchy, each side answering with its leaf's plane or a fill leaf's guard planes
// (docs/ALGORITHMS.md §4.4-4.5).
#include <algorithm>
#include <limits>

#include "drape/runtime/hull_collider_set.h"

namespace drape {

uint32_t HullColliderSet::Locate(const Hierarchy& k, HullUv q, uint32_t* steps) const {
  const double qu = q.u, qv = q.v;
  const double wu = k.interior_u - qu, wv = k.interior_v - qv;  // tie-break direction
  uint32_t tests = 0;
  // Accepts q (perturbed by simulation of simplicity towards the interior point, then along +u,
  // then +v) when all three canonical edge functions are positive.
  auto accept = [&](uint32_t node, double* min_edge) {
    ++tests;
    const EdgeFunction* e = &node_edges_[3 * size_t(node)];
    double lowest = std::numeric_limits<double>::infinity();
    bool inside = true;
    for (int i = 0; i < 3; ++i) {
      const double value = e[i].du * (qv - e[i].av) - e[i].dv * (qu - e[i].au);
      lowest = std::min(lowest, value);
      if (value > 0.0) continue;
      if (value < 0.0) {
        inside = false;
        continue;
      }
      double tie = e[i].du * wv - e[i].dv * wu;
      if (tie == 0.0) tie = -e[i].dv;
      if (tie == 0.0) tie = e[i].du;
      if (tie < 0.0) inside = false;
    }
    if (min_edge != nullptr) *min_edge = lowest;
    return inside;
  };
  // Picks the accepting node of [list], or (rounding, never in exact arithmetic) the one whose
  // smallest edge value is largest.
  auto pick = [&](const uint32_t* list, uint32_t count) {
    uint32_t best = list[0];
    double best_value = -std::numeric_limits<double>::infinity();
    for (uint32_t i = 0; i < count; ++i) {
      double lowest;
      if (accept(list[i], &lowest)) return list[i];
      if (lowest > best_value) {
        best_value = lowest;
        best = list[i];
      }
    }
    return best;
  };
  uint32_t node = k.root_begin;
  double best_root = -std::numeric_limits<double>::infinity();
  for (uint32_t r = k.root_begin; r < k.root_end; ++r) {
    double lowest;
    if (accept(r, &lowest)) {
      node = r;
      break;
    }
    if (lowest > best_root) {
      best_root = lowest;
      node = r;
    }
  }
  while (node_child_begin_[node + 1] > node_child_begin_[node]) {
    const uint32_t begin = node_child_begin_[node];
    node = pick(&node_children_[begin], node_child_begin_[node + 1] - begin);
  }
  if (steps != nullptr) *steps = tests;
  return node;
}

bool HullColliderSet::InsideKirkpatrick(const HullRecord& h, Float3 p) const {
  const HullUv q = ProjectHullUv(p, h.uv_origin, h.uv_u, h.uv_v);
  auto side_holds = [&](uint32_t leaf) {
    const int32_t plane = node_leaf_plane_[leaf];
    if (plane >= 0) return PlaneSignedDistance(planes_[h.plane_begin + plane], p) <= 0.f;
    const uint32_t begin = node_guard_begin_[leaf], end = node_guard_begin_[leaf + 1];
    if (begin == end) return false;  // outside the projected hull
    for (uint32_t i = begin; i < end; ++i)
      if (PlaneSignedDistance(planes_[h.plane_begin + node_guard_planes_[i]], p) > 0.f)
        return false;
    return true;
  };
  return side_holds(Locate(h.upper, q, nullptr)) && side_holds(Locate(h.lower, q, nullptr));
}

}  // namespace drape

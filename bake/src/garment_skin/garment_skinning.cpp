#include "garment_skin/garment_skinning.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <queue>
#include <sstream>
#include <string>
#include <utility>

#include "config/name_suggestions.h"
#include "drape/bake/mesh_reference.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "scene/scene_messages.h"

namespace drape::bake::detail {
namespace {

// Each vertex's neighbours along the triangles' edges, ascending, each once.
std::vector<std::vector<uint32_t>> EdgeNeighbours(std::span<const uint32_t> triangles,
                                                  size_t vertices) {
  std::vector<std::vector<uint32_t>> neighbours(vertices);
  for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = triangles[t + e], b = triangles[t + (e + 1) % 3];
      neighbours[a].push_back(b);
      neighbours[b].push_back(a);
    }
  }
  for (std::vector<uint32_t>& list : neighbours) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  return neighbours;
}

// Joint weights summed by joint (a handful of joints: a linear search), then the four heaviest.
class JointBlend {
 public:
  void Clear() { entries_.clear(); }
  bool empty() const { return entries_.empty(); }
  void Add(uint32_t joint, double weight) {
    for (auto& [j, w] : entries_) {
      if (j == joint) {
        w += weight;
        return;
      }
    }
    entries_.emplace_back(joint, weight);
  }
  void Add(const ClothSkinWeights& w, double scale) {
    for (int k = 0; k < 4; ++k)
      if (w.weights[k] > 0.f) Add(w.joints[k], w.weights[k] * scale);
  }
  // The four heaviest (ties to the lower joint: the same on every machine), renormalised into
  // *out; false (out untouched) when they weigh nothing.
  bool Heaviest(ClothSkinWeights* out) {
    std::sort(entries_.begin(), entries_.end(), [](const auto& a, const auto& b) {
      return a.second != b.second ? a.second > b.second : a.first < b.first;
    });
    const size_t kept = std::min<size_t>(4, entries_.size());
    double sum = 0.0;
    for (size_t k = 0; k < kept; ++k) sum += entries_[k].second;
    if (!(sum > 0.0)) return false;
    *out = ClothSkinWeights{};
    for (size_t k = 0; k < kept; ++k) {
      out->joints[k] = entries_[k].first;
      out->weights[k] = static_cast<float>(entries_[k].second / sum);
    }
    return true;
  }

 private:
  std::vector<std::pair<uint32_t, double>> entries_;  // (joint, weight)
};

// Barycentric coordinates of p (on or near the triangle abc), in double; equal thirds for a
// degenerate triangle.
std::array<double, 3> Barycentric(const double p[3], Float3 a, Float3 b, Float3 c) {
  const double e0[3] = {double(b.x) - a.x, double(b.y) - a.y, double(b.z) - a.z};
  const double e1[3] = {double(c.x) - a.x, double(c.y) - a.y, double(c.z) - a.z};
  const double q[3] = {p[0] - a.x, p[1] - a.y, p[2] - a.z};
  const auto dot = [](const double* u, const double* v) {
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
  };
  const double d00 = dot(e0, e0), d01 = dot(e0, e1), d11 = dot(e1, e1);
  const double d20 = dot(q, e0), d21 = dot(q, e1);
  const double det = d00 * d11 - d01 * d01;
  if (!(std::abs(det) > 1e-30 * (d00 * d11 + 1e-300))) return {1.0 / 3, 1.0 / 3, 1.0 / 3};
  const double v = (d11 * d20 - d01 * d21) / det;
  const double w = (d00 * d21 - d01 * d20) / det;
  return {std::clamp(1.0 - v - w, 0.0, 1.0), std::clamp(v, 0.0, 1.0), std::clamp(w, 0.0, 1.0)};
}

}  // namespace

Status TransferSkinWeights(const MeshData& body, std::span<const Float3> body_positions,
                           std::span<const Float3> garment, std::vector<ClothSkinWeights>* weights,
                           std::vector<float>* distances) {
  if (body.triangles.empty() || body_positions.size() != body.positions.size())
    return Status(StatusCode::kInvalidArgument,
                  "skin weights from the body: the asset has no body mesh");
  if (body.influence_offsets.size() != body.positions.size() + 1 || body.influence_joints.empty())
    return Status(StatusCode::kInvalidArgument,
                  "skin weights from the body: the asset's body mesh has no skin influences");
  const MeshReference surface(body_positions, body.triangles);
  weights->assign(garment.size(), ClothSkinWeights{});
  if (distances != nullptr) distances->assign(garment.size(), 0.f);
  JointBlend blend;
  for (size_t i = 0; i < garment.size(); ++i) {
    const double q[3] = {garment[i].x, garment[i].y, garment[i].z};
    double point[3];
    uint32_t triangle = 0;
    const double distance = surface.ClosestPoint(q, point, &triangle, nullptr);
    if (!std::isfinite(distance))
      return Status(StatusCode::kInvalidArgument, "skin weights from the body: particle " +
                                                      std::to_string(i) +
                                                      " has no closest body point (not finite)");
    if (distances != nullptr) (*distances)[i] = static_cast<float>(distance);
    const uint32_t* corner = &body.triangles[3 * size_t{triangle}];
    const std::array<double, 3> bary = Barycentric(
        point, body_positions[corner[0]], body_positions[corner[1]], body_positions[corner[2]]);
    blend.Clear();
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = corner[k];
      for (uint32_t f = body.influence_offsets[v]; f < body.influence_offsets[v + 1]; ++f)
        blend.Add(body.influence_joints[f], bary[k] * body.influence_weights[f]);
    }
    // Corners without influences: the root carries the particle.
    if (!blend.Heaviest(&(*weights)[i])) (*weights)[i].weights[0] = 1.f;
  }
  return Status::Ok();
}

Status ReadSkinWeightsFile(const std::string& file, const SkeletonData& skeleton, size_t vertices,
                           std::vector<ClothSkinWeights>* weights) {
  const auto invalid = [&](const std::string& message) {
    return Status(StatusCode::kInvalidArgument, "'" + file + "': " + message);
  };
  std::ifstream in(file);
  if (!in) return invalid("cannot open");
  weights->clear();
  std::string line;
  JointBlend blend;
  for (uint32_t number = 1; std::getline(in, line); ++number) {
    const size_t hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream tokens(line);
    std::string joint;
    blend.Clear();
    while (tokens >> joint) {
      double weight = 0.0;
      if (!(tokens >> weight) || !std::isfinite(weight) || weight < 0.0)
        return invalid("line " + std::to_string(number) + ": joint '" + joint +
                       "' needs a finite weight >= 0 after it");
      const int32_t j = FindJoint(skeleton, joint);
      if (j < 0) {
        const std::vector<std::string> near = NearestNames(joint, skeleton.joint_names, 3);
        return invalid("line " + std::to_string(number) + ": no joint named '" + joint + "'" +
                       (near.empty() ? "" : " (did you mean " + JoinNames(near) + "?)"));
      }
      blend.Add(static_cast<uint32_t>(j), weight);
    }
    if (blend.empty()) continue;  // blank or comment
    ClothSkinWeights w;
    if (!blend.Heaviest(&w))
      return invalid("line " + std::to_string(number) + ": the weights sum to 0");
    weights->push_back(w);
  }
  if (weights->size() != vertices)
    return invalid(std::to_string(weights->size()) + " weighted vertices for the garment's " +
                   std::to_string(vertices) + " (one line per vertex, in order)");
  return Status::Ok();
}

void SmoothSkinWeights(std::span<const uint32_t> triangles, uint32_t iterations,
                       std::vector<ClothSkinWeights>* weights) {
  const size_t n = weights->size();
  const std::vector<std::vector<uint32_t>> neighbours = EdgeNeighbours(triangles, n);
  std::vector<ClothSkinWeights> next(n);
  JointBlend blend;
  for (uint32_t it = 0; it < iterations; ++it) {
    for (size_t i = 0; i < n; ++i) {
      // Half its own weights, half its neighbours' mean.
      blend.Clear();
      blend.Add((*weights)[i], neighbours[i].empty() ? 1.0 : 0.5);
      const double share = 0.5 / static_cast<double>(std::max<size_t>(1, neighbours[i].size()));
      for (const uint32_t j : neighbours[i]) blend.Add((*weights)[j], share);
      next[i] = (*weights)[i];
      blend.Heaviest(&next[i]);
    }
    weights->swap(next);
  }
}

std::vector<float> DistanceAlongEdges(std::span<const uint32_t> triangles,
                                      std::span<const Float3> positions,
                                      std::span<const uint32_t> sources,
                                      std::vector<uint32_t>* nearest) {
  const size_t n = positions.size();
  const std::vector<std::vector<uint32_t>> neighbours = EdgeNeighbours(triangles, n);
  // Doubles: the sums of thousands of edges stay exact enough to order the vertices the same way
  // on every machine.
  std::vector<double> distance(n, std::numeric_limits<double>::infinity());
  std::vector<uint32_t> source_of(n, UINT32_MAX);
  using Entry = std::pair<double, uint32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  for (uint32_t k = 0; k < sources.size(); ++k) {
    if (distance[sources[k]] == 0.0) continue;  // listed twice: the first one
    distance[sources[k]] = 0.0;
    source_of[sources[k]] = k;
    queue.push({0.0, sources[k]});
  }
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > distance[v]) continue;
    for (const uint32_t w : neighbours[v]) {
      const double through = d + static_cast<double>(Length(positions[w] - positions[v]));
      if (through < distance[w]) {
        distance[w] = through;
        source_of[w] = source_of[v];
        queue.push({through, w});
      }
    }
  }
  if (nearest != nullptr) *nearest = std::move(source_of);
  return std::vector<float>(distance.begin(), distance.end());
}

}  // namespace drape::bake::detail

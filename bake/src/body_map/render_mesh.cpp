// The render mesh (drape/bake/render_mesh.h): meshoptimizer's edge-collapse simplification,
// checked against the exact reference both ways.
#include "drape/bake/render_mesh.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "drape/bake/mesh_reference.h"
#include "drape/formats/types.h"
#include "drape/runtime/math.h"

namespace drape::bake {
namespace {

// The simplifier's error metric (quadrics) underestimates the distance at creases, by up to 6x
// at small targets on the mannequin, and a collapse that turns a normal over can happen at one
// target and not at the next: the attempts go down a fixed ladder of targets from the tolerance,
// each from the bind mesh, and the first result within both limits is kept.
constexpr uint32_t kMaxAttempts = 10;
constexpr float kTargetStep = 0.75f;  // each attempt's target, relative to the one before
// A render mesh keeping more of the triangles is not stored: it saves little, and the bodies that
// simplify that little are low-poly ones, whose maps it changes most (the Fox's 576 -> 458 took
// its missed contacts from 0.01 to 0.34 %).
constexpr double kMinTriangleShare = 0.7;
// Degrees a kept vertex's normal may turn, and the share of kept vertices that may turn more.
// Within it the epsilon offset moves by at most 2 epsilon sin(15 deg), 2.6 mm at 5 mm, at that
// vertex alone; on the people the turns stay below 20 degrees but for a flipped vertex or two
// where a dense mesh collapses a lot. On low-poly bodies (Animated_Human, RobotExpressive) half
// the vertices turned 20-160 degrees, and the maps drawn from the simplified mesh missed 23-43 %
// of the contacts.
constexpr double kMaxNormalTurnDegrees = 30.0;
constexpr double kMaxTurnedShare = 0.002;

// The kept vertices renumbered in the order the triangles first use them, with their influences;
// bind_vertex: each kept vertex's index in `mesh`.
MeshData KeepUsedVertices(const MeshData& mesh, std::span<const uint32_t> triangles,
                          std::vector<uint32_t>* bind_vertex) {
  MeshData out;
  bind_vertex->clear();
  std::vector<uint32_t> remap(mesh.positions.size(), UINT32_MAX);
  const bool skinned = !mesh.influence_offsets.empty();
  if (skinned) out.influence_offsets.push_back(0);
  out.triangles.reserve(triangles.size());
  for (const uint32_t v : triangles) {
    if (remap[v] == UINT32_MAX) {
      remap[v] = static_cast<uint32_t>(out.positions.size());
      out.positions.push_back(mesh.positions[v]);
      bind_vertex->push_back(v);
      if (skinned) {
        for (uint32_t k = mesh.influence_offsets[v]; k < mesh.influence_offsets[v + 1]; ++k) {
          out.influence_joints.push_back(mesh.influence_joints[k]);
          out.influence_weights.push_back(mesh.influence_weights[k]);
        }
        out.influence_offsets.push_back(static_cast<uint32_t>(out.influence_joints.size()));
      }
    }
    out.triangles.push_back(remap[v]);
  }
  return out;
}

// The largest distance from the samples of `from` (its vertices, its edge midpoints when
// `midpoints`, its triangle centroids) to the surface `to`.
double FarthestSample(const MeshData& from, const MeshReference& to, bool vertices,
                      bool midpoints) {
  double farthest = 0.0;
  const auto measure = [&](Float3 p) {
    const double q[3] = {p.x, p.y, p.z};
    farthest = std::max(farthest, to.Distance(q));
  };
  if (vertices) {
    for (const Float3 p : from.positions) measure(p);
  }
  for (size_t t = 0; t + 2 < from.triangles.size(); t += 3) {
    const Float3 a = from.positions[from.triangles[t]];
    const Float3 b = from.positions[from.triangles[t + 1]];
    const Float3 c = from.positions[from.triangles[t + 2]];
    measure((a + b + c) * (1.f / 3.f));
    if (midpoints) {
      measure((a + b) * 0.5f);
      measure((b + c) * 0.5f);
      measure((c + a) * 0.5f);
    }
  }
  return farthest;
}

// Per vertex, the sum of its faces' area vectors (twice the area times the unit normal: the
// renderer offsets along it) and the sum of their areas' lengths.
struct VertexNormalSums {
  std::vector<Float3> sum;
  std::vector<float> area;
};
VertexNormalSums NormalSums(const MeshData& mesh) {
  VertexNormalSums s{std::vector<Float3>(mesh.positions.size(), Float3{}),
                     std::vector<float>(mesh.positions.size(), 0.f)};
  for (size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
    const uint32_t* v = &mesh.triangles[t];
    const Float3 face = Cross(mesh.positions[v[1]] - mesh.positions[v[0]],
                              mesh.positions[v[2]] - mesh.positions[v[0]]);
    for (int k = 0; k < 3; ++k) {
      s.sum[v[k]] = s.sum[v[k]] + face;
      s.area[v[k]] += Length(face);
    }
  }
  return s;
}

// How far the kept vertices' normals turned: the largest turn (degrees, 180 where one vanished)
// and how many turned beyond kMaxNormalTurnDegrees. A vertex whose own faces nearly cancel in the
// bind mesh (|sum| below half the areas: an edge of a fin, a sheet seen from both sides) has no
// normal to keep and is skipped.
struct NormalTurns {
  double largest = 0.0;
  uint32_t beyond = 0;
};
NormalTurns TurnsOf(const VertexNormalSums& bind, const MeshData& simplified,
                    std::span<const uint32_t> bind_vertex) {
  const VertexNormalSums kept = NormalSums(simplified);
  NormalTurns turns;
  for (size_t v = 0; v < kept.sum.size(); ++v) {
    const uint32_t b = bind_vertex[v];
    const float bind_length = Length(bind.sum[b]);
    if (!(bind_length >= 0.5f * bind.area[b])) continue;
    const float kept_length = Length(kept.sum[v]);
    const double cosine = kept_length > 0.f
                              ? Dot(kept.sum[v], bind.sum[b]) / (double(kept_length) * bind_length)
                              : -1.0;
    const double degrees = std::acos(std::clamp(cosine, -1.0, 1.0)) * 180.0 / std::numbers::pi;
    turns.largest = std::max(turns.largest, degrees);
    turns.beyond += degrees > kMaxNormalTurnDegrees ? 1u : 0u;
  }
  return turns;
}

// One simplification of `mesh` at `target` (metres), its vertices compacted.
MeshData Simplify(const MeshData& mesh, float target, std::vector<uint32_t>* bind_vertex) {
  const float scale = meshopt_simplifyScale(&mesh.positions[0].x, mesh.positions.size(),
                                            sizeof(Float3));  // metres per unit of error
  std::vector<uint32_t> kept(mesh.triangles.size());
  float error = 0.f;
  const size_t count = meshopt_simplify(
      kept.data(), mesh.triangles.data(), mesh.triangles.size(), &mesh.positions[0].x,
      mesh.positions.size(), sizeof(Float3), /*target_index_count=*/0,
      scale > 0.f ? target / scale : 0.f, meshopt_SimplifyLockBorder, &error);
  kept.resize(count);
  return KeepUsedVertices(mesh, kept, bind_vertex);
}

}  // namespace

Status SimplifyRenderMesh(const MeshData& mesh, float tolerance, MeshData* out,
                          RenderMeshReport* report) {
  *out = MeshData{};
  *report = RenderMeshReport{};
  if (!(std::isfinite(tolerance) && tolerance > 0.f))
    return Status(StatusCode::kInvalidArgument,
                  "render mesh: tolerance " + std::to_string(tolerance) + " m is not > 0");
  for (const uint32_t v : mesh.triangles) {
    if (v >= mesh.positions.size())
      return Status(StatusCode::kInvalidArgument,
                    "render mesh: a triangle index is out of range [0, " +
                        std::to_string(mesh.positions.size()) + ")");
  }
  report->triangles = mesh.triangle_count();
  if (mesh.triangle_count() == 0) return Status::Ok();
  const MeshReference original(mesh.positions, mesh.triangles);
  const VertexNormalSums bind_normals = NormalSums(mesh);
  std::vector<uint32_t> bind_vertex;
  float target = tolerance;
  for (uint32_t attempt = 0; attempt < kMaxAttempts; ++attempt) {
    MeshData simplified = Simplify(mesh, target, &bind_vertex);
    report->attempts = attempt + 1;
    if (simplified.triangle_count() >
        static_cast<uint32_t>(kMinTriangleShare * static_cast<double>(mesh.triangle_count())))
      return Status::Ok();  // too little to gain, now or at a smaller target
    // The simplified vertices lie on the bind mesh; its edges and faces may not. The bind mesh's
    // vertices and faces may lie off the simplified surface.
    const MeshReference reduced(simplified.positions, simplified.triangles);
    const double error = std::max(FarthestSample(simplified, original, false, true),
                                  FarthestSample(mesh, reduced, true, false));
    const NormalTurns turns = TurnsOf(bind_normals, simplified, bind_vertex);
    report->error = static_cast<float>(error);
    report->normal_turn_degrees = static_cast<float>(turns.largest);
    report->turned_vertices = turns.beyond;
    const bool few_turned = turns.beyond <= kMaxTurnedShare * simplified.vertex_count();
    if (!(error <= tolerance) || !few_turned) {
      target *= kTargetStep;
      continue;
    }
    report->kept = true;
    report->kept_triangles = simplified.triangle_count();
    report->kept_vertices = simplified.vertex_count();
    *out = std::move(simplified);
    return Status::Ok();
  }
  return Status::Ok();
}

}  // namespace drape::bake

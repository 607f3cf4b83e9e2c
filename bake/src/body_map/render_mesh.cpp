// The render mesh (drape/bake/render_mesh.h): meshoptimizer's edge-collapse simplification,
// checked against the exact reference both ways.
#include "drape/bake/render_mesh.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "drape/bake/mesh_reference.h"
#include "drape/formats/types.h"
#include "drape/runtime/math.h"

namespace drape::bake {
namespace {

// The simplifier's error metric (quadrics) underestimates the distance at creases, by up to 6x
// at small targets on the mannequin: each attempt beyond the tolerance tries again at a target
// scaled by the measured overshoot (and at least 10 % lower), from the bind mesh.
constexpr uint32_t kMaxAttempts = 8;
constexpr double kMinTriangleShare = 0.9;  // a render mesh keeping more is not worth storing

// The kept vertices renumbered in the order the triangles first use them, with their influences.
MeshData KeepUsedVertices(const MeshData& mesh, std::span<const uint32_t> triangles) {
  MeshData out;
  std::vector<uint32_t> remap(mesh.positions.size(), UINT32_MAX);
  const bool skinned = !mesh.influence_offsets.empty();
  if (skinned) out.influence_offsets.push_back(0);
  out.triangles.reserve(triangles.size());
  for (const uint32_t v : triangles) {
    if (remap[v] == UINT32_MAX) {
      remap[v] = static_cast<uint32_t>(out.positions.size());
      out.positions.push_back(mesh.positions[v]);
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

void ToDouble(Float3 p, double out[3]) {
  out[0] = p.x;
  out[1] = p.y;
  out[2] = p.z;
}

// The largest distance from the samples of `from` (its vertices, its edge midpoints when
// `midpoints`, its triangle centroids) to the surface `to`.
double FarthestSample(const MeshData& from, const MeshReference& to, bool vertices,
                      bool midpoints) {
  double farthest = 0.0;
  double q[3];
  const auto measure = [&](Float3 p) {
    ToDouble(p, q);
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

// One simplification of `mesh` at `target` (metres), its vertices compacted.
MeshData Simplify(const MeshData& mesh, float target) {
  const float scale = meshopt_simplifyScale(&mesh.positions[0].x, mesh.positions.size(),
                                            sizeof(Float3));  // metres per unit of error
  std::vector<uint32_t> kept(mesh.triangles.size());
  float error = 0.f;
  const size_t count = meshopt_simplify(
      kept.data(), mesh.triangles.data(), mesh.triangles.size(), &mesh.positions[0].x,
      mesh.positions.size(), sizeof(Float3), /*target_index_count=*/0,
      scale > 0.f ? target / scale : 0.f, meshopt_SimplifyLockBorder, &error);
  kept.resize(count);
  return KeepUsedVertices(mesh, kept);
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
  float target = tolerance;
  for (uint32_t attempt = 0; attempt < kMaxAttempts; ++attempt) {
    MeshData simplified = Simplify(mesh, target);
    report->attempts = attempt + 1;
    if (simplified.triangle_count() >
        static_cast<uint32_t>(kMinTriangleShare * static_cast<double>(mesh.triangle_count())))
      return Status::Ok();  // too little to gain, now or at a smaller target
    // The simplified vertices lie on the bind mesh; its edges and faces may not. The bind mesh's
    // vertices and faces may lie off the simplified surface.
    const MeshReference reduced(simplified.positions, simplified.triangles);
    const double error = std::max(FarthestSample(simplified, original, false, true),
                                  FarthestSample(mesh, reduced, true, false));
    report->error = static_cast<float>(error);
    if (!(error <= tolerance)) {
      target *= std::clamp(0.9f * tolerance / static_cast<float>(error), 0.25f, 0.9f);
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

#include "drape/runtime/skinning.h"

#include <string>

#include "drape/runtime/math.h"
#include "tasks/parallel_for.h"

namespace drape {

Status SkinMesh(const MeshData& mesh, std::span<const Mat34> skinning, std::span<Float3> posed) {
  const size_t count = mesh.positions.size();
  if (posed.size() != count) {
    return Status(StatusCode::kInvalidArgument, "output holds " + std::to_string(posed.size()) +
                                                    " positions, the mesh has " +
                                                    std::to_string(count));
  }
  const bool skinned = mesh.influence_offsets.size() == count + 1;
  const int64_t n = static_cast<int64_t>(count);
  detail::ParallelFor(n, detail::kParticleGrain, [&](int64_t v) {
    const Float3 bind = mesh.positions[v];
    if (!skinned || mesh.influence_offsets[v] == mesh.influence_offsets[v + 1]) {
      posed[v] = bind;
      return;
    }
    Float3 sum{0.f, 0.f, 0.f};
    for (uint32_t k = mesh.influence_offsets[v]; k < mesh.influence_offsets[v + 1]; ++k) {
      const uint16_t joint = mesh.influence_joints[k];
      if (joint >= skinning.size()) continue;  // validated at load; guards a hand-built mesh
      sum += TransformPoint(skinning[joint], bind) * mesh.influence_weights[k];
    }
    posed[v] = sum;
  });
  return Status::Ok();
}

}  // namespace drape

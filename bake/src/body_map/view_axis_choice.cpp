// The body maps' view axis: the asset axis whose slab holds the least air (docs/ALGORITHMS.md
// §6.9). A slab is everything between a texel's front and back surfaces, so what it wrongly
// calls inside is the air the view axis crosses between two parts of the body: under a
// quadruped's belly seen from the front, between a human's arms and torso seen from the side.
// The body's own volume is the same along every axis, so the least inside volume is the least air.
#include <algorithm>
#include <cstdint>

#include "drape/bake/body_map_baker.h"

namespace drape::bake {

double BodyMapInsideVolume(const BodyMapPose& pose) {
  const double area = static_cast<double>(pose.texel_size) * pose.texel_size;
  double volume = 0.0;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      const BodyMapTexel front = ReadBodyMapTexel(pose, 0, i, j);
      const BodyMapTexel back = ReadBodyMapTexel(pose, 1, i, j);
      if (!front.valid || !back.valid) continue;
      // Depths run from each view's plane: the slab spans depth_range less both.
      double thickness = static_cast<double>(pose.depth_range) - front.depth - back.depth;
      for (uint32_t layer = 1; layer < pose.layers; ++layer) {
        const BodyMapTexel upper = ReadBodyMapTexel(pose, 0, i, j, layer);
        const BodyMapTexel lower = ReadBodyMapTexel(pose, 1, i, j, layer);
        if (!upper.valid || !lower.valid) break;  // gaps are filled in order
        thickness -= static_cast<double>(pose.depth_range) - upper.depth - lower.depth;
      }
      volume += std::max(thickness, 0.0) * area;
    }
  }
  return volume;
}

Status ChooseBodyMapViewAxis(std::span<const Float3> positions, std::span<const uint32_t> triangles,
                             const BodyMapOptions& options, ViewAxisChoice* choice) {
  if (choice == nullptr) return Status(StatusCode::kInvalidArgument, "choice output is null");
  BodyMapOptions probe = options;
  probe.resolution = std::min(options.resolution, kViewAxisProbeResolution);
  probe.depth_encoding = DepthEncoding::kFloat32;
  probe.layout = BodyMapLayout::kDense;
  probe.renderer = MapRenderer::kCpu;  // deterministic, and cheap at this resolution
  // The slab alone: with gap layers every axis holds about the body's volume (the gaps take the
  // air out), yet the axis still decides how many texels need gaps, each of which costs the maps
  // bytes and the renderer a pass.
  probe.layers = 1;
  ViewAxisChoice result;
  for (BodyMapViewAxis axis : {BodyMapViewAxis::kZ, BodyMapViewAxis::kX, BodyMapViewAxis::kY}) {
    probe.view_axis = axis;
    BodyMapPose pose;
    if (Status s = BakeBodyMapPose(positions, triangles, probe, &pose); !s.ok()) return s;
    result.inside_volume[static_cast<int>(axis)] = BodyMapInsideVolume(pose);
  }
  // z unless another axis is clearly better; between x and y the smaller (x on a tie).
  const double z = result.inside_volume[0], x = result.inside_volume[1],
               y = result.inside_volume[2];
  const BodyMapViewAxis best_other = y < x ? BodyMapViewAxis::kY : BodyMapViewAxis::kX;
  const double other = std::min(x, y);
  result.axis = other < (1.0 - kViewAxisMinGain) * z ? best_other : BodyMapViewAxis::kZ;
  *choice = result;
  return Status::Ok();
}

}  // namespace drape::bake

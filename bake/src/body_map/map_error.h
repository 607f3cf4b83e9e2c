#pragma once
// How far a pose's body maps are wrong about inside and outside, measured against the exact mesh
// (MeshReference: generalised winding number and distance), and the cheapest map setting within
// an error budget (maps.max_error). docs/ALGORITHMS.md §6.10.
//
// A sample point's error is 0 when the maps classify it as the surface they stand for does (the
// body offset by epsilon along its normals), and otherwise its distance to that surface: how far
// the maps' boundary strays from it, outwards (air called body) or inwards (body called air).
// The samples: half area-weighted surface points moved up to 10 mm in a random direction (where
// texels decide), half uniform in the body's box widened by 10 % (the air a slab fills: under a
// belly, between arms and chest). Fixed seeds, each sample on its own: identical at any thread
// count.

#include <cstdint>
#include <span>
#include <vector>

#include "drape/bake/body_map_baker.h"
#include "drape/formats/body_map_data.h"
#include "drape/formats/types.h"

namespace drape::bake {

// The exact answers at the sample points of one body, computed once for every setting tried.
struct MapErrorSamples {
  std::vector<Float3> points;    // asset frame, metres: the shell's, then the box's
  size_t shell_count = 0;        // points near the surface (the first ones)
  std::vector<uint8_t> inside;   // 1: inside the mesh (winding number > 1/2)
  std::vector<double> distance;  // metres to the surface, >= 0
};
MapErrorSamples SampleMapError(std::span<const Float3> positions,
                               std::span<const uint32_t> triangles, uint32_t count = 20000);

struct MapError {
  // The larger 99th percentile (nearest rank) of the errors of the two kinds of sample.
  double p99_mm = 0.0;
  double max_mm = 0.0;
  // Of the samples farther than epsilon + 2 texels from the surface, the fraction the maps
  // classify wrongly (docs: "misclassified beyond the band"), [0, 1].
  double misclassified_beyond_band = 0.0;
  uint32_t samples = 0;
};
MapError MeasureMapError(const BodyMapPose& pose, float epsilon, const MapErrorSamples& samples);

// The settings maps.max_error tries, cheapest first: N = 256 .. 2048, one layer, then with air
// gaps (4 layers) at each N. The first within the budget wins; none: the one with the least p99.
struct MapSettingTried {
  uint32_t resolution = 0;
  uint8_t layers = 1;
  MapError error;
  size_t bytes = 0;
};
struct MapSettingChoice {
  uint32_t resolution = 0;
  uint8_t layers = 1;
  MapError error;
  bool within_budget = false;
  std::vector<MapSettingTried> tried;
};
// positions: the pose the error is measured on (the rest pose); options: everything but the
// resolution and the layers. Errors as BakeBodyMapPose's.
Status ChooseMapSetting(std::span<const Float3> positions, std::span<const uint32_t> triangles,
                        const BodyMapOptions& options, double max_error_mm,
                        MapSettingChoice* choice);

}  // namespace drape::bake

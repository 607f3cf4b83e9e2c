#pragma once
// The settings drape-speed-vs-error sweeps: the body-map settings of paper A (resolution,
// sampling, window, offset, encodings, air-gap layers, lanes) and the hull bakes of paper B
// (triangle budget, inflation, simplification, thresholds, map tables). --quick keeps a reduced
// sweep that still holds every --check claim.

#include <cstdint>
#include <string>
#include <vector>

#include "drape/bake/bake_config.h"
#include "drape/bake/body_map_baker.h"
#include "drape/bake/importer.h"
#include "drape/runtime/body_map_collider.h"
#include "methods.h"

namespace drape::bench {

struct MapSetting {
  uint32_t resolution = 1024;
  DepthSampling sampling = DepthSampling::kNearest;
  bool fitted = false;
  float epsilon = 0.005f;
  DepthEncoding depth = DepthEncoding::kUnorm16;
  NormalEncoding normals = NormalEncoding::kOct16;
  uint8_t layers = 1;                            // the slab plus layers - 1 air gaps per texel
  InstructionSet lanes = InstructionSet::kAvx2;  // the widest CollideBatch may use (kNearest)
  // Seen along z whatever the character's least-air axis (the one a default bake picks, which
  // every other setting uses): paper A's view, for comparison.
  bool z_view = false;
};

// The setting as the report names it: N and the sampling, then what differs from paper A's
// window, epsilon 5 mm, one layer, the widest lanes, unorm16 depth and oct16 normals.
std::string Describe(const MapSetting& m);

// The bake options of a setting (everything else at the bake's defaults), seen along
// `least_air_axis` unless the setting says z.
bake::BodyMapOptions BodyMapOptionsFor(const MapSetting& m, BodyMapViewAxis least_air_axis);

// The rest pose's body-map settings, in the order they are measured.
std::vector<MapSetting> MapSweep(bool quick);

struct HullBake {
  std::string label;  // what differs from the default bake
  bake::BakeConfig config;
};

// The rest pose's hull bakes (body maps off), the default first; `import` is the character's.
std::vector<HullBake> HullBakes(const bake::ImportOptions& import, bool quick);

}  // namespace drape::bench

#pragma once
// Every bake parameter in one place: its default, unit, valid range and meaning. The same table
// parses --config files (unknown keys and out-of-range values are errors naming the JSON path)
// and prints --dump-config, so the reference cannot drift from the code.

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "drape/bake/body_map_baker.h"
#include "drape/bake/bone_map_baker.h"
#include "drape/bake/capsule_fitter.h"
#include "drape/bake/hull_builder.h"
#include "drape/bake/importer.h"
#include "drape/bake/kirkpatrick_builder.h"
#include "drape/bake/map_table_builder.h"
#include "drape/formats/status.h"

namespace drape::bake {

// What a joint sphere's radius reaches (BuildJointSpheres).
enum class SphereCover : uint8_t {
  kFlexible = 0,     // every flexible vertex of the joint's two bones (paper B)
  kLeftByHulls = 1,  // only what the bones' hulls leave out of the rest-pose mesh
  kSurface = 2,      // as large as the body around the joint centre allows (no bulge)
};

struct BakeConfig {
  ImportOptions import;

  bool maps_enabled = true;  // paper A: front/back depth and normal maps of the rest pose
  // Depth as unorm16 by default: its error (depth range / 65535, about 5 um on a person) is far
  // below a texel, at half the bytes of float32. Air gaps by default (4 layers: the slab and up
  // to three gaps): paper A's slab alone misses 0.55-4.1 % of the contacts on real characters
  // (arms before a robot's chest, a fox's parts seen from above) and the gaps take that to
  // 0-0.03 % for 3-19 ns more per particle and a few percent more bytes (docs/ALGORITHMS.md §6.5).
  BodyMapOptions maps = [] {
    BodyMapOptions o;
    o.depth_encoding = DepthEncoding::kUnorm16;
    o.layers = kMaxBodyMapLayers;
    return o;
  }();
  // The axis the maps are seen along: kAuto picks the one whose slab holds the least air at the
  // rest pose (ChooseBodyMapViewAxis), for every pose of the set; else that axis.
  enum class MapViewAxis : uint8_t { kAuto, kX, kY, kZ };
  MapViewAxis maps_view_axis = MapViewAxis::kAuto;
  // Millimetres; 0: maps.resolution and maps.layers as given. > 0: the cheapest setting whose
  // measured error at the rest pose is within it (ChooseMapSetting, body_map/map_error.h).
  float maps_max_error_mm = 0.f;
  std::string maps_clip;  // empty: the rest pose; else every time of this clip at maps_clip_rate
  float maps_clip_rate = 0.f;  // Hz, >= 0; 0 = each of the clip's resampled frames
  // Where maps_clip was named ("config.json: /maps/clip", a scene's "/animation/clip"; empty:
  // "/maps/clip"): the refusal of a clip the character lacks names it. Not a config key.
  std::string maps_clip_origin;
  // Metres, [0, 0.1]: the render mesh (render_mesh.h) stays within this of the bind mesh; 0: none.
  // 1 mm by default: a fifth of epsilon and of the 5-7 mm texels that meet the people's error
  // targets at run time, where it keeps 55-80 % of a person's triangles and a fifth of a dense
  // mesh's (docs/ALGORITHMS.md §7.9).
  float maps_render_tolerance = 0.001f;
  // MB (10^6 bytes), >= 0; 0: none. The whole asset's budget: over it, the bake lowers the body
  // maps' resolution until the asset fits (never below N = 256, where the people meet the
  // speed-vs-error targets), and warns when it cannot. 8 MB: a character's share of a game's
  // memory; a default bake of a person takes 3-5 MB, a robot of 190 convex pieces at N = 1024
  // 11.7 MB.
  float maps_asset_budget_mb = 8.f;

  // Per-bone local maps (BakeBoneMaps): maps that follow any pose without rendering. Off by
  // default: the rest pose's maps render any pose at run time (BodyMapRenderer).
  bool bone_maps_enabled = false;
  BoneMapOptions bone_maps = [] {
    BoneMapOptions o;
    o.texel_size = 0.f;  // automatic: the rest pose's longest side / 600
    return o;
  }();

  bool hulls_enabled = true;      // paper B: a convex collider per bone
  float rigid_threshold = 0.99f;  // a vertex is rigid to its heaviest bone at this weight, (0.5, 1]
  // A flexible vertex also shapes its heaviest bone's hull at min(this, rigid_threshold), [0, 1]
  // (it stays in its joint sphere too); 1: hulls are shaped by rigid vertices only (paper B).
  // 0 by default: every triangle shapes the hull of the bone that carries most of it, so the
  // hulls hold the whole rest-pose surface whatever the rig's weights (smoothly weighted game
  // rigs have few vertices near any threshold; docs/ALGORITHMS.md §2.1).
  float shape_threshold = 0.f;
  HullOptions hull;
  // Metres, > 0: the report warns about every hull or joint sphere whose surface reaches farther
  // than this outside the body beyond its delta (the fit, measured against the exact mesh).
  float max_bloat = 0.015f;
  // >= 1: a bone's region whose convex hull bulges beyond cut_fraction x max_bloat is cut into at
  // most this many convex pieces, each its own hull (regions/convex_pieces.h); 1: one hull per
  // bone (paper B). Cuts stop once every piece fits, so a person's bones use few of them; a 6 m
  // creature's head of eyes and fangs needs about 30 to stay within 30 mm of the body.
  uint32_t hull_max_pieces = 32;
  // (0, 1]: pieces are cut to fit this fraction of max_bloat. A collider is its piece's hull
  // simplified and inflated, which adds 0.5-3.5 mm; pieces cut to max_bloat itself left most
  // colliders of a creature's legs at 14-17 mm (the Spider's bloat p99 11.1 mm, 26 colliders
  // beyond 15 mm; at 0.8: p99 8.5 mm, docs/ALGORITHMS.md §2.3).
  float hull_cut_fraction = 0.8f;
  KirkpatrickOptions kirkpatrick;
  MapTableOptions map_table;

  bool spheres_enabled = true;  // paper B: a sphere per joint over its flexible vertices
  float sphere_delta = 0.005f;  // metres added to each joint sphere's radius, >= 0
  // What a joint sphere holds (spheres.cover). kSurface by default: as large as the body around
  // the joint allows, so it never bulges out of the body; paper B's kFlexible reaches every
  // blended vertex (0.2-0.8 m radii on smoothly weighted rigs).
  SphereCover sphere_cover = SphereCover::kSurface;
  // Metres, >= 0: with kSurface, a joint whose centre is nearer the body surface than this gets
  // no sphere (it would hold nothing a hull does not).
  float sphere_min_radius = 0.01f;

  // Tapered capsules, one per bone that carries skin, fitted to the body's cross-section
  // (capsule/capsule_fit.h): the engines' cloth colliders, posed into a ShapeColliderSet.
  bool capsules_enabled = true;
  CapsuleFitOptions capsules;
};

// Reads a JSON config file over the defaults in `config`. `path` names the file in messages.
Status LoadBakeConfig(const std::string& path, BakeConfig* config);
// The same from the file's bytes; `source` names it in messages. A key given twice, a number
// beyond a double and any schema error are refused with the JSON path; nothing throws.
Status ParseBakeConfig(std::string_view text, const std::string& source, BakeConfig* config);
Status ApplyBakeConfig(const nlohmann::json& json, const std::string& source, BakeConfig* config);

// {"section.key": {"default", "unit", "range", "description"}, ...}
nlohmann::json BakeConfigReference();
// The values in effect, as a config file would spell them.
nlohmann::json BakeConfigToJson(const BakeConfig& config);

}  // namespace drape::bake

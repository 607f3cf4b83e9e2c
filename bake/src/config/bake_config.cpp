#include "drape/bake/bake_config.h"

#include <fstream>

#include "config/bake_config_schema.h"
#include "config/json_document.h"

namespace drape::bake {
namespace {

using nlohmann::json;

// Accessors by lambda keep the tables readable without pointer-to-nested-member gymnastics.

const JsonSchema<BakeConfig>& ImportSection() {
  static const JsonSchema<BakeConfig> schema =
      JsonSchema<BakeConfig>()
          .Number("unit_scale", "m per source unit", Closed(0, 1e6),
                  "0 = detect (FBX UnitScaleFactor, glTF metres, then a body-height sanity check)",
                  [](BakeConfig& c) -> double& { return c.import.unit_scale; })
          .Choice("up_axis", {"auto", "+X", "-X", "+Y", "-Y", "+Z", "-Z"},
                  "source axis that becomes the asset's +Y; auto = file metadata, else +Y",
                  [](BakeConfig& c) -> std::string& { return c.import.up_axis; })
          .Float("clip_sample_rate", "Hz", OpenBelow(0, 1000), "rate the clips are resampled at",
                 [](BakeConfig& c) -> float& { return c.import.clip_sample_rate; })
          .Bool("rename_duplicate_joints",
                "repair duplicate or empty joint names with suffixes instead of failing",
                [](BakeConfig& c) -> bool& { return c.import.rename_duplicate_joints; })
          .Unsigned<uint32_t>("memory_limit_mb", "MiB", 64, 1048576,
                              "memory the model reader may add; a file that needs more is refused",
                              [](BakeConfig& c) -> uint32_t& { return c.import.memory_limit_mb; })
          .Float("time_limit_s", "s", OpenBelow(0, 86400),
                 "time the model reader may take; a file that takes longer is refused",
                 [](BakeConfig& c) -> float& { return c.import.time_limit_s; });
  return schema;
}

const JsonSchema<BakeConfig>& MapsSection() {
  static const JsonSchema<BakeConfig> schema =
      JsonSchema<BakeConfig>()
          .Bool("enabled", "bake paper A's front/back depth and normal maps of the rest pose",
                [](BakeConfig& c) -> bool& { return c.maps_enabled; })
          .String("clip", StringRule::kAny,
                  "empty: the rest pose; a clip name: its poses at maps.clip_rate",
                  [](BakeConfig& c) -> std::string& { return c.maps_clip; })
          .Float("clip_rate", "Hz", Closed(0, 1000),
                 "poses per second of maps.clip; 0 = every resampled frame",
                 [](BakeConfig& c) -> float& { return c.maps_clip_rate; })
          .Unsigned<uint32_t>(
              "resolution", "texels", 16, 8192,
              "N: texels along the square window's side (the texel budget N*N for a fitted window)",
              [](BakeConfig& c) -> uint32_t& { return c.maps.resolution; })
          .Float("max_error", "mm", Closed(0, 1000),
                 "0: maps.resolution and maps.layers as given; > 0: the cheapest resolution "
                 "(256 to 2048) and layers (1 or 4) whose measured error at the rest pose (p99 "
                 "over points near the body and in its box, against the exact mesh) is within "
                 "this; the report gives the error of every setting tried",
                 [](BakeConfig& c) -> float& { return c.maps_max_error_mm; })
          .Bool("fitted_window", "fit the window to the body's L x H instead of the paper's square",
                [](BakeConfig& c) -> bool& { return c.maps.fitted_window; })
          .Float("epsilon", "m", Closed(0, 0.1),
                 "offset of the surface along its normals before rendering",
                 [](BakeConfig& c) -> float& { return c.maps.epsilon; })
          .Float("margin", "m", Closed(0, 1), "camera box enlargement beyond the offset surface",
                 [](BakeConfig& c) -> float& { return c.maps.margin; })
          .Float("render_tolerance", "m", Closed(0, 0.1),
                 "the asset's render mesh (the bind mesh simplified for drawing body maps at run "
                 "time) stays within this distance of the bind mesh, measured; 0: no render mesh",
                 [](BakeConfig& c) -> float& { return c.maps_render_tolerance; })
          .Float("asset_budget_mb", "MB", Closed(0, 1e6),
                 "the whole asset's size in MB (10^6 bytes) the bake keeps to by lowering the "
                 "body maps' resolution (not below 256); over it even then, a warning; 0: none",
                 [](BakeConfig& c) -> float& { return c.maps_asset_budget_mb; })
          .Enum<DepthEncoding>(
              "depth_encoding",
              {{"float32", DepthEncoding::kFloat32}, {"unorm16", DepthEncoding::kUnorm16}},
              "how depth is stored",
              [](BakeConfig& c) -> DepthEncoding& { return c.maps.depth_encoding; })
          .Enum<NormalEncoding>(
              "normal_encoding",
              {{"float32", NormalEncoding::kFloat32},
               {"oct16", NormalEncoding::kOct16},
               {"rgb8", NormalEncoding::kRgb8}},
              "how normals are stored (rgb8 is the paper's colour encoding)",
              [](BakeConfig& c) -> NormalEncoding& { return c.maps.normal_encoding; })
          .Enum<BodyMapLayout>(
              "layout", {{"spans", BodyMapLayout::kRowSpans}, {"dense", BodyMapLayout::kDense}},
              "spans: store only the covered texels, as row spans; dense: the whole rectangle "
              "around "
              "them (format version 1's layout); the runtime answers the same",
              [](BakeConfig& c) -> BodyMapLayout& { return c.maps.layout; })
          .Unsigned<uint8_t>(
              "layers", "layers", 1, kMaxBodyMapLayers,
              "depth layers per texel: 1 = paper A's slab (the air between an arm and the "
              "chest counts as inside); k adds up to k - 1 air gaps inside the slab, found by a "
              "CPU fragment pass (also with renderer osmesa); only the texels with a gap store "
              "the extra layers",
              [](BakeConfig& c) -> uint8_t& { return c.maps.layers; })
          .Enum<BakeConfig::MapViewAxis>(
              "view_axis",
              {{"auto", BakeConfig::MapViewAxis::kAuto},
               {"x", BakeConfig::MapViewAxis::kX},
               {"y", BakeConfig::MapViewAxis::kY},
               {"z", BakeConfig::MapViewAxis::kZ}},
              "the asset axis the maps are seen along; auto: the one whose slab holds the least "
              "air at the rest pose (a quadruped is seen from above: from the front, the air "
              "under its belly would be inside)",
              [](BakeConfig& c) -> BakeConfig::MapViewAxis& { return c.maps_view_axis; })
          .Enum<MapRenderer>(
              "renderer", {{"cpu", MapRenderer::kCpu}, {"osmesa", MapRenderer::kOsMesa}},
              "cpu: in-house deterministic rasterizer; osmesa: the paper's GL path (llvmpipe)",
              [](BakeConfig& c) -> MapRenderer& { return c.maps.renderer; });
  return schema;
}

const JsonSchema<BakeConfig>& BoneMapsSection() {
  static const JsonSchema<BakeConfig> schema =
      JsonSchema<BakeConfig>()
          .Bool("enabled",
                "bake per-bone local maps: each bone's part of the body in a frame fixed to the "
                "bone, so the maps follow any pose without rendering",
                [](BakeConfig& c) -> bool& { return c.bone_maps_enabled; })
          .Float("texel_size", "m", Closed(0, 1),
                 "the bone maps' texel; 0: the rest pose's longest side / 600 (3 mm on a 1.8 m "
                 "person)",
                 [](BakeConfig& c) -> float& { return c.bone_maps.texel_size; })
          .Float("epsilon", "m", Closed(0, 0.1),
                 "offset of the surface along its normals before rendering",
                 [](BakeConfig& c) -> float& { return c.bone_maps.epsilon; })
          .Float("min_weight", "", Closed(0.001, 1),
                 "a triangle joins a bone's part when the bone carries most of it or one of its "
                 "corners weighs this much on it (the overlap around joints)",
                 [](BakeConfig& c) -> float& { return c.bone_maps.min_weight; })
          .Unsigned<uint8_t>("layers", "", 1, kMaxBodyMapLayers,
                             "depth layers per texel: 1 the slab, more adds air gaps inside it",
                             [](BakeConfig& c) -> uint8_t& { return c.bone_maps.layers; });
  return schema;
}

const JsonSchema<BakeConfig>& HullsSection() {
  static const JsonSchema<BakeConfig> schema =
      JsonSchema<BakeConfig>()
          .Bool("enabled", "bake paper B's per-bone convex colliders",
                [](BakeConfig& c) -> bool& { return c.hulls_enabled; })
          .Float("rigid_threshold", "weight", OpenBelow(0.5, 1),
                 "a vertex is rigid to its heaviest bone when that weight reaches this",
                 [](BakeConfig& c) -> float& { return c.rigid_threshold; })
          .Float("shape_threshold", "weight", Closed(0, 1),
                 "a flexible vertex also shapes its heaviest bone's hull (and stays in its joint "
                 "sphere) when that weight reaches min(this, rigid_threshold); 0: every triangle "
                 "shapes the hull of the bone that carries most of its weight; 1: rigid vertices "
                 "only, as in paper B",
                 [](BakeConfig& c) -> float& { return c.shape_threshold; })
          .Float("delta", "m", Closed(0, 0.1),
                 "inflation: the delta-ball of every rigid and shaping vertex is inside",
                 [](BakeConfig& c) -> float& { return c.hull.delta; })
          .Enum<InflationMode>(
              "inflation",
              {{"minkowski", InflationMode::kMinkowskiIcosahedron},
               {"vertex_normal", InflationMode::kVertexNormalOffset}},
              "minkowski: guaranteed containment; vertex_normal: the paper's offset",
              [](BakeConfig& c) -> InflationMode& { return c.hull.inflation; })
          .Enum<SimplifyMode>("simplify",
                              {{"edge_collapse", SimplifyMode::kEdgeCollapse},
                               {"plane_removal", SimplifyMode::kPlaneRemoval},
                               {"none", SimplifyMode::kNone}},
                              "how the inflated hull is simplified, always convex and containing",
                              [](BakeConfig& c) -> SimplifyMode& { return c.hull.simplify; })
          .Unsigned<uint32_t>("max_triangles", "triangles", 4, 100000,
                              "simplification stops at or below this",
                              [](BakeConfig& c) -> uint32_t& { return c.hull.max_triangles; })
          .Float("max_growth", "m", Closed(0, 1),
                 "no collider vertex ends farther than this beyond the inflated hull (what "
                 "simplification may add to a collider's bloat)",
                 [](BakeConfig& c) -> float& { return c.hull.max_growth; })
          .Float("max_bloat", "m", OpenBelow(0, 1),
                 "a warning names every hull and joint sphere whose surface reaches farther than "
                 "this outside the body, beyond its delta (the report's \"fit\"); a bone whose "
                 "convex hull bulges farther than cut_fraction of it is cut into convex pieces "
                 "(max_pieces)",
                 [](BakeConfig& c) -> float& { return c.max_bloat; })
          .Float("cut_fraction", "ratio", OpenBelow(0, 1),
                 "convex pieces are cut until each one's hull bulges at most this fraction of "
                 "max_bloat out of the body: simplification and inflation make a collider bulge "
                 "0.5-3.5 mm more than its piece",
                 [](BakeConfig& c) -> float& { return c.hull_cut_fraction; })
          .Unsigned<uint32_t>(
              "max_pieces", "count", 1, 64,
              "a bone's region is cut into at most this many convex pieces, each its own hull, "
              "while its hull bulges beyond cut_fraction x max_bloat: its separate parts of the "
              "mesh (an eye, a fang) first, then plane cuts (a body without a skeleton is one "
              "region); 1: one hull per bone (paper B)",
              [](BakeConfig& c) -> uint32_t& { return c.hull_max_pieces; })
          .Enum<ObbMode>(
              "obb",
              {{"covariance", ObbMode::kCovariance}, {"cgal_optimal", ObbMode::kCgalOptimal}},
              "covariance: the paper's statistical box; cgal_optimal: CGAL's optimiser (seeded)",
              [](BakeConfig& c) -> ObbMode& { return c.hull.obb; })
          .Unsigned<uint32_t>(
              "min_points", "vertices", 1, 1000000,
              "bones with fewer distinct rigid vertices are left to the joint spheres",
              [](BakeConfig& c) -> uint32_t& { return c.hull.min_points; })
          .Enum<ProjectionAxis>(
              "projection_axis",
              {{"auto", ProjectionAxis::kAuto},
               {"longest", ProjectionAxis::kLongest},
               {"shortest", ProjectionAxis::kShortest}},
              "OBB axis the Kirkpatrick hierarchies project along (paper: longest)",
              [](BakeConfig& c) -> ProjectionAxis& { return c.kirkpatrick.axis; })
          .Enum<MapTableChoice>(
              "map_table",
              {{"auto", MapTableChoice::kAuto},
               {"sphere", MapTableChoice::kSphere},
               {"cylinder", MapTableChoice::kCylinder}},
              "response table shape; auto picks a cylinder for elongated colliders",
              [](BakeConfig& c) -> MapTableChoice& { return c.map_table.kind; })
          .Float("cylinder_elongation", "ratio", Closed(1, 1000),
                 "auto: a cylinder when the longest / middle OBB half extent reaches this",
                 [](BakeConfig& c) -> float& { return c.map_table.cylinder_elongation; })
          .Unsigned<uint32_t>("map_rows", "cells", 1, 1024,
                              "theta (sphere) or z (cylinder) cells of the map table",
                              [](BakeConfig& c) -> uint32_t& { return c.map_table.sphere_rows; })
          .Unsigned<uint32_t>("map_cols", "cells", 1, 1024, "phi cells of the map table",
                              [](BakeConfig& c) -> uint32_t& { return c.map_table.sphere_cols; });
  return schema;
}

const JsonSchema<BakeConfig>& SpheresSection() {
  static const JsonSchema<BakeConfig> schema =
      JsonSchema<BakeConfig>()
          .Bool("enabled", "bake paper B's joint spheres over the flexible vertices",
                [](BakeConfig& c) -> bool& { return c.spheres_enabled; })
          .Float("delta", "m", Closed(0, 0.1), "added to each joint sphere's radius",
                 [](BakeConfig& c) -> float& { return c.sphere_delta; })
          .Enum<SphereCover>(
              "cover",
              {{"flexible", SphereCover::kFlexible},
               {"left_by_hulls", SphereCover::kLeftByHulls},
               {"surface", SphereCover::kSurface}},
              "flexible: every flexible vertex of the joint (paper B); left_by_hulls: only the "
              "flexible corners of rest-pose triangles no single hull holds (smaller spheres on "
              "smoothly weighted rigs; needs hulls.enabled); surface: as large as the body "
              "around the joint centre allows (the centre's distance to the surface)",
              [](BakeConfig& c) -> SphereCover& { return c.sphere_cover; })
          .Float("min_radius", "m", Closed(0, 1),
                 "cover surface: a joint whose centre is nearer the body surface than this (or "
                 "outside the body) gets no sphere",
                 [](BakeConfig& c) -> float& { return c.sphere_min_radius; });
  return schema;
}

const JsonSchema<BakeConfig>& CapsulesSection() {
  static const JsonSchema<BakeConfig> schema =
      JsonSchema<BakeConfig>()
          .Bool("enabled",
                "bake a tapered capsule per bone that carries skin, fitted to the body's "
                "cross-section (the engines' cloth colliders)",
                [](BakeConfig& c) -> bool& { return c.capsules_enabled; })
          .Float("radius_quantile", "", OpenBelow(0, 1),
                 "of the surface's distances from the capsule's axis, per slab along it: the "
                 "radius there (1 bounds the surface and bloats where the cross-section is not "
                 "round; 0.5 is the median)",
                 [](BakeConfig& c) -> float& { return c.capsules.radius_quantile; })
          .Unsigned<uint32_t>("slabs", "", 1, 1000,
                              "slabs along the axis whose radii the taper is fitted to",
                              [](BakeConfig& c) -> uint32_t& { return c.capsules.slabs; })
          .Float("min_radius", "m", OpenBelow(0, 1), "the smallest radius of a capsule's end",
                 [](BakeConfig& c) -> float& { return c.capsules.min_radius; });
  return schema;
}

}  // namespace

const JsonSchema<BakeConfig>& BakeConfigSchema() {
  static const JsonSchema<BakeConfig> schema =
      JsonSchema<BakeConfig>(
          "drape-bake's parameters: a `drape-bake --config` file holds this object "
          "(`drape-bake --dump-config` prints it as JSON, with every default). A scene's `/bake` "
          "takes the same keys except the collider kinds (`enabled`) and `maps.clip`, which its "
          "`/collision/methods` and `/animation/clip` decide.")
          .Object("import", ImportSection(), "how the character file is read",
                  [](BakeConfig& c) -> BakeConfig& { return c; })
          .Object("maps", MapsSection(), "paper A's body maps",
                  [](BakeConfig& c) -> BakeConfig& { return c; })
          .Object("bone_maps", BoneMapsSection(), "per-bone local maps",
                  [](BakeConfig& c) -> BakeConfig& { return c; })
          .Object("hulls", HullsSection(), "paper B's per-bone convex colliders",
                  [](BakeConfig& c) -> BakeConfig& { return c; })
          .Object("spheres", SpheresSection(), "paper B's joint spheres",
                  [](BakeConfig& c) -> BakeConfig& { return c; })
          .Object("capsules", CapsulesSection(), "tapered capsules per bone",
                  [](BakeConfig& c) -> BakeConfig& { return c; })
          .Rule([](const JsonAt& at, BakeConfig& c) {
            if (c.maps_enabled || c.bone_maps_enabled || c.hulls_enabled || c.spheres_enabled ||
                c.capsules_enabled)
              return Status::Ok();
            return at.Error(
                "maps.enabled, bone_maps.enabled, hulls.enabled, spheres.enabled and "
                "capsules.enabled are all false: the asset would hold no collider");
          });
  return schema;
}

Status ApplyBakeConfig(const json& config, const std::string& source, BakeConfig* out) {
  if (!config.is_object())
    return Status(StatusCode::kInvalidArgument, source + ": the config must be a JSON object");
  const JsonDocument document{source, ""};
  BakeConfig result = *out;
  if (Status s = BakeConfigSchema().Read(JsonAt(config, "", document), &result); !s.ok()) return s;
  if (result.maps_clip != out->maps_clip) result.maps_clip_origin = source + ": /maps/clip";
  *out = result;
  return Status::Ok();
}

Status LoadBakeConfig(const std::string& path, BakeConfig* config) {
  json parsed;
  if (Status s = ReadJsonFile(path, "config", &parsed); !s.ok()) return s;
  return ApplyBakeConfig(parsed, path, config);
}

Status ParseBakeConfig(std::string_view text, const std::string& source, BakeConfig* config) {
  json parsed;
  if (Status s = ParseJsonText(text, source, &parsed); !s.ok()) return s;
  return ApplyBakeConfig(parsed, source, config);
}

json BakeConfigReference() {
  static const BakeConfig defaults;
  return BakeConfigSchema().Reference(defaults);
}

json BakeConfigToJson(const BakeConfig& config) { return BakeConfigSchema().ToJson(config); }

}  // namespace drape::bake

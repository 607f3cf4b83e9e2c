#include "drape/bake/bake_config.h"

#include <cmath>
#include <fstream>
#include <functional>
#include <type_traits>
#include <vector>

namespace drape::bake {
namespace {

using nlohmann::json;

struct Parameter {
  std::string section, key, unit, range, description;
  std::function<json(const BakeConfig&)> get;
  // Returns an empty string on success, else why the value is refused.
  std::function<std::string(const json&, BakeConfig&)> set;
};

// Accessors by lambda keep the table readable without pointer-to-nested-member gymnastics.
Parameter MakeNumber(std::string section, std::string key, std::string unit, double lo, double hi,
                     bool lo_open, std::string description,
                     std::function<double&(BakeConfig&)> field) {
  Parameter p;
  p.section = std::move(section);
  p.key = std::move(key);
  p.unit = std::move(unit);
  p.range = std::string(lo_open ? "(" : "[") + json(lo).dump() + ", " + json(hi).dump() + "]";
  p.description = std::move(description);
  p.get = [field](const BakeConfig& c) { return json(field(const_cast<BakeConfig&>(c))); };
  p.set = [field, lo, hi, lo_open, range = p.range](const json& v, BakeConfig& c) -> std::string {
    if (!v.is_number()) return "must be a number";
    const double x = v.get<double>();
    if (!std::isfinite(x) || x > hi || x < lo || (lo_open && x == lo)) return "must be in " + range;
    field(c) = x;
    return "";
  };
  return p;
}

// A float parameter is range-checked in float: a value at a bound (0.1 m) is stored as the float
// nearest to it (0.100000001), and that stored value must pass the check again when the config is
// written back out and re-read (found by the config fuzzer).
Parameter MakeFloat(std::string section, std::string key, std::string unit, double lo, double hi,
                    bool lo_open, std::string description,
                    std::function<float&(BakeConfig&)> field) {
  Parameter p = MakeNumber(std::move(section), std::move(key), std::move(unit), lo, hi, lo_open,
                           std::move(description), nullptr);
  p.get = [field](const BakeConfig& c) { return json(field(const_cast<BakeConfig&>(c))); };
  p.set = [field, lo, hi, lo_open, range = p.range](const json& v, BakeConfig& c) -> std::string {
    if (!v.is_number()) return "must be a number";
    const double x = v.get<double>();
    const float f = static_cast<float>(x);
    const float flo = static_cast<float>(lo), fhi = static_cast<float>(hi);
    if (!std::isfinite(x) || !std::isfinite(f) || f > fhi || f < flo || (lo_open && f == flo)) {
      return "must be in " + range;
    }
    field(c) = f;
    return "";
  };
  return p;
}

Parameter MakeBool(std::string section, std::string key, std::string description,
                   std::function<bool&(BakeConfig&)> field) {
  Parameter p{std::move(section),     std::move(key), "",     "true | false",
              std::move(description), nullptr,        nullptr};
  p.get = [field](const BakeConfig& c) { return json(field(const_cast<BakeConfig&>(c))); };
  p.set = [field](const json& v, BakeConfig& c) -> std::string {
    if (!v.is_boolean()) return "must be true or false";
    field(c) = v.get<bool>();
    return "";
  };
  return p;
}

Parameter MakeChoice(std::string section, std::string key, std::vector<std::string> choices,
                     std::string description, std::function<std::string&(BakeConfig&)> field) {
  std::string range;
  for (const auto& c : choices) range += (range.empty() ? "" : " | ") + c;
  Parameter p{std::move(section),     std::move(key), "",     range,
              std::move(description), nullptr,        nullptr};
  p.get = [field](const BakeConfig& c) { return json(field(const_cast<BakeConfig&>(c))); };
  p.set = [field, choices, range](const json& v, BakeConfig& c) -> std::string {
    if (!v.is_string()) return "must be a string: " + range;
    const std::string s = v.get<std::string>();
    if (std::find(choices.begin(), choices.end(), s) == choices.end())
      return "'" + s + "' is not one of " + range;
    field(c) = s;
    return "";
  };
  return p;
}

Parameter MakeString(std::string section, std::string key, std::string description,
                     std::function<std::string&(BakeConfig&)> field) {
  Parameter p{std::move(section),     std::move(key), "",     "any string",
              std::move(description), nullptr,        nullptr};
  p.get = [field](const BakeConfig& c) { return json(field(const_cast<BakeConfig&>(c))); };
  p.set = [field](const json& v, BakeConfig& c) -> std::string {
    if (!v.is_string()) return "must be a string";
    field(c) = v.get<std::string>();
    return "";
  };
  return p;
}

template <class Enum>
Parameter MakeEnum(std::string section, std::string key,
                   std::vector<std::pair<std::string, Enum>> names, std::string description,
                   std::function<Enum&(BakeConfig&)> field) {
  std::string range;
  for (const auto& [name, value] : names) range += (range.empty() ? "" : " | ") + name;
  Parameter p{std::move(section),     std::move(key), "",     range,
              std::move(description), nullptr,        nullptr};
  p.get = [field, names](const BakeConfig& c) {
    const Enum value = field(const_cast<BakeConfig&>(c));
    for (const auto& [name, v] : names)
      if (v == value) return json(name);
    return json(nullptr);
  };
  p.set = [field, names, range](const json& v, BakeConfig& c) -> std::string {
    if (!v.is_string()) return "must be a string: " + range;
    for (const auto& [name, value] : names) {
      if (name == v.get<std::string>()) {
        field(c) = value;
        return "";
      }
    }
    return "'" + v.get<std::string>() + "' is not one of " + range;
  };
  return p;
}

// An unsigned count in a field of type UInt (uint32_t unless the call names another).
template <class UInt = uint32_t>
Parameter MakeUint(std::string section, std::string key, std::string unit,
                   std::type_identity_t<UInt> lo, std::type_identity_t<UInt> hi,
                   std::string description,
                   std::type_identity_t<std::function<UInt&(BakeConfig&)>> field) {
  Parameter p{std::move(section),
              std::move(key),
              std::move(unit),
              "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]",
              std::move(description),
              nullptr,
              nullptr};
  p.get = [field](const BakeConfig& c) { return json(field(const_cast<BakeConfig&>(c))); };
  p.set = [field, lo, hi, range = p.range](const json& v, BakeConfig& c) -> std::string {
    if (!v.is_number_integer() && !v.is_number_unsigned()) return "must be an integer in " + range;
    const int64_t x = v.get<int64_t>();
    if (x < lo || x > hi) return "must be in " + range;
    field(c) = static_cast<UInt>(x);
    return "";
  };
  return p;
}

const std::vector<Parameter>& Parameters() {
  static const std::vector<Parameter> table = {
      MakeNumber("import", "unit_scale", "m per source unit", 0, 1e6, false,
                 "0 = detect (FBX UnitScaleFactor, glTF metres, then a body-height sanity check)",
                 [](BakeConfig& c) -> double& { return c.import.unit_scale; }),
      MakeChoice("import", "up_axis", {"auto", "+X", "-X", "+Y", "-Y", "+Z", "-Z"},
                 "source axis that becomes the asset's +Y; auto = file metadata, else +Y",
                 [](BakeConfig& c) -> std::string& { return c.import.up_axis; }),
      MakeFloat("import", "clip_sample_rate", "Hz", 0, 1000, true,
                "rate the clips are resampled at",
                [](BakeConfig& c) -> float& { return c.import.clip_sample_rate; }),
      MakeBool("import", "rename_duplicate_joints",
               "repair duplicate or empty joint names with suffixes instead of failing",
               [](BakeConfig& c) -> bool& { return c.import.rename_duplicate_joints; }),

      MakeBool("maps", "enabled",
               "bake paper A's front/back depth and normal maps of the rest pose",
               [](BakeConfig& c) -> bool& { return c.maps_enabled; }),
      MakeString("maps", "clip", "empty: the rest pose; a clip name: its poses at maps.clip_rate",
                 [](BakeConfig& c) -> std::string& { return c.maps_clip; }),
      MakeFloat("maps", "clip_rate", "Hz", 0, 1000, false,
                "poses per second of maps.clip; 0 = every resampled frame",
                [](BakeConfig& c) -> float& { return c.maps_clip_rate; }),
      MakeUint(
          "maps", "resolution", "texels", 16, 8192,
          "N: texels along the square window's side (the texel budget N*N for a fitted window)",
          [](BakeConfig& c) -> uint32_t& { return c.maps.resolution; }),
      MakeBool("maps", "fitted_window",
               "fit the window to the body's L x H instead of the paper's square",
               [](BakeConfig& c) -> bool& { return c.maps.fitted_window; }),
      MakeFloat("maps", "epsilon", "m", 0, 0.1, false,
                "offset of the surface along its normals before rendering",
                [](BakeConfig& c) -> float& { return c.maps.epsilon; }),
      MakeFloat("maps", "margin", "m", 0, 1, false,
                "camera box enlargement beyond the offset surface",
                [](BakeConfig& c) -> float& { return c.maps.margin; }),
      MakeEnum<DepthEncoding>(
          "maps", "depth_encoding",
          {{"float32", DepthEncoding::kFloat32}, {"unorm16", DepthEncoding::kUnorm16}},
          "how depth is stored",
          [](BakeConfig& c) -> DepthEncoding& { return c.maps.depth_encoding; }),
      MakeEnum<NormalEncoding>(
          "maps", "normal_encoding",
          {{"float32", NormalEncoding::kFloat32},
           {"oct16", NormalEncoding::kOct16},
           {"rgb8", NormalEncoding::kRgb8}},
          "how normals are stored (rgb8 is the paper's colour encoding)",
          [](BakeConfig& c) -> NormalEncoding& { return c.maps.normal_encoding; }),
      MakeEnum<BodyMapLayout>(
          "maps", "layout", {{"spans", BodyMapLayout::kRowSpans}, {"dense", BodyMapLayout::kDense}},
          "spans: store only the covered texels, as row spans; dense: the whole rectangle around "
          "them (format version 1's layout); the runtime answers the same",
          [](BakeConfig& c) -> BodyMapLayout& { return c.maps.layout; }),
      MakeUint<uint8_t>(
          "maps", "layers", "layers", 1, kMaxBodyMapLayers,
          "depth layers per texel: 1 = paper A's slab (the air between an arm and the "
          "chest counts as inside); k adds up to k - 1 air gaps inside the slab, found by a "
          "CPU fragment pass (also with renderer osmesa); only the texels with a gap store "
          "the extra layers",
          [](BakeConfig& c) -> uint8_t& { return c.maps.layers; }),
      MakeEnum<MapRenderer>(
          "maps", "renderer", {{"cpu", MapRenderer::kCpu}, {"osmesa", MapRenderer::kOsMesa}},
          "cpu: in-house deterministic rasterizer; osmesa: the paper's GL path (llvmpipe)",
          [](BakeConfig& c) -> MapRenderer& { return c.maps.renderer; }),

      MakeBool("hulls", "enabled", "bake paper B's per-bone convex colliders",
               [](BakeConfig& c) -> bool& { return c.hulls_enabled; }),
      MakeFloat("hulls", "rigid_threshold", "weight", 0.5, 1, true,
                "a vertex is rigid to its heaviest bone when that weight reaches this",
                [](BakeConfig& c) -> float& { return c.rigid_threshold; }),
      MakeFloat("hulls", "shape_threshold", "weight", 0.5, 1, true,
                "a flexible vertex also shapes its heaviest bone's hull (and stays in its joint "
                "sphere) when that weight reaches min(this, rigid_threshold); 1: rigid vertices "
                "only, as in paper B",
                [](BakeConfig& c) -> float& { return c.shape_threshold; }),
      MakeFloat("hulls", "delta", "m", 0, 0.1, false,
                "inflation: the delta-ball of every rigid and shaping vertex is inside",
                [](BakeConfig& c) -> float& { return c.hull.delta; }),
      MakeEnum<InflationMode>(
          "hulls", "inflation",
          {{"minkowski", InflationMode::kMinkowskiIcosahedron},
           {"vertex_normal", InflationMode::kVertexNormalOffset}},
          "minkowski: guaranteed containment; vertex_normal: the paper's offset",
          [](BakeConfig& c) -> InflationMode& { return c.hull.inflation; }),
      MakeEnum<SimplifyMode>("hulls", "simplify",
                             {{"edge_collapse", SimplifyMode::kEdgeCollapse},
                              {"plane_removal", SimplifyMode::kPlaneRemoval},
                              {"none", SimplifyMode::kNone}},
                             "how the inflated hull is simplified, always convex and containing",
                             [](BakeConfig& c) -> SimplifyMode& { return c.hull.simplify; }),
      MakeUint("hulls", "max_triangles", "triangles", 4, 100000,
               "simplification stops at or below this",
               [](BakeConfig& c) -> uint32_t& { return c.hull.max_triangles; }),
      MakeFloat("hulls", "max_growth", "m", 0, 1, false,
                "no collider vertex ends farther than this beyond the inflated hull",
                [](BakeConfig& c) -> float& { return c.hull.max_growth; }),
      MakeEnum<ObbMode>(
          "hulls", "obb",
          {{"covariance", ObbMode::kCovariance}, {"cgal_optimal", ObbMode::kCgalOptimal}},
          "covariance: the paper's statistical box; cgal_optimal: CGAL's optimiser (seeded)",
          [](BakeConfig& c) -> ObbMode& { return c.hull.obb; }),
      MakeUint("hulls", "min_points", "vertices", 1, 1000000,
               "bones with fewer distinct rigid vertices are left to the joint spheres",
               [](BakeConfig& c) -> uint32_t& { return c.hull.min_points; }),

      MakeEnum<ProjectionAxis>(
          "hulls", "projection_axis",
          {{"auto", ProjectionAxis::kAuto},
           {"longest", ProjectionAxis::kLongest},
           {"shortest", ProjectionAxis::kShortest}},
          "OBB axis the Kirkpatrick hierarchies project along (paper: longest)",
          [](BakeConfig& c) -> ProjectionAxis& { return c.kirkpatrick.axis; }),
      MakeEnum<MapTableChoice>(
          "hulls", "map_table",
          {{"auto", MapTableChoice::kAuto},
           {"sphere", MapTableChoice::kSphere},
           {"cylinder", MapTableChoice::kCylinder}},
          "response table shape; auto picks a cylinder for elongated colliders",
          [](BakeConfig& c) -> MapTableChoice& { return c.map_table.kind; }),
      MakeFloat("hulls", "cylinder_elongation", "ratio", 1, 1000, false,
                "auto: a cylinder when the longest / middle OBB half extent reaches this",
                [](BakeConfig& c) -> float& { return c.map_table.cylinder_elongation; }),
      MakeUint("hulls", "map_rows", "cells", 1, 1024,
               "theta (sphere) or z (cylinder) cells of the map table",
               [](BakeConfig& c) -> uint32_t& { return c.map_table.sphere_rows; }),
      MakeUint("hulls", "map_cols", "cells", 1, 1024, "phi cells of the map table",
               [](BakeConfig& c) -> uint32_t& { return c.map_table.sphere_cols; }),

      MakeBool("spheres", "enabled", "bake paper B's joint spheres over the flexible vertices",
               [](BakeConfig& c) -> bool& { return c.spheres_enabled; }),
      MakeFloat("spheres", "delta", "m", 0, 0.1, false, "added to each joint sphere's radius",
                [](BakeConfig& c) -> float& { return c.sphere_delta; }),
      MakeEnum<SphereCover>(
          "spheres", "cover",
          {{"flexible", SphereCover::kFlexible}, {"left_by_hulls", SphereCover::kLeftByHulls}},
          "flexible: every flexible vertex of the joint (paper B); left_by_hulls: only the "
          "flexible corners of rest-pose triangles no single hull holds (smaller spheres on "
          "smoothly weighted rigs; needs hulls.enabled)",
          [](BakeConfig& c) -> SphereCover& { return c.sphere_cover; }),
  };
  return table;
}

}  // namespace

Status ApplyBakeConfig(const json& config, const std::string& source, BakeConfig* out) {
  if (!config.is_object())
    return Status(StatusCode::kInvalidArgument, source + ": the config must be a JSON object");
  BakeConfig result = *out;
  for (const auto& [section, values] : config.items()) {
    if (!values.is_object()) {
      return Status(StatusCode::kInvalidArgument,
                    source + ": /" + section + " must be an object of parameters");
    }
    for (const auto& [key, value] : values.items()) {
      const Parameter* match = nullptr;
      for (const Parameter& p : Parameters())
        if (p.section == section && p.key == key) match = &p;
      const std::string where = source + ": /" + section + "/" + key;
      if (match == nullptr) {
        return Status(StatusCode::kInvalidArgument,
                      where + " is not a parameter (see drape-bake --dump-config)");
      }
      if (std::string why = match->set(value, result); !why.empty()) {
        return Status(StatusCode::kInvalidArgument, where + " " + why);
      }
    }
  }
  *out = result;
  return Status::Ok();
}

Status LoadBakeConfig(const std::string& path, BakeConfig* config) {
  std::ifstream in(path);
  if (!in) return Status(StatusCode::kIoError, path + ": cannot open the config file");
  json parsed;
  try {
    parsed = json::parse(in);
  } catch (const json::parse_error& e) {
    return Status(StatusCode::kInvalidArgument, path + ": not valid JSON: " + e.what());
  }
  return ApplyBakeConfig(parsed, path, config);
}

json BakeConfigReference() {
  const BakeConfig defaults;
  json out = json::object();
  for (const Parameter& p : Parameters()) {
    out[p.section][p.key] = {{"default", p.get(defaults)},
                             {"unit", p.unit},
                             {"range", p.range},
                             {"description", p.description}};
  }
  return out;
}

json BakeConfigToJson(const BakeConfig& config) {
  json out = json::object();
  for (const Parameter& p : Parameters()) out[p.section][p.key] = p.get(config);
  return out;
}

}  // namespace drape::bake

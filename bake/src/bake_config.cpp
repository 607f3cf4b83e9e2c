#include "drape/bake/bake_config.h"

#include <cmath>
#include <fstream>
#include <functional>
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

Parameter MakeFloat(std::string section, std::string key, std::string unit, double lo, double hi,
                    bool lo_open, std::string description,
                    std::function<float&(BakeConfig&)> field) {
  auto holder = std::make_shared<double>();
  Parameter p =
      MakeNumber(std::move(section), std::move(key), std::move(unit), lo, hi, lo_open,
                 std::move(description), [holder](BakeConfig&) -> double& { return *holder; });
  p.get = [field](const BakeConfig& c) { return json(field(const_cast<BakeConfig&>(c))); };
  auto check = p.set;
  p.set = [check, holder, field](const json& v, BakeConfig& c) -> std::string {
    std::string why = check(v, c);
    if (why.empty()) field(c) = static_cast<float>(*holder);
    return why;
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

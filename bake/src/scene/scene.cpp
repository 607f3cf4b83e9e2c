#include "drape/bake/scene.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <numbers>
#include <queue>
#include <sstream>
#include <utility>

#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"

namespace drape::bake {
namespace {

using nlohmann::json;

constexpr uint32_t kMaxGridCells = 1024;             // per side of a generated garment
constexpr uint32_t kMaxGarmentParticles = 1u << 20;  // per garment (a scene is a demo, not a film)
constexpr float kInf = std::numeric_limits<float>::infinity();

Status Invalid(const std::string& message) { return Status(StatusCode::kInvalidArgument, message); }

std::string Quote(const std::string& s) { return "'" + s + "'"; }

std::string JoinNames(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : " | ") + n;
  return out;
}

const char* TypeName(const json& value) {
  if (value.is_null()) return "null";
  if (value.is_boolean()) return "a boolean";
  if (value.is_number()) return "a number";
  if (value.is_string()) return "a string";
  if (value.is_array()) return "an array";
  return "an object";
}

// The fields of one JSON object at a JSON path; every error names the file and the path.
class Fields {
 public:
  Fields(const json& object, std::string path, const std::string& source)
      : object_(object), path_(std::move(path)), source_(source) {}

  const std::string& path() const { return path_; }
  const std::string& source() const { return source_; }
  Fields Sub(const json& object, const std::string& path) const {
    return Fields(object, path, source_);
  }
  std::string Path(const std::string& key) const { return path_ + "/" + key; }
  Status Error(const std::string& path, const std::string& why) const {
    return Invalid(source_ + ": " + (path.empty() ? "/" : path) + ": " + why);
  }

  // Every key must be one of `known`.
  Status CheckKeys(const std::vector<std::string>& known) const {
    for (const auto& item : object_.items()) {
      if (std::find(known.begin(), known.end(), item.key()) == known.end()) {
        return Error(Path(item.key()), "unknown key (known here: " + JoinNames(known) + ")");
      }
    }
    return Status::Ok();
  }

  const json* Find(const std::string& key) const {
    const auto it = object_.find(key);
    return it == object_.end() ? nullptr : &*it;
  }

  // A number in [lo, hi] (open ends excluded); absent keeps *out.
  Status Number(const std::string& key, float* out, double lo, double hi, bool lo_open = false,
                bool hi_open = false) const {
    const json* v = Find(key);
    if (v == nullptr) return Status::Ok();
    return NumberValue(*v, Path(key), out, lo, hi, lo_open, hi_open);
  }
  Status NumberValue(const json& v, const std::string& path, float* out, double lo, double hi,
                     bool lo_open, bool hi_open) const {
    const std::string range = std::string(lo_open ? "(" : "[") + FormatNumber(lo) + ", " +
                              FormatNumber(hi) + (hi_open ? ")" : "]");
    if (!v.is_number())
      return Error(path, std::string("must be a number in ") + range + ", not " + TypeName(v));
    const double x = v.get<double>();
    if (!std::isfinite(x) || x < lo || x > hi || (lo_open && x == lo) || (hi_open && x == hi)) {
      return Error(path, FormatNumber(x) + " is out of range: must be in " + range);
    }
    *out = static_cast<float>(x);
    return Status::Ok();
  }

  Status Uint(const std::string& key, uint32_t* out, uint32_t lo, uint32_t hi) const {
    const json* v = Find(key);
    if (v == nullptr) return Status::Ok();
    const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    if (!v->is_number_integer()) {
      return Error(Path(key), std::string("must be an integer in ") + range + ", not " +
                                  (v->is_number() ? "a fraction" : TypeName(*v)));
    }
    const int64_t x = v->get<int64_t>();
    if (x < lo || x > hi) {
      return Error(Path(key), std::to_string(x) + " is out of range: must be in " + range);
    }
    *out = static_cast<uint32_t>(x);
    return Status::Ok();
  }

  Status Bool(const std::string& key, bool* out) const {
    const json* v = Find(key);
    if (v == nullptr) return Status::Ok();
    if (!v->is_boolean())
      return Error(Path(key), std::string("must be true or false, not ") + TypeName(*v));
    *out = v->get<bool>();
    return Status::Ok();
  }

  Status String(const std::string& key, std::string* out, bool required = false) const {
    const json* v = Find(key);
    if (v == nullptr) {
      return required ? Error(Path(key), "missing (a string is required)") : Status::Ok();
    }
    if (!v->is_string())
      return Error(Path(key), std::string("must be a string, not ") + TypeName(*v));
    *out = v->get<std::string>();
    if (out->empty()) return Error(Path(key), "must not be empty");
    return Status::Ok();
  }

  // A string that must be one of `names`; *out gets its index.
  Status Choice(const std::string& key, const std::vector<std::string>& names, size_t* out) const {
    const json* v = Find(key);
    if (v == nullptr) return Status::Ok();
    if (!v->is_string()) {
      return Error(Path(key),
                   std::string("must be a string: ") + JoinNames(names) + ", not " + TypeName(*v));
    }
    const std::string s = v->get<std::string>();
    for (size_t i = 0; i < names.size(); ++i) {
      if (names[i] == s) {
        *out = i;
        return Status::Ok();
      }
    }
    return Error(Path(key), Quote(s) + " is not one of " + JoinNames(names));
  }

  // [x, y, z], finite, each within +-limit.
  Status Vec3(const std::string& key, Float3* out, double limit = 1e4) const {
    const json* v = Find(key);
    if (v == nullptr) return Status::Ok();
    return Vec3Value(*v, Path(key), out, limit);
  }
  Status Vec3Value(const json& v, const std::string& path, Float3* out, double limit) const {
    if (!v.is_array() || v.size() != 3) {
      return Error(path, std::string("must be an array of 3 numbers [x, y, z], not ") +
                             (v.is_array() ? "an array of " + std::to_string(v.size())
                                           : std::string(TypeName(v))));
    }
    float c[3];
    for (size_t i = 0; i < 3; ++i) {
      if (Status s =
              NumberValue(v[i], path + "/" + std::to_string(i), &c[i], -limit, limit, false, false);
          !s.ok())
        return s;
    }
    *out = {c[0], c[1], c[2]};
    return Status::Ok();
  }

  // A sub-object (absent: *present = false).
  Status Object(const std::string& key, const json** out) const {
    *out = nullptr;
    const json* v = Find(key);
    if (v == nullptr) return Status::Ok();
    if (!v->is_object())
      return Error(Path(key), std::string("must be an object, not ") + TypeName(*v));
    *out = v;
    return Status::Ok();
  }

 private:
  static std::string FormatNumber(double x) {
    std::ostringstream out;
    out << x;
    return out.str();
  }

  const json& object_;
  std::string path_;
  const std::string& source_;
};

#define DRAPE_RETURN_IF_ERROR(expr)     \
  do {                                  \
    if (Status _s = (expr); !_s.ok()) { \
      return _s;                        \
    }                                   \
  } while (0)

std::string ResolvePath(const std::string& directory, const std::string& file) {
  std::filesystem::path p(file);
  if (p.is_relative() && !directory.empty()) p = std::filesystem::path(directory) / p;
  return p.lexically_normal().string();
}

Status ParseMaterial(const Fields& f, const std::string& key, SpringMaterial* material) {
  const json* object = nullptr;
  DRAPE_RETURN_IF_ERROR(f.Object(key, &object));
  if (object == nullptr) return Status::Ok();
  const Fields m = f.Sub(*object, f.Path(key));
  DRAPE_RETURN_IF_ERROR(m.CheckKeys({"stiffness", "damping", "correction"}));
  DRAPE_RETURN_IF_ERROR(m.Number("stiffness", &material->stiffness, 0, 1e7));
  DRAPE_RETURN_IF_ERROR(m.Number("damping", &material->damping, 0, 1e4));
  DRAPE_RETURN_IF_ERROR(m.Number("correction", &material->correction, 0, 1));
  return Status::Ok();
}

// One selection object: exactly one of ring, vertices, box (plus `extra` keys allowed).
Status ParseSelection(const Fields& f, const json& value, const std::string& path,
                      std::vector<std::string> extra, SceneSelection* out, const json** object) {
  if (!value.is_object())
    return f.Error(path, std::string("must be an object, not ") + TypeName(value));
  *object = &value;
  const Fields s = f.Sub(value, path);
  std::vector<std::string> known = {"ring", "vertices", "box"};
  known.insert(known.end(), extra.begin(), extra.end());
  DRAPE_RETURN_IF_ERROR(s.CheckKeys(known));
  out->path = path;
  int given = 0;
  if (s.Find("ring") != nullptr) {
    ++given;
    DRAPE_RETURN_IF_ERROR(s.String("ring", &out->ring));
  }
  if (const json* v = s.Find("vertices"); v != nullptr) {
    ++given;
    if (!v->is_array() || v->empty()) {
      return f.Error(s.Path("vertices"), std::string("must be a non-empty array of particle ") +
                                             "indices, not " +
                                             (v->is_array() ? "an empty array" : TypeName(*v)));
    }
    for (size_t i = 0; i < v->size(); ++i) {
      const json& e = (*v)[i];
      if (!e.is_number_integer() || e.get<int64_t>() < 0 || e.get<int64_t>() > 0xffffffffll) {
        return f.Error(s.Path("vertices") + "/" + std::to_string(i),
                       "must be a particle index (an integer >= 0)");
      }
      out->vertices.push_back(static_cast<uint32_t>(e.get<int64_t>()));
    }
  }
  if (s.Find("box") != nullptr) {
    ++given;
    const json* box = nullptr;
    DRAPE_RETURN_IF_ERROR(s.Object("box", &box));
    const Fields b = f.Sub(*box, s.Path("box"));
    DRAPE_RETURN_IF_ERROR(b.CheckKeys({"min", "max"}));
    if (b.Find("min") == nullptr) return f.Error(b.Path("min"), "missing ([x, y, z] in metres)");
    if (b.Find("max") == nullptr) return f.Error(b.Path("max"), "missing ([x, y, z] in metres)");
    DRAPE_RETURN_IF_ERROR(b.Vec3("min", &out->box_min));
    DRAPE_RETURN_IF_ERROR(b.Vec3("max", &out->box_max));
    if (out->box_max.x < out->box_min.x || out->box_max.y < out->box_min.y ||
        out->box_max.z < out->box_min.z) {
      return f.Error(b.Path("max"), "must be >= min in every coordinate");
    }
    out->has_box = true;
  }
  if (given != 1) {
    return f.Error(path, given == 0 ? "names no particles: give one of ring, vertices, box"
                                    : "give only one of ring, vertices, box");
  }
  return Status::Ok();
}

// An object or an array of objects: calls `each(value, path)` for every element.
Status ForEachObject(const Fields& f, const std::string& key,
                     const std::function<Status(const json&, const std::string&)>& each) {
  const json* v = f.Find(key);
  if (v == nullptr) return Status::Ok();
  if (v->is_object()) return each(*v, f.Path(key));
  if (!v->is_array()) {
    return f.Error(f.Path(key),
                   std::string("must be an object or an array of objects, not ") + TypeName(*v));
  }
  for (size_t i = 0; i < v->size(); ++i) {
    DRAPE_RETURN_IF_ERROR(each((*v)[i], f.Path(key) + "/" + std::to_string(i)));
  }
  return Status::Ok();
}

// A unit direction (normalised here; must not be zero).
Status UnitVec3(const Fields& f, const std::string& key, Float3* out) {
  Float3 v = *out;
  DRAPE_RETURN_IF_ERROR(f.Vec3(key, &v));
  const float length = Length(v);
  if (!(length > 1e-6f)) return f.Error(f.Path(key), "must not be the zero vector");
  *out = v * (1.f / length);
  return Status::Ok();
}

Status ParseShape(const Fields& g, const Scene& scene, SceneGarment* garment) {
  const json* object = nullptr;
  DRAPE_RETURN_IF_ERROR(g.Object("shape", &object));
  const json empty = json::object();
  if (object == nullptr) {
    if (garment->type == GarmentType::kObj) {
      return g.Error(g.Path("shape"), "missing (an OBJ garment needs {\"file\": ...})");
    }
    object = &empty;  // the generator's defaults
  }
  const Fields s = g.Sub(*object, g.Path("shape"));
  constexpr double kMaxSize = 100;  // metres
  switch (garment->type) {
    case GarmentType::kSheet: {
      SheetShape& sh = garment->sheet;
      DRAPE_RETURN_IF_ERROR(
          s.CheckKeys({"center", "axis_u", "axis_v", "width", "height", "columns", "rows"}));
      DRAPE_RETURN_IF_ERROR(s.Vec3("center", &sh.center));
      DRAPE_RETURN_IF_ERROR(UnitVec3(s, "axis_u", &sh.axis_u));
      DRAPE_RETURN_IF_ERROR(UnitVec3(s, "axis_v", &sh.axis_v));
      if (std::fabs(Dot(sh.axis_u, sh.axis_v)) > 1e-3f)
        return s.Error(s.Path("axis_v"), "must be perpendicular to axis_u");
      DRAPE_RETURN_IF_ERROR(s.Number("width", &sh.width, 0, kMaxSize, true));
      DRAPE_RETURN_IF_ERROR(s.Number("height", &sh.height, 0, kMaxSize, true));
      DRAPE_RETURN_IF_ERROR(s.Uint("columns", &sh.columns, 1, kMaxGridCells));
      DRAPE_RETURN_IF_ERROR(s.Uint("rows", &sh.rows, 1, kMaxGridCells));
      break;
    }
    case GarmentType::kSkirt: {
      SkirtShape& sk = garment->skirt;
      DRAPE_RETURN_IF_ERROR(s.CheckKeys(
          {"top_center", "top_radius", "bottom_radius", "length", "segments", "rings"}));
      DRAPE_RETURN_IF_ERROR(s.Vec3("top_center", &sk.top_center));
      DRAPE_RETURN_IF_ERROR(s.Number("top_radius", &sk.top_radius, 0, kMaxSize, true));
      DRAPE_RETURN_IF_ERROR(s.Number("bottom_radius", &sk.bottom_radius, 0, kMaxSize, true));
      DRAPE_RETURN_IF_ERROR(s.Number("length", &sk.length, 0, kMaxSize, true));
      DRAPE_RETURN_IF_ERROR(s.Uint("segments", &sk.segments, 3, kMaxGridCells));
      DRAPE_RETURN_IF_ERROR(s.Uint("rings", &sk.rings, 1, kMaxGridCells));
      break;
    }
    case GarmentType::kCape: {
      CapeShape& c = garment->cape;
      DRAPE_RETURN_IF_ERROR(
          s.CheckKeys({"top_center", "top_width", "bottom_width", "length", "columns", "rows"}));
      DRAPE_RETURN_IF_ERROR(s.Vec3("top_center", &c.top_center));
      DRAPE_RETURN_IF_ERROR(s.Number("top_width", &c.top_width, 0, kMaxSize, true));
      DRAPE_RETURN_IF_ERROR(s.Number("bottom_width", &c.bottom_width, 0, kMaxSize, true));
      DRAPE_RETURN_IF_ERROR(s.Number("length", &c.length, 0, kMaxSize, true));
      DRAPE_RETURN_IF_ERROR(s.Uint("columns", &c.columns, 1, kMaxGridCells));
      DRAPE_RETURN_IF_ERROR(s.Uint("rows", &c.rows, 1, kMaxGridCells));
      break;
    }
    case GarmentType::kSleeve: {
      SleeveShape& sl = garment->sleeve;
      DRAPE_RETURN_IF_ERROR(
          s.CheckKeys({"start", "axis", "radius", "length", "segments", "rings"}));
      DRAPE_RETURN_IF_ERROR(s.Vec3("start", &sl.start));
      DRAPE_RETURN_IF_ERROR(UnitVec3(s, "axis", &sl.axis));
      DRAPE_RETURN_IF_ERROR(s.Number("radius", &sl.radius, 0, kMaxSize, true));
      DRAPE_RETURN_IF_ERROR(s.Number("length", &sl.length, 0, kMaxSize, true));
      DRAPE_RETURN_IF_ERROR(s.Uint("segments", &sl.segments, 3, kMaxGridCells));
      DRAPE_RETURN_IF_ERROR(s.Uint("rings", &sl.rings, 1, kMaxGridCells));
      break;
    }
    case GarmentType::kObj: {
      DRAPE_RETURN_IF_ERROR(s.CheckKeys({"file", "scale", "offset"}));
      std::string file;
      DRAPE_RETURN_IF_ERROR(s.String("file", &file, true));
      garment->obj_file = ResolvePath(scene.directory, file);
      if (!std::filesystem::is_regular_file(garment->obj_file))
        return s.Error(s.Path("file"), Quote(garment->obj_file) + " not found");
      DRAPE_RETURN_IF_ERROR(s.Number("scale", &garment->obj_scale, 0, 1e6, true));
      DRAPE_RETURN_IF_ERROR(s.Vec3("offset", &garment->obj_offset));
      break;
    }
  }
  return Status::Ok();
}

Status ParseGarment(const Fields& f, const json& value, const std::string& path, size_t index,
                    const Scene& scene, SceneGarment* garment) {
  if (!value.is_object())
    return f.Error(path, std::string("must be an object, not ") + TypeName(value));
  const Fields g = f.Sub(value, path);
  DRAPE_RETURN_IF_ERROR(g.CheckKeys(
      {"name", "type", "frame", "anchor", "shape", "material", "attach", "pin", "color"}));
  garment->path = path;
  if (g.Find("type") == nullptr)
    return g.Error(g.Path("type"), "missing (sheet | skirt | cape | sleeve | obj)");
  size_t type = 0;
  DRAPE_RETURN_IF_ERROR(g.Choice("type", {"sheet", "skirt", "cape", "sleeve", "obj"}, &type));
  garment->type = static_cast<GarmentType>(type);
  garment->name = std::string(ToString(garment->type)) + "_" + std::to_string(index);
  DRAPE_RETURN_IF_ERROR(g.String("name", &garment->name));
  size_t frame = 0;
  DRAPE_RETURN_IF_ERROR(g.Choice("frame", {"bind", "rest"}, &frame));
  garment->frame = static_cast<GarmentFrame>(frame);
  DRAPE_RETURN_IF_ERROR(g.String("anchor", &garment->anchor));
  DRAPE_RETURN_IF_ERROR(ParseShape(g, scene, garment));

  const json* material = nullptr;
  DRAPE_RETURN_IF_ERROR(g.Object("material", &material));
  if (material != nullptr) {
    const Fields m = g.Sub(*material, g.Path("material"));
    DRAPE_RETURN_IF_ERROR(
        m.CheckKeys({"density", "total_mass", "stretch", "bend", "bend_springs"}));
    DRAPE_RETURN_IF_ERROR(m.Number("density", &garment->density, 0, 1e3, true));
    DRAPE_RETURN_IF_ERROR(m.Number("total_mass", &garment->total_mass, 0, 1e4));
    DRAPE_RETURN_IF_ERROR(ParseMaterial(m, "stretch", &garment->stretch));
    DRAPE_RETURN_IF_ERROR(ParseMaterial(m, "bend", &garment->bend));
    DRAPE_RETURN_IF_ERROR(m.Bool("bend_springs", &garment->bend_springs));
  }

  Status attach_status = ForEachObject(g, "attach", [&](const json& v, const std::string& p) {
    SceneAttachment attachment;
    const json* object = nullptr;
    DRAPE_RETURN_IF_ERROR(ParseSelection(g, v, p, {"joint"}, &attachment.particles, &object));
    const Fields a = g.Sub(*object, p);
    DRAPE_RETURN_IF_ERROR(a.String("joint", &attachment.joint, true));
    garment->attachments.push_back(std::move(attachment));
    return Status::Ok();
  });
  if (!attach_status.ok()) return attach_status;
  Status pin_status = ForEachObject(g, "pin", [&](const json& v, const std::string& p) {
    SceneSelection pin;
    const json* object = nullptr;
    DRAPE_RETURN_IF_ERROR(ParseSelection(g, v, p, {}, &pin, &object));
    garment->pins.push_back(std::move(pin));
    return Status::Ok();
  });
  if (!pin_status.ok()) return pin_status;

  if (const json* color = g.Find("color"); color != nullptr) {
    if (!color->is_array() || color->size() != 3)
      return g.Error(g.Path("color"), "must be [r, g, b] with each in [0, 1]");
    for (size_t i = 0; i < 3; ++i) {
      DRAPE_RETURN_IF_ERROR(g.NumberValue((*color)[i], g.Path("color") + "/" + std::to_string(i),
                                          &garment->color[i], 0, 1, false, false));
    }
  }
  return Status::Ok();
}

Status ParseAnimation(const Fields& root, Scene* scene) {
  const json* object = nullptr;
  DRAPE_RETURN_IF_ERROR(root.Object("animation", &object));
  if (object == nullptr) return Status::Ok();
  const Fields a = root.Sub(*object, "/animation");
  DRAPE_RETURN_IF_ERROR(a.CheckKeys({"clip", "pose", "start", "duration", "loop", "settle"}));
  SceneAnimation& anim = scene->animation;
  DRAPE_RETURN_IF_ERROR(a.String("clip", &anim.clip));
  if (a.Find("pose") != nullptr && !anim.clip.empty())
    return a.Error(a.Path("pose"), "give either a clip or a static pose, not both");
  size_t pose = 0;
  DRAPE_RETURN_IF_ERROR(a.Choice("pose", {"rest", "bind"}, &pose));
  anim.pose = static_cast<ScenePose>(pose);
  DRAPE_RETURN_IF_ERROR(a.Number("start", &anim.start, 0, 1e5));
  DRAPE_RETURN_IF_ERROR(a.Number("duration", &anim.duration, 0, 3600, true));
  DRAPE_RETURN_IF_ERROR(a.Bool("loop", &anim.loop));
  DRAPE_RETURN_IF_ERROR(a.Number("settle", &anim.settle, 0, 60));
  return Status::Ok();
}

Status ParseCollision(const Fields& root, Scene* scene) {
  const json* object = nullptr;
  DRAPE_RETURN_IF_ERROR(root.Object("collision", &object));
  if (object == nullptr) return Status::Ok();
  const Fields c = root.Sub(*object, "/collision");
  DRAPE_RETURN_IF_ERROR(c.CheckKeys({"methods", "maps_sampling", "maps_blend", "inside_test",
                                     "hull_response", "continuous", "entry_response", "passes",
                                     "reach_margin", "reach_stretch", "prune"}));
  if (const json* methods = c.Find("methods"); methods != nullptr) {
    if (!methods->is_array()) {
      return c.Error(
          c.Path("methods"),
          std::string("must be an array of maps | hulls | spheres, not ") + TypeName(*methods));
    }
    scene->use_maps = scene->use_hulls = scene->use_spheres = false;
    for (size_t i = 0; i < methods->size(); ++i) {
      const json& m = (*methods)[i];
      const std::string path = c.Path("methods") + "/" + std::to_string(i);
      if (!m.is_string())
        return c.Error(path, std::string("must be maps | hulls | spheres, not ") + TypeName(m));
      const std::string name = m.get<std::string>();
      bool* flag = name == "maps"      ? &scene->use_maps
                   : name == "hulls"   ? &scene->use_hulls
                   : name == "spheres" ? &scene->use_spheres
                                       : nullptr;
      if (flag == nullptr)
        return c.Error(path, Quote(name) + " is not a collision method (maps | hulls | spheres)");
      if (*flag) return c.Error(path, Quote(name) + " is listed twice");
      *flag = true;
    }
  }
  size_t choice = 0;
  choice = static_cast<size_t>(scene->maps_sampling);
  DRAPE_RETURN_IF_ERROR(c.Choice("maps_sampling", {"nearest", "bilinear"}, &choice));
  scene->maps_sampling = static_cast<DepthSampling>(choice);
  choice = static_cast<size_t>(scene->maps_blend);
  DRAPE_RETURN_IF_ERROR(c.Choice("maps_blend", {"nearest", "bracket"}, &choice));
  scene->maps_blend = static_cast<PoseBlend>(choice);
  HullColliderOptions& h = scene->hull_options;
  choice = static_cast<size_t>(h.inside_test);
  DRAPE_RETURN_IF_ERROR(c.Choice("inside_test", {"planes", "kirkpatrick"}, &choice));
  h.inside_test = static_cast<InsideTest>(choice);
  choice = static_cast<size_t>(h.response);
  DRAPE_RETURN_IF_ERROR(c.Choice("hull_response", {"push_out", "map_table_ray"}, &choice));
  h.response = static_cast<HullResponse>(choice);
  DRAPE_RETURN_IF_ERROR(c.Bool("continuous", &h.continuous));
  choice = static_cast<size_t>(h.entry_response);
  DRAPE_RETURN_IF_ERROR(c.Choice("entry_response", {"project_end", "entry_point"}, &choice));
  h.entry_response = static_cast<EntryResponse>(choice);
  DRAPE_RETURN_IF_ERROR(c.Uint("passes", &h.gauss_seidel_passes, 1, 16));
  DRAPE_RETURN_IF_ERROR(c.Number("reach_margin", &scene->reach_margin, 0, 100));
  DRAPE_RETURN_IF_ERROR(c.Number("reach_stretch", &scene->reach_stretch, 0, 100));
  DRAPE_RETURN_IF_ERROR(c.Bool("prune", &scene->prune));
  return Status::Ok();
}

Status ParseSolver(const Fields& root, Scene* scene) {
  const json* object = nullptr;
  DRAPE_RETURN_IF_ERROR(root.Object("solver", &object));
  if (object == nullptr) return Status::Ok();
  const Fields s = root.Sub(*object, "/solver");
  DRAPE_RETURN_IF_ERROR(
      s.CheckKeys({"integrator", "dt", "substeps", "iterations", "buckling", "gravity", "damping",
                   "drag", "wind", "friction", "restitution", "separation", "relative"}));
  ClothSolverSettings& st = scene->solver;
  size_t integrator = 0;
  DRAPE_RETURN_IF_ERROR(s.Choice("integrator", {"verlet", "euler"}, &integrator));
  st.integrator = static_cast<ClothIntegrator>(integrator);
  DRAPE_RETURN_IF_ERROR(s.Number("dt", &scene->dt, 0, 1, true));
  const json* substeps = s.Find("substeps");
  if (substeps != nullptr && substeps->is_string()) {
    if (substeps->get<std::string>() != "auto")
      return s.Error(s.Path("substeps"), "must be an integer in [1, 256] or \"auto\"");
    if (st.integrator != ClothIntegrator::kExplicitEuler)
      return s.Error(s.Path("substeps"), "\"auto\" is for the euler integrator only");
    scene->auto_substeps = true;
  } else {
    DRAPE_RETURN_IF_ERROR(s.Uint("substeps", &st.substeps, 1, 256));
    // Explicit Euler without a count: the stability bound decides.
    scene->auto_substeps = substeps == nullptr && st.integrator == ClothIntegrator::kExplicitEuler;
  }
  DRAPE_RETURN_IF_ERROR(s.Uint("iterations", &st.iterations, 1, 256));
  DRAPE_RETURN_IF_ERROR(s.Bool("buckling", &st.buckling));
  DRAPE_RETURN_IF_ERROR(s.Vec3("gravity", &st.gravity, 1e3));
  DRAPE_RETURN_IF_ERROR(s.Number("damping", &st.damping, 0, 1e3));
  DRAPE_RETURN_IF_ERROR(s.Number("drag", &st.drag, 0, 1e3));
  DRAPE_RETURN_IF_ERROR(s.Vec3("wind", &st.wind, 1e3));
  DRAPE_RETURN_IF_ERROR(s.Number("friction", &scene->response.friction, 0, 1));
  DRAPE_RETURN_IF_ERROR(s.Number("restitution", &scene->response.restitution, 0, 1));
  DRAPE_RETURN_IF_ERROR(s.Number("separation", &scene->response.separation, 0, 0.1));
  DRAPE_RETURN_IF_ERROR(s.Bool("relative", &scene->relative));
  return Status::Ok();
}

Status ParseOutput(const Fields& root, Scene* scene) {
  const json* object = nullptr;
  DRAPE_RETURN_IF_ERROR(root.Object("output", &object));
  if (object == nullptr) return Status::Ok();
  const Fields o = root.Sub(*object, "/output");
  DRAPE_RETURN_IF_ERROR(
      o.CheckKeys({"every", "width", "height", "overlay_colliders", "obj", "animation", "camera"}));
  SceneOutput& out = scene->output;
  DRAPE_RETURN_IF_ERROR(o.Uint("every", &out.every, 1, 100000));
  DRAPE_RETURN_IF_ERROR(o.Uint("width", &out.width, 16, 4096));
  DRAPE_RETURN_IF_ERROR(o.Uint("height", &out.height, 16, 4096));
  DRAPE_RETURN_IF_ERROR(o.Bool("overlay_colliders", &out.overlay_colliders));
  DRAPE_RETURN_IF_ERROR(o.Bool("obj", &out.obj));
  size_t animation = 0;
  DRAPE_RETURN_IF_ERROR(
      o.Choice("animation", {"auto", "mp4", "gif", "contact_sheet", "none"}, &animation));
  out.animation = static_cast<SceneAnimationOutput>(animation);
  const json* camera = nullptr;
  DRAPE_RETURN_IF_ERROR(o.Object("camera", &camera));
  if (camera != nullptr) {
    const Fields c = o.Sub(*camera, o.Path("camera"));
    DRAPE_RETURN_IF_ERROR(c.CheckKeys({"yaw_deg", "pitch_deg", "zoom"}));
    DRAPE_RETURN_IF_ERROR(c.Number("yaw_deg", &out.camera_yaw_deg, -360, 360));
    DRAPE_RETURN_IF_ERROR(c.Number("pitch_deg", &out.camera_pitch_deg, -89, 89));
    DRAPE_RETURN_IF_ERROR(c.Number("zoom", &out.camera_zoom, 0, 100, true));
  }
  return Status::Ok();
}

// The scene's /bake overrides, checked against drape-bake's parameter table. The collider kinds
// and the maps' clip follow from /collision/methods and /animation/clip instead.
Status CheckBakeOverrides(const Fields& root, const json& bake, BakeConfig* config) {
  if (!bake.is_object())
    return root.Error("/bake", std::string("must be an object, not ") + TypeName(bake));
  for (const auto& [section, values] : bake.items()) {
    if (!values.is_object()) continue;  // ApplyBakeConfig names it
    for (const auto& [key, value] : values.items()) {
      const std::string name = section + "." + key;
      if (name == "maps.enabled" || name == "hulls.enabled" || name == "spheres.enabled") {
        return root.Error("/bake/" + section + "/" + key,
                          "the collider kinds come from /collision/methods");
      }
      if (name == "maps.clip")
        return root.Error("/bake/maps/clip", "the maps' clip comes from /animation/clip");
    }
  }
  // ApplyBakeConfig says "<source>: /section/key ..."; re-root its path under /bake.
  const std::string marker = "\x01";
  if (Status s = ApplyBakeConfig(bake, marker, config); !s.ok()) {
    std::string message = s.message();
    if (message.rfind(marker + ": /", 0) == 0) {
      // "<marker>: /maps/resolution must be ..." -> "<scene>: /bake/maps/resolution: must be ..."
      std::string rest = message.substr(marker.size() + 3);
      if (const size_t space = rest.find(' '); space != std::string::npos)
        rest = rest.substr(0, space) + ": " + rest.substr(space + 1);
      message = root.source() + ": /bake/" + rest;
    } else if (message.rfind(marker, 0) == 0) {
      message = root.source() + ": /bake" + message.substr(marker.size());
    }
    return Status(s.code(), message);
  }
  return Status::Ok();
}

uint32_t FrameCountFor(float duration, float dt) {
  const double frames = std::ceil(static_cast<double>(duration) / dt - 1e-4);
  return static_cast<uint32_t>(std::clamp(frames, 1.0, 1e7));
}

// ---- Garment construction ---------------------------------------------------------------------

Status ReadObj(const std::string& file, const std::string& where, std::vector<Float3>* positions,
               std::vector<uint32_t>* triangles) {
  std::ifstream in(file);
  if (!in) return Invalid(where + ": cannot open " + Quote(file));
  std::string line;
  uint32_t line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    std::istringstream tokens(line);
    std::string tag;
    if (!(tokens >> tag) || tag[0] == '#') continue;
    const std::string at = where + ": " + Quote(file) + " line " + std::to_string(line_number);
    if (tag == "v") {
      double x = 0, y = 0, z = 0;
      if (!(tokens >> x >> y >> z) || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
        return Invalid(at + ": a vertex needs 3 finite coordinates");
      }
      positions->push_back({static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
    } else if (tag == "f") {
      std::vector<uint32_t> face;
      std::string corner;
      while (tokens >> corner) {
        long long index = 0;
        try {
          index = std::stoll(corner.substr(0, corner.find('/')));
        } catch (...) {
          return Invalid(at + ": bad face corner " + Quote(corner));
        }
        const long long count = static_cast<long long>(positions->size());
        if (index < 0) index += count + 1;  // relative to the vertices read so far
        if (index < 1 || index > count) {
          return Invalid(at + ": face index " + corner + " is out of range (" +
                         std::to_string(count) + " vertices so far)");
        }
        face.push_back(static_cast<uint32_t>(index - 1));
      }
      if (face.size() < 3) return Invalid(at + ": a face needs at least 3 corners");
      for (size_t k = 1; k + 1 < face.size(); ++k) {  // fan: convex polygons
        triangles->insert(triangles->end(), {face[0], face[k], face[k + 1]});
      }
    }
  }
  if (positions->empty() || triangles->empty())
    return Invalid(where + ": " + Quote(file) + " holds no triangles");
  return Status::Ok();
}

// The particles of a named ring of a generated garment, or empty when the name is unknown.
std::vector<uint32_t> RingParticles(const SceneGarment& g, const GarmentMesh& mesh,
                                    const std::string& name) {
  std::vector<uint32_t> out;
  if (name == "held") return mesh.held;
  const auto row = [&](uint32_t stride, uint32_t r) {
    for (uint32_t i = 0; i < stride; ++i) out.push_back(r * stride + i);
  };
  const auto column = [&](uint32_t stride, uint32_t rows, uint32_t c) {
    for (uint32_t j = 0; j <= rows; ++j) out.push_back(j * stride + c);
  };
  switch (g.type) {
    case GarmentType::kSheet:
      if (name == "top") row(g.sheet.columns + 1, g.sheet.rows);
      if (name == "bottom") row(g.sheet.columns + 1, 0);
      if (name == "left") column(g.sheet.columns + 1, g.sheet.rows, 0);
      if (name == "right") column(g.sheet.columns + 1, g.sheet.rows, g.sheet.columns);
      break;
    case GarmentType::kSkirt:
      if (name == "waist") row(g.skirt.segments, 0);
      if (name == "hem") row(g.skirt.segments, g.skirt.rings);
      break;
    case GarmentType::kCape:
      if (name == "top") row(g.cape.columns + 1, 0);
      if (name == "bottom") row(g.cape.columns + 1, g.cape.rows);
      if (name == "left") column(g.cape.columns + 1, g.cape.rows, 0);
      if (name == "right") column(g.cape.columns + 1, g.cape.rows, g.cape.columns);
      break;
    case GarmentType::kSleeve:
      if (name == "start") row(g.sleeve.segments, 0);
      if (name == "end") row(g.sleeve.segments, g.sleeve.rings);
      break;
    case GarmentType::kObj:
      break;
  }
  return out;
}

Status SelectParticles(const Scene& scene, const SceneGarment& g, const GarmentMesh& mesh,
                       const SceneSelection& sel, Float3 anchor, std::vector<uint32_t>* out) {
  const uint32_t count = static_cast<uint32_t>(mesh.positions.size());
  const std::string prefix = scene.source + ": ";
  if (!sel.ring.empty()) {
    std::vector<std::string> names = GarmentRingNames(g.type);
    if (g.type != GarmentType::kObj) names.insert(names.begin(), "held");
    if (std::find(names.begin(), names.end(), sel.ring) == names.end()) {
      return Invalid(prefix + sel.path + "/ring: " +
                     (names.empty() ? "an OBJ garment has no rings; use vertices or box"
                                    : "no ring named " + Quote(sel.ring) + " on a " +
                                          ToString(g.type) + " (rings: " + JoinNames(names) + ")"));
    }
    *out = RingParticles(g, mesh, sel.ring);
  } else if (!sel.vertices.empty()) {
    for (size_t i = 0; i < sel.vertices.size(); ++i) {
      if (sel.vertices[i] >= count) {
        return Invalid(prefix + sel.path + "/vertices/" + std::to_string(i) + ": particle " +
                       std::to_string(sel.vertices[i]) + " is out of range (the garment has " +
                       std::to_string(count) + " particles)");
      }
    }
    *out = sel.vertices;
  } else {
    const Float3 lo = sel.box_min + anchor, hi = sel.box_max + anchor;
    out->clear();
    for (uint32_t i = 0; i < count; ++i) {
      const Float3 p = mesh.positions[i];
      if (p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z)
        out->push_back(i);
    }
    if (out->empty()) return Invalid(prefix + sel.path + "/box: selects no particle");
  }
  std::sort(out->begin(), out->end());
  out->erase(std::unique(out->begin(), out->end()), out->end());
  return Status::Ok();
}

Float3 Translation(const Mat34& m) { return {m.m[3], m.m[7], m.m[11]}; }

// Distance from p to an oriented box (centre, orthonormal axes, half extents).
float DistanceToBox(Float3 p, Float3 center, const Float3 axes[3], Float3 half) {
  const Float3 d = p - center;
  const float h[3] = {half.x, half.y, half.z};
  float squared = 0.f;
  for (int k = 0; k < 3; ++k) {
    const float c = Dot(d, axes[k]);
    const float beyond = std::fabs(c) - h[k];
    if (beyond > 0.f) squared += beyond * beyond;
  }
  return std::sqrt(squared);
}

// The clip time a scene time plays (what SkeletonPose::SampleClip does with it).
float ClipTime(const ClipData& clip, float time, bool loop) {
  if (loop && clip.duration > 0.f) {
    time = std::fmod(time, clip.duration);
    if (time < 0.f) time += clip.duration;
  }
  return std::fmin(std::fmax(time, 0.f), clip.duration);
}

}  // namespace

const char* ToString(GarmentType type) {
  switch (type) {
    case GarmentType::kSheet:
      return "sheet";
    case GarmentType::kSkirt:
      return "skirt";
    case GarmentType::kCape:
      return "cape";
    case GarmentType::kSleeve:
      return "sleeve";
    case GarmentType::kObj:
      return "obj";
  }
  return "?";
}

std::vector<std::string> GarmentRingNames(GarmentType type) {
  switch (type) {
    case GarmentType::kSheet:
      return {"top", "bottom", "left", "right"};
    case GarmentType::kSkirt:
      return {"waist", "hem"};
    case GarmentType::kCape:
      return {"top", "bottom", "left", "right"};
    case GarmentType::kSleeve:
      return {"start", "end"};
    case GarmentType::kObj:
      return {};
  }
  return {};
}

Status ParseScene(const json& value, const std::string& source, const std::string& directory,
                  Scene* scene) {
  Scene result;
  result.source = source;
  result.directory = directory;
  if (!value.is_object())
    return Invalid(source + ": the scene must be a JSON object, not " + TypeName(value));
  const Fields root(value, "", result.source);
  DRAPE_RETURN_IF_ERROR(root.CheckKeys({"description", "character", "bake", "animation", "garments",
                                        "collision", "solver", "output"}));
  if (const json* d = root.Find("description"); d != nullptr && !d->is_string())
    return root.Error("/description", std::string("must be a string, not ") + TypeName(*d));

  std::string character;
  if (root.Find("character") == nullptr) {
    return root.Error("/character",
                      "missing (the character's model file or .drape, relative to the scene)");
  }
  DRAPE_RETURN_IF_ERROR(root.String("character", &character, true));
  result.character = ResolvePath(directory, character);
  if (!std::filesystem::is_regular_file(result.character))
    return root.Error("/character", Quote(result.character) + " not found");

  if (const json* bake = root.Find("bake"); bake != nullptr) {
    BakeConfig scratch;
    DRAPE_RETURN_IF_ERROR(CheckBakeOverrides(root, *bake, &scratch));
    result.bake = *bake;
  }
  DRAPE_RETURN_IF_ERROR(ParseAnimation(root, &result));
  DRAPE_RETURN_IF_ERROR(ParseCollision(root, &result));
  DRAPE_RETURN_IF_ERROR(ParseSolver(root, &result));
  DRAPE_RETURN_IF_ERROR(ParseOutput(root, &result));

  const json* garments = root.Find("garments");
  if (garments == nullptr) return root.Error("/garments", "missing (an array of garments)");
  if (!garments->is_array() || garments->empty()) {
    return root.Error("/garments",
                      std::string("must be a non-empty array of garments, not ") +
                          (garments->is_array() ? "an empty array" : TypeName(*garments)));
  }
  for (size_t i = 0; i < garments->size(); ++i) {
    SceneGarment garment;
    DRAPE_RETURN_IF_ERROR(
        ParseGarment(root, (*garments)[i], "/garments/" + std::to_string(i), i, result, &garment));
    for (const SceneGarment& other : result.garments) {
      if (other.name == garment.name) {
        return root.Error(garment.path + "/name",
                          Quote(garment.name) + " is already the name of " + other.path);
      }
    }
    result.garments.push_back(std::move(garment));
  }

  // The maps of a static scene are baked of the rest pose (drape-bake's pose without a clip).
  if (result.use_maps && result.animation.clip.empty() &&
      result.animation.pose == ScenePose::kBind) {
    return root.Error("/animation/pose",
                      "maps are baked of the rest pose: use \"rest\" or a clip with maps");
  }
  if (result.animation.clip.empty() && result.animation.duration < 0.f)
    result.animation.duration = 1.f;  // a static scene: one second unless told
  if (result.animation.duration > 0.f)
    result.frame_count = FrameCountFor(result.animation.duration, result.dt);
  *scene = std::move(result);
  return Status::Ok();
}

Status LoadScene(const std::string& path, Scene* scene) {
  std::ifstream in(path);
  if (!in) {
    return Status(StatusCode::kIoError, path + ": cannot open the scene file" +
                                            (std::filesystem::exists(path) ? "" : " (not found)"));
  }
  json parsed;
  try {
    parsed = json::parse(in);
  } catch (const json::parse_error& e) {
    return Invalid(path + ": not valid JSON: " + e.what());
  }
  const std::string directory = std::filesystem::path(path).parent_path().string();
  return ParseScene(parsed, path, directory, scene);
}

Status ApplySceneToBakeConfig(const Scene& scene, BakeConfig* config) {
  static const json kNoFields = json::object();
  const Fields root(kNoFields, "", scene.source);
  BakeConfig result = *config;
  if (!scene.bake.empty()) DRAPE_RETURN_IF_ERROR(CheckBakeOverrides(root, scene.bake, &result));
  result.maps_enabled = scene.use_maps;
  result.hulls_enabled = scene.use_hulls;
  result.spheres_enabled = scene.use_spheres;
  // Maps of the poses the scene plays: its clip (at maps.clip_rate), or the rest pose.
  result.maps_clip = scene.use_maps ? scene.animation.clip : std::string();
  *config = result;
  return Status::Ok();
}

Status ResolveSceneClip(const CharacterAsset& asset, Scene* scene, int32_t* clip) {
  *clip = -1;
  if (scene->animation.clip.empty()) {
    if (scene->frame_count == 0) scene->frame_count = FrameCountFor(1.f, scene->dt);
    return Status::Ok();
  }
  std::vector<std::string> names;
  for (size_t c = 0; c < asset.clips.size(); ++c) {
    names.push_back(asset.clips[c].name);
    if (asset.clips[c].name == scene->animation.clip) *clip = static_cast<int32_t>(c);
  }
  if (*clip < 0) {
    return Invalid(scene->source + ": /animation/clip: no clip named " +
                   Quote(scene->animation.clip) + " in " + Quote(scene->character) +
                   " (clips: " + (names.empty() ? "none" : JoinNames(names)) + ")");
  }
  if (scene->frame_count == 0) {
    const float duration = asset.clips[static_cast<size_t>(*clip)].duration;
    scene->frame_count = FrameCountFor(duration > 0.f ? duration : scene->dt, scene->dt);
  }
  return Status::Ok();
}

Status ResolveGarment(const Scene& scene, size_t index, const SkeletonData& skeleton,
                      ResolvedGarment* out) {
  *out = ResolvedGarment{};
  if (index >= scene.garments.size())
    return Invalid(scene.source + ": no garment " + std::to_string(index));
  const SceneGarment& g = scene.garments[index];
  const std::string prefix = scene.source + ": ";
  SkeletonPose rest;
  DRAPE_RETURN_IF_ERROR(rest.Init(skeleton));
  rest.SetRest();
  const uint32_t joints = skeleton.joint_count();

  // Joint positions and frame -> bind matrices in the garment's frame.
  out->frame_to_bind.assign(joints, Mat34{});
  std::vector<Float3> joint_positions(joints);
  for (uint32_t j = 0; j < joints; ++j) {
    Mat34 bind_world;
    if (!InverseAffine(skeleton.inverse_bind[j], &bind_world)) bind_world = Mat34{};
    if (g.frame == GarmentFrame::kBind) {
      joint_positions[j] = Translation(bind_world);
    } else {
      joint_positions[j] = Translation(rest.world()[j]);
      if (!InverseAffine(rest.skinning()[j], &out->frame_to_bind[j])) {
        return Invalid(prefix + g.path + "/frame: the rest skinning matrix of joint " +
                       Quote(skeleton.joint_names[j]) + " is singular; use \"bind\"");
      }
    }
  }
  const auto find_joint = [&](const std::string& name, const std::string& path, int32_t* j) {
    *j = FindJoint(skeleton, name);
    if (*j >= 0) return Status::Ok();
    // A few names help more than seventy: the joints sharing the name's first letter, else all.
    std::vector<std::string> similar;
    for (const std::string& n : skeleton.joint_names)
      if (!n.empty() && !name.empty() && std::tolower(n[0]) == std::tolower(name[0]))
        similar.push_back(n);
    if (similar.empty() || similar.size() > 12) similar.clear();
    return Invalid(prefix + path + ": no joint named " + Quote(name) +
                   (similar.empty() ? " (" + std::to_string(joints) + " joints)"
                                    : " (did you mean " + JoinNames(similar) + "?)"));
  };
  Float3 anchor;
  if (!g.anchor.empty()) {
    int32_t j = -1;
    DRAPE_RETURN_IF_ERROR(find_joint(g.anchor, g.path + "/anchor", &j));
    anchor = joint_positions[static_cast<size_t>(j)];
  }

  GarmentMesh mesh;
  Status made;
  switch (g.type) {
    case GarmentType::kSheet: {
      SheetShape s = g.sheet;
      s.center += anchor;
      made = MakeSheet(s, &mesh);
      break;
    }
    case GarmentType::kSkirt: {
      SkirtShape s = g.skirt;
      s.top_center += anchor;
      made = MakeSkirt(s, &mesh);
      break;
    }
    case GarmentType::kCape: {
      CapeShape s = g.cape;
      s.top_center += anchor;
      made = MakeCape(s, &mesh);
      break;
    }
    case GarmentType::kSleeve: {
      SleeveShape s = g.sleeve;
      s.start += anchor;
      made = MakeSleeve(s, &mesh);
      break;
    }
    case GarmentType::kObj: {
      made = ReadObj(g.obj_file, prefix + g.path + "/shape/file", &mesh.positions, &mesh.triangles);
      if (!made.ok()) return made;
      for (Float3& p : mesh.positions) p = p * g.obj_scale + g.obj_offset + anchor;
      break;
    }
  }
  if (!made.ok()) return Invalid(prefix + g.path + "/shape: " + made.message());
  if (mesh.positions.size() > kMaxGarmentParticles) {
    return Invalid(prefix + g.path + "/shape: " + std::to_string(mesh.positions.size()) +
                   " particles: at most " + std::to_string(kMaxGarmentParticles));
  }

  ClothDescription& d = out->description;
  d.positions = mesh.positions;
  d.triangles = mesh.triangles;
  d.density = g.density;
  d.total_mass = g.total_mass;
  d.stretch = g.stretch;
  d.bend = g.bend;
  d.bend_springs = g.bend_springs;
  // Which selection holds each particle, for messages about conflicts.
  std::vector<const std::string*> held_by(mesh.positions.size(), nullptr);
  std::vector<int32_t> held_joint(mesh.positions.size(), -2);  // -2 free, -1 pinned
  for (const SceneAttachment& a : g.attachments) {
    int32_t joint = -1;
    DRAPE_RETURN_IF_ERROR(find_joint(a.joint, a.particles.path + "/joint", &joint));
    std::vector<uint32_t> particles;
    DRAPE_RETURN_IF_ERROR(SelectParticles(scene, g, mesh, a.particles, anchor, &particles));
    for (uint32_t p : particles) {
      if (held_by[p] != nullptr) {
        if (held_joint[p] == joint) continue;  // the same hold twice
        return Invalid(prefix + a.particles.path + ": particle " + std::to_string(p) +
                       " is already held by " + *held_by[p]);
      }
      held_by[p] = &a.particles.path;
      held_joint[p] = joint;
      d.attachments.push_back(
          {p, joint,
           TransformPoint(out->frame_to_bind[static_cast<size_t>(joint)], mesh.positions[p])});
    }
  }
  for (const SceneSelection& pin : g.pins) {
    std::vector<uint32_t> particles;
    DRAPE_RETURN_IF_ERROR(SelectParticles(scene, g, mesh, pin, anchor, &particles));
    for (uint32_t p : particles) {
      if (held_by[p] != nullptr) {
        if (held_joint[p] == -1) continue;
        return Invalid(prefix + pin.path + ": particle " + std::to_string(p) +
                       " is already held by " + *held_by[p]);
      }
      held_by[p] = &pin.path;
      held_joint[p] = -1;
      d.pinned.push_back(p);
    }
  }

  // Validate the cloth now, so that a bad garment is refused with its path.
  Cloth check;
  if (Status s = BuildCloth(d, &check); !s.ok())
    return Invalid(prefix + g.path + ": " + s.message());

  std::vector<float> distance;
  std::vector<uint32_t> nearest;
  NearestHeldParticles(d, &distance, &nearest);
  out->carrier_joint.assign(d.positions.size(), -1);
  for (size_t i = 0; i < d.positions.size(); ++i) {
    if (nearest[i] != UINT32_MAX) out->carrier_joint[i] = std::max(held_joint[nearest[i]], -1);
  }
  return Status::Ok();
}

void PlaceGarment(const ResolvedGarment& garment, std::span<const Mat34> skinning,
                  std::vector<Float3>* positions) {
  const std::vector<Float3>& rest = garment.description.positions;
  positions->resize(rest.size());
  for (size_t i = 0; i < rest.size(); ++i) {
    const int32_t j = garment.carrier_joint[i];
    if (j < 0 || static_cast<size_t>(j) >= skinning.size()) {
      (*positions)[i] = rest[i];
      continue;
    }
    const Mat34 m =
        Multiply(skinning[static_cast<size_t>(j)], garment.frame_to_bind[static_cast<size_t>(j)]);
    (*positions)[i] = TransformPoint(m, rest[i]);
  }
}

void NearestHeldParticles(const ClothDescription& cloth, std::vector<float>* distance,
                          std::vector<uint32_t>* nearest) {
  const size_t n = cloth.positions.size();
  distance->assign(n, kInf);
  nearest->assign(n, UINT32_MAX);
  // Undirected edge lists (compressed rows), from the triangles.
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  for (size_t t = 0; t + 2 < cloth.triangles.size(); t += 3) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = cloth.triangles[t + k], b = cloth.triangles[t + (k + 1) % 3];
      if (a >= n || b >= n || a == b) continue;
      edges.push_back({a, b});
      edges.push_back({b, a});
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  std::vector<uint32_t> offsets(n + 1, 0);
  for (const auto& e : edges) ++offsets[e.first + 1];
  for (size_t i = 0; i < n; ++i) offsets[i + 1] += offsets[i];

  // Dijkstra from every held particle at once; ties resolved by the smaller particle index, so
  // the result is a function of the description only.
  using Entry = std::pair<float, uint32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  const auto seed = [&](uint32_t p) {
    if (p >= n) return;
    (*distance)[p] = 0.f;
    (*nearest)[p] = p;
    queue.push({0.f, p});
  };
  for (const ClothAttachment& a : cloth.attachments) seed(a.particle);
  for (uint32_t p : cloth.pinned) seed(p);
  while (!queue.empty()) {
    const auto [d, p] = queue.top();
    queue.pop();
    if (d > (*distance)[p]) continue;
    for (uint32_t e = offsets[p]; e < offsets[p + 1]; ++e) {
      const uint32_t q = edges[e].second;
      const float candidate = d + Length(cloth.positions[q] - cloth.positions[p]);
      if (candidate < (*distance)[q] ||
          (candidate == (*distance)[q] && (*nearest)[p] < (*nearest)[q])) {
        (*distance)[q] = candidate;
        (*nearest)[q] = (*nearest)[p];
        queue.push({candidate, q});
      }
    }
  }
}

Status AnalyzeSceneReach(const Scene& scene, const CharacterAsset& asset, SceneReach* out) {
  *out = SceneReach{};
  Scene resolved = scene;  // frame_count and the clip, without touching the caller's scene
  int32_t clip = -1;
  DRAPE_RETURN_IF_ERROR(ResolveSceneClip(asset, &resolved, &clip));
  out->clip = clip;

  // Garments: held particles and reach radii.
  struct Held {
    int32_t joint;    // -1: pinned in the world
    Float3 position;  // bind frame (attached) or world (pinned)
    float radius;
  };
  std::vector<Held> held;
  bool bounded = true;
  for (size_t g = 0; g < resolved.garments.size(); ++g) {
    ResolvedGarment garment;
    DRAPE_RETURN_IF_ERROR(ResolveGarment(resolved, g, asset.skeleton, &garment));
    const ClothDescription& d = garment.description;
    std::vector<float> distance;
    std::vector<uint32_t> nearest;
    NearestHeldParticles(d, &distance, &nearest);
    GarmentReach reach;
    reach.name = resolved.garments[g].name;
    reach.held_particles = static_cast<uint32_t>(d.attachments.size() + d.pinned.size());
    for (float x : distance) {
      if (std::isinf(x))
        reach.bounded = false;
      else
        reach.max_path = std::max(reach.max_path, x);
    }
    reach.radius = reach.bounded
                       ? (1.f + resolved.reach_stretch) * reach.max_path + resolved.reach_margin
                       : kInf;
    bounded = bounded && reach.bounded;
    for (const ClothAttachment& a : d.attachments)
      held.push_back({a.joint, a.bind_position, reach.radius});
    for (uint32_t p : d.pinned) held.push_back({-1, d.positions[p], reach.radius});
    out->garments.push_back(reach);
  }

  HullColliderSet colliders;
  if (Status s = colliders.Build(asset.hulls, asset.joint_spheres, asset.skeleton.joint_count());
      !s.ok()) {
    return Status(s.code(), asset.info.source_name + ": the asset's colliders: " + s.message());
  }
  const auto joint_name = [&](int32_t j) {
    return j >= 0 && static_cast<size_t>(j) < asset.skeleton.joint_names.size()
               ? asset.skeleton.joint_names[static_cast<size_t>(j)]
               : std::string("?");
  };
  for (const HullColliderData& h : asset.hulls)
    out->hulls.push_back({h.joint, joint_name(h.joint), !bounded, bounded ? kInf : -kInf});
  for (const JointSphereData& s : asset.joint_spheres)
    out->spheres.push_back({s.joint, joint_name(s.joint), !bounded, bounded ? kInf : -kInf});

  // The poses played: the start (settle), then every substep boundary of every frame.
  const SceneAnimation& anim = resolved.animation;
  const uint32_t substeps = resolved.auto_substeps ? 4u : std::max(resolved.solver.substeps, 1u);
  std::vector<float> times;
  times.push_back(anim.start);
  for (uint32_t k = 0; k < resolved.frame_count; ++k) {
    for (uint32_t s = 1; s <= substeps; ++s) {
      times.push_back(anim.start + (static_cast<float>(k) +
                                    static_cast<float>(s) / static_cast<float>(substeps)) *
                                       resolved.dt);
    }
  }
  if (clip < 0) times.resize(1);  // a static pose is one pose
  out->sampled_poses = static_cast<uint32_t>(times.size());

  SkeletonPose pose;
  DRAPE_RETURN_IF_ERROR(pose.Init(asset.skeleton));
  const int32_t root = 0;
  Float3 root_bind;
  {
    Mat34 m;
    if (!asset.skeleton.inverse_bind.empty() && InverseAffine(asset.skeleton.inverse_bind[0], &m))
      root_bind = Translation(m);
  }
  Float3 root_start;
  std::vector<Float3> centers(held.size());
  const ClipData* clip_data = clip >= 0 ? &asset.clips[static_cast<size_t>(clip)] : nullptr;
  if (clip_data != nullptr) {
    out->clip_time_min = kInf;
    out->clip_time_max = -kInf;
  }
  for (size_t t = 0; t < times.size(); ++t) {
    if (clip_data != nullptr) {
      DRAPE_RETURN_IF_ERROR(pose.SampleClip(*clip_data, times[t], anim.loop));
      const float ct = ClipTime(*clip_data, times[t], anim.loop);
      out->clip_time_min = std::min(out->clip_time_min, ct);
      out->clip_time_max = std::max(out->clip_time_max, ct);
    } else if (anim.pose == ScenePose::kRest) {
      pose.SetRest();
    } else {
      pose.SetBind();
    }
    const std::span<const Mat34> skinning = pose.skinning();
    if (!bounded) continue;
    DRAPE_RETURN_IF_ERROR(colliders.SetPose(skinning, skinning));
    // Relative simulation carries pinned particles with the root's translation.
    const Float3 root_now = skinning.empty() ? Float3{} : TransformPoint(skinning[root], root_bind);
    if (t == 0) root_start = root_now;
    const Float3 root_shift = resolved.relative ? root_now - root_start : Float3{};
    for (size_t i = 0; i < held.size(); ++i) {
      centers[i] = held[i].joint >= 0 ? TransformPoint(skinning[static_cast<size_t>(held[i].joint)],
                                                       held[i].position)
                                      : held[i].position + root_shift;
    }
    for (uint32_t h = 0; h < colliders.hull_count(); ++h) {
      const Mat34 world = colliders.HullWorldTransform(h, 0.f);
      const Obb& obb = asset.hulls[h].obb;
      const Float3 center = TransformPoint(world, obb.center);
      const Float3 axes[3] = {NormalizeOr(TransformVector(world, obb.axes[0]), {1, 0, 0}),
                              NormalizeOr(TransformVector(world, obb.axes[1]), {0, 1, 0}),
                              NormalizeOr(TransformVector(world, obb.axes[2]), {0, 0, 1})};
      float& clearance = out->hulls[h].clearance;
      for (size_t i = 0; i < held.size(); ++i) {
        clearance = std::min(
            clearance, DistanceToBox(centers[i], center, axes, asset.hulls[h].obb.half_extents) -
                           held[i].radius);
      }
    }
    for (uint32_t s = 0; s < colliders.sphere_count(); ++s) {
      const Float3 center = colliders.SphereCenter(s, 0.f);
      float& clearance = out->spheres[s].clearance;
      for (size_t i = 0; i < held.size(); ++i) {
        clearance = std::min(clearance, Length(centers[i] - center) -
                                            asset.joint_spheres[s].radius - held[i].radius);
      }
    }
  }
  for (ColliderReach& c : out->hulls) c.reachable = c.clearance <= 0.f;
  for (ColliderReach& c : out->spheres) c.reachable = c.clearance <= 0.f;

  if (clip_data != nullptr) {
    const float end_time = anim.start + static_cast<float>(resolved.frame_count) * resolved.dt;
    out->whole_clip = (anim.loop && end_time - anim.start >= clip_data->duration) ||
                      (out->clip_time_min <= 0.f && out->clip_time_max >= clip_data->duration);
  }

  // Body-map poses: those of the scene's clip (or the static poses) nearest to and bracketing
  // the time at the end of each frame, where the solver reads them.
  std::vector<uint32_t> candidates;
  for (size_t p = 0; p < asset.body_maps.poses.size(); ++p) {
    if (asset.body_maps.poses[p].clip == clip) candidates.push_back(static_cast<uint32_t>(p));
  }
  std::vector<uint8_t> played(asset.body_maps.poses.size(), 0);
  if (clip_data == nullptr) {
    for (uint32_t p : candidates) played[p] = 1;
  } else if (!candidates.empty()) {
    std::vector<float> frame_ends = {ClipTime(*clip_data, anim.start, anim.loop)};
    for (uint32_t k = 0; k < resolved.frame_count; ++k) {
      frame_ends.push_back(
          ClipTime(*clip_data, anim.start + static_cast<float>(k + 1) * resolved.dt, anim.loop));
    }
    for (float t : frame_ends) {
      uint32_t best = candidates[0], below = UINT32_MAX, above = UINT32_MAX;
      for (uint32_t p : candidates) {
        const float pt = asset.body_maps.poses[p].time;
        if (std::fabs(pt - t) < std::fabs(asset.body_maps.poses[best].time - t)) best = p;
        if (pt <= t && (below == UINT32_MAX || pt > asset.body_maps.poses[below].time)) below = p;
        if (pt >= t && (above == UINT32_MAX || pt < asset.body_maps.poses[above].time)) above = p;
      }
      played[best] = 1;
      if (below != UINT32_MAX) played[below] = 1;
      if (above != UINT32_MAX) played[above] = 1;
    }
  }
  for (size_t p = 0; p < played.size(); ++p)
    if (played[p]) out->played_map_poses.push_back(static_cast<uint32_t>(p));
  return Status::Ok();
}

json SceneReachToJson(const SceneReach& reach) {
  const auto number = [](float x) { return std::isfinite(x) ? json(x) : json(nullptr); };
  json garments = json::array();
  for (const GarmentReach& g : reach.garments) {
    garments.push_back({{"name", g.name},
                        {"held_particles", g.held_particles},
                        {"bounded", g.bounded},
                        {"max_path_m", g.max_path},
                        {"radius_m", number(g.radius)}});
  }
  json colliders = json::array();
  const auto add = [&](const std::vector<ColliderReach>& list, const char* kind) {
    for (const ColliderReach& c : list) {
      colliders.push_back({{"bone", c.joint_name},
                           {"kind", kind},
                           {"reachable", c.reachable},
                           {"clearance_m", number(c.clearance)}});
    }
  };
  add(reach.hulls, "hull");
  add(reach.spheres, "sphere");
  json out = {{"clip", reach.clip},
              {"sampled_poses", reach.sampled_poses},
              {"garments", garments},
              {"colliders", colliders},
              {"played_map_poses", reach.played_map_poses}};
  if (reach.clip >= 0) {
    out["clip_time_range_s"] = {reach.clip_time_min, reach.clip_time_max};
    out["whole_clip"] = reach.whole_clip;
  }
  return out;
}

void PruneUnreachable(const SceneReach& reach, CharacterAsset* asset, json* left_out) {
  if (!left_out->is_array()) *left_out = json::array();
  const auto why = [&](const ColliderReach& c) {
    char text[160];
    std::snprintf(text, sizeof(text),
                  "the garments cannot reach it: it stays %.3f m beyond their reach over the %u "
                  "poses the scene plays",
                  static_cast<double>(c.clearance), reach.sampled_poses);
    return std::string(text);
  };
  if (reach.hulls.size() == asset->hulls.size()) {
    std::vector<HullColliderData> kept;
    for (size_t h = 0; h < asset->hulls.size(); ++h) {
      if (reach.hulls[h].reachable) {
        kept.push_back(std::move(asset->hulls[h]));
      } else {
        left_out->push_back({{"bone", reach.hulls[h].joint_name},
                             {"kind", "hull"},
                             {"reason", why(reach.hulls[h])}});
      }
    }
    asset->hulls = std::move(kept);
  }
  if (reach.spheres.size() == asset->joint_spheres.size()) {
    std::vector<JointSphereData> kept;
    for (size_t s = 0; s < asset->joint_spheres.size(); ++s) {
      if (reach.spheres[s].reachable) {
        kept.push_back(asset->joint_spheres[s]);
      } else {
        left_out->push_back({{"bone", reach.spheres[s].joint_name},
                             {"kind", "joint_sphere"},
                             {"reason", why(reach.spheres[s])}});
      }
    }
    asset->joint_spheres = std::move(kept);
  }
  std::vector<BodyMapPose>& poses = asset->body_maps.poses;
  if (poses.empty()) return;
  if (reach.played_map_poses.empty()) {
    left_out->push_back({{"kind", "body_map_pose"},
                         {"reason", "kept all " + std::to_string(poses.size()) +
                                        " poses: none of them is a pose the scene plays"}});
    return;
  }
  std::vector<BodyMapPose> kept;
  size_t next = 0;
  for (size_t p = 0; p < poses.size(); ++p) {
    if (next < reach.played_map_poses.size() && reach.played_map_poses[next] == p) {
      kept.push_back(std::move(poses[p]));
      ++next;
      continue;
    }
    const std::string name = poses[p].clip < 0
                                 ? std::string("rest")
                                 : (static_cast<size_t>(poses[p].clip) < asset->clips.size()
                                        ? asset->clips[static_cast<size_t>(poses[p].clip)].name
                                        : std::string("?")) +
                                       "@" + std::to_string(poses[p].time);
    left_out->push_back(
        {{"pose", name}, {"kind", "body_map_pose"}, {"reason", "not played by the scene"}});
  }
  poses = std::move(kept);
}

}  // namespace drape::bake

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <sstream>
#include <utility>

#include "drape/bake/scene.h"
#include "drape/runtime/math.h"
#include "scene/scene_frames.h"
#include "scene/scene_messages.h"

namespace drape::bake {
namespace {

using namespace detail;
using nlohmann::json;

constexpr uint32_t kMaxGridCells = 1024;  // per side of a generated garment

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
}  // namespace

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

}  // namespace drape::bake

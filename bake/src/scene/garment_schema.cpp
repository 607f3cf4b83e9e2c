#include "scene/garment_schema.h"

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "drape/runtime/math.h"
#include "scene/scene_messages.h"

namespace drape::bake::detail {
namespace {

using nlohmann::json;

constexpr uint32_t kMaxGridCells = 1024;  // per side of a generated garment
constexpr double kMaxSize = 100;          // metres, any size of a generated garment
constexpr double kMaxCoordinate = 1e4;    // metres, any coordinate of a position

json FloatsJson(const float* values, size_t count) {
  json out = json::array();
  for (size_t i = 0; i < count; ++i) out.push_back(FloatJson(values[i]));
  return out;
}

// A direction: [x, y, z], not zero, stored normalised.
template <class T>
JsonSchema<T>& Direction(JsonSchema<T>& schema, std::string key, std::string meaning,
                         std::function<Float3&(T&)> field) {
  return schema.Custom(
      CustomFieldInfo(std::move(key), "[x, y, z], non-zero (normalised)",
                      "an array of 3 numbers [x, y, z]", std::move(meaning)),
      [field](const JsonAt& at, T& t) {
        float c[3];
        DRAPE_RETURN_IF_ERROR(
            ReadFloats(at, Closed(-kMaxCoordinate, kMaxCoordinate), "x, y, z", 3, c));
        const Float3 v{c[0], c[1], c[2]};
        const float length = Length(v);
        if (!(length > 1e-6f)) return at.Error("must not be the zero vector");
        field(t) = v * (1.f / length);
        return Status::Ok();
      },
      [field](const T& t) {
        const Float3 v = field(const_cast<T&>(t));
        return json::array({FloatJson(v.x), FloatJson(v.y), FloatJson(v.z)});
      });
}

// ---- /garments/i/shape, one table per garment type ----------------------------------------

const JsonSchema<SceneGarment>& SheetSchema() {
  static const JsonSchema<SceneGarment> schema = [] {
    JsonSchema<SceneGarment> s(
        "A width x height rectangle of (columns + 1) x (rows + 1) particles centred on `center`, "
        "spanning `axis_u` (columns, width) and `axis_v` (rows, height).");
    s.Vector("center", "m", kMaxCoordinate, "the centre",
             [](SceneGarment& g) -> Float3& { return g.sheet.center; });
    Direction<SceneGarment>(s, "axis_u", "the direction of the width",
                            [](SceneGarment& g) -> Float3& { return g.sheet.axis_u; });
    Direction<SceneGarment>(s, "axis_v", "the direction of the height, perpendicular to axis_u",
                            [](SceneGarment& g) -> Float3& { return g.sheet.axis_v; });
    s.Float("width", "m", OpenBelow(0, kMaxSize), "along axis_u",
            [](SceneGarment& g) -> float& { return g.sheet.width; })
        .Float("height", "m", OpenBelow(0, kMaxSize), "along axis_v",
               [](SceneGarment& g) -> float& { return g.sheet.height; })
        .Unsigned<uint32_t>("columns", "", 1, kMaxGridCells, "cells along axis_u",
                            [](SceneGarment& g) -> uint32_t& { return g.sheet.columns; })
        .Unsigned<uint32_t>("rows", "", 1, kMaxGridCells, "cells along axis_v",
                            [](SceneGarment& g) -> uint32_t& { return g.sheet.rows; })
        .Rule([](const JsonAt& at, SceneGarment& g) {
          if (std::fabs(Dot(g.sheet.axis_u, g.sheet.axis_v)) > 1e-3f)
            return at.Member("axis_v").Error("must be perpendicular to axis_u");
          return Status::Ok();
        });
    return s;
  }();
  return schema;
}

const JsonSchema<SceneGarment>& SkirtSchema() {
  static const JsonSchema<SceneGarment> schema =
      JsonSchema<SceneGarment>(
          "A ring around the vertical (+y) axis through `top_center`: `segments` particles around, "
          "`rings` + 1 rings from `top_radius` at the top down to `bottom_radius` at `length` "
          "below (a cylinder when the radii are equal, a flared skirt when the bottom is wider).")
          .Vector("top_center", "m", kMaxCoordinate, "the centre of the waist",
                  [](SceneGarment& g) -> Float3& { return g.skirt.top_center; })
          .Float("top_radius", "m", OpenBelow(0, kMaxSize), "radius at the waist",
                 [](SceneGarment& g) -> float& { return g.skirt.top_radius; })
          .Float("bottom_radius", "m", OpenBelow(0, kMaxSize), "radius at the hem",
                 [](SceneGarment& g) -> float& { return g.skirt.bottom_radius; })
          .Float("length", "m", OpenBelow(0, kMaxSize), "from the waist down to the hem",
                 [](SceneGarment& g) -> float& { return g.skirt.length; })
          .Unsigned<uint32_t>("segments", "", 3, kMaxGridCells, "particles around",
                              [](SceneGarment& g) -> uint32_t& { return g.skirt.segments; })
          .Unsigned<uint32_t>("rings", "", 1, kMaxGridCells, "cells down",
                              [](SceneGarment& g) -> uint32_t& { return g.skirt.rings; });
  return schema;
}

const JsonSchema<SceneGarment>& CapeSchema() {
  static const JsonSchema<SceneGarment> schema =
      JsonSchema<SceneGarment>(
          "A trapezoid hanging from a horizontal top edge centred on `top_center`, in the plane "
          "z = top_center.z: `top_width` at the top, `bottom_width` at `length` below. Its outside "
          "faces -z (the back of a character facing +z).")
          .Vector("top_center", "m", kMaxCoordinate, "the centre of the top edge",
                  [](SceneGarment& g) -> Float3& { return g.cape.top_center; })
          .Float("top_width", "m", OpenBelow(0, kMaxSize), "width of the top edge",
                 [](SceneGarment& g) -> float& { return g.cape.top_width; })
          .Float("bottom_width", "m", OpenBelow(0, kMaxSize), "width of the bottom edge",
                 [](SceneGarment& g) -> float& { return g.cape.bottom_width; })
          .Float("length", "m", OpenBelow(0, kMaxSize), "from the top edge down",
                 [](SceneGarment& g) -> float& { return g.cape.length; })
          .Unsigned<uint32_t>("columns", "", 1, kMaxGridCells, "cells across",
                              [](SceneGarment& g) -> uint32_t& { return g.cape.columns; })
          .Unsigned<uint32_t>("rows", "", 1, kMaxGridCells, "cells down",
                              [](SceneGarment& g) -> uint32_t& { return g.cape.rows; });
  return schema;
}

const JsonSchema<SceneGarment>& SleeveSchema() {
  static const JsonSchema<SceneGarment> schema = [] {
    JsonSchema<SceneGarment> s(
        "A tube of `radius` from `start` along `axis` for `length`: `segments` particles around, "
        "`rings` + 1 rings, open ends.");
    s.Vector("start", "m", kMaxCoordinate, "the centre of the shoulder seam",
             [](SceneGarment& g) -> Float3& { return g.sleeve.start; });
    Direction<SceneGarment>(s, "axis", "the direction along the arm",
                            [](SceneGarment& g) -> Float3& { return g.sleeve.axis; });
    s.Float("radius", "m", OpenBelow(0, kMaxSize), "of the tube",
            [](SceneGarment& g) -> float& { return g.sleeve.radius; })
        .Float("length", "m", OpenBelow(0, kMaxSize), "along axis",
               [](SceneGarment& g) -> float& { return g.sleeve.length; })
        .Unsigned<uint32_t>("segments", "", 3, kMaxGridCells, "particles around",
                            [](SceneGarment& g) -> uint32_t& { return g.sleeve.segments; })
        .Unsigned<uint32_t>("rings", "", 1, kMaxGridCells, "cells along",
                            [](SceneGarment& g) -> uint32_t& { return g.sleeve.rings; });
    return s;
  }();
  return schema;
}

const JsonSchema<SceneGarment>& ObjSchema() {
  static const JsonSchema<SceneGarment> schema =
      JsonSchema<SceneGarment>(
          "An OBJ file's mesh: its `v` and `f` lines (polygons are fanned into triangles).")
          .FilePath("file", "an OBJ file, relative to the scene",
                    [](SceneGarment& g) -> std::string& { return g.obj_file; })
          .Required()
          .Float("scale", "", OpenBelow(0, 1e6), "metres per OBJ unit",
                 [](SceneGarment& g) -> float& { return g.obj_scale; })
          .Vector("offset", "m", kMaxCoordinate, "added after scaling",
                  [](SceneGarment& g) -> Float3& { return g.obj_offset; });
  return schema;
}

const JsonSchema<SceneGarment>& GltfSchema() {
  static const JsonSchema<SceneGarment> schema =
      JsonSchema<SceneGarment>(
          "A glTF 2.0 file's mesh (.gltf or .glb; its triangle primitives merged, vertices split "
          "at UV or normal seams welded). A mesh with a skin is bound to the character's "
          "skeleton by joint name: each vertex keeps its JOINTS_0 / WEIGHTS_0 (four joints) and "
          "is placed by the file's inverse bind matrices, which must agree with the "
          "character's skeleton at bind; `scale`, `offset` and the garment's `anchor` then do not "
          "apply. Optional SCALAR float attributes `_MAX_DISTANCE` and `_BACKSTOP` paint the "
          "skin's distances per vertex (file units; negative: unlimited; see `/skin/paint`).")
          .FilePath("file", "a glTF file, relative to the scene",
                    [](SceneGarment& g) -> std::string& { return g.obj_file; })
          .Required()
          .String("mesh", StringRule::kNonEmpty, "the mesh node's (or mesh's) name",
                  [](SceneGarment& g) -> std::string& { return g.gltf_mesh; })
          .Default("the file's only mesh")
          .Float("scale", "", OpenBelow(0, 1e6), "metres per file unit (a mesh without a skin)",
                 [](SceneGarment& g) -> float& { return g.obj_scale; })
          .Vector("offset", "m", kMaxCoordinate, "added after scaling (a mesh without a skin)",
                  [](SceneGarment& g) -> Float3& { return g.obj_offset; });
  return schema;
}

const JsonSchema<SceneGarment>& ShapeSchema(GarmentType type) {
  switch (type) {
    case GarmentType::kSheet:
      return SheetSchema();
    case GarmentType::kSkirt:
      return SkirtSchema();
    case GarmentType::kCape:
      return CapeSchema();
    case GarmentType::kSleeve:
      return SleeveSchema();
    case GarmentType::kGltf:
      return GltfSchema();
    case GarmentType::kObj:
      break;
  }
  return ObjSchema();
}

// ---- /garments/i/material ------------------------------------------------------------------

const JsonSchema<SpringMaterial>& SpringSchema() {
  static const JsonSchema<SpringMaterial> schema =
      JsonSchema<SpringMaterial>()
          .Float("stiffness", "N/m", Closed(0, 1e7), "force per metre of length error",
                 [](SpringMaterial& m) -> float& { return m.stiffness; })
          .Float("damping", "N·s/m", Closed(0, 1e4),
                 "force per m/s of length change (explicit Euler)",
                 [](SpringMaterial& m) -> float& { return m.damping; })
          .Float("correction", "", Closed(0, 1),
                 "Verlet: the fraction of the length error one iteration removes",
                 [](SpringMaterial& m) -> float& { return m.correction; });
  return schema;
}

const JsonSchema<SceneGarment>& MaterialSchema() {
  static const JsonSchema<SceneGarment> schema =
      JsonSchema<SceneGarment>()
          .Float("density", "kg/m²", OpenBelow(0, 1e3), "areal density; masses from triangle areas",
                 [](SceneGarment& g) -> float& { return g.density; })
          .Float("total_mass", "kg", Closed(0, 1e4), "> 0 rescales the masses to this total",
                 [](SceneGarment& g) -> float& { return g.total_mass; })
          .Object("stretch", SpringSchema(), "the edge springs",
                  [](SceneGarment& g) -> SpringMaterial& { return g.stretch; })
          .Object("bend", SpringSchema(), "the bend springs",
                  [](SceneGarment& g) -> SpringMaterial& { return g.bend; })
          .Bool("bend_springs", "false: stretch springs only",
                [](SceneGarment& g) -> bool& { return g.bend_springs; })
          .Float("tether_stretch", "", Closed(0, 10),
                 "how far beyond its geodesic distance to the held particles a particle may go "
                 "(the long-range tethers of `/solver/tethers`)",
                 [](SceneGarment& g) -> float& { return g.tether_stretch; });
  return schema;
}

// ---- /garments/i/skin ----------------------------------------------------------------------

// A distance in metres, or "none" (+inf: no limit).
Status ReadDistanceOrNone(const JsonAt& at, float* out) {
  if (at.value().is_string()) {
    if (at.value().get<std::string>() != "none")
      return at.Error("must be a number in [0, 100] (metres) or \"none\"");
    *out = std::numeric_limits<float>::infinity();
    return Status::Ok();
  }
  return ReadFloat(at, Closed(0, 100), out);
}

// "r", "g", "b" (a colour channel: 0, 1, 2), "attribute", "ramp" or "none" (-1).
Status ReadPaintChannel(const JsonAt& at, SceneGarment& g) {
  const std::string value = at.value().is_string() ? at.value().get<std::string>() : "";
  const size_t channel = std::string("rgb").find(value);
  if (value == "none") {
    g.max_distance_channel = -1;
  } else if (value == "attribute") {
    g.max_distance_channel = SceneGarment::kPaintAttribute;
  } else if (value == "ramp") {
    g.max_distance_channel = SceneGarment::kPaintRamp;
  } else if (value.size() == 1 && channel != std::string::npos) {
    g.max_distance_channel = static_cast<int32_t>(channel);
  } else {
    return at.Error("must be one of \"r\", \"g\", \"b\", \"attribute\", \"ramp\", \"none\"");
  }
  return Status::Ok();
}

const JsonSchema<SceneGarment>& SkinSchema() {
  static const JsonSchema<SceneGarment> schema =
      JsonSchema<SceneGarment>(
          "A skinned garment: each particle takes the skin weights of the closest point of the "
          "character's body (or the `weights_file`'s, or a skinned glTF garment's own) and follows "
          "the skinned surface within "
          "`max_distance`, never more "
          "than `backstop` behind it (along the garment's normal: the side its triangles' "
          "counter-clockwise winding faces, which should face away from the body). Attached "
          "and pinned particles stay held.")
          .Custom(CustomFieldInfo("max_distance", "metres ≥ 0 or `\"none\"`",
                                  "a number in [0, 100] or \"none\"",
                                  "how far a particle may move from its skinned position (0: it "
                                  "follows the skin exactly)"),
                  [](const JsonAt& at, SceneGarment& g) {
                    return ReadDistanceOrNone(at, &g.max_distance);
                  })
          .Default("0.05")
          .Custom(
              CustomFieldInfo("backstop", "metres ≥ 0 or `\"none\"`",
                              "a number in [0, 100] or \"none\"",
                              "how far behind its skinned position a particle may go"),
              [](const JsonAt& at, SceneGarment& g) { return ReadDistanceOrNone(at, &g.backstop); })
          .Default("none")
          .Custom(CustomFieldInfo("paint",
                                  "`\"r\"` \\| `\"g\"` \\| `\"b\"` \\| `\"attribute\"` \\| "
                                  "`\"ramp\"` \\| `\"none\"`",
                                  "one of \"r\", \"g\", \"b\", \"attribute\", \"ramp\", \"none\"",
                                  "a vertex colour channel of the garment file (an OBJ's `v x y z "
                                  "r g b`, a glTF's COLOR_0) that scales `max_distance` per "
                                  "particle (painted black: the particle follows the skin "
                                  "exactly); `attribute`: a glTF garment's `_MAX_DISTANCE` "
                                  "attribute gives it per vertex, and `_BACKSTOP`, when present, "
                                  "the backstop (file units scaled to metres; negative: "
                                  "unlimited); `ramp`: `max_distance` times the particle's "
                                  "distance from the held particles along the garment over the "
                                  "farthest one's (0 at a waistband, `max_distance` at the hem: "
                                  "what is painted on a skirt or cape; needs an `attach` or "
                                  "`pin`)"),
                  [](const JsonAt& at, SceneGarment& g) { return ReadPaintChannel(at, g); })
          .Default("none")
          .FilePath("weights_file",
                    "authored skin weights instead of the body's, relative to the scene: one "
                    "line per garment vertex, in order, of `joint weight` pairs (joint names of "
                    "the character's skeleton; the four heaviest kept); `#` starts a comment",
                    [](SceneGarment& g) -> std::string& { return g.skin_weights_file; })
          .Default("none: from the body")
          .Enum<SkinTransfer>(
              "transfer", {{"closest", SkinTransfer::kClosest}, {"held", SkinTransfer::kHeld}},
              "where the weights come from the body. `closest`: each particle takes the body's "
              "closest point's (a shirt, a sleeve: the garment follows the limb under it). "
              "`held`: each particle takes those of its nearest held particle along the garment "
              "(attached or pinned; a dress or a cape then follows its waistband or shoulders, "
              "and the legs move under it instead of dragging it along; a short skirt the thighs "
              "fill is better with `closest`). Not with authored weights (a `weights_file`, a "
              "skinned glTF garment)",
              [](SceneGarment& g) -> SkinTransfer& { return g.skin_transfer; })
          .Default("closest")
          .Unsigned<uint32_t>("smoothing", "", 0, 1000,
                              "passes averaging each particle's weights from the body with its "
                              "mesh neighbours' (a skirt then follows the hips and both legs, not "
                              "one leg on each side); authored weights are kept as they are",
                              [](SceneGarment& g) -> uint32_t& { return g.skin_smoothing; });
  return schema;
}

// ---- Selections: /garments/i/attach, /garments/i/pin ---------------------------------------

const JsonSchema<SceneSelection>& BoxSchema() {
  static const JsonSchema<SceneSelection> schema =
      JsonSchema<SceneSelection>(
          "Every particle inside the axis-aligned box, in the garment's `frame` shifted by its "
          "`anchor`; it must select at least one.")
          .Vector("min", "m", kMaxCoordinate, "the lowest corner",
                  [](SceneSelection& s) -> Float3& { return s.box_min; })
          .Required()
          .Vector("max", "m", kMaxCoordinate, "the highest corner, >= min in every coordinate",
                  [](SceneSelection& s) -> Float3& { return s.box_max; })
          .Required()
          .Rule([](const JsonAt& at, SceneSelection& s) {
            if (s.box_max.x < s.box_min.x || s.box_max.y < s.box_min.y ||
                s.box_max.z < s.box_min.z) {
              return at.Member("max").Error("must be >= min in every coordinate");
            }
            s.has_box = true;
            return Status::Ok();
          });
  return schema;
}

// The selection keys (exactly one of ring, vertices, box) of a T that holds a SceneSelection.
template <class T>
void AddSelection(JsonSchema<T>* schema, std::function<SceneSelection&(T&)> selection) {
  schema->String("ring", StringRule::kNonEmpty,
                 "a generator ring: every generator has `held` (its suggested hold). sheet: `top` "
                 "(the +axis_v edge, = held), `bottom`, `left` (-axis_u), `right`; skirt: `waist` "
                 "(= held), `hem`; cape: `top` (= held), `bottom`, `left` (-x), `right`; sleeve: "
                 "`start` (= held), `end`; obj: none",
                 [selection](T& t) -> std::string& { return selection(t).ring; });
  schema->Custom(
      CustomFieldInfo("vertices", "array of integers", "a non-empty array of particle indices",
                      "particle indices (for an OBJ: its vertex order, 0-based)"),
      [selection](const JsonAt& at, T& t) {
        const json& v = at.value();
        if (!v.is_array() || v.empty()) {
          return at.Error(std::string("must be a non-empty array of particle indices, not ") +
                          (v.is_array() ? "an empty array" : JsonTypeName(v)));
        }
        for (size_t i = 0; i < v.size(); ++i) {
          const json& e = v[i];
          if (!e.is_number_integer() || e.get<int64_t>() < 0 || e.get<int64_t>() > 0xffffffffll)
            return at.Element(i).Error("must be a particle index (an integer >= 0)");
          selection(t).vertices.push_back(static_cast<uint32_t>(e.get<int64_t>()));
        }
        return Status::Ok();
      });
  schema->Object("box", BoxSchema(), "every particle inside an axis-aligned box", selection);
  schema->Rule([](const JsonAt& at, T&) {
    const int given = (at.Find("ring") != nullptr) + (at.Find("vertices") != nullptr) +
                      (at.Find("box") != nullptr);
    if (given == 0) return at.Error("names no particles: give one of ring, vertices, box");
    if (given > 1) return at.Error("give only one of ring, vertices, box");
    return Status::Ok();
  });
}

const JsonSchema<SceneAttachment>& AttachmentSchema() {
  static const JsonSchema<SceneAttachment> schema = [] {
    JsonSchema<SceneAttachment> s(
        "Particles held by a joint: exactly one of `ring`, `vertices`, `box`, and the `joint`. "
        "A particle may be held by one joint or pin only.");
    s.String("joint", StringRule::kNonEmpty, "the joint that carries the particles",
             [](SceneAttachment& a) -> std::string& { return a.joint; })
        .Required();
    AddSelection<SceneAttachment>(
        &s, [](SceneAttachment& a) -> SceneSelection& { return a.particles; });
    return s;
  }();
  return schema;
}

const JsonSchema<SceneSelection>& PinSchema() {
  static const JsonSchema<SceneSelection> schema = [] {
    JsonSchema<SceneSelection> s(
        "Particles fixed in the world: exactly one of `ring`, `vertices`, `box`.");
    AddSelection<SceneSelection>(&s, [](SceneSelection& p) -> SceneSelection& { return p; });
    return s;
  }();
  return schema;
}

// An object or an array of objects, each read by `schema` into an element appended to a list.
template <class Element>
Status ReadSelections(const JsonAt& at, const JsonSchema<Element>& schema,
                      const std::function<SceneSelection&(Element&)>& selection,
                      std::vector<Element>* out) {
  return ForEachObject(at, [&](const JsonAt& element) {
    Element value;
    selection(value).path = element.path();
    DRAPE_RETURN_IF_ERROR(schema.Read(element, &value));
    out->push_back(std::move(value));
    return Status::Ok();
  });
}

}  // namespace

// ---- /garments/i ---------------------------------------------------------------------------

const JsonSchema<SceneGarment>& GarmentSchema() {
  static const JsonSchema<SceneGarment> schema =
      JsonSchema<SceneGarment>(
          "The garment starts at the scene's start pose: each particle is moved rigidly by the "
          "joint of its nearest held particle (along the mesh), from `frame` to that pose. "
          "Attached particles then follow their joint exactly (paper B's geometric constraints); "
          "pinned ones stay put. A garment with no held particle falls freely. Garments do not "
          "collide with each other; a floor is one of `/collision/shapes`. A garment has at most "
          "2^20 "
          "particles.")
          .Enum<GarmentType>("type",
                             {{"sheet", GarmentType::kSheet},
                              {"skirt", GarmentType::kSkirt},
                              {"cape", GarmentType::kCape},
                              {"sleeve", GarmentType::kSleeve},
                              {"obj", GarmentType::kObj},
                              {"gltf", GarmentType::kGltf}},
                             "a procedural generator (drape/runtime/garments.h), an OBJ file or "
                             "a glTF file (skinned to the character's skeleton, or not)",
                             [](SceneGarment& g) -> GarmentType& { return g.type; })
          .Required()
          .String("name", StringRule::kNonEmpty, "unique; names the OBJ files",
                  [](SceneGarment& g) -> std::string& { return g.name; })
          .Default("`<type>_<i>`")
          .Enum<GarmentFrame>(
              "frame", {{"bind", GarmentFrame::kBind}, {"rest", GarmentFrame::kRest}},
              "the frame the garment's positions are written in. `bind`: the bind-pose asset "
              "frame the attachments are stored in. `rest`: the rest pose as authored (what a "
              "viewer shows); use it when the bind pose differs (e.g. CesiumMan's bind pose lies "
              "in a Z-up frame)",
              [](SceneGarment& g) -> GarmentFrame& { return g.frame; })
          .String("anchor", StringRule::kNonEmpty,
                  "a joint: its position in `frame` is added to every position of the shape and "
                  "to box selections, so garments can be written relative to the body",
                  [](SceneGarment& g) -> std::string& { return g.anchor; })
          .Custom(
              CustomFieldInfo("shape", "object", "an object",
                              "the generator's or the OBJ file's parameters"),
              [](const JsonAt& at, SceneGarment& g) { return ShapeSchema(g.type).Read(at, &g); },
              nullptr,
              [](const SceneGarment& defaults, const std::string& path, std::string* out) {
                for (GarmentType type :
                     {GarmentType::kSheet, GarmentType::kSkirt, GarmentType::kCape,
                      GarmentType::kSleeve, GarmentType::kObj, GarmentType::kGltf}) {
                  ShapeSchema(type).WriteSections(
                      defaults, path, "`" + path + "` of `" + ToString(type) + "`", out);
                }
              })
          .Default("the generator's defaults")
          .Object("material", MaterialSchema(), "the cloth material",
                  [](SceneGarment& g) -> SceneGarment& { return g; })
          .Custom(
              CustomFieldInfo("skin", "object", "an object",
                              "skin the garment to the body (weights from its closest point)"),
              [](const JsonAt& at, SceneGarment& g) {
                g.skinned = true;
                return SkinSchema().Read(at, &g);
              },
              nullptr,
              [](const SceneGarment& defaults, const std::string& path, std::string* out) {
                SkinSchema().WriteSections(defaults, path, "`" + path + "`", out);
              })
          .Default("not skinned")
          .Custom(
              CustomFieldInfo("attach", "object or array of objects",
                              "an object or an array of objects", "selections held by joints"),
              [](const JsonAt& at, SceneGarment& g) {
                return ReadSelections<SceneAttachment>(
                    at, AttachmentSchema(),
                    [](SceneAttachment& a) -> SceneSelection& { return a.particles; },
                    &g.attachments);
              },
              nullptr,
              [](const SceneGarment&, const std::string& path, std::string* out) {
                AttachmentSchema().WriteSections(SceneAttachment{}, path,
                                                 "`" + path + "` (an object, or each of an array)",
                                                 out);
              })
          .Default("none")
          .Custom(
              CustomFieldInfo("pin", "object or array of objects",
                              "an object or an array of objects", "selections fixed in the world"),
              [](const JsonAt& at, SceneGarment& g) {
                return ReadSelections<SceneSelection>(
                    at, PinSchema(), [](SceneSelection& s) -> SceneSelection& { return s; },
                    &g.pins);
              },
              nullptr,
              [](const SceneGarment&, const std::string& path, std::string* out) {
                PinSchema().WriteSections(SceneSelection{}, path,
                                          "`" + path + "` (an object, or each of an array)", out);
              })
          .Default("none")
          .Custom(
              CustomFieldInfo("color", "[r, g, b], each in [0, 1]",
                              "an array of 3 numbers [r, g, b]", "linear RGB of the pictures"),
              [](const JsonAt& at, SceneGarment& g) {
                return ReadFloats(at, Closed(0, 1), "r, g, b", 3, g.color.data());
              },
              [](const SceneGarment& g) { return FloatsJson(g.color.data(), 3); })
          .Rule([](const JsonAt& at, SceneGarment& g) {
            if (g.type == GarmentType::kObj && at.Find("shape") == nullptr)
              return at.Member("shape").Error("missing (an OBJ garment needs {\"file\": ...})");
            if (g.type == GarmentType::kGltf && at.Find("shape") == nullptr)
              return at.Member("shape").Error("missing (a glTF garment needs {\"file\": ...})");
            if (g.max_distance_channel == SceneGarment::kPaintAttribute &&
                g.type != GarmentType::kGltf)
              return at.Member("skin").Member("paint").Error(
                  "\"attribute\" paints from a glTF garment's _MAX_DISTANCE attribute; this "
                  "garment is not glTF");
            return Status::Ok();
          });
  return schema;
}

}  // namespace drape::bake::detail

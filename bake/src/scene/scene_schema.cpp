#include "scene/scene_schema.h"

#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "config/bake_config_schema.h"
#include "drape/runtime/math.h"
#include "scene/garment_schema.h"
#include "scene/scene_messages.h"

namespace drape::bake::detail {
namespace {

using nlohmann::json;

// ---- /animation, /collision, /solver, /output ------------------------------------------------

const JsonSchema<SceneAnimation>& AnimationSchema() {
  static const JsonSchema<SceneAnimation> schema =
      JsonSchema<SceneAnimation>(
          "Frame k covers scene time [start + k dt, start + (k + 1) dt]: the solver gets the "
          "skinning matrices sampled at both ends (attachments and colliders move between them "
          "within the frame); the body-map pose is the one for the frame's end time.")
          .String("clip", StringRule::kNonEmpty,
                  "clip name in the character; without it the scene holds a static pose",
                  [](SceneAnimation& a) -> std::string& { return a.clip; })
          .Enum<ScenePose>("pose", {{"rest", ScenePose::kRest}, {"bind", ScenePose::kBind}},
                           "the static pose (only without `clip`): the rest pose as authored, or "
                           "the bind pose",
                           [](SceneAnimation& a) -> ScenePose& { return a.pose; })
          .Float("start", "s", Closed(0, 1e5), "seconds into the clip at frame 0",
                 [](SceneAnimation& a) -> float& { return a.start; })
          .Float("duration", "s", OpenBelow(0, 3600),
                 "seconds of scene time; frames = ceil(duration / dt) (drape-sim --frames "
                 "overrides)",
                 [](SceneAnimation& a) -> float& { return a.duration; })
          .Default("the clip's duration (1 s static)")
          .Bool("loop", "wrap clip time by the clip's duration, else clamp to its end",
                [](SceneAnimation& a) -> bool& { return a.loop; })
          .Float("settle", "s", Closed(0, 60),
                 "seconds simulated with the body held at the start pose before frame 0 (not "
                 "output), so garments hang before the motion starts",
                 [](SceneAnimation& a) -> float& { return a.settle; })
          .String("blend_clip", StringRule::kNonEmpty,
                  "a second clip played at the same time and blended with `clip` (a pose no "
                  "bake saw)",
                  [](SceneAnimation& a) -> std::string& { return a.blend_clip; })
          .Float("blend_weight", "", Closed(0, 1), "0: `clip` alone, 1: `blend_clip` alone",
                 [](SceneAnimation& a) -> float& { return a.blend_weight; })
          .Float("perturb_degrees", "deg", Closed(0, 90),
                 "every joint turned by a fixed random rotation of up to this angle on top of the "
                 "clip or pose (0: none)",
                 [](SceneAnimation& a) -> float& { return a.perturb_degrees; })
          .Unsigned<uint32_t>("perturb_seed", "", 0, 4294967295u, "the perturbation's random seed",
                              [](SceneAnimation& a) -> uint32_t& { return a.perturb_seed; })
          .Rule([](const JsonAt& at, SceneAnimation& a) {
            if (at.Find("pose") != nullptr && !a.clip.empty())
              return at.Member("pose").Error("give either a clip or a static pose, not both");
            if (!a.blend_clip.empty() && a.clip.empty())
              return at.Member("blend_clip").Error("blends with `clip`: give a clip too");
            return Status::Ok();
          });
  return schema;
}

const JsonSchema<SceneShape>& ShapeSchema() {
  constexpr double kLimit = 1e4;  // metres
  static const JsonSchema<SceneShape> schema =
      JsonSchema<SceneShape>(
          "An engine collider (drape/runtime/shape_collider_set.h): continuous collision and the "
          "scene's friction like the character's colliders. Positions in the world at the rest "
          "pose; with a `joint` the shape moves with it.")
          .Enum<SceneShapeType>("type",
                                {{"plane", SceneShapeType::kPlane},
                                 {"sphere", SceneShapeType::kSphere},
                                 {"capsule", SceneShapeType::kCapsule},
                                 {"box", SceneShapeType::kBox}},
                                "a half-space (a floor), a sphere, a tapered capsule or a box",
                                [](SceneShape& s) -> SceneShapeType& { return s.type; })
          .Required()
          .String("joint", StringRule::kNonEmpty, "the joint that carries it (none: fixed)",
                  [](SceneShape& s) -> std::string& { return s.joint; })
          .Vector("center", "m", kLimit, "plane: a point on it; sphere, box: the centre",
                  [](SceneShape& s) -> Float3& { return s.center; })
          .Vector("normal", "", 1, "plane: the outward normal (normalised)",
                  [](SceneShape& s) -> Float3& { return s.normal; })
          .Vector("from", "m", kLimit, "capsule: the centre of one end sphere",
                  [](SceneShape& s) -> Float3& { return s.from; })
          .Vector("to", "m", kLimit, "capsule: the centre of the other",
                  [](SceneShape& s) -> Float3& { return s.to; })
          .Float("radius", "m", OpenBelow(0, 100), "sphere; capsule at `from`",
                 [](SceneShape& s) -> float& { return s.radius; })
          .Float("radius_to", "m", OpenBelow(0, 100), "capsule at `to`",
                 [](SceneShape& s) -> float& { return s.radius_to; })
          .Default("`radius`")
          .Vector("half_extents", "m", 100, "box: half its size along x, y, z (each > 0)",
                  [](SceneShape& s) -> Float3& { return s.half_extents; })
          .Rule([](const JsonAt& at, SceneShape& s) {
            if (s.type == SceneShapeType::kPlane && !(Length(s.normal) > 1e-6f))
              return at.Member("normal").Error("must not be zero");
            if (s.type == SceneShapeType::kBox &&
                !(s.half_extents.x > 0.f && s.half_extents.y > 0.f && s.half_extents.z > 0.f))
              return at.Member("half_extents").Error("each must be > 0");
            return Status::Ok();
          });
  return schema;
}

const JsonSchema<Scene>& CollisionSchema() {
  static const JsonSchema<Scene> schema =
      JsonSchema<Scene>(
          "The response parameters (friction, restitution, separation) are in `/solver`.")
          .Custom(
              CustomFieldInfo(
                  "methods", "array of `maps` \\| `hulls` \\| `spheres` \\| `capsules`",
                  "an array of maps | hulls | spheres | capsules",
                  "any combination (empty: no collision). `maps`: paper A's front/back depth and "
                  "normal maps of the pose of every frame (see `maps_source`); "
                  "`hulls`: paper B's per-bone convex hulls; `spheres`: paper B's joint "
                  "spheres; `capsules`: a tapered capsule per bone fitted to the body (posed "
                  "with the engine shapes of `shapes`). The bake builds only these"),
              [](const JsonAt& at, Scene& scene) {
                const json& methods = at.value();
                if (!methods.is_array()) {
                  return at.Error(
                      std::string("must be an array of maps | hulls | spheres | capsules, not ") +
                      JsonTypeName(methods));
                }
                scene.use_maps = scene.use_hulls = scene.use_spheres = scene.use_capsules = false;
                for (size_t i = 0; i < methods.size(); ++i) {
                  const JsonAt m = at.Element(i);
                  if (!m.value().is_string()) {
                    return m.Error(std::string("must be maps | hulls | spheres | capsules, not ") +
                                   JsonTypeName(m.value()));
                  }
                  const std::string name = m.value().get<std::string>();
                  bool* flag = name == "maps"       ? &scene.use_maps
                               : name == "hulls"    ? &scene.use_hulls
                               : name == "spheres"  ? &scene.use_spheres
                               : name == "capsules" ? &scene.use_capsules
                                                    : nullptr;
                  if (flag == nullptr) {
                    return m.Error(
                        Quote(name) +
                        " is not a collision method (maps | hulls | spheres | capsules)");
                  }
                  if (*flag) return m.Error(Quote(name) + " is listed twice");
                  *flag = true;
                }
                return Status::Ok();
              },
              [](const Scene& scene) {
                json methods = json::array();
                if (scene.use_maps) methods.push_back("maps");
                if (scene.use_hulls) methods.push_back("hulls");
                if (scene.use_spheres) methods.push_back("spheres");
                if (scene.use_capsules) methods.push_back("capsules");
                return methods;
              })
          .Enum<DepthSampling>(
              "maps_sampling",
              {{"nearest", DepthSampling::kNearest}, {"bilinear", DepthSampling::kBilinear}},
              "depth between texel centres",
              [](Scene& s) -> DepthSampling& { return s.maps_sampling; })
          .Enum<MapSource>("maps_source",
                           {{"rendered", MapSource::kRendered}, {"baked", MapSource::kBaked}},
                           "`rendered`: the maps of each frame's pose, rendered at run time over "
                           "the garments' reach (the asset holds the rest pose's alone); "
                           "`baked`: every pose of the clip baked at `/bake/maps/clip_rate`",
                           [](Scene& s) -> MapSource& { return s.maps_source; })
          .Enum<PoseBlend>("maps_blend",
                           {{"nearest", PoseBlend::kNearest}, {"bracket", PoseBlend::kBracket}},
                           "baked maps, for a time between baked poses: the nearest pose, or "
                           "a per-texel blend of the two around it",
                           [](Scene& s) -> PoseBlend& { return s.maps_blend; })
          .Enum<InsideTest>(
              "inside_test",
              {{"planes", InsideTest::kPlanes}, {"kirkpatrick", InsideTest::kKirkpatrick}},
              "the hulls' inside test (same answers; Kirkpatrick is paper B's)",
              [](Scene& s) -> InsideTest& { return s.hull_options.inside_test; })
          .Enum<HullResponse>(
              "hull_response",
              {{"push_out", HullResponse::kPushOut}, {"map_table_ray", HullResponse::kMapTableRay}},
              "the exact minimal push-out, or paper B's map sphere / cylinder ray",
              [](Scene& s) -> HullResponse& { return s.hull_options.response; })
          .Bool("continuous", "test each particle's motion segment, not only its end",
                [](Scene& s) -> bool& { return s.hull_options.continuous; })
          .Enum<EntryResponse>(
              "entry_response",
              {{"project_end", EntryResponse::kProjectEnd},
               {"entry_point", EntryResponse::kEntryPoint}},
              "where a particle entering a hull goes",
              [](Scene& s) -> EntryResponse& { return s.hull_options.entry_response; })
          .Unsigned<uint32_t>(
              "passes", "", 1, 16,
              "Gauss-Seidel passes over the colliders per particle (fewer let a hem pinched "
              "between thigh and shin hulls sink a few mm)",
              [](Scene& s) -> uint32_t& { return s.hull_options.gauss_seidel_passes; })
          .Float("reach_margin", "m", Closed(0, 100), "added to each garment's reach radius",
                 [](Scene& s) -> float& { return s.reach_margin; })
          .Float("reach_stretch", "", Closed(0, 100),
                 "how much the cloth may stretch beyond its rest lengths, for the reach radius",
                 [](Scene& s) -> float& { return s.reach_stretch; })
          .Bool("prune", "drop the colliders the garments cannot reach before simulating",
                [](Scene& s) -> bool& { return s.prune; })
          .Custom(
              CustomFieldInfo("shapes", "array of objects", "an array of shapes",
                              "the engine's own colliders (a floor, props), besides the "
                              "character's"),
              [](const JsonAt& at, Scene& scene) {
                if (!at.value().is_array())
                  return at.Error(std::string("must be an array of shapes, not ") +
                                  JsonTypeName(at.value()));
                for (size_t i = 0; i < at.value().size(); ++i) {
                  const JsonAt element = at.Element(i);
                  SceneShape shape;
                  shape.path = element.path();
                  DRAPE_RETURN_IF_ERROR(ShapeSchema().Read(element, &shape));
                  scene.shapes.push_back(std::move(shape));
                }
                return Status::Ok();
              },
              nullptr,
              [](const Scene&, const std::string& path, std::string* out) {
                ShapeSchema().WriteSections(SceneShape{}, path + "/i", "`" + path + "/i`", out);
              })
          .Default("none");
  return schema;
}

const JsonSchema<Scene>& SolverSchema() {
  static const JsonSchema<Scene> schema =
      JsonSchema<Scene>()
          .Enum<ClothIntegrator>(
              "integrator",
              {{"verlet", ClothIntegrator::kVerlet}, {"euler", ClothIntegrator::kExplicitEuler}},
              "paper B: Verlet with iterative spring correction; paper A: explicit Euler with "
              "spring forces",
              [](Scene& s) -> ClothIntegrator& { return s.solver.integrator; })
          .Float("dt", "s", OpenBelow(0, 1), "frame length",
                 [](Scene& s) -> float& { return s.dt; })
          .Default("1/60")
          .Custom(CustomFieldInfo("substeps", "integer [1, 256] or `\"auto\"`",
                                  "an integer in [1, 256] or \"auto\"",
                                  "substeps per frame; `auto` (euler only) is the stability bound "
                                  "RecommendedEulerSubsteps"),
                  [](const JsonAt& at, Scene& s) {
                    if (at.value().is_string()) {
                      if (at.value().get<std::string>() != "auto")
                        return at.Error("must be an integer in [1, 256] or \"auto\"");
                      s.auto_substeps = true;
                      return Status::Ok();
                    }
                    uint64_t substeps = 0;
                    DRAPE_RETURN_IF_ERROR(ReadUnsigned(at, 1, 256, &substeps));
                    s.solver.substeps = static_cast<uint32_t>(substeps);
                    return Status::Ok();
                  })
          .Default("4 (euler: `auto`)")
          .Unsigned<uint32_t>("iterations", "", 1, 256,
                              "Verlet spring-correction passes per substep",
                              [](Scene& s) -> uint32_t& { return s.solver.iterations; })
          .Bool("buckling",
                "paper A's buckling model (stretch springs only pull, bend springs only push)",
                [](Scene& s) -> bool& { return s.solver.buckling; })
          .Vector("gravity", "m/s²", 1e3, "the acceleration of gravity",
                  [](Scene& s) -> Float3& { return s.solver.gravity; })
          .Float("damping", "1/s", Closed(0, 1e3), "velocity damping",
                 [](Scene& s) -> float& { return s.solver.damping; })
          .Float("drag", "kg/(m² s)", Closed(0, 1e3), "fluid drag against `wind`",
                 [](Scene& s) -> float& { return s.solver.drag; })
          .Vector("wind", "m/s", 1e3, "the air's velocity",
                  [](Scene& s) -> Float3& { return s.solver.wind; })
          .Bool("tethers",
                "long-range tethers from every particle to the held ones (geodesic lengths; "
                "the garment's `tether_stretch`)",
                [](Scene& s) -> bool& { return s.solver.tethers; })
          .Custom(CustomFieldInfo("max_stretch", "number ≥ 0 or `\"none\"`",
                                  "a number >= 0 or \"none\"",
                                  "strain limit: after the iterations one pass shortens every "
                                  "stretch spring longer than rest × (1 + this) to that length "
                                  "(springs sharing a particle can stretch each other again, and "
                                  "colliders can: stats.json counts those beyond it)"),
                  [](const JsonAt& at, Scene& s) {
                    if (at.value().is_string()) {
                      if (at.value().get<std::string>() != "none")
                        return at.Error("must be a number >= 0 or \"none\"");
                      s.solver.max_stretch = std::numeric_limits<float>::infinity();
                      return Status::Ok();
                    }
                    return ReadFloat(at, Closed(0, 100), &s.solver.max_stretch);
                  })
          .Default("0.1")
          .Float("linear_inertia", "", Closed(0, 1),
                 "how much of the root's translation the cloth resists: 1 simulates in the "
                 "world, 0 carries the cloth with the character",
                 [](Scene& s) -> float& { return s.solver.linear_inertia; })
          .Float("angular_inertia", "", Closed(0, 1), "the same for the root's rotation",
                 [](Scene& s) -> float& { return s.solver.angular_inertia; })
          .Float("centrifugal_inertia", "", Closed(0, 1),
                 "the outward push of a carried rotation (1: as in the world)",
                 [](Scene& s) -> float& { return s.solver.centrifugal_inertia; })
          .Enum<FrictionModel>(
              "friction_model",
              {{"coulomb", FrictionModel::kCoulomb}, {"paper_a", FrictionModel::kPaperA}},
              "`coulomb`: static and kinetic friction (a particle sticks while its sliding speed "
              "is below static_friction × the speed it hit with); `paper_a`: eq. 5's scaling "
              "of the tangential velocity by 1 − friction",
              [](Scene& s) -> FrictionModel& { return s.response.friction_model; })
          .Float("friction", "", Closed(0, 1),
                 "Coulomb's kinetic coefficient, or paper A eq. 5 c_fric",
                 [](Scene& s) -> float& { return s.response.friction; })
          .Float("static_friction", "", Closed(0, 4), "Coulomb's static coefficient",
                 [](Scene& s) -> float& { return s.response.static_friction; })
          .Float("restitution", "", Closed(0, 1), "paper A eq. 5 c_res",
                 [](Scene& s) -> float& { return s.response.restitution; })
          .Float("separation", "m", Closed(0, 0.1),
                 "how far outside a surface a contact places the particle",
                 [](Scene& s) -> float& { return s.response.separation; })
          .Bool("relative",
                "relative simulation: the root joint's translation is applied to the cloth "
                "without inertia",
                [](Scene& s) -> bool& { return s.relative; })
          .Rule([](const JsonAt& at, Scene& s) {
            const bool euler = s.solver.integrator == ClothIntegrator::kExplicitEuler;
            if (s.auto_substeps && !euler)
              return at.Member("substeps").Error("\"auto\" is for the euler integrator only");
            // Explicit Euler without a count: the stability bound decides.
            if (at.Find("substeps") == nullptr && euler) s.auto_substeps = true;
            return Status::Ok();
          });
  return schema;
}

const JsonSchema<SceneOutput>& CameraSchema() {
  static const JsonSchema<SceneOutput> schema =
      JsonSchema<SceneOutput>()
          .Float("yaw_deg", "°", Closed(-360, 360),
                 "about +Y, from the character's front (+Z); positive turns towards +X",
                 [](SceneOutput& o) -> float& { return o.camera_yaw_deg; })
          .Float("pitch_deg", "°", Closed(-89, 89), "above the horizon",
                 [](SceneOutput& o) -> float& { return o.camera_pitch_deg; })
          .Float("zoom", "", OpenBelow(0, 100),
                 "1: the body's bounds over the scene fill the picture",
                 [](SceneOutput& o) -> float& { return o.camera_zoom; });
  return schema;
}

const JsonSchema<SceneOutput>& OutputSchema() {
  static const JsonSchema<SceneOutput> schema =
      JsonSchema<SceneOutput>()
          .Unsigned<uint32_t>("every", "", 1, 100000,
                              "write every k-th frame (frames 0, k, 2k ...; a k of at least the "
                              "frame count writes frame 0 only: there is no setting for no "
                              "picture at all)",
                              [](SceneOutput& o) -> uint32_t& { return o.every; })
          .Unsigned<uint32_t>("width", "px", 16, 4096,
                              "picture width (rendered at 2x and filtered down)",
                              [](SceneOutput& o) -> uint32_t& { return o.width; })
          .Unsigned<uint32_t>("height", "px", 16, 4096, "picture height",
                              [](SceneOutput& o) -> uint32_t& { return o.height; })
          .Bool("overlay_colliders",
                "draw the hulls' edges (yellow) and the joint spheres (cyan) in use; hidden parts "
                "faint",
                [](SceneOutput& o) -> bool& { return o.overlay_colliders; })
          .Bool("obj", "write the cloth of every written frame as OBJ",
                [](SceneOutput& o) -> bool& { return o.obj; })
          .Enum<SceneAnimationOutput>(
              "animation",
              {{"auto", SceneAnimationOutput::kAuto},
               {"mp4", SceneAnimationOutput::kMp4},
               {"gif", SceneAnimationOutput::kGif},
               {"contact_sheet", SceneAnimationOutput::kContactSheet},
               {"none", SceneAnimationOutput::kNone}},
              "`auto`: mp4 through ffmpeg when it is on PATH, else a contact sheet (up to 16 "
              "frames); mp4 and gif fall back to the contact sheet (with a warning) without ffmpeg",
              [](SceneOutput& o) -> SceneAnimationOutput& { return o.animation; })
          .Object("camera", CameraSchema(), "where the pictures are taken from",
                  [](SceneOutput& o) -> SceneOutput& { return o; });
  return schema;
}

}  // namespace

Status ReadBakeOverrides(const JsonAt& at, BakeConfig* config) {
  const json& bake = at.value();
  if (!bake.is_object())
    return at.Error(std::string("must be an object, not ") + JsonTypeName(bake));
  for (const auto& [section, values] : bake.items()) {
    if (!values.is_object()) continue;  // the schema names it
    for (const auto& [key, value] : values.items()) {
      const std::string name = section + "." + key;
      if (name == "maps.enabled" || name == "hulls.enabled" || name == "spheres.enabled" ||
          name == "capsules.enabled")
        return at.Member(section).Member(key).Error(
            "the collider kinds come from /collision/methods");
      if (name == "maps.clip")
        return at.Member(section).Member(key).Error("the maps' clip comes from /animation/clip");
    }
  }
  return BakeConfigSchema().Read(at, config);
}

const JsonSchema<Scene>& SceneSchema() {
  static const JsonSchema<Scene> schema =
      JsonSchema<Scene>("A scene file is one JSON object.")
          .Custom(CustomFieldInfo("description", "string", "a string", "free text"),
                  [](const JsonAt& at, Scene&) {
                    std::string ignored;
                    return ReadString(at, StringRule::kAny, &ignored);
                  })
          .Default("none")
          .FilePath("character",
                    "a model file (anything drape-bake reads: glTF, FBX, COLLADA, .X ...) or a "
                    "`.drape`, relative to the scene",
                    [](Scene& s) -> std::string& { return s.character; })
          .Required()
          .Object("animation", AnimationSchema(), "pose or clip, time range",
                  [](Scene& s) -> SceneAnimation& { return s.animation; })
          .Custom(
              CustomFieldInfo("garments", "array of objects", "a non-empty array of garments",
                              "the garments"),
              [](const JsonAt& at, Scene& scene) {
                const json& garments = at.value();
                if (!garments.is_array() || garments.empty()) {
                  return at.Error(
                      std::string("must be a non-empty array of garments, not ") +
                      (garments.is_array() ? "an empty array" : JsonTypeName(garments)));
                }
                for (size_t i = 0; i < garments.size(); ++i) {
                  const JsonAt element = at.Element(i);
                  SceneGarment garment;
                  garment.path = element.path();
                  DRAPE_RETURN_IF_ERROR(GarmentSchema().Read(element, &garment));
                  if (element.Find("name") == nullptr)
                    garment.name = std::string(ToString(garment.type)) + "_" + std::to_string(i);
                  for (const SceneGarment& other : scene.garments) {
                    if (other.name == garment.name) {
                      return element.Member("name").Error(Quote(garment.name) +
                                                          " is already the name of " + other.path);
                    }
                  }
                  scene.garments.push_back(std::move(garment));
                }
                return Status::Ok();
              },
              nullptr,
              [](const Scene&, const std::string& path, std::string* out) {
                GarmentSchema().WriteSections(SceneGarment{}, path + "/i", "`" + path + "/i`", out);
              })
          .Required()
          .Object("collision", CollisionSchema(), "collision methods and their options",
                  [](Scene& s) -> Scene& { return s; })
          .Object("solver", SolverSchema(), "integrator and parameters",
                  [](Scene& s) -> Scene& { return s; })
          .Object("output", OutputSchema(), "pictures, meshes, animation",
                  [](Scene& s) -> SceneOutput& { return s.output; })
          .Custom(
              CustomFieldInfo(
                  "bake", "object", "an object",
                  "bake parameter overrides, exactly as a `drape-bake --config` file "
                  "(`drape-bake --dump-config` lists them). Not allowed: `maps.enabled`, "
                  "`hulls.enabled`, `spheres.enabled` (they follow `/collision/methods`) and "
                  "`maps.clip` (it follows `/animation/clip`)"),
              [](const JsonAt& at, Scene& scene) {
                BakeConfig checked;
                DRAPE_RETURN_IF_ERROR(ReadBakeOverrides(at, &checked));
                scene.bake = at.value();
                return Status::Ok();
              },
              nullptr,
              [](const Scene&, const std::string& path, std::string* out) {
                static const BakeConfig defaults;
                BakeConfigSchema().WriteSections(defaults, path, "`" + path + "`", out);
              })
          .Default("{}");
  return schema;
}

}  // namespace drape::bake::detail
#pragma once
// A scene: one character, the pose or clip it plays, the garments it wears and how they are
// held, which collision methods run, the solver's parameters and what to output. The editable
// description (Scene), its JSON parser (every refusal names the file and the JSON path of the bad
// field), its resolution against a skeleton, and "model only what a scene needs": the colliders
// and poses the garments can reach over the frames the scene plays (AnalyzeSceneReach). The
// format field by field: docs/SCENES.md (generated from the parser's schema); frames, settling
// and reach: docs/ALGORITHMS.md §13.

#include <array>
#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "drape/bake/bake_config.h"
#include "drape/formats/character_asset.h"
#include "drape/formats/status.h"
#include "drape/formats/types.h"
#include "drape/runtime/body_map_collider.h"
#include "drape/runtime/body_map_sequence.h"
#include "drape/runtime/cloth.h"
#include "drape/runtime/cloth_solver.h"
#include "drape/runtime/garments.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/skeleton_pose.h"

namespace drape::bake {

enum class GarmentType : uint8_t { kSheet, kSkirt, kCape, kSleeve, kObj, kGltf };
const char* ToString(GarmentType type);

// The frame a garment's positions are written in. kBind: the bind-pose asset frame (attachments
// are stored in it). kRest: the rest pose as authored (what a viewer shows); an attached particle
// is mapped to the bind frame through the inverse of its joint's rest skinning matrix.
enum class GarmentFrame : uint8_t { kBind, kRest };

// Where a skinned garment's weights come from the body (SceneGarment::skin_transfer).
enum class SkinTransfer : uint8_t {
  kClosest,  // each particle: the body's closest point (a shirt, a sleeve, tights)
  kHeld,     // each particle: its nearest held particle's (a skirt follows its waistband)
};

// Which particles of a garment: exactly one of a generator ring (by name, see GarmentRingNames),
// explicit vertex indices, or the particles inside an axis-aligned box.
struct SceneSelection {
  std::string ring;
  std::vector<uint32_t> vertices;
  bool has_box = false;
  Float3 box_min, box_max;  // metres, in the garment's frame after anchoring
  std::string path;         // JSON path of the selection object, for messages
};

struct SceneAttachment {
  std::string joint;  // joint name in the character's skeleton
  SceneSelection particles;
};

struct SceneGarment {
  std::string name;
  GarmentType type = GarmentType::kSkirt;
  GarmentFrame frame = GarmentFrame::kBind;
  // Empty, or a joint whose position (in `frame`) is added to every position of the shape
  // (centres, starts, OBJ offset, box corners): garments can be written relative to the body.
  std::string anchor;
  SheetShape sheet;
  SkirtShape skirt;
  CapeShape cape;
  SleeveShape sleeve;
  std::string obj_file;   // kObj, kGltf: resolved against the scene's directory
  float obj_scale = 1.f;  // kObj, kGltf without a skin: metres per file unit, > 0
  Float3 obj_offset;      // kObj, kGltf without a skin: metres, added after scaling
  std::string gltf_mesh;  // kGltf: the mesh node's (or mesh's) name; empty: the file's only one
  // Cloth material (drape/runtime/cloth.h). Masses come from area and density, rescaled to
  // total_mass when it is > 0.
  float density = 0.15f;   // kg/m^2
  float total_mass = 0.f;  // kg, 0 = from density
  SpringMaterial stretch;
  SpringMaterial bend{20.f, 0.01f, 0.2f};
  bool bend_springs = true;
  std::vector<SceneAttachment> attachments;  // particles moving rigidly with a joint
  std::vector<SceneSelection> pins;          // particles fixed in the world
  // A skinned garment: every particle carried by the body's skin weights at its closest body
  // point, free within max_distance of that skinned position and outside the backstop plane
  // that far behind it (+inf: unlimited / none). Attached and pinned particles stay held.
  bool skinned = false;
  float max_distance = 0.05f;                               // metres, >= 0
  float backstop = std::numeric_limits<float>::infinity();  // metres, >= 0
  uint32_t skin_smoothing = 20;  // passes averaging the weights with the mesh neighbours
  SkinTransfer skin_transfer = SkinTransfer::kClosest;
  std::string skin_weights_file;  // authored weights, one line per vertex (empty: from the body)
  // -1: max_distance everywhere; 0, 1, 2: the garment file's vertex colour channel (r, g, b) in
  // [0, 1] scales it per particle (painted 0: the particle follows the skin exactly);
  // kPaintAttribute: a glTF garment's _MAX_DISTANCE (and _BACKSTOP) attributes give them;
  // kPaintRamp: max_distance times the particle's distance from the held particles along the
  // garment, over the farthest particle's (0 at the held ones, max_distance at the farthest).
  static constexpr int32_t kPaintAttribute = 3;
  static constexpr int32_t kPaintRamp = 4;
  int32_t max_distance_channel = -1;
  float tether_stretch = 0.02f;                   // long-range tethers' allowed stretch, >= 0
  std::array<float, 3> color{0.8f, 0.25f, 0.3f};  // linear RGB in [0, 1], for pictures
  std::string path;                               // "/garments/<index>"
};

// An engine collider of the scene (drape/runtime/shape_collider_set.h): fixed in the world, or
// carried by a joint. Positions are in the world at the rest pose; a carried shape moves with
// its joint's world matrix from there.
enum class SceneShapeType : uint8_t { kPlane, kSphere, kCapsule, kBox };
struct SceneShape {
  SceneShapeType type = SceneShapeType::kPlane;
  std::string joint;                      // empty: fixed in the world
  Float3 center;                          // plane: a point on it; sphere, box: the centre; metres
  Float3 normal{0.f, 1.f, 0.f};           // plane: the outward normal (the solid side is behind it)
  Float3 from, to;                        // capsule: the centres of its end spheres, metres
  float radius = 0.1f;                    // sphere; capsule at `from`; metres, > 0
  float radius_to = -1.f;                 // capsule at `to` (< 0: radius), metres
  Float3 half_extents{0.1f, 0.1f, 0.1f};  // box, axis-aligned, metres
  std::string path;                       // "/collision/shapes/<index>"
};

enum class ScenePose : uint8_t { kRest, kBind };

struct SceneAnimation {
  std::string clip;                   // empty: a static pose
  ScenePose pose = ScenePose::kRest;  // the static pose (without a clip)
  float start = 0.f;                  // seconds into the clip, >= 0
  float duration = -1.f;  // seconds of scene time, > 0; -1: the clip's duration (1 s static)
  bool loop = true;
  float settle = 0.5f;  // seconds simulated at the start pose before frame 0, >= 0
  // Poses no bake saw: the clip blended with another at the same time (empty: none) ...
  std::string blend_clip;
  float blend_weight = 0.5f;  // [0, 1]: 0 the clip alone, 1 blend_clip alone
  // ... and a fixed random rotation of up to this many degrees on every joint, [0, 90].
  float perturb_degrees = 0.f;
  uint32_t perturb_seed = 1;
};

enum class SceneAnimationOutput : uint8_t { kAuto, kMp4, kGif, kContactSheet, kNone };

struct SceneOutput {
  uint32_t every = 1;                  // write every k-th frame, >= 1
  uint32_t width = 640, height = 640;  // pixels, [16, 4096]
  bool overlay_colliders = false;      // hull edges and sphere outlines over the picture
  bool obj = false;                    // the cloth mesh per written frame as OBJ
  SceneAnimationOutput animation = SceneAnimationOutput::kAuto;
  float camera_yaw_deg = 35.f;    // about +Y, from the character's front (+Z) towards +X
  float camera_pitch_deg = 12.f;  // above the horizon, (-89, 89)
  float camera_zoom = 1.f;        // > 0; 1 fits the body's bounds over the clip
};

// Where a scene's body maps come from.
//  kRendered: rendered from the skinned mesh for every frame's pose (BodyMapRenderer), over the
//    garments' reach; the bake keeps the rest pose's maps alone (their texel size and grid).
//  kBaked: baked of every pose of the clip at /bake/maps/clip_rate, read nearest or blended.
enum class MapSource : uint8_t { kRendered = 0, kBaked = 1 };

struct Scene {
  std::string source;     // the scene file as named by the caller: prefix of every message
  std::string directory;  // relative paths resolve against it
  std::string character;  // model file (anything drape-bake reads) or a .drape, resolved
  nlohmann::json bake = nlohmann::json::object();  // overrides, as a drape-bake --config file

  SceneAnimation animation;
  std::vector<SceneGarment> garments;

  // Collision: any combination of the three methods.
  bool use_maps = false, use_hulls = true, use_spheres = true, use_capsules = false;
  DepthSampling maps_sampling = DepthSampling::kNearest;
  MapSource maps_source = MapSource::kRendered;
  PoseBlend maps_blend = PoseBlend::kBracket;  // kBaked only
  HullColliderOptions hull_options;
  float reach_margin = 0.05f;      // metres added to each garment's reach radius, >= 0
  float reach_stretch = 0.15f;     // fraction the cloth may stretch beyond its rest lengths, >= 0
  bool prune = true;               // drape-sim drops colliders the garments cannot reach
  std::vector<SceneShape> shapes;  // the engine's own colliders: floors, props

  // Solver. settings.root_joint/root_bind_position are filled at resolution (relative).
  // Engine defaults (long-range tethers, a 10 % strain limit) with paper B's Verlet.
  ClothSolverSettings solver = [] {
    ClothSolverSettings s;
    s.substeps = 4;
    s.iterations = 5;
    s.damping = 0.2f;
    return s;
  }();
  bool auto_substeps = false;  // explicit Euler: RecommendedEulerSubsteps per garment
  bool relative = false;       // relative simulation against the skeleton's root joint
  float dt = 1.f / 60.f;       // seconds per frame, (0, 1]
  ResponseParams response{0.3f, 0.f, 1e-3f, 0.5f};  // Coulomb: kinetic 0.3, static 0.5

  SceneOutput output;

  // Frames simulated after the settle (a caller may override it, e.g. drape-sim --frames);
  // computed by the parser as ceil(duration / dt) once the duration is known (ResolveSceneClip
  // fills it for a clip's default duration). 0 until then.
  uint32_t frame_count = 0;
};

// Rotates every joint's local rotation by a fixed random rotation (a uniform random axis, an
// angle uniform in [-max_degrees, max_degrees]), the same for a seed on every machine
// (splitmix64, no library distributions).
void PerturbJointRotations(std::span<Transform> local, float max_degrees, uint32_t seed);

// The skeleton pose a scene plays at a scene time: its clip (or static pose), blended with
// animation.blend_clip, perturbed by animation.perturb_degrees. drape-sim, the reach analysis and
// the camera all pose the body through it.
class ScenePoser {
 public:
  // `scene` and `asset` must outlive the poser; `clip` as ResolveSceneClip gave it. Allocates.
  // Error: "<scene>: /animation/blend_clip: no clip named 'x' (clips: ...)".
  Status Init(const Scene& scene, const CharacterAsset& asset, int32_t clip);
  // The pose at scene time `time` into *pose (initialised on the asset's skeleton). No
  // allocation.
  Status Pose(float time, SkeletonPose* pose);

 private:
  const Scene* scene_ = nullptr;
  const CharacterAsset* asset_ = nullptr;
  int32_t clip_ = -1, blend_clip_ = -1;
  SkeletonPose blend_pose_;
  std::vector<Transform> local_;  // scratch for the perturbation
};

// Reads and parses a scene file. Relative paths in it resolve against its directory.
Status LoadScene(const std::string& path, Scene* scene);
// The same from the file's bytes (relative paths resolve against `directory`); nothing throws.
Status ParseSceneText(std::string_view text, const std::string& source,
                      const std::string& directory, Scene* scene);
// Parses a scene already read; `source` names it in messages, `directory` resolves paths.
Status ParseScene(const nlohmann::json& json, const std::string& source,
                  const std::string& directory, Scene* scene);

// The scenes reference (docs/SCENES.md) as markdown: the conventions, the sample scenes and one
// table per JSON object of a scene, generated from the schema ParseScene reads with.
std::string SceneReferenceMarkdown();

// The bake configuration a scene needs: the scene's /bake overrides, then the collider kinds from
// its collision methods (maps, hulls, spheres each on or off) and, when maps are used with a
// clip, maps.clip = that clip. Fails with the JSON path of a bad override.
Status ApplySceneToBakeConfig(const Scene& scene, BakeConfig* config);

// Finds the scene's clip in the asset (-1 for a static pose) and fills scene->frame_count when the
// duration defaults to the clip's. Error: "<scene>: /animation/clip: no clip named 'x' (clips:
// ..)".
Status ResolveSceneClip(const CharacterAsset& asset, Scene* scene, int32_t* clip);

// Ring names a garment type offers for attach/pin selections ("held" is every generator's
// suggested set). Sheet: top (the +axis_v edge, held), bottom, left (-axis_u), right. Skirt:
// waist (held), hem. Cape: top (held), bottom, left (-x), right. Sleeve: start (held), end. OBJ:
// none.
std::vector<std::string> GarmentRingNames(GarmentType type);

// A garment resolved against a skeleton: the cloth description (rest shape in the garment's
// frame, attachments with joint indices and bind-frame positions, pins, material) and, per
// particle, the joint whose pose carries it initially (the joint of its nearest held particle
// along the mesh; -1 for none, e.g. pinned-only or free garments).
struct ResolvedGarment {
  ClothDescription description;
  std::vector<int32_t> carrier_joint;
  // Per joint of the skeleton: garment frame -> bind-pose asset frame (identity for kBind; the
  // inverse rest skinning matrix for kRest). A particle p carried by joint j sits at
  // S[j] * frame_to_bind[j] * p at a pose with skinning matrices S.
  std::vector<Mat34> frame_to_bind;
  std::vector<Float3> colors;  // an OBJ or glTF garment's vertex colours (empty: none)
  // A glTF garment with a skin: its weights by the skeleton's joints and bind positions (the
  // skin stage takes them instead of the body's), empty otherwise; and for any glTF garment the
  // distances painted in its _MAX_DISTANCE / _BACKSTOP attributes in metres (+inf: unlimited),
  // empty when the file has none.
  std::vector<ClothSkinWeights> file_skin;
  std::vector<Float3> file_bind_positions;
  std::vector<float> painted_max_distance, painted_backstop;
};

// Builds garment `index` of the scene against the skeleton: generator or OBJ mesh, anchoring,
// selections (errors name the JSON path: unknown ring, vertex index out of range, empty box,
// unknown joint, a particle both attached and pinned ...). Allocates.
Status ResolveGarment(const Scene& scene, size_t index, const SkeletonData& skeleton,
                      ResolvedGarment* out);

// The skin of a resolved garment (/garments/i/skin; nothing for an unskinned one): skin weights
// from the closest point of `body` (the asset's mesh, posed at the rest pose for a garment
// authored there), smoothed over the garment's mesh, bind positions, and max distance (painted
// from an OBJ's vertex colours if asked) and backstop for the particles no joint or pin holds.
// Errors name the JSON path (no body mesh, no vertex colours to paint with). Allocates.
Status SkinGarment(const Scene& scene, size_t index, const SkeletonData& skeleton,
                   const MeshData& body, ResolvedGarment* garment);

// Positions of the garment at a pose: every particle moved rigidly by its carrier joint's
// skinning matrix from the garment frame (S[j] * frame_to_bind[j] * p); particles without one
// keep their rest positions. `positions` gets the particle count.
void PlaceGarment(const ResolvedGarment& garment, std::span<const Mat34> skinning,
                  std::vector<Float3>* positions);

// Per particle: the length (metres) of the shortest path along the rest shape's edges to the
// nearest held (attached or pinned) particle, and that particle's index; +inf and UINT32_MAX
// when no held particle is connected to it. An upper bound of the geodesic distance, so a
// particle of a cloth stretched by at most s lies within (1 + s) * distance of that particle.
void NearestHeldParticles(const ClothDescription& cloth, std::vector<float>* distance,
                          std::vector<uint32_t>* nearest);

// What one collider is to the scene's garments.
struct ColliderReach {
  int32_t joint = -1;
  std::string joint_name;
  bool reachable = true;
  // Metres: min over the sampled poses of (distance from the collider's bound to the nearest
  // held particle) - that garment's reach radius. <= 0: reachable.
  float clearance = -std::numeric_limits<float>::infinity();
};

struct GarmentReach {
  std::string name;
  uint32_t held_particles = 0;
  bool bounded = true;   // false: a part of the garment is held by nothing (it can go anywhere)
  float max_path = 0.f;  // metres, longest shortest path from a particle to a held particle
  float radius = 0.f;    // metres, (1 + reach_stretch) * max_path + reach_margin
};

struct SceneReach {
  int32_t clip = -1;           // -1: a static pose
  uint32_t sampled_poses = 0;  // poses tested (substep boundaries of every frame + settle)
  float clip_time_min = 0.f, clip_time_max = 0.f;  // range of clip times played
  bool whole_clip = true;                          // every part of the clip is played
  std::vector<GarmentReach> garments;
  std::vector<ColliderReach> hulls;    // one per asset.hulls, same order
  std::vector<ColliderReach> spheres;  // one per asset.joint_spheres, same order
  // Indices into asset.body_maps.poses the scene reads (nearest and bracketing poses of every
  // frame end time; the poses of the scene's clip, or the static poses), ascending.
  std::vector<uint32_t> played_map_poses;
};

// Over every pose the scene plays (settle, then each frame at its substep boundaries): the
// region the garments can reach is the union of spheres of radius GarmentReach::radius around
// their posed held particles; a hull is reachable when its posed OBB meets that region in some
// pose, a joint sphere when its posed sphere does. A garment with an unheld part reaches
// everything. Needs scene.frame_count (ResolveSceneClip). Allocates.
Status AnalyzeSceneReach(const Scene& scene, const CharacterAsset& asset, SceneReach* out);

// The analysis as JSON (for reports): garments, per collider {bone, kind, reachable, clearance_m},
// played clip range, played map poses.
nlohmann::json SceneReachToJson(const SceneReach& reach);

// Drops the hulls, joint spheres and body-map poses the scene cannot reach or does not play from
// `asset`, appending one {"bone"/"pose", "kind", "reason"} entry per dropped item to *left_out (a
// JSON array). `reach` must come from AnalyzeSceneReach on this asset. Keeps every map pose when
// none of them is played (and says so).
void PruneUnreachable(const SceneReach& reach, CharacterAsset* asset, nlohmann::json* left_out);

}  // namespace drape::bake

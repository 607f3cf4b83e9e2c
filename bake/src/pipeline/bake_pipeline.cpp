#include "drape/bake/bake_pipeline.h"

#include "preview/collider_preview.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "config/clip_lookup.h"
#include "drape/bake/body_map_baker.h"
#include "drape/bake/bone_map_baker.h"
#include "drape/bake/capsule_fitter.h"
#include "drape/bake/importer.h"
#include "drape/bake/mesh_reference.h"
#include "drape/bake/regions.h"
#include "drape/bake/render_mesh.h"
#include "drape/formats/asset_file.h"
#include "drape/runtime/body_map_collider.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"
#include "fit/collider_fit.h"
#include "fit/fit_report.h"
#include "pipeline/hull_stage.h"
#include "pipeline/map_stage.h"
#include "regions/surface_spheres.h"

namespace drape::bake {
namespace {

using Clock = std::chrono::steady_clock;
using nlohmann::json;

double MillisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Below this fraction of vertices shaping a hull (rigid, or shaping at hulls.shape_threshold)
// the hulls cover little of the body: smoothly weighted rigs, e.g. CesiumMan 13 % at the
// defaults, 5 hulls, 6 % of the speed-vs-error motions missed.
constexpr double kLowHullVertexFraction = 0.5;
// Warn when spheres.cover left_by_hulls would take more than a fifth off the joint spheres'
// radii (CesiumMan: 43 %; the mannequin: 14 %, RobotExpressive 5 %, the others under 3 %).
constexpr double kSphereShrinkWorthWarning = 0.8;

// The report's header: what was baked, by which tool, for which format, with which config.
void StartReport(const std::string& input, const BakeConfig& config, json* report) {
  *report = json::object();
  (*report)["input"] = input;
  (*report)["tool_version"] = DRAPE_VERSION_STRING;
  (*report)["format_version"] = kAssetFormatVersion;
  (*report)["config"] = BakeConfigToJson(config);
}

// The asset starts as the imported character; the report says what was imported.
void StartAsset(const Character& character, CharacterAsset* asset, json* report) {
  *asset = CharacterAsset{};
  asset->info = character.info;
  asset->skeleton = character.skeleton;
  asset->clips = character.clips;
  asset->mesh = character.mesh;

  (*report)["unit_scale"] = character.info.unit_scale;
  (*report)["frame"] = character.frame_provenance;
  (*report)["up_axis"] = character.info.up_axis;
  json matrix = json::array();
  for (int r = 0; r < 4; ++r) {
    matrix.push_back({character.source_to_asset[4 * r], character.source_to_asset[4 * r + 1],
                      character.source_to_asset[4 * r + 2], character.source_to_asset[4 * r + 3]});
  }
  (*report)["source_to_asset"] = matrix;
  (*report)["joint_count"] = asset->skeleton.joint_count();
  json clips = json::array();
  for (const ClipData& clip : asset->clips) {
    clips.push_back(
        {{"name", clip.name}, {"duration_s", clip.duration}, {"frames", clip.frame_count}});
  }
  (*report)["clips"] = clips;
  (*report)["mesh"] = {{"vertices", asset->mesh.vertex_count()},
                       {"triangles", asset->mesh.triangle_count()}};
}

// Hulls kept without Kirkpatrick hierarchies (their shadow boundary is not one simple cycle on
// any OBB axis): the default plane test covers them; the Kirkpatrick inside test refuses the asset.
void WarnAboutHullsWithoutKirkpatrick(const json& hulls, std::vector<std::string>* warnings) {
  std::string bones;
  size_t count = 0;
  for (const json& c : hulls["colliders"]) {
    if (!c["kirkpatrick"].contains("not_built")) continue;
    bones += (count++ == 0 ? "'" : ", '") + c["bone"].get<std::string>() + "'";
  }
  if (count == 0) return;
  warnings->push_back(std::to_string(count) + (count == 1 ? " hull has" : " hulls have") +
                      " no Kirkpatrick hierarchy (" + bones +
                      "; the report says why): the plane inside test covers them, and "
                      "HullColliderOptions::inside_test kKirkpatrick refuses this asset");
}

// A warning when the hulls shape less than kLowHullVertexFraction of the vertices, with advice.
void WarnIfHullsCoverLittle(const BakeConfig& config, double fraction, size_t hull_count,
                            std::vector<std::string>* warnings) {
  if (fraction >= kLowHullVertexFraction) return;
  const auto value = [](float v) { return std::to_string(v).substr(0, 4); };
  std::string advice =
      config.shape_threshold > 0.f
          ? "; hulls.shape_threshold 0 (the default; " + value(config.shape_threshold) +
                " here) lets every triangle shape the hull of the bone that carries most of it "
                "(docs/ALGORITHMS.md §2.1)"
          : "; most vertices are blended with no bone above half their weight, which no "
            "hull can follow: use the body maps for this character";
  warnings->push_back("only " + std::to_string(static_cast<int>(std::lround(fraction * 100.0))) +
                      " % of the vertices shape a hull at hulls.rigid_threshold " +
                      value(config.rigid_threshold) + " and hulls.shape_threshold " +
                      value(config.shape_threshold) + " (" + std::to_string(hull_count) +
                      " hulls): the skin weights are smooth and the joint spheres carry most of "
                      "the body" +
                      advice);
}

// Smoothly weighted rigs get spheres of a limb's size: a warning when spheres.cover
// left_by_hulls would shrink the paper's spheres by more than kSphereShrinkWorthWarning.
void AdviseSphereCover(const BakeConfig& config, const Regions& regions, const Character& character,
                       const CharacterAsset& asset, std::vector<std::string>* warnings) {
  const auto radius_sum = [](const std::vector<JointSphereData>& spheres) {
    double sum = 0.0;
    for (const JointSphereData& s : spheres) sum += s.radius;
    return sum;
  };
  const double paper_b = radius_sum(asset.joint_spheres);
  const double shrunk = radius_sum(
      BuildJointSpheres(regions, config.sphere_delta, asset.hulls, character.mesh.triangles));
  if (shrunk < kSphereShrinkWorthWarning * paper_b) {
    const auto metres = [](double m) {
      char text[32];
      std::snprintf(text, sizeof(text), "%.2f m", m);
      return std::string(text);
    };
    warnings->push_back(
        "the joint spheres reach every flexible vertex (paper B); their radii sum to " +
        metres(paper_b) + ", and spheres.cover left_by_hulls would shrink that to " +
        metres(shrunk) +
        " (CesiumMan: 66 -> 47 % false contacts, normals 43 -> 25 deg; docs/ALGORITHMS.md §9)");
  }
}

// The joint spheres (paper B's, or only what the hulls leave uncovered), and the report's list.
void BakeSpheres(const BakeConfig& config, const Regions& regions, Character& character,
                 CharacterAsset* asset, json* report) {
  const bool left_by_hulls = config.sphere_cover == SphereCover::kLeftByHulls;
  if (left_by_hulls && asset->hulls.empty()) {
    character.warnings.push_back(
        "spheres.cover is left_by_hulls but no hull was baked: the joint spheres cover every "
        "flexible vertex (paper B)");
  }
  json left_out = json::array();
  if (config.sphere_cover == SphereCover::kSurface) {
    const MeshReference body(regions.rest_positions, character.mesh.triangles);
    std::vector<SphereLeftOut> dropped;
    asset->joint_spheres = BuildSurfaceJointSpheres(regions, body, config.sphere_delta,
                                                    config.sphere_min_radius, &dropped);
    for (const SphereLeftOut& d : dropped) {
      left_out.push_back(
          {{"joint", asset->skeleton.joint_names[d.joint]},
           {"parent", d.parent_joint >= 0 ? asset->skeleton.joint_names[d.parent_joint] : ""},
           {"reason", d.reason}});
    }
  } else {
    asset->joint_spheres = left_by_hulls ? BuildJointSpheres(regions, config.sphere_delta,
                                                             asset->hulls, character.mesh.triangles)
                                         : BuildJointSpheres(regions, config.sphere_delta);
  }
  if (config.sphere_cover == SphereCover::kFlexible && !asset->hulls.empty()) {
    AdviseSphereCover(config, regions, character, *asset, &character.warnings);
  }
  json spheres = json::array();
  for (const JointSphereData& s : asset->joint_spheres) {
    spheres.push_back(
        {{"joint", asset->skeleton.joint_names[s.joint]},
         {"parent", s.parent_joint >= 0 ? asset->skeleton.joint_names[s.parent_joint] : ""},
         {"radius_mm", s.radius * 1000.f}});
  }
  (*report)["joint_spheres"] = spheres;
  (*report)["joint_spheres_left_out"] = left_out;
}

// The proxies' fit to the rest-pose body (fit/collider_fit.h): each collider's bloat on its
// report entry (report["hulls"]["colliders"] and report["joint_spheres"] list the colliders in
// the asset's order), the whole in report["fit"], and the warnings of fit/fit_report.h.
ColliderFit ReportFit(const BakeConfig& config, const Regions& regions, const CharacterAsset& asset,
                      json* report, std::vector<std::string>* warnings) {
  ColliderFitOptions options;
  options.hull_delta = config.hull.delta;
  options.sphere_delta = config.sphere_delta;
  const ColliderFit fit =
      MeasureColliderFit(regions.rest_positions, asset.mesh.triangles, asset.hulls,
                         asset.joint_spheres, {}, regions.rest_skinning, options);
  std::vector<std::string> hull_names, sphere_names;
  for (const HullColliderData& h : asset.hulls)
    hull_names.push_back(asset.skeleton.joint_names[h.joint]);
  for (const JointSphereData& s : asset.joint_spheres)
    sphere_names.push_back(asset.skeleton.joint_names[s.joint]);
  if (report->contains("hulls")) {
    json& entries = (*report)["hulls"]["colliders"];
    for (size_t h = 0; h < fit.hulls.size() && h < entries.size(); ++h)
      AddBloatToReport(fit.hulls[h], &entries[h]);
  }
  if (report->contains("joint_spheres")) {
    json& entries = (*report)["joint_spheres"];
    for (size_t s = 0; s < fit.spheres.size() && s < entries.size(); ++s)
      AddBloatToReport(fit.spheres[s], &entries[s]);
  }
  (*report)["fit"] = FitToJson(fit, options, config.max_bloat);
  for (std::string& w : FitWarnings(fit, options, hull_names, sphere_names, config.max_bloat))
    warnings->push_back(std::move(w));
  return fit;
}

// The tapered capsules, and the report's list with each one's fit and the fit of the capsules
// as a proxy set of their own (report["capsules"], report["fit_capsules"]).
void BakeCapsules(const BakeConfig& config, const Regions& regions, const MeshData& mesh,
                  CharacterAsset* asset, json* report) {
  asset->capsules = FitCapsules(regions, mesh, asset->skeleton.parents, config.capsules);
  ColliderFitOptions options;
  const ColliderFit fit = MeasureColliderFit(regions.rest_positions, mesh.triangles, {}, {},
                                             asset->capsules, regions.rest_skinning, options);
  json capsules = json::array();
  for (size_t c = 0; c < asset->capsules.size(); ++c) {
    const CapsuleColliderData& k = asset->capsules[c];
    const Float3 a = TransformPoint(regions.rest_skinning[k.joint], k.from);
    const Float3 b = TransformPoint(regions.rest_skinning[k.joint], k.to);
    json entry = {{"joint", asset->skeleton.joint_names[k.joint]},
                  {"length_mm", 1000.f * Length(b - a)},
                  {"radius_from_mm", 1000.f * k.radius_from},
                  {"radius_to_mm", 1000.f * k.radius_to}};
    if (c < fit.capsules.size()) AddBloatToReport(fit.capsules[c], &entry);
    capsules.push_back(entry);
  }
  (*report)["capsules"] = capsules;
  (*report)["fit_capsules"] = FitToJson(fit, options, config.max_bloat);
}

// The preview's colours: each collider's bloat max, red at hulls.max_bloat.
PreviewBloat PreviewBloatOf(const ColliderFit& fit, float max_bloat) {
  PreviewBloat bloat;
  for (const ColliderBloat& b : fit.hulls) bloat.hull_mm.push_back(b.max_mm);
  for (const ColliderBloat& b : fit.spheres) bloat.sphere_mm.push_back(b.max_mm);
  bloat.red_mm = 1000.0 * max_bloat;
  return bloat;
}

// What the scene's garment can reach; the rest is left out of the asset and the report says so.
Status ApplySceneReach(const Scene& scene, CharacterAsset* asset, json* report) {
  SceneReach reach;
  if (Status s = AnalyzeSceneReach(scene, *asset, &reach); !s.ok()) return s;
  json left_out = json::array();
  PruneUnreachable(reach, asset, &left_out);
  (*report)["scene"] = SceneReachToJson(reach);
  (*report)["scene"]["source"] = scene.source;
  (*report)["scene"]["left_out"] = left_out;
  return Status::Ok();
}

// The file validator, then the runtime's own builders: a bake the runtime would refuse fails
// here.
Status CheckRuntimeAccepts(const std::string& input, const CharacterAsset& asset) {
  if (Status s = ValidateAsset(asset); !s.ok()) {
    return Status(s.code(), input + ": the baked asset does not validate: " + s.message());
  }
  HullColliderSet hulls;
  if (Status s = hulls.Build(asset.hulls, asset.joint_spheres, asset.skeleton.joint_count());
      !s.ok()) {
    return Status(s.code(), input + ": the runtime refuses the baked colliders: " + s.message());
  }
  for (const BodyMapPose& pose : asset.body_maps.poses) {
    BodyMapCollider maps;
    if (Status s = maps.Build(pose); !s.ok()) {
      return Status(s.code(), input + ": the runtime refuses the baked body maps: " + s.message());
    }
  }
  return Status::Ok();
}

// The render mesh (render_mesh.h) into asset->render_mesh, and what it kept into
// report["render_mesh"].
Status BakeRenderMesh(const BakeConfig& config, const Character& character, CharacterAsset* asset,
                      json* report) {
  RenderMeshReport kept;
  if (Status s = SimplifyRenderMesh(character.mesh, config.maps_render_tolerance,
                                    &asset->render_mesh, &kept);
      !s.ok())
    return s;
  (*report)["render_mesh"] = {{"kept", kept.kept},
                              {"triangles", kept.kept_triangles},
                              {"vertices", kept.kept_vertices},
                              {"of_triangles", kept.triangles},
                              {"error_mm", 1000.0 * kept.error},
                              {"normal_turn_deg", kept.normal_turn_degrees},
                              {"turned_vertices", kept.turned_vertices},
                              {"tolerance_mm", 1000.0 * config.maps_render_tolerance},
                              {"attempts", kept.attempts}};
  return Status::Ok();
}

// Per-bone local maps, and per bone what the report lists: its part, axis choice, size.
Status BakeBoneMapStage(const BakeConfig& config, const Regions& regions,
                        const Character& character, CharacterAsset* asset, json* report) {
  std::vector<BoneMapStats> stats;
  BoneMapOptions options = config.bone_maps;
  if (options.texel_size == 0.f) options.texel_size = AutomaticBoneMapTexel(regions.rest_positions);
  if (Status s = BakeBoneMaps(character.mesh, character.skeleton, regions.rest_skinning, options,
                              &asset->bone_maps, &stats);
      !s.ok()) {
    return s;
  }
  json bones = json::array();
  size_t bytes = 0;
  for (const BoneMapStats& b : stats) {
    bones.push_back({{"bone", character.skeleton.joint_names[b.joint]},
                     {"triangles", b.triangles},
                     {"facing", b.facing},
                     {"width", b.width},
                     {"height", b.height},
                     {"bytes", b.bytes}});
    bytes += b.bytes;
  }
  *report = {{"count", stats.size()},
             {"bytes", bytes},
             {"texel_size_mm", options.texel_size * 1000.f},
             {"bones", bones}};
  return Status::Ok();
}

}  // namespace

Status BakeCharacter(const std::string& input, const BakeConfig& config, BakeResult* result,
                     const std::string& preview_dir, const Scene* scene) {
  json& report = result->report;
  StartReport(input, config, &report);
  json timings = json::object();
  // A stage's error, prefixed with the input's name.
  const auto failed = [&](const Status& s) { return Status(s.code(), input + ": " + s.message()); };

  auto start = Clock::now();
  Character character;
  if (Status s = ImportCharacter(input, config.import, &character); !s.ok()) return s;
  timings["import_ms"] = MillisecondsSince(start);
  result->input_files = character.source_files;
  if (scene != nullptr) {  // the scene's reach analysis reads its garment meshes
    for (const SceneGarment& g : scene->garments)
      if (g.type == GarmentType::kObj) result->input_files.push_back(g.obj_file);
  }
  std::vector<detail::MapPoseRequest> map_requests;
  if (config.maps_enabled) {
    if (Status s = detail::MapPoseRequests(input, config, character, &map_requests); !s.ok())
      return s;
  }
  CharacterAsset& asset = result->asset;
  StartAsset(character, &asset, &report);

  start = Clock::now();
  Regions regions;
  if (Status s = SplitRegions(character, config.rigid_threshold, &regions, config.shape_threshold);
      !s.ok()) {
    return failed(s);
  }
  timings["regions_ms"] = MillisecondsSince(start);

  if (config.maps_enabled) {
    start = Clock::now();
    json maps = {{"renderer", detail::RendererName(config.maps.renderer)},
                 {"poses", json::array()}};
    if (Status s = detail::BakeMapStage(config, map_requests, regions, character, preview_dir,
                                        &asset, &maps);
        !s.ok())
      return failed(s);
    report["body_maps"] = maps;
    timings["maps_ms"] = MillisecondsSince(start);
    if (config.maps_render_tolerance > 0.f) {
      start = Clock::now();
      if (Status s = BakeRenderMesh(config, character, &asset, &report["body_maps"]); !s.ok())
        return failed(s);
      timings["render_mesh_ms"] = MillisecondsSince(start);
    }
  }
  if (config.bone_maps_enabled) {
    start = Clock::now();
    json bone_maps;
    if (Status s = BakeBoneMapStage(config, regions, character, &asset, &bone_maps); !s.ok())
      return failed(s);
    report["bone_maps"] = bone_maps;
    timings["bone_maps_ms"] = MillisecondsSince(start);
  }
  if (config.hulls_enabled) {
    start = Clock::now();
    json hulls = json::object();
    if (Status s = detail::BakeHullStage(config, regions, character, &asset, &hulls); !s.ok())
      return failed(s);
    report["hulls"] = hulls;
    timings["hulls_ms"] = MillisecondsSince(start);
    WarnIfHullsCoverLittle(config, hulls["hull_vertex_fraction"].get<double>(), asset.hulls.size(),
                           &character.warnings);
    WarnAboutHullsWithoutKirkpatrick(hulls, &character.warnings);
  }
  if (config.spheres_enabled) {
    start = Clock::now();
    BakeSpheres(config, regions, character, &asset, &report);
    timings["spheres_ms"] = MillisecondsSince(start);
  }
  if (config.capsules_enabled) {
    start = Clock::now();
    BakeCapsules(config, regions, character.mesh, &asset, &report);
    timings["capsules_ms"] = MillisecondsSince(start);
  }
  if (config.hulls_enabled || config.spheres_enabled) {
    start = Clock::now();
    const ColliderFit fit = ReportFit(config, regions, asset, &report, &character.warnings);
    timings["fit_ms"] = MillisecondsSince(start);
    if (!preview_dir.empty()) {
      const PreviewBloat bloat = PreviewBloatOf(fit, config.max_bloat);
      if (Status s = WriteColliderPreview(asset, regions.rest_positions, regions.rest_skinning,
                                          preview_dir, 800, &bloat);
          !s.ok()) {
        return failed(s);
      }
    }
  }
  if (scene != nullptr) {
    start = Clock::now();
    if (Status s = ApplySceneReach(*scene, &asset, &report); !s.ok()) return s;
    timings["reach_ms"] = MillisecondsSince(start);
  }
  if (config.maps_enabled) {
    start = Clock::now();
    if (Status s = detail::FitMapsToBudget(config, map_requests, regions, character, preview_dir,
                                           &asset, &report);
        !s.ok())
      return failed(s);
    timings["budget_ms"] = MillisecondsSince(start);
  }
  report["warnings"] = character.warnings;

  start = Clock::now();
  if (Status s = CheckRuntimeAccepts(input, asset); !s.ok()) return s;
  timings["validate_ms"] = MillisecondsSince(start);
  report["timings"] = timings;
  return Status::Ok();
}

}  // namespace drape::bake

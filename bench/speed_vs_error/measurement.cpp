#include "measurement.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "checks.h"
#include "drape/bake/bake_pipeline.h"
#include "drape/bake/body_map_baker.h"
#include "drape/bake/scene.h"
#include "drape/formats/asset_file.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"
#include "map_dump.h"
#include "sweep.h"

namespace drape::bench {
namespace {

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// Bytes of the baked hulls and spheres in the file (encoded asset with them minus without).
size_t HullBakedBytes(const CharacterAsset& asset) {
  std::vector<uint8_t> with, without;
  CharacterAsset bare = asset;
  bare.hulls.clear();
  bare.joint_spheres.clear();
  if (!EncodeAsset(asset, &with).ok() || !EncodeAsset(bare, &without).ok()) return 0;
  return with.size() - without.size();
}

// The hull settings the posed run measures: the defaults, the thresholds, and the spheres left
// by hulls (a bent joint is what a joint sphere is for).
bool MeasuredPosed(const std::string& label) {
  for (const char* prefix : {"default", "shape threshold", "paper B's rigid-only",
                             "rigid threshold", "spheres left by hulls"}) {
    if (label.rfind(prefix, 0) == 0) return true;
  }
  return false;
}

std::string PerBoneTable(const nlohmann::json& report) {
  std::ostringstream md;
  md << "Default bake: per bone, the collider's triangles, its growth beyond the inflated hull "
        "and its bloat (how far its surface reaches outside the body beyond delta: the 99th "
        "percentile and the maximum over samples on it), from the bake report.\n\n| bone | "
        "triangles | planes | growth mm | bloat p99 mm | bloat max mm | bytes |\n"
        "|---|---:|---:|---:|---:|---:|---:|\n";
  if (!report.contains("hulls") || !report["hulls"].contains("colliders")) return "";

  for (const auto& c : report["hulls"]["colliders"]) {
    char line[256];
    std::snprintf(line, sizeof(line), "| %s | %d | %d | %.1f | %.1f | %.1f | %d |\n",
                  c.value("bone", std::string("?")).c_str(), c.value("triangles_after", 0),
                  c.value("planes_after", 0), c.value("growth_mm", 0.0),
                  c.value("bloat_p99_mm", 0.0), c.value("bloat_max_mm", 0.0), c.value("bytes", 0));
    md << line;
  }
  return md.str();
}

}  // namespace

void Measurement::RunCharacter(const CharacterSpec& spec) {
  const auto start = std::chrono::steady_clock::now();
  bake::Character character;
  std::string note;
  const bake::ImportOptions import = ImportFor(spec, &character, &note);
  bake::Regions regions;
  const Status s = bake::SplitRegions(character, 0.99f, &regions);
  if (!s.ok()) Fail(spec.path + ": " + s.message());
  const std::vector<Float3>& positions = regions.rest_positions;
  if (spec.human) {  // the rescale above took: the targets' millimetres are a person's
    const float height = HeightOf(positions);
    if (height > kTallestHuman) {
      char what[128];
      std::snprintf(what, sizeof(what), "the measured rest pose is %.2f m tall, over %.2f m",
                    height, kTallestHuman);
      set_violations_.push_back(spec.label + ": " + what + " for a human");
    }
  }
  const std::vector<uint32_t>& triangles = character.mesh.triangles;
  std::printf("%s: %zu triangles%s%s\n", spec.label.c_str(), triangles.size() / 3,
              note.empty() ? "" : ", ", note.c_str());
  if (!note.empty()) notes_.push_back(spec.label + ": " + note);

  const bake::MeshReference reference(positions, triangles);
  Context context = MakeContext(spec, positions, triangles, reference);

  if (options_.dump_maps) DumpMotions(options_.out_dir, spec, context.sets.back());

  // The maps' view axis a default bake picks, for this character's rest and posed runs.
  bake::ViewAxisChoice choice;
  if (!bake::ChooseBodyMapViewAxis(positions, triangles, BodyMapOptionsFor(MapSetting{}, {}),
                                   &choice)
           .ok()) {
    Fail(spec.label + ": cannot choose the maps' view axis");
  }
  view_axis_ = choice.axis;
  std::printf("%s: maps seen along %s (inside %.2f / %.2f / %.2f litres along x / y / z)\n",
              spec.label.c_str(), BodyMapViewAxisName(view_axis_), choice.inside_volume[1] * 1e3,
              choice.inside_volume[2] * 1e3, choice.inside_volume[0] * 1e3);
  std::unique_ptr<Method> default_maps = MeasureRestMaps(context, positions, triangles);
  const HullAssets for_posed =
      MeasureRestHulls(context, import, regions.rest_skinning, std::move(default_maps));

  // Peers, on a subset: the exact query costs microseconds per particle.
  MeasurePeer(context, *MakeExactMeshPeer(reference));
  MeasurePeer(context, *MakeFclPeer(positions, triangles));
  std::printf("%s: done in %.1f s\n", spec.label.c_str(), Seconds(start));

  if (spec.label == "mannequin" && !options_.quick) ResolutionIndependence(spec, context);
  if (spec.label == "mannequin") ClothSolvers(spec, import);
  if (!options_.quick || options_.posed) RunPosed(spec, character, for_posed);
}

std::unique_ptr<Method> Measurement::MeasureRestMaps(const Context& context,
                                                     const std::vector<Float3>& positions,
                                                     const std::vector<uint32_t>& triangles) {
  const CharacterSpec& spec = context.spec;
  std::unique_ptr<Method> default_maps;
  std::vector<MapSetting> sweep = MapSweep(options_.quick);
  if (view_axis_ != BodyMapViewAxis::kZ) {  // the default setting along paper A's axis
    MapSetting z;
    z.resolution = options_.quick ? 512u : 1024u;
    z.z_view = true;
    sweep.push_back(z);
  }
  for (const MapSetting& m : sweep) {
    const bake::BodyMapOptions o = BodyMapOptionsFor(m, view_axis_);
    BodyMapPose pose;
    bake::BodyMapPoseStats stats;
    const Status baked = bake::BakeBodyMapPose(positions, triangles, o, &pose, &stats);
    if (!baked.ok()) Fail(spec.label + " maps " + Describe(m) + ": " + baked.message());
    if (options_.dump_maps) DumpMapPose(options_.out_dir, spec, m, pose);
    Measure(context, *MakeBodyMapMethod(pose, m.sampling, Describe(m), stats.bytes, m.lanes));
    const bool combo = m.sampling == DepthSampling::kBilinear && !m.fitted && m.epsilon == 0.005f &&
                       m.depth == DepthEncoding::kUnorm16 && m.normals == NormalEncoding::kOct16 &&
                       m.resolution == (options_.quick ? 512u : 1024u) && !m.z_view;
    if (combo) default_maps = MakeBodyMapMethod(pose, m.sampling, Describe(m), stats.bytes);
  }
  return default_maps;
}

// The bake does not depend on the pose: the settings the posed run measures keep their asset.
Measurement::HullAssets Measurement::MeasureRestHulls(const Context& context,
                                                      const bake::ImportOptions& import,
                                                      const std::vector<Mat34>& rest_skinning,
                                                      std::unique_ptr<Method> default_maps) {
  const CharacterSpec& spec = context.spec;
  std::string per_bone;
  HullAssets for_posed;
  for (const HullBake& hb : HullBakes(import, options_.quick)) {
    bake::BakeResult result;
    const Status baked = bake::BakeCharacter(spec.path, hb.config, &result);
    if (!baked.ok()) Fail(spec.label + " hulls " + hb.label + ": " + baked.message());
    const CharacterAsset& a = result.asset;
    if (MeasuredPosed(hb.label)) for_posed.emplace_back(hb.label, a);
    const uint32_t joints = a.skeleton.joint_count();
    const size_t bytes = HullBakedBytes(a);
    const bool is_default = hb.label.rfind("default", 0) == 0;
    const std::string tris = " (" + std::to_string(a.hulls.size()) + " hulls, " +
                             std::to_string(a.joint_spheres.size()) + " spheres)";
    HullColliderOptions runtime;
    Measure(context, *MakeHullMethod(a.hulls, a.joint_spheres, joints, rest_skinning, runtime,
                                     "hulls+spheres", hb.label + tris, bytes));
    if (hb.label.rfind("table", 0) == 0) {
      runtime.response = HullResponse::kMapTableRay;
      Measure(context, *MakeHullMethod(a.hulls, a.joint_spheres, joints, rest_skinning, runtime,
                                       "hulls+spheres", hb.label + ", map-table ray", bytes));
    }
    if (!is_default) continue;
    per_bone = PerBoneTable(result.report);
    if (const nlohmann::json& fit = result.report["fit"]; fit.is_object()) {
      const Fit f{spec.label, fit.value("bloat_p99_mm", 0.0), fit.value("bloat_max_mm", 0.0),
                  fit.value("coverage", 0.0), a.hulls.size()};
      char line[256];
      std::snprintf(
          line, sizeof(line),
          "Every collider together: bloat p99 %.1f mm, max %.1f mm; coverage %.2f %%.\n\n",
          f.bloat_p99_mm, f.bloat_max_mm, 100.0 * f.coverage);
      per_bone = line + per_bone;
      fits_.push_back(f);
    }
    MeasureDefaultHullVariants(context, a, rest_skinning, bytes, hb.label, std::move(default_maps));
  }
  if (!per_bone.empty()) sections_.push_back({spec.label + ": hulls per bone", per_bone});
  return for_posed;
}

// The default bake with the runtime's inside tests and responses, discrete, hulls alone, joint
// spheres alone, and behind the default maps (what a scene with both methods does).
void Measurement::MeasureDefaultHullVariants(const Context& context, const CharacterAsset& a,
                                             const std::vector<Mat34>& rest_skinning, size_t bytes,
                                             const std::string& label,
                                             std::unique_ptr<Method> default_maps) {
  const uint32_t joints = a.skeleton.joint_count();
  const HullColliderOptions runtime;
  struct Variant {
    const char* label;
    InsideTest inside;
    HullResponse response;
    bool continuous;
  };
  const Variant variants[] = {
      {", Kirkpatrick", InsideTest::kKirkpatrick, HullResponse::kPushOut, true},
      {", map-table ray", InsideTest::kPlanes, HullResponse::kMapTableRay, true},
      {", Kirkpatrick + map-table ray (paper B)", InsideTest::kKirkpatrick,
       HullResponse::kMapTableRay, true},
      {", discrete (end position only)", InsideTest::kPlanes, HullResponse::kPushOut, false},
  };
  // A hull the bake kept without Kirkpatrick hierarchies rules the Kirkpatrick test out.
  const bool hierarchies =
      std::all_of(a.hulls.begin(), a.hulls.end(),
                  [](const HullColliderData& h) { return !h.upper.node_triangles.empty(); });
  for (const Variant& v : variants) {
    if ((options_.quick || !hierarchies) && v.inside == InsideTest::kKirkpatrick) continue;
    HullColliderOptions o;
    o.inside_test = v.inside;
    o.response = v.response;
    o.continuous = v.continuous;
    Measure(context, *MakeHullMethod(a.hulls, a.joint_spheres, joints, rest_skinning, o,
                                     "hulls+spheres", label + v.label, bytes));
  }
  Measure(context, *MakeHullMethod(a.hulls, {}, joints, rest_skinning, runtime, "hulls",
                                   "default hulls alone", bytes));
  Measure(context, *MakeHullMethod({}, a.joint_spheres, joints, rest_skinning, runtime, "spheres",
                                   "joint spheres alone", bytes));
  Measure(context,
          *MakeCapsuleMethod(a.capsules, rest_skinning,
                             "default (" + std::to_string(a.capsules.size()) + " capsules)"));
  if (default_maps) {
    const std::string combined = default_maps->setting + " + default hulls";
    Measure(context,
            *MakeCombinedMethod(std::move(default_maps),
                                MakeHullMethod(a.hulls, a.joint_spheres, joints, rest_skinning,
                                               runtime, "hulls+spheres", "default", bytes),
                                combined));
  }
}

// The same character in two poses of its longest clip, 40 % and 80 % into it (limbs bent, unlike
// the rest pose): maps baked for that pose, hulls and spheres posed by its skinning matrices (what
// the runtime does every frame), against the posed exact mesh. A shorter sweep: the defaults and
// the settings the rest pose singles out.
void Measurement::RunPosed(const CharacterSpec& spec, const bake::Character& character,
                           const HullAssets& hull_assets) {
  if (character.clips.empty()) return;
  const ClipData& clip = *std::max_element(
      character.clips.begin(), character.clips.end(),
      [](const ClipData& a, const ClipData& b) { return a.duration < b.duration; });
  for (const float fraction : {0.4f, 0.8f})
    RunPosedAt(spec, character, hull_assets, clip, fraction);
  // A pose no clip holds: the clip at 60 % with every joint turned by up to 30 degrees.
  RunPosedAt(spec, character, hull_assets, clip, 0.6f, 30.f);
}

void Measurement::RunPosedAt(const CharacterSpec& spec, const bake::Character& character,
                             const HullAssets& hull_assets, const ClipData& clip, float fraction,
                             float perturb_degrees) {
  const float time = fraction * clip.duration;
  SkeletonPose pose;
  std::vector<Float3> positions(character.mesh.vertex_count());
  if (!pose.Init(character.skeleton).ok() || !pose.SampleClip(clip, time, false).ok()) {
    Fail(spec.label + ": cannot pose its longest clip");
  }
  if (perturb_degrees > 0.f) {
    std::vector<Transform> local(pose.local().begin(), pose.local().end());
    bake::PerturbJointRotations(local, perturb_degrees, 1);
    if (!pose.SetLocalTransforms(local).ok()) Fail(spec.label + ": cannot perturb the pose");
  }
  if (!SkinMesh(character.mesh, pose.skinning(), positions).ok()) {
    Fail(spec.label + ": cannot skin the pose");
  }
  const std::vector<Mat34> skinning(pose.skinning().begin(), pose.skinning().end());
  const std::vector<uint32_t>& triangles = character.mesh.triangles;
  CharacterSpec posed = spec;
  char label[96];
  char turned[48] = "";
  if (perturb_degrees > 0.f) {
    std::snprintf(turned, sizeof(turned), ", joints turned up to %.0f deg",
                  static_cast<double>(perturb_degrees));
  }
  std::snprintf(label, sizeof(label), " posed (%s t=%.2f s%s)",
                clip.name.empty() ? "unnamed clip" : clip.name.c_str(), time, turned);
  posed.label += label;
  std::printf("%s\n", posed.label.c_str());
  const bake::MeshReference reference(positions, triangles);
  Context context = MakeContext(posed, positions, triangles, reference);
  // The quick sweep's nearest settings, and N = 1024 with and without air gaps: posed bodies
  // are where parts overlap along the view axis.
  std::vector<MapSetting> posed_maps = MapSweep(true);
  for (uint8_t layers : {uint8_t{1}, uint8_t{4}}) {
    MapSetting m;
    m.layers = layers;
    posed_maps.push_back(m);  // N = 1024
  }
  for (const MapSetting& m : posed_maps) {
    const MapSetting defaults;
    if (m.sampling != DepthSampling::kNearest || m.fitted || m.epsilon != defaults.epsilon ||
        m.depth != defaults.depth || m.normals != defaults.normals ||
        m.lanes != InstructionSet::kAvx2) {
      continue;
    }
    const bake::BodyMapOptions o = BodyMapOptionsFor(m, view_axis_);
    BodyMapPose map;
    bake::BodyMapPoseStats stats;
    if (!bake::BakeBodyMapPose(positions, triangles, o, &map, &stats).ok()) {
      Fail(posed.label + ": cannot bake maps " + Describe(m));
    }
    Measure(context, *MakeBodyMapMethod(map, m.sampling, Describe(m), stats.bytes));
  }
  MeasureFollowingMaps(context, character, skinning);
  for (const auto& [setting, a] : hull_assets) {
    const std::string counts = " (" + std::to_string(a.hulls.size()) + " hulls, " +
                               std::to_string(a.joint_spheres.size()) + " spheres)";
    Measure(context, *MakeHullMethod(a.hulls, a.joint_spheres, a.skeleton.joint_count(), skinning,
                                     HullColliderOptions{}, "hulls+spheres", setting + counts,
                                     HullBakedBytes(a)));
    if (setting.rfind("default", 0) == 0) {
      Measure(context,
              *MakeCapsuleMethod(a.capsules, skinning,
                                 "default (" + std::to_string(a.capsules.size()) + " capsules)"));
    }
  }
  MeasurePeer(context, *MakeExactMeshPeer(reference));
}

void Measurement::Finish() {
  MarkParetoFronts(&rows_);
  const std::string dir = options_.out_dir;
  if (!WriteCsv(dir + "/speed_vs_error.csv", rows_))
    Fail(dir + "/speed_vs_error.csv: cannot write");
  if (std::ofstream fit(dir + "/fit.csv"); fit) {
    fit << "character,bloat_p99_mm,bloat_max_mm,coverage,hulls\n";
    for (const Fit& f : fits_) {
      fit << f.character << ',' << f.bloat_p99_mm << ',' << f.bloat_max_mm << ',' << f.coverage
          << ',' << f.hulls << '\n';
    }
    if (!fit) Fail(dir + "/fit.csv: cannot write");
  } else {
    Fail(dir + "/fit.csv: cannot write");
  }
  const std::vector<std::string> charts = WriteCharts(dir, rows_);
  std::ostringstream header;
  header << "# Speed against error\n\nWritten by `drape-speed-vs-error` ("
         << (options_.quick ? "quick sweep, " : "") << options_.queries
         << " motions per query set; OpenMP threads 1 and 2). Definitions: "
            "bench/speed_vs_error/evaluation.h.\n";
  for (const std::string& n : notes_) header << "\n- " << n;
  header << "\n";
  if (charts.empty()) header << "\n(gnuplot not installed: no charts)\n";
  for (const std::string& c : charts) {
    if (c.find("speed_vs_error.png") == std::string::npos) {
      header << "\n![" << std::filesystem::path(c).stem().string() << "]("
             << std::filesystem::path(c).filename().string() << ")\n";
    }
  }
  if (!WriteMarkdown(dir + "/speed_vs_error.md", rows_, sections_, header.str())) {
    Fail(dir + "/speed_vs_error.md: cannot write");
  }
  std::printf("wrote %s/speed_vs_error.csv, speed_vs_error.md and %zu charts\n", dir.c_str(),
              charts.size());
}

bool Measurement::Check() const { return CheckAccuracyClaims(rows_, set_violations_); }

Measurement::Context Measurement::MakeContext(const CharacterSpec& spec,
                                              const std::vector<Float3>& positions,
                                              const std::vector<uint32_t>& triangles,
                                              const bake::MeshReference& reference) {
  Context c;
  c.spec = spec;
  c.triangles = triangles.size() / 3;
  c.reference = &reference;
  QuerySetOptions qo;
  qo.count = options_.queries;
  c.sets = MakeQuerySets(positions, triangles, reference, qo);
  // The moving sets' contract, checked against the mesh apart from the generator (the starts
  // are stored in float).
  for (const QuerySet& set : c.sets) {
    if (set.name != "thin_crossing" && set.name != "fast") continue;
    size_t close = 0;
    for (const Float3& p : set.previous) {
      const double q[3] = {p.x, p.y, p.z};
      close += reference.Distance(q) < qo.start_clearance - 1e-6;
    }
    if (close > 0) {
      set_violations_.push_back(spec.label + " " + set.name + ": " + std::to_string(close) +
                                " starts nearer the mesh than the start clearance");
    }
  }
  c.sets.push_back(ConcatenateQuerySets(std::span<const QuerySet>(c.sets)));
  for (const QuerySet& set : c.sets) c.answers.push_back(AnswerQueries(reference, set));
  const QuerySet& all = c.sets.back();
  const size_t stride = std::max<size_t>(1, all.size() / 2000);
  c.peer_subset.name = "all";
  for (size_t i = 0; i < all.size(); i += stride) {
    c.peer_subset.previous.push_back(all.previous[i]);
    c.peer_subset.current.push_back(all.current[i]);
    c.peer_answers.push_back(c.answers.back()[i]);
  }
  for (size_t i = 0; i < c.sets.size(); ++i) {
    size_t expected = 0;
    for (const ReferenceAnswer& a : c.answers[i]) expected += a.contact_expected;
    std::printf("  set %-15s %6zu motions, %6zu expect contact\n", c.sets[i].name.c_str(),
                c.sets[i].size(), expected);
  }
  return c;
}

Row Measurement::MakeRow(const Context& c, const Method& m, const std::string& set,
                         const Metrics& metrics) {
  Row r;
  r.character = c.spec.label;
  r.human = c.spec.human;
  r.triangles = c.triangles;
  r.family = m.family;
  r.setting = m.setting;
  r.query_set = set;
  r.metrics = metrics;
  r.baked_bytes = m.baked_bytes;
  r.runtime_bytes = m.runtime_bytes;
  r.peer = m.peer;
  return r;
}

void Measurement::Measure(const Context& c, const Method& method) {
  EvaluationOptions all_options;
  all_options.repetitions = options_.quick ? 3 : 5;
  const size_t last = c.sets.size() - 1;
  const Metrics all = Evaluate(method, c.sets[last], c.answers[last], *c.reference, all_options);
  rows_.push_back(MakeRow(c, method, "all", all));
  std::printf("  %-14s %-60s %7.1f ns  missed %6.3f %%  p99 %6.2f mm\n", method.family.c_str(),
              method.setting.c_str(), all.ns_one_thread, 100.0 * all.missed_rate,
              all.penetration_p99_mm);
  EvaluationOptions per_set = all_options;
  per_set.two_threads = false;
  per_set.repetitions = 2;
  for (size_t i = 0; i < last; ++i) {
    rows_.push_back(MakeRow(c, method, c.sets[i].name,
                            Evaluate(method, c.sets[i], c.answers[i], *c.reference, per_set)));
  }
}

void Measurement::MeasurePeer(const Context& c, const Method& method) {
  // The peers' time is the fastest of as many runs as ours (Measure): a single run would take
  // the machine's slow spells into the peers' time alone and so into the ratios, in our favour
  // (Animated_Human's exact query spans 14.3-19.1 us over three runs).
  EvaluationOptions o;
  o.repetitions = options_.quick ? 3 : 5;
  const Metrics m = Evaluate(method, c.peer_subset, c.peer_answers, *c.reference, o);
  rows_.push_back(MakeRow(c, method, "all", m));
  std::printf("  %-14s %-60s %7.1f ns  (%zu motions)\n", method.family.c_str(),
              method.setting.c_str(), m.ns_one_thread, c.peer_subset.size());
}

}  // namespace drape::bench

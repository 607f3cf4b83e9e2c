#include "run_scene.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "asset_cache.h"
#include "drape/bake/gltf_export.h"
#include "drape/bake/scene.h"
#include "drape/runtime/math.h"
#include "drape/runtime/task_system.h"
#include "frame_renderer.h"
#include "renderer.h"
#include "run_output.h"
#include "simulation.h"

namespace drape::sim {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

int Fail(const std::string& message) {
  std::fprintf(stderr, "drape-sim: error: %s\n", message.c_str());
  return 1;
}

double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// A directory and its parents. The run creates its output directory first (the bake caches its
// asset there) and its picture folders only once the scene has been checked: a scene refused
// after the bake leaves the cached asset, not empty folders.
Status CreateDirectory(const std::string& path) {
  std::error_code error;
  fs::create_directories(path, error);
  if (error) return Status(StatusCode::kIoError, path + ": cannot create: " + error.message());
  return Status::Ok();
}

void PrintAssetSource(const bake::Scene& scene, const SceneAsset& loaded) {
  if (loaded.baked) {
    std::printf("drape-sim: baked %s -> %s in %.2f s (%s)\n", scene.character.c_str(),
                loaded.path.c_str(), loaded.bake_ms / 1000.0, loaded.reason.c_str());
  } else {
    std::printf("drape-sim: using the %s asset %s\n",
                loaded.reason == "cached" ? "cached" : "scene's", loaded.path.c_str());
  }
}

// ", + 3.1 ms/frame rendering maps" when the scene renders its maps.
std::string RenderNote(const bake::Scene& scene, const RunSummary& summary) {
  if (!scene.use_maps || scene.maps_source != bake::MapSource::kRendered) return "";
  char text[64];
  std::snprintf(text, sizeof(text), " + %.2f ms/frame rendering maps", summary.maps_render_ms_mean);
  return text;
}

// " (held particles: up to 20 inside, 100.5 mm deep, where the scene put them)" when the scene
// holds particles inside a collider (a waistband drawn inside the hips): apart from the
// penetration figure, which is the simulated particles'.
std::string HeldNote(const RunSummary& summary) {
  if (summary.held_inside_particles_max == 0) return "";
  char text[128];
  std::snprintf(text, sizeof(text),
                " (held particles: up to %u inside, %.1f mm deep, where the scene put them)",
                summary.held_inside_particles_max,
                static_cast<double>(summary.held_max_penetration) * 1000.0);
  return text;
}

// Model only what the scene needs: the colliders its garments can reach, the poses it plays.
// With scene.prune the others leave the asset, each listed in *left_out.
Status KeepReachable(const bake::Scene& scene, CharacterAsset* asset, bake::SceneReach* reach,
                     json* left_out) {
  if (Status s = bake::AnalyzeSceneReach(scene, *asset, reach); !s.ok()) return s;
  *left_out = json::array();
  const size_t hulls_before = asset->hulls.size(), spheres_before = asset->joint_spheres.size(),
               poses_before = asset->body_maps.poses.size();
  if (scene.prune) bake::PruneUnreachable(*reach, asset, left_out);
  std::string dropped;
  for (const json& entry : *left_out) {
    if (entry.contains("bone"))
      dropped += (dropped.empty() ? "" : ", ") + entry["kind"].get<std::string>() + " " +
                 entry["bone"].get<std::string>();
  }
  std::printf(
      "drape-sim: reach: kept %zu/%zu hulls, %zu/%zu joint spheres, %zu/%zu map poses%s%s\n",
      asset->hulls.size(), hulls_before, asset->joint_spheres.size(), spheres_before,
      asset->body_maps.poses.size(), poses_before,
      dropped.empty() ? "" : "; out of reach: ", dropped.c_str());
  return Status::Ok();
}

Status WriteReach(const std::string& dir, const bake::Scene& scene, const bake::SceneReach& reach,
                  const json& left_out) {
  json reach_json = bake::SceneReachToJson(reach);
  reach_json["pruned"] = scene.prune;
  reach_json["left_out"] = left_out;
  return WriteText(dir + "/reach.json", reach_json.dump(2) + "\n");
}

// The frames before frame 0 (not output), with the body held at the start pose.
// --export-garments: each garment bound to the skeleton, by its skin or rigidly by the joint
// that carries each particle (the root joint for particles nothing carries).
Status ExportGarments(const bake::Scene& scene, const CharacterAsset& asset,
                      const SceneSimulation& sim, const std::string& dir) {
  std::error_code error;
  fs::create_directories(dir, error);
  if (error) return Status(StatusCode::kIoError, dir + ": cannot create: " + error.message());
  for (size_t g = 0; g < sim.garment_count(); ++g) {
    const bake::ResolvedGarment& resolved = sim.resolved_garment(g);
    const ClothDescription& d = resolved.description;
    bake::GarmentExport out;
    out.name = scene.garments[g].name;
    out.triangles = d.triangles;
    if (!d.skin.empty()) {
      out.bind_positions = d.skin_bind_positions;
      out.skin = d.skin;
      out.max_distance = d.max_distance;
      out.backstop = d.backstop;
      // Held by a joint: the skin holds it in the file (max distance 0 follows the skin).
      for (const ClothAttachment& a : d.attachments) out.max_distance[a.particle] = 0.f;
    } else {
      for (size_t i = 0; i < d.positions.size(); ++i) {
        const int32_t joint = std::max(resolved.carrier_joint[i], 0);
        ClothSkinWeights w;
        w.joints[0] = static_cast<uint32_t>(joint);
        w.weights[0] = 1.f;
        out.skin.push_back(w);
        out.bind_positions.push_back(
            TransformPoint(resolved.frame_to_bind[static_cast<size_t>(joint)], d.positions[i]));
      }
      // Free but for the held particles, which follow their joint (max distance 0).
      out.max_distance.assign(d.positions.size(), std::numeric_limits<float>::infinity());
      for (const ClothAttachment& a : d.attachments) out.max_distance[a.particle] = 0.f;
    }
    const std::string path = (fs::path(dir) / (out.name + ".glb")).string();
    if (Status s = bake::WriteGarmentGltf(asset, out, path); !s.ok()) return s;
    std::printf("drape-sim: wrote %s\n", path.c_str());
  }
  return Status::Ok();
}

Status Settle(SceneSimulation* sim, json* settle) {
  double settle_ms = 0.0;
  FrameStats stats;
  for (int64_t k = -sim->settle_frames(); k < 0; ++k) {
    if (Status s = sim->Step(k, &stats); !s.ok()) return s;
    settle_ms += stats.step_ms;
  }
  *settle = {{"frames", sim->settle_frames()}, {"step_ms_total", settle_ms}};
  return Status::Ok();
}

// What the frame loop gathered.
struct FrameLoop {
  std::vector<FrameStats> frames;
  double step_ms_total = 0.0, render_ms = 0.0;
  uint64_t contact_total = 0;
  uint32_t contact_max = 0;
  float stretch_max = 0.f;
  uint32_t overstretched_max = 0;
  uint64_t overstretched_total = 0;
  int64_t written = 0;  // pictures written
  std::vector<Thumbnail> thumbnails;
  Status failure = Status::Ok();  // the step that failed, if one did
  // --gltf: every record_every-th written frame (0: none recorded).
  int64_t record_every = 0;
  bake::SimulationRecording recording;
};

// The glTF recording keeps at most this many frames (each holds every particle).
constexpr int64_t kMaxRecordedFrames = 300;

void RecordFrame(const bake::Scene& scene, const SceneSimulation& sim, FrameLoop* loop) {
  bake::SimulationRecording& r = loop->recording;
  r.skinning.emplace_back(sim.skinning().begin(), sim.skinning().end());
  r.garments.resize(sim.garment_count());
  for (size_t g = 0; g < sim.garment_count(); ++g) {
    if (r.garments[g].name.empty()) {
      r.garments[g].name = scene.garments[g].name;
      r.garments[g].triangles.assign(sim.garment_triangles(g).begin(),
                                     sim.garment_triangles(g).end());
    }
    r.garments[g].positions.emplace_back(sim.garment_positions(g).begin(),
                                         sim.garment_positions(g).end());
  }
}

// Writes the picture of simulation frame `frame` (and its OBJ meshes), named by the frame,
// keeping a thumbnail when the contact sheet shows it (sheet_frames counts pictures).
Status WriteFrameOutputs(const bake::Scene& scene, const std::string& dir, int64_t frame,
                         const SceneSimulation& sim, FrameRenderer* renderer,
                         const std::vector<int64_t>& sheet_frames, FrameLoop* loop) {
  const std::vector<uint8_t> rgb = renderer->Render(sim);
  char name[64];
  std::snprintf(name, sizeof(name), "/frames/frame_%04lld.png", static_cast<long long>(frame));
  const int w = static_cast<int>(scene.output.width), h = static_cast<int>(scene.output.height);
  if (Status s = WritePng(dir + name, w, h, rgb); !s.ok()) return s;
  if (std::find(sheet_frames.begin(), sheet_frames.end(), loop->written) != sheet_frames.end()) {
    Thumbnail t;
    t.rgb = Downscale(rgb, w, h, 240, &t.width, &t.height);
    loop->thumbnails.push_back(std::move(t));
  }
  if (loop->record_every > 0 && loop->written % loop->record_every == 0)
    RecordFrame(scene, sim, loop);
  if (scene.output.obj) {
    for (size_t g = 0; g < sim.garment_count(); ++g) {
      std::snprintf(name, sizeof(name), "_%04lld.obj", static_cast<long long>(frame));
      const std::string path = dir + "/obj/" + scene.garments[g].name + name;
      if (Status s = WriteObj(path, sim.garment_positions(g), sim.garment_triangles(g)); !s.ok())
        return s;
    }
  }
  ++loop->written;
  return Status::Ok();
}

// The scene's frames: each stepped, and every output.every-th one written. A failed step ends
// the loop (loop->failure); a failed write is the returned error.
Status SimulateFrames(const bake::Scene& scene, const std::string& dir, SceneSimulation* sim,
                      FrameRenderer* renderer, FrameLoop* loop) {
  const int64_t frames = scene.frame_count;
  const uint32_t every = scene.output.every;
  const int64_t written_total = (frames + every - 1) / every;
  if (loop->record_every > 0) {
    loop->record_every = (written_total + kMaxRecordedFrames - 1) / kMaxRecordedFrames;
    loop->recording.frame_seconds =
        scene.dt * static_cast<float>(every) * static_cast<float>(loop->record_every);
  }
  // Frames for the contact sheet: up to 16, evenly spread.
  const int64_t sheet_count = std::min<int64_t>(16, written_total);
  std::vector<int64_t> sheet_frames;
  for (int64_t i = 0; i < sheet_count; ++i) {
    sheet_frames.push_back(sheet_count == 1 ? 0 : (i * (written_total - 1)) / (sheet_count - 1));
  }
  Progress progress(frames);
  // Reserved up front: the run's own bookkeeping must not grow the memory a long run measures.
  loop->frames.reserve(static_cast<size_t>(frames));
  for (int64_t k = 0; k < frames; ++k) {
    FrameStats stats;
    loop->failure = sim->Step(k, &stats);
    loop->frames.push_back(stats);
    loop->step_ms_total += stats.step_ms;
    loop->contact_total += stats.contacts;
    loop->contact_max = std::max(loop->contact_max, stats.contacts);
    loop->stretch_max = std::max(loop->stretch_max, stats.max_stretch);
    loop->overstretched_max = std::max(loop->overstretched_max, stats.overstretched_springs);
    loop->overstretched_total += stats.overstretched_springs;
    if (!loop->failure.ok()) break;
    if (k % every == 0) {
      const auto render_start = Clock::now();
      if (Status s = WriteFrameOutputs(scene, dir, k, *sim, renderer, sheet_frames, loop); !s.ok())
        return s;
      loop->render_ms +=
          std::chrono::duration<double, std::milli>(Clock::now() - render_start).count();
    }
    progress.Update(k + 1, loop->step_ms_total / static_cast<double>(k + 1));
  }
  return Status::Ok();
}

}  // namespace

int RunScene(const RunOptions& options) {
  const auto wall_start = Clock::now();
  bake::Scene scene;
  if (Status s = bake::LoadScene(options.scene_path, &scene); !s.ok()) return Fail(s.message());
  if (options.frames > 0) scene.frame_count = static_cast<uint32_t>(options.frames);
  // The runtime runs on drape's std::thread pool, whose idle workers sleep after a few
  // microseconds (OpenMP's default spin-waits made a step 30x slower on a busy 2-core machine);
  // OpenMP keeps the bake's loops.
  const int threads = options.threads > 0
                          ? options.threads
                          : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  omp_set_num_threads(threads);
  ThreadPoolTaskSystem pool(static_cast<uint32_t>(threads));
  SetTaskSystem(&pool);
  struct RestoreTasks {
    ~RestoreTasks() { SetTaskSystem(nullptr); }
  } restore_tasks;
  const std::string dir = options.out_dir;
  if (Status s = CreateDirectory(dir); !s.ok()) return Fail(s.message());

  // The asset: cached, or baked now.
  SceneAsset loaded;
  if (Status s = LoadOrBakeAsset(scene, dir, &loaded); !s.ok()) return Fail(s.message());
  PrintAssetSource(scene, loaded);
  CharacterAsset& asset = loaded.asset;
  int32_t clip = -1;
  if (Status s = bake::ResolveSceneClip(asset, &scene, &clip); !s.ok()) return Fail(s.message());
  if (options.frames > 0) scene.frame_count = static_cast<uint32_t>(options.frames);
  bake::SceneReach reach;
  json left_out;
  if (Status s = KeepReachable(scene, &asset, &reach, &left_out); !s.ok()) return Fail(s.message());

  SceneSimulation sim;
  if (Status s = sim.Init(scene, asset, clip); !s.ok()) return Fail(s.message());
  if (!options.garments_dir.empty()) {
    if (Status s = ExportGarments(scene, asset, sim, options.garments_dir); !s.ok())
      return Fail(s.message());
  }
  std::printf(
      "drape-sim: simulating %u frames (+%lld settle) of %u particles, dt %.4f s, %u substeps, "
      "%s\n",
      scene.frame_count, static_cast<long long>(sim.settle_frames()), sim.particle_count(),
      static_cast<double>(scene.dt), sim.substeps(0),
      scene.solver.integrator == ClothIntegrator::kVerlet ? "verlet" : "euler");
  std::fflush(stdout);
  FrameRenderer renderer;
  if (Status s = renderer.Frame(scene, asset, clip, sim); !s.ok()) return Fail(s.message());

  // From here on this run writes its outputs: those of an earlier run go first.
  if (Status s = CreateDirectory(dir + "/frames"); !s.ok()) return Fail(s.message());
  if (scene.output.obj) {
    if (Status s = CreateDirectory(dir + "/obj"); !s.ok()) return Fail(s.message());
  }
  RemoveStaleOutputs(dir);
  if (Status s = WriteReach(dir, scene, reach, left_out); !s.ok()) return Fail(s.message());
  json settle;
  if (Status s = Settle(&sim, &settle); !s.ok()) return Fail(s.message());
  FrameLoop loop;
  loop.record_every = options.gltf_path.empty() ? 0 : 1;
  if (Status s = SimulateFrames(scene, dir, &sim, &renderer, &loop); !s.ok())
    return Fail(s.message());
  if (!options.gltf_path.empty()) {
    if (Status s = bake::WriteSimulationGltf(asset, loop.recording, options.gltf_path); !s.ok())
      return Fail(s.message());
  }
  const int64_t simulated = static_cast<int64_t>(loop.frames.size());
  // Read before stats.json is built: the peak of the bake, setup and simulation.
  const uint64_t rss_peak = PeakResidentSetBytes();
  const RunSummary summary = SummarizeRun(loop.frames);

  std::string animation = "none";
  const double fps = 1.0 / (static_cast<double>(scene.dt) * scene.output.every);
  if (scene.output.animation != bake::SceneAnimationOutput::kNone && loop.written > 0) {
    if (Status s =
            WriteAnimation(scene.output, dir, fps, loop.written, loop.thumbnails, &animation);
        !s.ok())
      return Fail(s.message());
  }

  const double overstretched_mean =
      simulated > 0 ? static_cast<double>(loop.overstretched_total) / static_cast<double>(simulated)
                    : 0.0;
  const json totals = {{"frames", simulated},
                       {"frames_written", loop.written},
                       {"particles", sim.particle_count()},
                       {"step_ms_total", loop.step_ms_total},
                       {"step_ms_mean", summary.step_ms_mean},
                       {"step_ms_median", summary.step_ms_median},
                       {"step_ms_p99", summary.step_ms_p99},
                       {"step_ms_max", summary.step_ms_max},
                       {"step_ms_tenths", summary.step_ms_tenths},
                       {"measure_ms_mean", summary.measure_ms_mean},
                       {"maps_render_ms_mean", summary.maps_render_ms_mean},
                       {"contacts_mean", simulated > 0 ? static_cast<double>(loop.contact_total) /
                                                             static_cast<double>(simulated)
                                                       : 0.0},
                       {"contacts_max", loop.contact_max},
                       {"max_penetration_mm", summary.max_penetration * 1000.f},
                       {"max_penetration_frame", summary.max_penetration_frame},
                       {"frames_with_particles_inside", summary.frames_with_inside},
                       {"inside_particles_max", summary.inside_particles_max},
                       {"held_inside_particles_max", summary.held_inside_particles_max},
                       {"held_max_penetration_mm", summary.held_max_penetration * 1000.f},
                       {"max_stretch", loop.stretch_max},
                       {"overstretched_springs_mean", overstretched_mean},
                       {"overstretched_springs_max", loop.overstretched_max},
                       {"nan_frames", summary.nan_frames},
                       {"rss_peak_bytes", rss_peak},
                       {"rss_after_100_frames_bytes", summary.rss_after_100_frames},
                       {"rss_end_bytes", summary.rss_end},
                       {"rss_growth_bytes", summary.rss_growth},
                       {"render_ms_total", loop.render_ms},
                       {"wall_s", Seconds(wall_start)},
                       {"threads", threads}};
  json frame_list = json::array();
  for (const FrameStats& f : loop.frames) frame_list.push_back(FrameJson(f));
  const json stats = {
      {"scene", options.scene_path},
      {"character", scene.character},
      {"asset",
       {{"path", loaded.path},
        {"baked", loaded.baked},
        {"reason", loaded.reason},
        {"bake_ms", loaded.bake_ms}}},
      {"clip", clip >= 0 ? json(asset.clips[static_cast<size_t>(clip)].name) : json(nullptr)},
      {"dt_s", scene.dt},
      {"substeps", sim.substeps(0)},
      {"methods",
       {{"maps", scene.use_maps}, {"hulls", scene.use_hulls}, {"spheres", scene.use_spheres}}},
      {"maps_source", scene.maps_source == bake::MapSource::kRendered ? "rendered" : "baked"},
      {"colliders",
       {{"hulls", scene.use_hulls ? asset.hulls.size() : 0},
        {"joint_spheres", scene.use_spheres ? asset.joint_spheres.size() : 0},
        {"map_poses", scene.use_maps ? asset.body_maps.poses.size() : 0}}},
      {"animation", animation},
      {"settle", settle},
      {"totals", totals},
      {"frames", frame_list}};
  if (Status s = WriteText(dir + "/stats.json", stats.dump(1) + "\n"); !s.ok())
    return Fail(s.message());
  if (!loop.failure.ok()) return Fail(loop.failure.message());

  constexpr double kMiB = 1024.0 * 1024.0;
  std::printf(
      "drape-sim: %lld frames, %.2f ms/step mean (%.2f p99, %.2f max)%s, %.0f contacts/frame, "
      "max penetration %.2f mm%s, %.0f springs/frame beyond the strain limit, %u NaN frames; "
      "RSS peak %.1f MiB, %+.1f MiB after frame 100; %lld pictures, %s; %.1f s\n",
      static_cast<long long>(simulated), summary.step_ms_mean, summary.step_ms_p99,
      summary.step_ms_max, RenderNote(scene, summary).c_str(),
      totals["contacts_mean"].get<double>(), static_cast<double>(summary.max_penetration) * 1000.0,
      HeldNote(summary).c_str(), overstretched_mean, summary.nan_frames,
      static_cast<double>(rss_peak) / kMiB, static_cast<double>(summary.rss_growth) / kMiB,
      static_cast<long long>(loop.written), animation.c_str(), Seconds(wall_start));
  return 0;
}

}  // namespace drape::sim

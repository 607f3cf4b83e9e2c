// drape-sim SCENE.json -o DIR [--frames N] [--threads T]
// drape-sim --dump-scene-reference   (docs/SCENES.md: every scene field, from the parser's schema)
// Bakes the scene's character when its cached asset is missing or stale, simulates the garments
// against the colliders the scene names, and writes DIR/frames/frame_NNNN.png, an animation
// (DIR/animation.mp4 or .gif through ffmpeg when it is on PATH, else DIR/contact_sheet.png),
// optionally DIR/obj/<garment>_NNNN.obj, DIR/stats.json and DIR/reach.json.
// Progress goes to stderr (a bar on a terminal, else a line per 10 %), log lines to stdout. On
// any error: one line on stderr naming the input and the reason, exit code 1.

#include <omp.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "asset_cache.h"
#include "drape/bake/scene.h"
#include "drape/formats/asset_file.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skinning.h"
#include "renderer.h"
#include "simulation.h"

extern char** environ;

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

// Progress on stderr: a redrawn bar on a terminal, else one line per 10 %.
class Progress {
 public:
  explicit Progress(int64_t total) : total_(std::max<int64_t>(total, 1)), tty_(isatty(2) != 0) {}

  void Update(int64_t done, double mean_step_ms) {
    const int percent = static_cast<int>(done * 100 / total_);
    if (tty_) {
      constexpr int kWidth = 30;
      const int filled = static_cast<int>(done * kWidth / total_);
      std::fprintf(stderr, "\rdrape-sim: [%s%s] %3d%%  frame %lld/%lld  %.2f ms/step ",
                   std::string(static_cast<size_t>(filled), '#').c_str(),
                   std::string(static_cast<size_t>(kWidth - filled), '.').c_str(), percent,
                   static_cast<long long>(done), static_cast<long long>(total_), mean_step_ms);
      if (done == total_) std::fprintf(stderr, "\n");
      std::fflush(stderr);
    } else if (percent / 10 > reported_ / 10 || done == total_) {
      reported_ = percent;
      std::fprintf(stderr, "drape-sim: %3d%% (%lld/%lld frames, %.2f ms/step)\n", percent,
                   static_cast<long long>(done), static_cast<long long>(total_), mean_step_ms);
    }
  }

 private:
  int64_t total_;
  bool tty_;
  int reported_ = 0;
};

std::string FindOnPath(const std::string& program) {
  const char* path = std::getenv("PATH");
  if (path == nullptr) return "";
  std::stringstream dirs(path);
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    const std::string candidate = (dir.empty() ? "." : dir) + "/" + program;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return "";
}

// Runs a program with arguments (no shell); true when it exits with 0.
bool Run(const std::vector<std::string>& argv) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, argv[0].c_str(), nullptr, nullptr, args.data(), environ) != 0) return false;
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) return false;
  return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

// Edges between triangles of different planes: the hull's visible outline in a wireframe.
std::vector<std::pair<Float3, Float3>> FeatureEdges(const HullColliderData& hull) {
  struct Edge {
    uint32_t a, b, plane;
  };
  std::vector<Edge> edges;
  for (size_t t = 0; t * 3 + 2 < hull.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      uint32_t a = hull.triangles[t * 3 + k], b = hull.triangles[t * 3 + (k + 1) % 3];
      if (a > b) std::swap(a, b);
      edges.push_back({a, b, t < hull.triangle_planes.size() ? hull.triangle_planes[t] : 0u});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) {
    return x.a != y.a ? x.a < y.a : (x.b != y.b ? x.b < y.b : x.plane < y.plane);
  });
  std::vector<std::pair<Float3, Float3>> out;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    bool crease = false;
    while (j < edges.size() && edges[j].a == edges[i].a && edges[j].b == edges[i].b) {
      crease = crease || edges[j].plane != edges[i].plane;
      ++j;
    }
    if (crease || j - i == 1) out.push_back({hull.vertices[edges[i].a], hull.vertices[edges[i].b]});
    i = j;
  }
  return out;
}

struct FrameRenderer {
  const bake::Scene* scene = nullptr;
  const CharacterAsset* asset = nullptr;
  Camera camera;
  Light light;
  float floor_y = 0.f, floor_x = 0.f, floor_z = 0.f;
  std::vector<std::vector<std::pair<Float3, Float3>>> hull_edges;  // per hull of the set
  std::vector<Float3> body;
  static constexpr int kSupersample = 2;

  std::vector<uint8_t> Render(const SceneSimulation& sim) {
    const bake::SceneOutput& out = scene->output;
    Canvas canvas(static_cast<int>(out.width), static_cast<int>(out.height), kSupersample);
    canvas.Clear({0.78f, 0.83f, 0.90f}, {0.95f, 0.95f, 0.96f});
    DrawFloor(&canvas, camera, light, floor_x, floor_y, floor_z, 0.25f, 16);
    sim.SkinBody(&body);
    const Rgb grey{0.55f, 0.55f, 0.56f};
    DrawMesh(&canvas, camera, light, body, asset->mesh.triangles, grey, false, grey);
    for (size_t g = 0; g < sim.garment_count(); ++g) {
      const auto& c = scene->garments[g].color;
      const Rgb front{c[0], c[1], c[2]};
      const Rgb back{c[0] * 0.7f, c[1] * 0.7f, c[2] * 0.7f};
      DrawMesh(&canvas, camera, light, sim.garment_positions(g), sim.garment_triangles(g), front,
               true, back);
    }
    if (out.overlay_colliders && sim.hulls() != nullptr) DrawColliders(sim, &canvas);
    return canvas.Resolve();
  }

  void DrawColliders(const SceneSimulation& sim, Canvas* canvas) {
    const HullColliderSet& set = *sim.hulls();
    if (hull_edges.empty()) {
      for (uint32_t h : sim.hull_indices()) hull_edges.push_back(FeatureEdges(asset->hulls[h]));
    }
    const Rgb hull_color{1.f, 0.8f, 0.1f}, sphere_color{0.1f, 0.85f, 1.f};
    for (uint32_t h = 0; h < set.hull_count(); ++h) {
      const Mat34 world = set.HullWorldTransform(h, 1.f);
      for (const auto& [a, b] : hull_edges[h]) {
        canvas->DrawLine(camera, TransformPoint(world, a), TransformPoint(world, b), hull_color,
                         0.12f, 1);
      }
    }
    for (uint32_t s = 0; s < set.sphere_count(); ++s) {
      const Float3 c = set.SphereCenter(s, 1.f);
      const float r = asset->joint_spheres[sim.sphere_indices()[s]].radius;
      constexpr int kSegments = 36;
      for (int axis = 0; axis < 3; ++axis) {
        for (int k = 0; k < kSegments; ++k) {
          const auto point = [&](int i) {
            const float a = 2.f * 3.14159265f * static_cast<float>(i) / kSegments;
            const float u = r * std::cos(a), v = r * std::sin(a);
            return axis == 0 ? c + Float3{0.f, u, v}
                             : (axis == 1 ? c + Float3{u, 0.f, v} : c + Float3{u, v, 0.f});
          };
          canvas->DrawLine(camera, point(k), point(k + 1), sphere_color, 0.12f, 1);
        }
      }
    }
  }
};

Status WriteObj(const std::string& path, std::span<const Float3> positions,
                std::span<const uint32_t> triangles) {
  std::ostringstream out;
  out << "# drape-sim cloth, metres, asset frame (+Y up)\n";
  char line[96];
  for (const Float3& p : positions) {
    std::snprintf(line, sizeof(line), "v %.6f %.6f %.6f\n", static_cast<double>(p.x),
                  static_cast<double>(p.y), static_cast<double>(p.z));
    out << line;
  }
  for (size_t t = 0; t + 2 < triangles.size(); t += 3)
    out << "f " << triangles[t] + 1 << ' ' << triangles[t + 1] + 1 << ' ' << triangles[t + 2] + 1
        << '\n';
  return WriteFileAtomically(path, out.str());
}

Status WriteText(const std::string& path, const std::string& text) {
  return WriteFileAtomically(path, text);
}

// Removes the outputs of an earlier run that this run would not overwrite (a longer run's extra
// frames would otherwise end up in the animation).
void RemoveStaleOutputs(const std::string& dir) {
  std::error_code error;
  for (const char* sub : {"/frames", "/obj"}) {
    if (!fs::is_directory(dir + sub, error)) continue;
    for (const auto& entry : fs::directory_iterator(dir + sub, error)) {
      const std::string name = entry.path().filename().string();
      const std::string ext = entry.path().extension().string();
      if ((name.rfind("frame_", 0) == 0 && ext == ".png") || ext == ".obj")
        fs::remove(entry.path(), error);
    }
  }
  for (const char* file :
       {"/animation.mp4", "/animation.gif", "/contact_sheet.png", "/stats.json", "/reach.json"})
    fs::remove(dir + file, error);
}

json FrameJson(const FrameStats& f) {
  return {{"frame", f.frame},
          {"time_s", f.time},
          {"step_ms", f.step_ms},
          {"contacts", f.contacts},
          {"hull_contacts", f.hull_contacts},
          {"body_map_contacts", f.body_map_contacts},
          {"inside_particles", f.inside_particles},
          {"max_penetration_mm", f.max_penetration * 1000.f},
          {"max_stretch", f.max_stretch},
          {"nan", !f.finite},
          {"rss_bytes", f.rss_bytes},
          {"measure_ms", f.measure_ms}};
}

struct Options {
  std::string scene_path, out_dir;
  int64_t frames = 0;
  int threads = 0;
};

int RunScene(const Options& options) {
  const auto wall_start = Clock::now();
  bake::Scene scene;
  if (Status s = bake::LoadScene(options.scene_path, &scene); !s.ok()) return Fail(s.message());
  if (options.frames > 0) scene.frame_count = static_cast<uint32_t>(options.frames);
  if (options.threads > 0) omp_set_num_threads(options.threads);

  const std::string dir = options.out_dir;
  std::error_code error;
  fs::create_directories(dir + "/frames", error);
  if (error) return Fail(dir + ": cannot create the output directory: " + error.message());
  if (scene.output.obj) {
    fs::create_directories(dir + "/obj", error);
    if (error) return Fail(dir + "/obj: cannot create: " + error.message());
  }

  // The asset: cached, or baked now.
  SceneAsset loaded;
  if (Status s = LoadOrBakeAsset(scene, dir, &loaded); !s.ok()) return Fail(s.message());
  if (loaded.baked) {
    std::printf("drape-sim: baked %s -> %s in %.2f s (%s)\n", scene.character.c_str(),
                loaded.path.c_str(), loaded.bake_ms / 1000.0, loaded.reason.c_str());
  } else {
    std::printf("drape-sim: using the %s asset %s\n",
                loaded.reason == "cached" ? "cached" : "scene's", loaded.path.c_str());
  }
  CharacterAsset& asset = loaded.asset;
  int32_t clip = -1;
  if (Status s = bake::ResolveSceneClip(asset, &scene, &clip); !s.ok()) return Fail(s.message());
  if (options.frames > 0) scene.frame_count = static_cast<uint32_t>(options.frames);

  // Model only what the scene needs: the colliders its garments can reach, the poses it plays.
  bake::SceneReach reach;
  if (Status s = bake::AnalyzeSceneReach(scene, asset, &reach); !s.ok()) return Fail(s.message());
  json left_out = json::array();
  const size_t hulls_before = asset.hulls.size(), spheres_before = asset.joint_spheres.size(),
               poses_before = asset.body_maps.poses.size();
  if (scene.prune) bake::PruneUnreachable(reach, &asset, &left_out);
  {
    std::string dropped;
    for (const json& entry : left_out) {
      if (entry.contains("bone"))
        dropped += (dropped.empty() ? "" : ", ") + entry["kind"].get<std::string>() + " " +
                   entry["bone"].get<std::string>();
    }
    std::printf(
        "drape-sim: reach: kept %zu/%zu hulls, %zu/%zu joint spheres, %zu/%zu map poses%s%s\n",
        asset.hulls.size(), hulls_before, asset.joint_spheres.size(), spheres_before,
        asset.body_maps.poses.size(), poses_before,
        dropped.empty() ? "" : "; out of reach: ", dropped.c_str());
  }

  SceneSimulation sim;
  if (Status s = sim.Init(scene, asset, clip); !s.ok()) return Fail(s.message());
  std::printf(
      "drape-sim: simulating %u frames (+%lld settle) of %u particles, dt %.4f s, %u substeps, "
      "%s\n",
      scene.frame_count, static_cast<long long>(sim.settle_frames()), sim.particle_count(),
      static_cast<double>(scene.dt), sim.substeps(0),
      scene.solver.integrator == ClothIntegrator::kVerlet ? "verlet" : "euler");
  std::fflush(stdout);

  // The camera frames the body over the whole scene and the garments at the start.
  FrameRenderer renderer;
  renderer.scene = &scene;
  renderer.asset = &asset;
  {
    Float3 lo{1e30f, 1e30f, 1e30f}, hi{-1e30f, -1e30f, -1e30f};
    const auto grow = [&](std::span<const Float3> points) {
      for (const Float3& p : points) {
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
      }
    };
    SkeletonPose pose;
    if (Status s = pose.Init(asset.skeleton); !s.ok()) return Fail(s.message());
    std::vector<Float3> posed(asset.mesh.vertex_count());
    constexpr int kSamples = 8;
    for (int k = 0; k < kSamples; ++k) {
      const float t = scene.animation.start + static_cast<float>(scene.frame_count) * scene.dt *
                                                  static_cast<float>(k) / (kSamples - 1);
      if (clip >= 0) {
        (void)pose.SampleClip(asset.clips[static_cast<size_t>(clip)], t, scene.animation.loop);
      } else if (scene.animation.pose == bake::ScenePose::kRest) {
        pose.SetRest();
      } else {
        pose.SetBind();
      }
      (void)SkinMesh(asset.mesh, pose.skinning(), posed);
      grow(posed);
    }
    for (size_t g = 0; g < sim.garment_count(); ++g) grow(sim.garment_start_positions(g));
    const bake::SceneOutput& out = scene.output;
    renderer.camera = FitCamera(lo, hi, out.camera_yaw_deg, out.camera_pitch_deg, out.camera_zoom,
                                static_cast<int>(out.width) * FrameRenderer::kSupersample,
                                static_cast<int>(out.height) * FrameRenderer::kSupersample);
    const Camera& c = renderer.camera;
    renderer.light.direction = NormalizeOr(
        -c.forward * 0.6f + Float3{0.f, 0.9f, 0.f} - c.right * 0.35f, Float3{0.f, 1.f, 0.f});
    renderer.floor_y = lo.y - 0.002f;
    renderer.floor_x = (lo.x + hi.x) * 0.5f;
    renderer.floor_z = (lo.z + hi.z) * 0.5f;
  }

  // From here on this run writes its outputs: those of an earlier run go first.
  RemoveStaleOutputs(dir);
  {
    json reach_json = bake::SceneReachToJson(reach);
    reach_json["pruned"] = scene.prune;
    reach_json["left_out"] = left_out;
    if (Status s = WriteText(dir + "/reach.json", reach_json.dump(2) + "\n"); !s.ok())
      return Fail(s.message());
  }

  // Settle, then the frames.
  json settle = json::object();
  {
    double settle_ms = 0.0;
    FrameStats stats;
    for (int64_t k = -sim.settle_frames(); k < 0; ++k) {
      if (Status s = sim.Step(k, &stats); !s.ok()) return Fail(s.message());
      settle_ms += stats.step_ms;
    }
    settle = {{"frames", sim.settle_frames()}, {"step_ms_total", settle_ms}};
  }

  const int64_t frames = scene.frame_count;
  const uint32_t every = scene.output.every;
  const int64_t written_total = (frames + every - 1) / every;
  // Frames for the contact sheet: up to 16, evenly spread.
  const int64_t sheet_count = std::min<int64_t>(16, written_total);
  std::vector<int64_t> sheet_frames;
  for (int64_t i = 0; i < sheet_count; ++i) {
    sheet_frames.push_back(sheet_count == 1 ? 0 : (i * (written_total - 1)) / (sheet_count - 1));
  }
  struct Thumb {
    std::vector<uint8_t> rgb;
    int width = 0, height = 0;
  };
  std::vector<Thumb> thumbs;

  Progress progress(frames);
  // Reserved up front: the run's own bookkeeping must not grow the memory a long run measures.
  std::vector<FrameStats> frame_stats;
  frame_stats.reserve(static_cast<size_t>(frames));
  double step_total = 0.0, render_ms = 0.0;
  uint64_t contact_total = 0;
  uint32_t contact_max = 0;
  float stretch_max = 0.f;
  int64_t written = 0;
  Status failure = Status::Ok();
  for (int64_t k = 0; k < frames; ++k) {
    FrameStats stats;
    failure = sim.Step(k, &stats);
    frame_stats.push_back(stats);
    step_total += stats.step_ms;
    contact_total += stats.contacts;
    contact_max = std::max(contact_max, stats.contacts);
    stretch_max = std::max(stretch_max, stats.max_stretch);
    if (!failure.ok()) break;
    if (k % every == 0) {
      const auto render_start = Clock::now();
      const std::vector<uint8_t> rgb = renderer.Render(sim);
      char name[64];
      std::snprintf(name, sizeof(name), "/frames/frame_%04lld.png",
                    static_cast<long long>(written));
      const int w = static_cast<int>(scene.output.width), h = static_cast<int>(scene.output.height);
      if (Status s = WritePng(dir + name, w, h, rgb); !s.ok()) return Fail(s.message());
      if (std::find(sheet_frames.begin(), sheet_frames.end(), written) != sheet_frames.end()) {
        Thumb t;
        t.rgb = Downscale(rgb, w, h, 240, &t.width, &t.height);
        thumbs.push_back(std::move(t));
      }
      if (scene.output.obj) {
        for (size_t g = 0; g < sim.garment_count(); ++g) {
          std::snprintf(name, sizeof(name), "_%04lld.obj", static_cast<long long>(written));
          const std::string path = dir + "/obj/" + scene.garments[g].name + name;
          if (Status s = WriteObj(path, sim.garment_positions(g), sim.garment_triangles(g));
              !s.ok())
            return Fail(s.message());
        }
      }
      ++written;
      render_ms += std::chrono::duration<double, std::milli>(Clock::now() - render_start).count();
    }
    progress.Update(k + 1, step_total / static_cast<double>(k + 1));
  }
  const int64_t simulated = static_cast<int64_t>(frame_stats.size());
  // Read before stats.json is built: the peak of the bake, setup and simulation.
  const uint64_t rss_peak = PeakResidentSetBytes();
  const RunSummary summary = SummarizeRun(frame_stats);

  // The animation: ffmpeg when it is there, else a contact sheet.
  std::string animation = "none";
  const double fps = 1.0 / (static_cast<double>(scene.dt) * every);
  if (scene.output.animation != bake::SceneAnimationOutput::kNone && written > 0) {
    const std::string ffmpeg = FindOnPath("ffmpeg");
    const bool want_gif = scene.output.animation == bake::SceneAnimationOutput::kGif;
    const bool want_sheet = scene.output.animation == bake::SceneAnimationOutput::kContactSheet;
    if (!ffmpeg.empty() && !want_sheet) {
      const std::string target = dir + (want_gif ? "/animation.gif" : "/animation.mp4");
      char rate[32];
      std::snprintf(rate, sizeof(rate), "%.4f", fps);
      std::vector<std::string> args = {
          ffmpeg,       "-y", "-loglevel", "error",
          "-framerate", rate, "-i",        dir + "/frames/frame_%04d.png"};
      if (want_gif) {
        args.insert(args.end(), {"-vf", "split[a][b];[a]palettegen[p];[b][p]paletteuse"});
      } else {
        args.insert(args.end(), {"-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-pix_fmt", "yuv420p"});
      }
      args.push_back(target);
      if (Run(args)) {
        animation = target;
      } else {
        std::fprintf(stderr,
                     "drape-sim: warning: ffmpeg failed; writing a contact sheet instead\n");
      }
    } else if (!want_sheet && scene.output.animation != bake::SceneAnimationOutput::kAuto) {
      std::fprintf(stderr, "drape-sim: warning: ffmpeg is not on PATH; writing a contact sheet\n");
    }
    if (animation == "none" && !thumbs.empty()) {
      const int cols = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(thumbs.size()))));
      const int rows = (static_cast<int>(thumbs.size()) + cols - 1) / cols;
      const int tw = thumbs[0].width, th = thumbs[0].height, gap = 4;
      const int sw = cols * tw + (cols + 1) * gap, sh = rows * th + (rows + 1) * gap;
      std::vector<uint8_t> sheet(static_cast<size_t>(sw) * static_cast<size_t>(sh) * 3, 255);
      for (size_t i = 0; i < thumbs.size(); ++i) {
        const int x0 = gap + static_cast<int>(i % static_cast<size_t>(cols)) * (tw + gap);
        const int y0 = gap + static_cast<int>(i / static_cast<size_t>(cols)) * (th + gap);
        for (int y = 0; y < th; ++y) {
          std::copy_n(thumbs[i].rgb.begin() + static_cast<ptrdiff_t>(y) * tw * 3, tw * 3,
                      sheet.begin() + (static_cast<ptrdiff_t>(y0 + y) * sw + x0) * 3);
        }
      }
      animation = dir + "/contact_sheet.png";
      if (Status s = WritePng(animation, sw, sh, sheet); !s.ok()) return Fail(s.message());
    }
  }

  const json totals = {
      {"frames", simulated},
      {"frames_written", written},
      {"particles", sim.particle_count()},
      {"step_ms_total", step_total},
      {"step_ms_mean", summary.step_ms_mean},
      {"step_ms_median", summary.step_ms_median},
      {"step_ms_p99", summary.step_ms_p99},
      {"step_ms_max", summary.step_ms_max},
      {"step_ms_tenths", summary.step_ms_tenths},
      {"measure_ms_mean", summary.measure_ms_mean},
      {"contacts_mean",
       simulated > 0 ? static_cast<double>(contact_total) / static_cast<double>(simulated) : 0.0},
      {"contacts_max", contact_max},
      {"max_penetration_mm", summary.max_penetration * 1000.f},
      {"max_penetration_frame", summary.max_penetration_frame},
      {"frames_with_particles_inside", summary.frames_with_inside},
      {"inside_particles_max", summary.inside_particles_max},
      {"max_stretch", stretch_max},
      {"nan_frames", summary.nan_frames},
      {"rss_peak_bytes", rss_peak},
      {"rss_after_100_frames_bytes", summary.rss_after_100_frames},
      {"rss_end_bytes", summary.rss_end},
      {"rss_growth_bytes", summary.rss_growth},
      {"render_ms_total", render_ms},
      {"wall_s", Seconds(wall_start)},
      {"threads", omp_get_max_threads()}};
  json frame_list = json::array();
  for (const FrameStats& f : frame_stats) frame_list.push_back(FrameJson(f));
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
  if (!failure.ok()) return Fail(failure.message());

  constexpr double kMiB = 1024.0 * 1024.0;
  std::printf(
      "drape-sim: %lld frames, %.2f ms/step mean (%.2f p99, %.2f max), %.0f contacts/frame, max "
      "penetration %.2f mm, %u NaN frames; RSS peak %.1f MiB, %+.1f MiB after frame 100; %lld "
      "pictures, %s; %.1f s\n",
      static_cast<long long>(simulated), summary.step_ms_mean, summary.step_ms_p99,
      summary.step_ms_max, totals["contacts_mean"].get<double>(),
      static_cast<double>(summary.max_penetration) * 1000.0, summary.nan_frames,
      static_cast<double>(rss_peak) / kMiB, static_cast<double>(summary.rss_growth) / kMiB,
      static_cast<long long>(written), animation.c_str(), Seconds(wall_start));
  return 0;
}

}  // namespace
}  // namespace drape::sim

int main(int argc, char** argv) {
  CLI::App app{
      "drape-sim: bakes a scene's character if needed, simulates its garments and "
      "writes pictures and figures"};
  drape::sim::Options options;
  bool dump_reference = false;
  app.add_option("SCENE", options.scene_path, "the scene JSON (see docs/SCENES.md)");
  app.add_option("-o,--output", options.out_dir, "output directory (created)");
  app.add_option("--frames", options.frames, "frames to simulate (overrides the scene's duration)")
      ->check(CLI::PositiveNumber);
  app.add_option("--threads", options.threads, "OpenMP threads (default: all)")
      ->check(CLI::PositiveNumber);
  app.add_flag("--dump-scene-reference", dump_reference,
               "print the scenes reference (docs/SCENES.md) as markdown and exit");
  try {
    app.parse(argc, argv);
    if (dump_reference) {
      std::fputs(drape::bake::SceneReferenceMarkdown().c_str(), stdout);
      return 0;
    }
    if (options.scene_path.empty()) throw CLI::RequiredError("SCENE");
    if (options.out_dir.empty()) throw CLI::RequiredError("--output");
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return drape::sim::RunScene(options);
}

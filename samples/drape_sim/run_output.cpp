#include "run_output.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "drape/formats/asset_file.h"
#include "renderer.h"

extern char** environ;

namespace drape::sim {
namespace {

namespace fs = std::filesystem;

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

// `text` with glob(3)'s special characters escaped, for a pattern that must match it literally.
std::string GlobEscaped(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '*' || c == '?' || c == '[' || c == ']' || c == '\\') out += '\\';
    out += c;
  }
  return out;
}

}  // namespace

Progress::Progress(int64_t total) : total_(std::max<int64_t>(total, 1)), tty_(isatty(2) != 0) {}

void Progress::Update(int64_t done, double mean_step_ms) {
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

Status WriteAnimation(const bake::SceneOutput& output, const std::string& dir, double fps,
                      int64_t written, const std::vector<Thumbnail>& thumbnails,
                      std::string* animation) {
  *animation = "none";
  if (output.animation != bake::SceneAnimationOutput::kNone && written > 0) {
    const std::string ffmpeg = FindOnPath("ffmpeg");
    const bool want_gif = output.animation == bake::SceneAnimationOutput::kGif;
    const bool want_sheet = output.animation == bake::SceneAnimationOutput::kContactSheet;
    if (!ffmpeg.empty() && !want_sheet) {
      const std::string target = dir + (want_gif ? "/animation.gif" : "/animation.mp4");
      char rate[32];
      std::snprintf(rate, sizeof(rate), "%.4f", fps);
      std::vector<std::string> args = {ffmpeg,
                                       "-y",
                                       "-loglevel",
                                       "error",
                                       "-framerate",
                                       rate,
                                       "-pattern_type",
                                       "glob",
                                       "-i",
                                       GlobEscaped(dir) + "/frames/frame_*.png"};
      if (want_gif) {
        args.insert(args.end(), {"-vf", "split[a][b];[a]palettegen[p];[b][p]paletteuse"});
      } else {
        args.insert(args.end(), {"-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-pix_fmt", "yuv420p"});
      }
      args.push_back(target);
      if (Run(args)) {
        *animation = target;
      } else {
        std::fprintf(stderr,
                     "drape-sim: warning: ffmpeg failed; writing a contact sheet instead\n");
      }
    } else if (!want_sheet && output.animation != bake::SceneAnimationOutput::kAuto) {
      std::fprintf(stderr, "drape-sim: warning: ffmpeg is not on PATH; writing a contact sheet\n");
    }
    if (*animation == "none" && !thumbnails.empty()) {
      const int cols =
          static_cast<int>(std::ceil(std::sqrt(static_cast<double>(thumbnails.size()))));
      const int rows = (static_cast<int>(thumbnails.size()) + cols - 1) / cols;
      const int tw = thumbnails[0].width, th = thumbnails[0].height, gap = 4;
      const int sw = cols * tw + (cols + 1) * gap, sh = rows * th + (rows + 1) * gap;
      std::vector<uint8_t> sheet(static_cast<size_t>(sw) * static_cast<size_t>(sh) * 3, 255);
      for (size_t i = 0; i < thumbnails.size(); ++i) {
        const int x0 = gap + static_cast<int>(i % static_cast<size_t>(cols)) * (tw + gap);
        const int y0 = gap + static_cast<int>(i / static_cast<size_t>(cols)) * (th + gap);
        for (int y = 0; y < th; ++y) {
          std::copy_n(thumbnails[i].rgb.begin() + static_cast<ptrdiff_t>(y) * tw * 3, tw * 3,
                      sheet.begin() + (static_cast<ptrdiff_t>(y0 + y) * sw + x0) * 3);
        }
      }
      *animation = dir + "/contact_sheet.png";
      if (Status s = WritePng(*animation, sw, sh, sheet); !s.ok()) return s;
    }
  }
  return Status::Ok();
}

nlohmann::json FrameJson(const FrameStats& f) {
  return {{"frame", f.frame},
          {"time_s", f.time},
          {"step_ms", f.step_ms},
          {"contacts", f.contacts},
          {"hull_contacts", f.hull_contacts},
          {"body_map_contacts", f.body_map_contacts},
          {"shape_contacts", f.shape_contacts},
          {"inside_particles", f.inside_particles},
          {"max_penetration_mm", f.max_penetration * 1000.f},
          {"held_inside_particles", f.held_inside_particles},
          {"held_max_penetration_mm", f.held_max_penetration * 1000.f},
          {"max_stretch", f.max_stretch},
          {"overstretched_springs", f.overstretched_springs},
          {"nan", !f.finite},
          {"rss_bytes", f.rss_bytes},
          {"measure_ms", f.measure_ms},
          {"maps_render_ms", f.maps_render_ms}};
}

}  // namespace drape::sim

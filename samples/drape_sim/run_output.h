#pragma once
// What a drape-sim run writes besides the frames' pictures: progress, OBJ meshes, text files, the
// removal of an earlier run's outputs, the animation (ffmpeg, or a contact sheet) and the
// per-frame figures of stats.json.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "drape/bake/scene.h"
#include "drape/formats/status.h"
#include "drape/formats/types.h"
#include "simulation.h"

namespace drape::sim {

// Progress on stderr: a redrawn bar on a terminal, else one line per 10 %.
class Progress {
 public:
  explicit Progress(int64_t total);
  void Update(int64_t done, double mean_step_ms);

 private:
  int64_t total_;
  bool tty_;
  int reported_ = 0;
};

Status WriteObj(const std::string& path, std::span<const Float3> positions,
                std::span<const uint32_t> triangles);
Status WriteText(const std::string& path, const std::string& text);
// Removes the outputs of an earlier run that this run would not overwrite (a longer run's extra
// frames would otherwise end up in the animation).
void RemoveStaleOutputs(const std::string& dir);

// A small copy of a frame's picture for the contact sheet.
struct Thumbnail {
  std::vector<uint8_t> rgb;
  int width = 0, height = 0;
};
// The animation of the `written` frames in dir/frames at `fps`: an mp4 or gif through ffmpeg
// when the scene asks for it and ffmpeg is on PATH, else a contact sheet of the thumbnails.
// Returns the file written, "none", or an error.
Status WriteAnimation(const bake::SceneOutput& output, const std::string& dir, double fps,
                      int64_t written, const std::vector<Thumbnail>& thumbnails,
                      std::string* animation);

nlohmann::json FrameJson(const FrameStats& f);

}  // namespace drape::sim

#include "preview/map_preview.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "drape/bake/body_map_baker.h"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wall"
#pragma GCC diagnostic ignored "-Wextra"
#pragma GCC diagnostic ignored "-Wpedantic"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wconversion"
#pragma GCC diagnostic ignored "-Wsign-conversion"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
// Static: stb's functions stay private to this file, so samples may compile their own copy.
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STBI_WRITE_NO_STDIO_WARNINGS
#include <stb/stb_image_write.h>
#pragma GCC diagnostic pop

namespace drape::bake {

Status WritePreviewPng(const std::string& path, uint32_t width, uint32_t height, int channels,
                       std::span<const uint8_t> pixels) {
  const size_t row_bytes = static_cast<size_t>(width) * static_cast<size_t>(channels);
  if (width == 0 || height == 0 || (channels != 1 && channels != 3) ||
      pixels.size() != row_bytes * height) {
    return Status(StatusCode::kInvalidArgument,
                  "WritePreviewPng: bad image size or channel count for " + path);
  }
  std::vector<uint8_t> flipped(pixels.size());
  for (uint32_t row = 0; row < height; ++row) {
    std::copy_n(pixels.data() + static_cast<size_t>(row) * row_bytes, row_bytes,
                flipped.data() + static_cast<size_t>(height - 1 - row) * row_bytes);
  }
  const int ok = stbi_write_png(path.c_str(), static_cast<int>(width), static_cast<int>(height),
                                channels, flipped.data(), static_cast<int>(row_bytes));
  if (ok == 0) {
    return Status(StatusCode::kIoError, "WritePreviewPng: cannot write " + path);
  }
  return Status::Ok();
}

namespace {

// Grey: the valid depth range of one view and layer stretched to 255 (nearest) .. 40 (farthest),
// so that background (0) stays distinguishable from the farthest surface. `colour`, when not
// null, receives the normals as (n*0.5+0.5)*255.
std::vector<uint8_t> DepthPreview(const BodyMapPose& pose, int view, uint32_t layer,
                                  std::vector<uint8_t>* colour) {
  const size_t texels = static_cast<size_t>(pose.width) * pose.height;
  float near_depth = pose.depth_range, far_depth = 0.f;
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      const BodyMapTexel texel = ReadBodyMapTexel(pose, view, i, j, layer);
      if (!texel.valid) continue;
      near_depth = std::min(near_depth, texel.depth);
      far_depth = std::max(far_depth, texel.depth);
    }
  }
  const float span = std::max(far_depth - near_depth, 1e-9f);
  std::vector<uint8_t> grey(texels, 0);
  if (colour != nullptr) colour->assign(3 * texels, 0);
  for (uint32_t j = 0; j < pose.height; ++j) {
    for (uint32_t i = 0; i < pose.width; ++i) {
      const BodyMapTexel texel = ReadBodyMapTexel(pose, view, i, j, layer);
      if (!texel.valid) continue;
      const size_t index = static_cast<size_t>(j) * pose.width + i;
      const float shade = 255.f - 215.f * (texel.depth - near_depth) / span;
      grey[index] = static_cast<uint8_t>(std::lround(std::clamp(shade, 0.f, 255.f)));
      if (colour != nullptr) EncodeNormalRgb8(texel.normal, &(*colour)[3 * index]);
    }
  }
  return grey;
}

}  // namespace

Status WriteBodyMapPreview(const BodyMapPose& pose, const std::string& directory,
                           const std::string& prefix) {
  if (pose.width == 0 || pose.height == 0 || !(pose.depth_range > 0.f)) {
    return Status(StatusCode::kInvalidArgument,
                  "WriteBodyMapPreview: the pose '" + prefix + "' holds no maps");
  }
  const char* view_names[2] = {"front", "back"};
  for (int view = 0; view < 2; ++view) {
    std::vector<uint8_t> colour;
    const std::vector<uint8_t> grey = DepthPreview(pose, view, 0, &colour);
    const std::string base = directory + "/" + prefix + "_" + view_names[view];
    Status status = WritePreviewPng(base + "_depth.png", pose.width, pose.height, 1, grey);
    if (!status.ok()) return status;
    status = WritePreviewPng(base + "_normal.png", pose.width, pose.height, 3, colour);
    if (!status.ok()) return status;
  }
  // Gap layers: the upper boundaries (front) and lower boundaries (back) of the k-th gap.
  for (uint32_t layer = 1; layer < pose.layers; ++layer) {
    for (int view = 0; view < 2; ++view) {
      const std::vector<uint8_t> grey = DepthPreview(pose, view, layer, nullptr);
      const std::string path = directory + "/" + prefix + "_gap" + std::to_string(layer) + "_" +
                               view_names[view] + "_depth.png";
      if (Status status = WritePreviewPng(path, pose.width, pose.height, 1, grey); !status.ok()) {
        return status;
      }
    }
  }
  return Status::Ok();
}

}  // namespace drape::bake

// stb_image_write's implementation lives in this one translation unit (compiled without the
// project's warning flags: it is third-party code). Static: drape_bake carries its own copy for
// its preview pictures, and two external copies would collide at link time.
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

#include "renderer.h"

namespace drape::sim {

Status WritePng(const std::string& path, int width, int height, std::span<const uint8_t> rgb) {
  if (rgb.size() != static_cast<size_t>(width) * static_cast<size_t>(height) * 3)
    return Status(StatusCode::kInvalidArgument, path + ": pixel buffer does not match the size");
  if (stbi_write_png(path.c_str(), width, height, 3, rgb.data(), width * 3) == 0)
    return Status(StatusCode::kIoError, path + ": cannot write the PNG");
  return Status::Ok();
}

}  // namespace drape::sim

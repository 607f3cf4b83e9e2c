#pragma once
// Private to the bake: assimp's file access, recording every file a loader opens (the model and
// what it names: a glTF's .bin buffers, an OBJ's .mtl, textures), so that drape-bake --depfile
// lists exactly what the bake read.

#include <assimp/DefaultIOSystem.h>

#include <string>
#include <vector>

namespace drape::bake::detail {

class RecordingIOSystem final : public Assimp::DefaultIOSystem {
 public:
  // `opened` (owned by the caller, which outlives the importer) receives each path once, as the
  // loader named it, in the order first opened.
  explicit RecordingIOSystem(std::vector<std::string>* opened) : opened_(opened) {}

  Assimp::IOStream* Open(const char* file, const char* mode = "rb") override {
    Assimp::IOStream* stream = DefaultIOSystem::Open(file, mode);
    if (stream != nullptr && file != nullptr) {
      const std::string path(file);
      bool seen = false;
      for (const std::string& p : *opened_) seen = seen || p == path;
      if (!seen) opened_->push_back(path);
    }
    return stream;
  }

 private:
  std::vector<std::string>* opened_;
};

}  // namespace drape::bake::detail

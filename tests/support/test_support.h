#pragma once
// Paths shared by the tests. Header-only: linked into runtime-only builds too.

#include <filesystem>
#include <string>

namespace drape::test {

inline std::string SharedDir() { return DRAPE_SHARED_DIR; }
inline std::string SourceDir() { return DRAPE_SOURCE_DIR; }
inline std::string GoldenDir() { return DRAPE_GOLDEN_DIR; }
inline std::string BinDir() { return DRAPE_BIN_DIR; }
inline std::string CharacterPath(const std::string& relative) {
  return SharedDir() + "/assets/characters/" + relative;
}
inline std::string MannequinPath() { return SourceDir() + "/samples/mannequin/mannequin.gltf"; }
// A parameterised test's name for a character path under shared/assets/characters ("" is the
// mannequin): its file name without extension, so test names stay the same from build to build.
inline std::string CharacterTestName(const std::string& relative) {
  if (relative.empty()) return "mannequin";
  std::string name = std::filesystem::path(relative).stem().string();
  for (char& c : name) {
    const bool alnum = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
    if (!alnum) c = '_';
  }
  return name;
}

}  // namespace drape::test

// Skips the current test with a clear message when a shared asset is absent.
#define DRAPE_REQUIRE_FILE(path)                                                           \
  do {                                                                                     \
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared asset absent: " << (path); \
  } while (0)

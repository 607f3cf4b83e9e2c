// Files a game engine loads but assimp's strict validation refuses, repaired with a warning; files
// whose headers claim more than they hold, refused before assimp allocates; a reader that crashes,
// hangs or runs out of memory, contained in the child process that reads first.
//
// The .b3d files are written here, chunk by chunk, as Blitz3D and Minetest's exporters lay them
// out: a root node holding the mesh and the ANIM chunk, one node per bone with its BONE weights
// and KEYS. A Minetest player model's keys run one frame past the duration its ANIM chunk states.

#include <gtest/gtest.h>
#include <unistd.h>
#include <assimp/Importer.hpp>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "drape/bake/importer.h"
#include "import/child_process.h"
#include "test_support.h"

namespace drape {
namespace {

using bake::Character;
using bake::ImportCharacter;
using bake::ImportOptions;

// --- A Blitz3D (.b3d) writer: chunks are a tag, a 32-bit size and their content.
class B3dWriter {
 public:
  void Begin(const char* tag) {
    bytes_.insert(bytes_.end(), tag, tag + 4);
    open_.push_back(bytes_.size());
    Int(0);  // size, patched by End()
  }
  void End() {
    const size_t at = open_.back();
    open_.pop_back();
    const uint32_t size = static_cast<uint32_t>(bytes_.size() - at - 4);
    std::memcpy(bytes_.data() + at, &size, 4);
  }
  void Int(int32_t v) { Raw(&v, 4); }
  void Float(float v) { Raw(&v, 4); }
  void String(const std::string& s) { Raw(s.c_str(), s.size() + 1); }
  // A node's name and its position, scale and rotation (w, x, y, z).
  void NodeHeader(const std::string& name, float y) {
    String(name);
    for (float v : {0.f, y, 0.f, 1.f, 1.f, 1.f, 1.f, 0.f, 0.f, 0.f}) Float(v);
  }
  void Write(const std::string& path) const {
    std::ofstream(path, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes_.data()),
               static_cast<std::streamsize>(bytes_.size()));
  }

 private:
  void Raw(const void* p, size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    bytes_.insert(bytes_.end(), b, b + n);
  }
  std::vector<uint8_t> bytes_;
  std::vector<size_t> open_;
};

struct B3dClip {
  int32_t duration_frames = 20;
  float fps = 10.f;
  std::vector<int32_t> key_frames;  // the frames of each bone's rotation keys, in file order
};

// A 1.6 m column of three square rings: the lower two rings on bone "hips" (at 0.8 m), the top
// ring on its child "chest" (at 1.2 m); both bones keyed at clip.key_frames, turning about +Y.
std::string WriteColumnB3d(const std::string& name, const B3dClip& clip) {
  B3dWriter w;
  w.Begin("BB3D");
  w.Int(1);
  w.Begin("NODE");
  w.NodeHeader("root", 0.f);
  w.Begin("MESH");
  w.Int(-1);
  w.Begin("VRTS");
  w.Int(0);  // flags: positions only
  w.Int(0);  // no texture coordinates
  w.Int(0);
  const float heights[3] = {0.f, 0.8f, 1.6f};
  for (float y : heights) {
    for (int k = 0; k < 4; ++k) {
      w.Float(k == 0 || k == 3 ? -0.15f : 0.15f);
      w.Float(y);
      w.Float(k < 2 ? -0.1f : 0.1f);
    }
  }
  w.End();
  w.Begin("TRIS");
  w.Int(-1);
  for (int ring = 0; ring < 2; ++ring) {
    for (int k = 0; k < 4; ++k) {
      const int a = ring * 4 + k, b = ring * 4 + (k + 1) % 4;
      for (int v : {a, b, b + 4, a, b + 4, a + 4}) w.Int(v);
    }
  }
  for (int v : {0, 2, 1, 0, 3, 2, 8, 9, 10, 8, 10, 11}) w.Int(v);  // caps
  w.End();
  w.End();  // MESH
  w.Begin("ANIM");
  w.Int(0);
  w.Int(clip.duration_frames);
  w.Float(clip.fps);
  w.End();
  const auto keys = [&](float turns_per_frame) {
    w.Begin("KEYS");
    w.Int(4);  // rotation keys
    for (int32_t frame : clip.key_frames) {
      const float half = 0.5f * turns_per_frame * static_cast<float>(frame);
      w.Int(frame);
      for (float v : {std::cos(half), 0.f, std::sin(half), 0.f}) w.Float(v);
    }
    w.End();
  };
  w.Begin("NODE");
  w.NodeHeader("hips", 0.8f);
  w.Begin("BONE");
  for (int v = 0; v < 8; ++v) {
    w.Int(v);
    w.Float(1.f);
  }
  w.End();
  keys(0.01f);
  w.Begin("NODE");
  w.NodeHeader("chest", 0.4f);
  w.Begin("BONE");
  for (int v = 8; v < 12; ++v) {
    w.Int(v);
    w.Float(1.f);
  }
  w.End();
  keys(0.02f);
  w.End();  // chest
  w.End();  // hips
  w.End();  // root
  w.End();  // BB3D
  const std::string path = ::testing::TempDir() + "/" + name + ".b3d";
  w.Write(path);
  return path;
}

bool HasWarning(const Character& c, const std::string& text) {
  for (const std::string& w : c.warnings)
    if (w.find(text) != std::string::npos) return true;
  return false;
}

std::string Warnings(const Character& c) {
  std::string out;
  for (const std::string& w : c.warnings) out += w + "\n";
  return out;
}

TEST(ImportRepair, KeysPastTheClipDurationExtendIt) {
  // The Minetest player model's case: 20 frames stated, keys on frames 1..21.
  B3dClip clip;
  for (int32_t f = 1; f <= 21; ++f) clip.key_frames.push_back(f);
  const std::string path = WriteColumnB3d("keys_past_duration", clip);
  Character c;
  const Status s = ImportCharacter(path, ImportOptions{}, &c);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(c.clips.size(), 1u);
  EXPECT_NEAR(c.clips[0].duration, 21.f / 10.f, 1e-5f);  // 21 frames at 10 fps
  EXPECT_TRUE(HasWarning(c, "keys run to tick 21, past its duration of 20 ticks")) << Warnings(c);
  EXPECT_EQ(c.skeleton.joint_names.size(), 2u);
}

TEST(ImportRepair, UnsortedAndRepeatedKeysAreSortedKeepingTheLast) {
  B3dClip clip;
  clip.key_frames = {0, 10, 5, 5, 20};
  const std::string path = WriteColumnB3d("unsorted_keys", clip);
  Character c;
  const Status s = ImportCharacter(path, ImportOptions{}, &c);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(c.clips.size(), 1u);
  EXPECT_TRUE(HasWarning(c, "keys of 2 channels were out of order, repeated")) << Warnings(c);
  // Sorted, the clip plays forward: the chest turns a little more at each later sample.
  EXPECT_NEAR(c.clips[0].duration, 2.f, 1e-5f);
}

TEST(ImportRepair, ZeroFramesPerSecondBecomesTwentyFive) {
  B3dClip clip;
  clip.fps = 0.f;
  clip.key_frames = {0, 25};
  clip.duration_frames = 25;
  const std::string path = WriteColumnB3d("zero_fps", clip);
  Character c;
  const Status s = ImportCharacter(path, ImportOptions{}, &c);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(c.clips.size(), 1u);
  EXPECT_NEAR(c.clips[0].duration, 1.f, 1e-5f);
  EXPECT_TRUE(HasWarning(c, "0 ticks per second; 25 used")) << Warnings(c);
}

// --- Headers that claim more than the file holds: refused before assimp allocates.

std::string WriteText(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// Refused, quickly, naming the file and the claim.
void ExpectRefusedQuickly(const std::string& path, const std::string& reason) {
  const auto start = std::chrono::steady_clock::now();
  Character c;
  const Status s = ImportCharacter(path, ImportOptions{}, &c);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_FALSE(s.ok()) << path;
  EXPECT_EQ(s.message().rfind(path + ": ", 0), 0u) << s.message();
  EXPECT_NE(s.message().find(reason), std::string::npos) << s.message();
  EXPECT_LT(seconds, 5.0) << s.message();
}

TEST(ImportRepair, HostileHeadersAreRefusedBeforeReading) {
  // 353 billion faces in a 300-byte OFF file.
  std::string off = "OFF\n3 353000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  off.resize(300, '\n');
  ExpectRefusedQuickly(WriteText("huge_faces.off", off), "declares 353000000000 faces");
  // Counts within 32 bits that the file cannot hold: 2.8 GB of assimp arrays from 26 bytes.
  ExpectRefusedQuickly(WriteText("huge_counts.off", "OFF\n100000000 100000000 0\n"),
                       "declares 200000000 vertex and face records");
  ExpectRefusedQuickly(WriteText("long_line.off", "OFF\n3 1 0\n" + std::string(5000, '1') + "\n"),
                       "a line of 5000 bytes");
  ExpectRefusedQuickly(WriteText("huge_elements.ply",
                                 "ply\nformat ascii 1.0\nelement vertex 4000000000\n"
                                 "property float x\nend_header\n0\n"),
                       "declares 4000000000 'vertex' elements");
  // A binary face list that claims 2^31 indices.
  std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\nproperty list int int vertex_index\n"
      "end_header\n";
  ply += std::string(36, '\0');
  const int32_t items = 0x7fffffff;
  ply.append(reinterpret_cast<const char*>(&items), 4);
  ply += std::string(12, '\0');
  ExpectRefusedQuickly(WriteText("huge_list.ply", ply),
                       "declares 2147483647 items in a list of 'face'");
  // A B3D chunk larger than its parent.
  B3dClip clip;
  clip.key_frames = {0, 10};
  std::ifstream in(WriteColumnB3d("chunk_source", clip), std::ios::binary);
  std::string b3d((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t tris = b3d.find("TRIS");
  ASSERT_NE(tris, std::string::npos);
  const uint32_t huge = 0xfffffff0u;
  std::memcpy(b3d.data() + tris + 4, &huge, 4);
  ExpectRefusedQuickly(WriteText("huge_chunk.b3d", b3d), "chunk 'TRIS' at byte");
}

TEST(ImportRepair, ADrapeAssetIsNamedForWhatItIs) {
  const std::string asset = test::GoldenDir() + "/mannequin_v1.drape";
  DRAPE_REQUIRE_FILE(asset);
  ExpectRefusedQuickly(asset, "is a baked drape asset, not a character model");
}

// --- The child process: what happens there is reported, not suffered.

TEST(ChildProcess, ReportsTheStepsStatus) {
  using bake::detail::RunInChildProcess;
  EXPECT_TRUE(RunInChildProcess("x", {}, [] { return Status::Ok(); }).ok());
  const Status s =
      RunInChildProcess("x", {}, [] { return Status(StatusCode::kCorrupt, "x: the reason"); });
  EXPECT_EQ(s.code(), StatusCode::kCorrupt);
  EXPECT_EQ(s.message(), "x: the reason");
}

TEST(ChildProcess, ACrashIsAnError) {
  const Status s =
      bake::detail::RunInChildProcess("model.fbx", {}, []() -> Status { std::abort(); });
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message().rfind("model.fbx: the model reader crashed on this file (signal 6", 0), 0u)
      << s.message();
}

TEST(ChildProcess, AHangIsStoppedAtTheTimeLimit) {
  const auto start = std::chrono::steady_clock::now();
  const Status s = bake::detail::RunInChildProcess("model.fbx", {0, 0.3}, []() -> Status {
    std::this_thread::sleep_for(std::chrono::seconds(30));
    return Status::Ok();
  });
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("took longer than the import's 0.3 s time limit"), std::string::npos)
      << s.message();
  EXPECT_LT(seconds, 10.0);
}

#if !defined(__SANITIZE_ADDRESS__)
TEST(ChildProcess, AllocationPastTheMemoryLimitIsAnError) {
  const Status s = bake::detail::RunInChildProcess("model.fbx", {256ull << 20, 0}, []() -> Status {
    std::vector<char> big(size_t{1} << 30, 1);  // 1 GiB, past the 256 MiB limit
    return Status(StatusCode::kCorrupt, std::to_string(big[12345]));
  });
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("needs more than the import's 256 MiB memory limit"),
            std::string::npos)
      << s.message();
}

TEST(ChildProcess, TheMemoryLimitStopsAHostileHeaderTheScanDoesNotKnow) {
  // assimp alone on the 353-billion-face OFF file: 12.7 GB resident and 35 s unlimited.
  std::string off = "OFF\n3 353000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  off.resize(300, '\n');
  const std::string path = ::testing::TempDir() + "/unscanned.off";
  std::ofstream(path, std::ios::binary) << off;
  const auto start = std::chrono::steady_clock::now();
  const Status s = bake::detail::RunInChildProcess(path, {1024ull << 20, 60}, [&]() -> Status {
    Assimp::Importer importer;
    if (importer.ReadFile(path, 0) == nullptr)
      return Status(StatusCode::kCorrupt, importer.GetErrorString());
    return Status::Ok();
  });
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("memory limit"), std::string::npos) << s.message();
  EXPECT_LT(seconds, 10.0);
}
#endif

}  // namespace
}  // namespace drape

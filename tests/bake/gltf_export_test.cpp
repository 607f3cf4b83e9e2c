// The glTF exports read back (tinygltf's loader): the asset's skeleton, skin and colliders, and a
// recorded simulation whose animation, evaluated at each frame, gives back the recorded
// skinning matrices and garment positions. (The Khronos validator runs on real exports in
// tests/tools/gltf_export_test.sh.)
#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "drape/bake/gltf_export.h"
#include "drape/formats/asset_file.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"

namespace drape::bake {
namespace {

const std::string kGolden = std::string(DRAPE_GOLDEN_DIR) + "/mannequin_colliders_v2.drape";

template <class T>
std::vector<T> Read(const tinygltf::Model& m, int accessor_index) {
  const tinygltf::Accessor& a = m.accessors[static_cast<size_t>(accessor_index)];
  const tinygltf::BufferView& v = m.bufferViews[static_cast<size_t>(a.bufferView)];
  const size_t components = static_cast<size_t>(tinygltf::GetNumComponentsInType(a.type));
  std::vector<T> out(a.count * components);
  std::memcpy(out.data(),
              m.buffers[static_cast<size_t>(v.buffer)].data.data() + v.byteOffset + a.byteOffset,
              out.size() * sizeof(T));
  return out;
}

tinygltf::Model Load(const std::string& path) {
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string error, warning;
  EXPECT_TRUE(loader.LoadBinaryFromFile(&model, &error, &warning, path)) << error;
  return model;
}

Mat34 FromTrs(const float* t, const float* r, const float* s) {
  Transform x;
  x.translation = {t[0], t[1], t[2]};
  x.rotation = {r[0], r[1], r[2], r[3]};
  x.scale = {s[0], s[1], s[2]};
  return ToMatrix(x);
}

// Node j's local transform at keyframe `frame` of the animation's channels.
Mat34 AnimatedLocal(const tinygltf::Model& m, const tinygltf::Animation& a, int node,
                    size_t frame) {
  float t[3] = {0, 0, 0}, r[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
  for (const tinygltf::AnimationChannel& c : a.channels) {
    if (c.target_node != node) continue;
    const std::vector<float> out =
        Read<float>(m, a.samplers[static_cast<size_t>(c.sampler)].output);
    float* dst = c.target_path == "translation" ? t : c.target_path == "rotation" ? r : s;
    const size_t n = c.target_path == "rotation" ? 4 : 3;
    for (size_t k = 0; k < n; ++k) dst[k] = out[frame * n + k];
  }
  return FromTrs(t, r, s);
}

TEST(GltfExport, SimulationAnimationGivesBackTheRecordedPosesAndGarments) {
  CharacterAsset asset;
  ASSERT_TRUE(ReadAssetFile(kGolden, &asset).ok());
  ASSERT_FALSE(asset.clips.empty());
  SkeletonPose pose;
  ASSERT_TRUE(pose.Init(asset.skeleton).ok());
  SimulationRecording recording;
  recording.frame_seconds = 0.1f;
  SimulationRecording::Garment sheet;
  sheet.name = "sheet";
  sheet.triangles = {0, 1, 2, 2, 1, 3};
  for (int f = 0; f < 6; ++f) {
    ASSERT_TRUE(pose.SampleClip(asset.clips[0], 0.13f * static_cast<float>(f), true).ok());
    recording.skinning.emplace_back(pose.skinning().begin(), pose.skinning().end());
    const float y = 1.f - 0.05f * static_cast<float>(f);
    sheet.positions.push_back(
        {{0, y, 0}, {0.5f, y, 0}, {0, y, 0.5f}, {0.5f, y + 0.01f * static_cast<float>(f), 0.5f}});
  }
  recording.garments.push_back(sheet);
  const std::string path = testing::TempDir() + "/simulation.glb";
  ASSERT_TRUE(WriteSimulationGltf(asset, recording, path).ok());

  const tinygltf::Model m = Load(path);
  ASSERT_EQ(m.animations.size(), 1u);
  const tinygltf::Animation& a = m.animations[0];
  const uint32_t joints = asset.skeleton.joint_count();
  const std::vector<float> ibm = Read<float>(m, m.skins[0].inverseBindMatrices);
  for (size_t f = 0; f < recording.skinning.size(); ++f) {
    std::vector<Mat34> world(joints);
    for (uint32_t j = 0; j < joints; ++j) {
      const Mat34 local = AnimatedLocal(m, a, static_cast<int>(j), f);
      const int32_t p = asset.skeleton.parents[j];
      world[j] = p < 0 ? local : Multiply(world[static_cast<size_t>(p)], local);
      Mat34 inverse_bind;  // glTF's column-major 4x4 back to row-major 3x4
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c)
          inverse_bind.m[r * 4 + c] = ibm[j * 16 + static_cast<size_t>(c * 4 + r)];
      const Mat34 skinning = Multiply(world[j], inverse_bind);
      for (int k = 0; k < 12; ++k)
        ASSERT_NEAR(skinning.m[k], recording.skinning[f][j].m[k], 2e-4f)
            << "frame " << f << " joint " << j;
    }
  }
  // The garment: frame 0 in the mesh, frame f = base + target f - 1, switched by STEP weights.
  const tinygltf::Mesh* mesh = nullptr;
  for (const tinygltf::Node& n : m.nodes)
    if (n.name == "sheet") mesh = &m.meshes[static_cast<size_t>(n.mesh)];
  ASSERT_NE(mesh, nullptr);
  const tinygltf::Primitive& prim = mesh->primitives[0];
  const std::vector<float> base = Read<float>(m, prim.attributes.at("POSITION"));
  ASSERT_EQ(prim.targets.size(), recording.skinning.size() - 1);
  for (size_t f = 1; f < recording.skinning.size(); ++f) {
    const std::vector<float> delta = Read<float>(m, prim.targets[f - 1].at("POSITION"));
    for (size_t i = 0; i < 4; ++i) {
      const Float3 want = sheet.positions[f][i];
      EXPECT_NEAR(base[3 * i] + delta[3 * i], want.x, 1e-6f);
      EXPECT_NEAR(base[3 * i + 1] + delta[3 * i + 1], want.y, 1e-6f);
      EXPECT_NEAR(base[3 * i + 2] + delta[3 * i + 2], want.z, 1e-6f);
    }
  }
  std::filesystem::remove(path);
}

TEST(GltfExport, AssetHoldsItsSkinAndCollidersOnTheirJoints) {
  CharacterAsset asset;
  ASSERT_TRUE(ReadAssetFile(kGolden, &asset).ok());
  const std::string path = testing::TempDir() + "/asset.glb";
  ASSERT_TRUE(WriteAssetGltf(asset, path).ok());
  const tinygltf::Model m = Load(path);
  const uint32_t joints = asset.skeleton.joint_count();
  ASSERT_EQ(m.skins[0].joints.size(), joints);
  size_t hulls = 0, spheres = 0;
  for (uint32_t j = 0; j < joints; ++j) {
    for (const int child : m.nodes[j].children) {
      const tinygltf::Node& n = m.nodes[static_cast<size_t>(child)];
      hulls += n.name.rfind("hull ", 0) == 0 ? 1 : 0;
      spheres += n.name.rfind("joint sphere ", 0) == 0 ? 1 : 0;
    }
  }
  EXPECT_EQ(hulls, asset.hulls.size());
  EXPECT_EQ(spheres, asset.joint_spheres.size());
  EXPECT_EQ(m.animations.size(), asset.clips.size());
  // Nothing is written where the path cannot be.
  EXPECT_FALSE(WriteAssetGltf(asset, testing::TempDir() + "/no/such/dir/x.glb").ok());
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace drape::bake

// glTF in and out. Out (read back with tinygltf's loader): the asset's skeleton, skin and
// colliders, a recorded simulation whose animation, evaluated at each frame, gives back the
// recorded skinning matrices and garment positions, and a garment bound to the skeleton. In: a
// scene's `gltf` garment, from drape's own export and from another file's skeleton (other units,
// joint order, seams), with every refusal naming its cause, and no crash on corrupt bytes.
// (The Khronos validator runs on real exports in tests/tools/gltf_export_test.sh.)
#include <gtest/gtest.h>
#include <tiny_gltf.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "drape/bake/gltf_export.h"
#include "drape/bake/scene.h"
#include "drape/formats/asset_file.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "scene/gltf_garment.h"
#include "test_support.h"

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
  size_t hulls = 0, spheres = 0, capsules = 0;
  for (uint32_t j = 0; j < joints; ++j) {
    for (const int child : m.nodes[j].children) {
      const tinygltf::Node& n = m.nodes[static_cast<size_t>(child)];
      hulls += n.name.rfind("hull ", 0) == 0 ? 1 : 0;
      spheres += n.name.rfind("joint sphere ", 0) == 0 ? 1 : 0;
      capsules += n.name.rfind("capsule ", 0) == 0 ? 1 : 0;
    }
  }
  EXPECT_EQ(hulls, asset.hulls.size());
  EXPECT_EQ(spheres, asset.joint_spheres.size());
  ASSERT_FALSE(asset.capsules.empty());
  EXPECT_EQ(capsules, asset.capsules.size());
  EXPECT_EQ(m.animations.size(), asset.clips.size());
  // Nothing is written where the path cannot be.
  EXPECT_FALSE(WriteAssetGltf(asset, testing::TempDir() + "/no/such/dir/x.glb").ok());
  std::filesystem::remove(path);
}

// ---- glTF garments --------------------------------------------------------------------------

constexpr float kInf = std::numeric_limits<float>::infinity();

// A band of 3 rings x 16 particles around the mannequin's hips at bind: ring 0 on the hips
// (max distance 0), ring 1 blending the hips and the nearer thigh (3 cm), ring 2 on that thigh
// (unlimited, 1 cm backstop).
GarmentExport HipBand(const SkeletonData& skeleton) {
  const auto joint = [&](const char* name) {
    return static_cast<uint32_t>(FindJoint(skeleton, name));
  };
  Mat34 hips_world;
  EXPECT_TRUE(InverseAffine(skeleton.inverse_bind[joint("hips")], &hips_world));
  const Float3 hips{hips_world.m[3], hips_world.m[7], hips_world.m[11]};
  GarmentExport g;
  g.name = "band";
  constexpr uint32_t kSegments = 16;
  for (uint32_t r = 0; r < 3; ++r) {
    for (uint32_t s = 0; s < kSegments; ++s) {
      const float a = 6.2831853f * static_cast<float>(s) / kSegments;
      const Float3 p =
          hips + Float3{0.2f * std::cos(a), -0.06f * static_cast<float>(r), 0.2f * std::sin(a)};
      g.bind_positions.push_back(p);
      ClothSkinWeights w;
      const uint32_t thigh = p.x > hips.x ? joint("hip_l") : joint("hip_r");
      w.joints[0] = r == 2 ? thigh : joint("hips");
      w.weights[0] = r == 1 ? 0.625f : 1.f;
      if (r == 1) w.joints[1] = thigh, w.weights[1] = 0.375f;
      g.skin.push_back(w);
      g.max_distance.push_back(r == 0 ? 0.f : r == 1 ? 0.03f : kInf);
      g.backstop.push_back(r == 2 ? 0.01f : kInf);
    }
  }
  for (uint32_t r = 0; r < 2; ++r) {
    for (uint32_t s = 0; s < kSegments; ++s) {
      const uint32_t a = r * kSegments + s, b = r * kSegments + (s + 1) % kSegments;
      g.triangles.insert(g.triangles.end(), {a, a + kSegments, b, b, a + kSegments, b + kSegments});
    }
  }
  return g;
}

// The demo scene (the mannequin) with one glTF garment.
Status ParseGltfScene(const nlohmann::json& garment, Scene* scene) {
  std::ifstream in(test::SourceDir() + "/samples/scenes/demo.json");
  nlohmann::json j = nlohmann::json::parse(in);
  j["garments"] = nlohmann::json::array({garment});
  return ParseScene(j, "scene.json", test::SourceDir() + "/samples/scenes", scene);
}

Status ResolveGltf(const nlohmann::json& garment, const CharacterAsset& asset,
                   ResolvedGarment* out) {
  Scene scene;
  if (Status s = ParseGltfScene(garment, &scene); !s.ok()) return s;
  if (Status s = ResolveGarment(scene, 0, asset.skeleton, out); !s.ok()) return s;
  return SkinGarment(scene, 0, asset.skeleton, asset.mesh, out);
}

// drape's export read back as a scene garment: the same particles (the body in the file is
// skipped by name), weights, bind positions, painted max distance (0 holds the ring on the
// skin) and backstop, unlimited ones kept unlimited.
TEST(GltfGarment, ExportedGarmentReadsBackWithItsSkinAndPaint) {
  CharacterAsset asset;
  ASSERT_TRUE(ReadAssetFile(kGolden, &asset).ok());
  const GarmentExport band = HipBand(asset.skeleton);
  const std::string path = testing::TempDir() + "/band.glb";
  ASSERT_TRUE(WriteGarmentGltf(asset, band, path).ok());
  ResolvedGarment g;
  Status s = ResolveGltf({{"type", "gltf"},
                          {"shape", {{"file", path}, {"mesh", "band"}}},
                          {"skin", {{"paint", "attribute"}}}},
                         asset, &g);
  ASSERT_TRUE(s.ok()) << s.message();
  const ClothDescription& d = g.description;
  ASSERT_EQ(d.positions.size(), band.bind_positions.size());
  EXPECT_EQ(d.triangles, band.triangles);
  for (size_t i = 0; i < d.positions.size(); ++i) {
    EXPECT_LT(Length(d.positions[i] - band.bind_positions[i]), 1e-5f) << i;
    EXPECT_LT(Length(d.skin_bind_positions[i] - band.bind_positions[i]), 1e-5f) << i;
    for (int k = 0; k < 4; ++k) {
      EXPECT_EQ(d.skin[i].joints[k], band.skin[i].joints[k]) << i;
      EXPECT_NEAR(d.skin[i].weights[k], band.skin[i].weights[k], 1e-6f) << i;
    }
    EXPECT_EQ(d.max_distance[i], band.max_distance[i]) << i;
    EXPECT_EQ(d.backstop[i], band.backstop[i]) << i;
  }
  Cloth cloth;
  ASSERT_TRUE(BuildCloth(d, &cloth).ok());
  EXPECT_EQ(cloth.kinematic_particles().size(), 16u);  // ring 0: max distance 0

  // The file holds the body too: without `mesh` the reader asks which.
  s = ResolveGltf({{"type", "gltf"}, {"shape", {{"file", path}}}}, asset, &g);
  EXPECT_NE(s.message().find("the file holds several meshes ('body' | 'band'); name one in `mesh`"),
            std::string::npos)
      << s.message();
  s = ResolveGltf({{"type", "gltf"}, {"shape", {{"file", path}, {"mesh", "band"}, {"scale", 2}}}},
                  asset, &g);
  EXPECT_NE(s.message().find("/garments/0: a skinned glTF garment is placed by its skin"),
            std::string::npos)
      << s.message();
  s = ResolveGltf({{"type", "gltf"},
                   {"shape", {{"file", path}, {"mesh", "band"}}},
                   {"skin", {{"weights_file", path}}}},
                  asset, &g);
  EXPECT_NE(s.message().find("the glTF garment has its own skin"), std::string::npos)
      << s.message();
  std::filesystem::remove(path);
}

// A glTF garment written by hand: positions, triangles, an optional skin (joint names, inverse
// bind matrices, four joints per vertex) and SCALAR float attributes; one node with `node_scale`.
struct HandFile {
  std::vector<Float3> positions;
  std::vector<uint32_t> triangles;
  std::vector<std::string> joint_names;
  std::vector<Mat34> inverse_bind;
  std::vector<uint16_t> joints;  // 4 per vertex
  std::vector<float> weights;    // 4 per vertex
  std::map<std::string, std::vector<float>> scalars;
  Float3 node_translation;
};

void WriteHandFile(const HandFile& f, const std::string& path) {
  tinygltf::Model m;
  m.asset.version = "2.0";
  m.buffers.emplace_back();
  const auto add = [&](const void* data, size_t bytes, int component, size_t count, int type) {
    std::vector<unsigned char>& buffer = m.buffers[0].data;
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = buffer.size();
    view.byteLength = bytes;
    buffer.insert(buffer.end(), static_cast<const unsigned char*>(data),
                  static_cast<const unsigned char*>(data) + bytes);
    m.bufferViews.push_back(view);
    tinygltf::Accessor a;
    a.bufferView = static_cast<int>(m.bufferViews.size()) - 1;
    a.componentType = component;
    a.count = count;
    a.type = type;
    m.accessors.push_back(a);
    return static_cast<int>(m.accessors.size()) - 1;
  };
  tinygltf::Primitive p;
  p.mode = TINYGLTF_MODE_TRIANGLES;
  p.attributes["POSITION"] =
      add(f.positions.data(), f.positions.size() * 12, TINYGLTF_COMPONENT_TYPE_FLOAT,
          f.positions.size(), TINYGLTF_TYPE_VEC3);
  p.indices = add(f.triangles.data(), f.triangles.size() * 4, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT,
                  f.triangles.size(), TINYGLTF_TYPE_SCALAR);
  for (const auto& [name, values] : f.scalars)
    p.attributes[name] = add(values.data(), values.size() * 4, TINYGLTF_COMPONENT_TYPE_FLOAT,
                             values.size(), TINYGLTF_TYPE_SCALAR);
  tinygltf::Node node;
  node.name = "garment";
  node.mesh = 0;
  node.translation = {f.node_translation.x, f.node_translation.y, f.node_translation.z};
  if (!f.joint_names.empty()) {
    p.attributes["JOINTS_0"] =
        add(f.joints.data(), f.joints.size() * 2, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
            f.joints.size() / 4, TINYGLTF_TYPE_VEC4);
    p.attributes["WEIGHTS_0"] =
        add(f.weights.data(), f.weights.size() * 4, TINYGLTF_COMPONENT_TYPE_FLOAT,
            f.weights.size() / 4, TINYGLTF_TYPE_VEC4);
    std::vector<float> matrices;
    for (const Mat34& ibm : f.inverse_bind)
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
          matrices.push_back(r < 3 ? ibm.m[r * 4 + c] : (c == 3 ? 1.f : 0.f));
    tinygltf::Skin skin;
    skin.inverseBindMatrices =
        add(matrices.data(), matrices.size() * 4, TINYGLTF_COMPONENT_TYPE_FLOAT,
            f.inverse_bind.size(), TINYGLTF_TYPE_MAT4);
    for (const std::string& name : f.joint_names) {
      tinygltf::Node joint;
      joint.name = name;
      m.nodes.push_back(joint);
      skin.joints.push_back(static_cast<int>(m.nodes.size()));  // after the garment node
    }
    m.skins.push_back(skin);
    node.skin = 0;
  }
  tinygltf::Mesh mesh;
  mesh.primitives.push_back(p);
  m.meshes.push_back(mesh);
  m.nodes.insert(m.nodes.begin(), node);
  tinygltf::Scene scene;
  for (size_t i = 0; i < m.nodes.size(); ++i) scene.nodes.push_back(static_cast<int>(i));
  m.scenes.push_back(scene);
  m.defaultScene = 0;
  tinygltf::TinyGLTF writer;
  ASSERT_TRUE(writer.WriteGltfSceneToFile(&m, path, false, true, false, true));
}

// The hip band from another tool: a skeleton in centimetres whose skin lists only the joints it
// uses, in reverse order; vertices split at a UV seam (column 0 written twice); distances
// painted in centimetres. Bound by name, welded, scaled to metres. Then the same file with one
// joint's bind moved 10 cm, a joint the character lacks, and without its skin.
TEST(GltfGarment, AnotherToolsFileBindsByJointNameInItsOwnUnits) {
  CharacterAsset asset;
  ASSERT_TRUE(ReadAssetFile(kGolden, &asset).ok());
  const SkeletonData& skeleton = asset.skeleton;
  const GarmentExport band = HipBand(skeleton);
  const size_t n = band.bind_positions.size();
  HandFile f;
  const char* names[] = {"hip_r", "hip_l", "hips"};  // the skin's order: reversed
  Mat34 to_centimetres;
  for (int k = 0; k < 3; ++k) to_centimetres.m[k * 5] = 100.f;
  Mat34 to_metres;
  ASSERT_TRUE(InverseAffine(to_centimetres, &to_metres));
  for (const char* name : names) {
    f.joint_names.push_back(name);
    f.inverse_bind.push_back(
        Multiply(skeleton.inverse_bind[static_cast<size_t>(FindJoint(skeleton, name))], to_metres));
  }
  const auto file_joint = [&](uint32_t joint) {
    for (uint16_t k = 0; k < 3; ++k)
      if (FindJoint(skeleton, names[k]) == static_cast<int32_t>(joint)) return k;
    return uint16_t{99};
  };
  const auto add_vertex = [&](size_t i) {
    f.positions.push_back(band.bind_positions[i] * 100.f);
    for (int k = 0; k < 4; ++k) {
      f.joints.push_back(band.skin[i].weights[k] > 0.f ? file_joint(band.skin[i].joints[k]) : 0);
      f.weights.push_back(band.skin[i].weights[k]);
    }
    f.scalars["_MAX_DISTANCE"].push_back(
        std::isfinite(band.max_distance[i]) ? band.max_distance[i] * 100.f : -1.f);
  };
  for (size_t i = 0; i < n; ++i) add_vertex(i);
  f.triangles = band.triangles;
  for (size_t t = 0; t < f.triangles.size(); ++t) {  // the seam: column 0 closing the ring
    const bool closing = (t / 3 % 32) / 2 == 15;     // the quad from column 15 to 0
    if (closing && f.triangles[t] % 16 == 0) {
      const uint32_t original = f.triangles[t];
      f.triangles[t] = static_cast<uint32_t>(f.positions.size());
      add_vertex(original);
    }
  }
  ASSERT_GT(f.positions.size(), n);
  const std::string path = testing::TempDir() + "/band_cm.glb";
  WriteHandFile(f, path);
  const nlohmann::json garment = {
      {"type", "gltf"}, {"shape", {{"file", path}}}, {"skin", {{"paint", "attribute"}}}};
  ResolvedGarment g;
  Status s = ResolveGltf(garment, asset, &g);
  ASSERT_TRUE(s.ok()) << s.message();
  const ClothDescription& d = g.description;
  ASSERT_EQ(d.positions.size(), n);  // welded
  for (size_t i = 0; i < n; ++i) {
    EXPECT_LT(Length(d.positions[i] - band.bind_positions[i]), 1e-5f) << i;
    std::map<uint32_t, float> want, got;  // by joint: the order may differ
    for (int k = 0; k < 4; ++k) {
      if (band.skin[i].weights[k] > 0.f) want[band.skin[i].joints[k]] += band.skin[i].weights[k];
      if (d.skin[i].weights[k] > 0.f) got[d.skin[i].joints[k]] += d.skin[i].weights[k];
    }
    ASSERT_EQ(got.size(), want.size()) << i;
    for (const auto& [joint, weight] : want) EXPECT_NEAR(got[joint], weight, 1e-6f) << i;
    if (std::isfinite(band.max_distance[i]))
      EXPECT_NEAR(d.max_distance[i], band.max_distance[i], 1e-6f) << i;
    else
      EXPECT_EQ(d.max_distance[i], kInf) << i;
  }
  Cloth cloth;
  ASSERT_TRUE(BuildCloth(d, &cloth).ok());

  HandFile moved = f;  // hip_l bound 10 cm higher than the character's
  moved.inverse_bind[1] = Multiply(moved.inverse_bind[1], TranslationMatrix({0.f, -10.f, 0.f}));
  WriteHandFile(moved, path);
  s = ResolveGltf(garment, asset, &g);
  EXPECT_NE(s.message().find("joint 'hip_l' places vertex"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("from where joint 'hips' does"), std::string::npos) << s.message();

  HandFile renamed = f;
  renamed.joint_names[2] = "hipz";
  WriteHandFile(renamed, path);
  s = ResolveGltf(garment, asset, &g);
  EXPECT_NE(s.message().find("/garments/0/shape/file: the garment's skin joint 'hipz' is not a "
                             "joint of the character (did you mean hips"),
            std::string::npos)
      << s.message();

  HandFile unskinned;  // placed by its node, then the scene's scale and offset
  unskinned.positions = {{0, 0, 0}, {10, 0, 0}, {0, 0, 10}};
  unskinned.triangles = {0, 1, 2};
  unskinned.node_translation = {0, 100, 0};
  WriteHandFile(unskinned, path);
  s = ResolveGltf(
      {{"type", "gltf"}, {"shape", {{"file", path}, {"scale", 0.01}, {"offset", {0.5, 0, 0}}}}},
      asset, &g);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(g.description.positions.size(), 3u);
  EXPECT_LT(Length(g.description.positions[1] - Float3{0.6f, 1.f, 0.f}), 1e-6f);
  s = ResolveGltf(
      {{"type", "gltf"}, {"shape", {{"file", path}}}, {"skin", {{"paint", "attribute"}}}}, asset,
      &g);
  EXPECT_NE(s.message().find("/skin/paint: the glTF garment has no _MAX_DISTANCE attribute"),
            std::string::npos)
      << s.message();
  std::filesystem::remove(path);
}

// Corrupt files: every truncation and sampled byte flip of an export is read or refused with a
// message naming the scene path; none crashes or reads beyond its buffers (the accessors are
// checked against their buffers before any read).
TEST(GltfGarment, CorruptFilesAreRefusedNotRead) {
  CharacterAsset asset;
  ASSERT_TRUE(ReadAssetFile(kGolden, &asset).ok());
  const std::string good = testing::TempDir() + "/good.glb", bad = testing::TempDir() + "/bad.glb";
  ASSERT_TRUE(WriteGarmentGltf(asset, HipBand(asset.skeleton), good).ok());
  std::ifstream in(good, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto read = [&](const std::string& content) {
    std::ofstream(bad, std::ios::binary) << content;
    detail::GltfGarmentMesh mesh;
    const Status s =
        detail::ReadGltfGarment(bad, "scene.json: /garments/0/shape/file", "band", &mesh);
    if (!s.ok()) {
      EXPECT_EQ(s.message().rfind("scene.json: /garments/0/shape/file: " + bad, 0), 0u);
    }
    return s.ok();
  };
  EXPECT_TRUE(read(bytes));
  size_t refused = 0;
  for (size_t cut = 0; cut < bytes.size(); cut += bytes.size() / 61 + 1)
    refused += read(bytes.substr(0, cut)) ? 0 : 1;
  EXPECT_GE(refused, 55u);
  std::mt19937 random(7);
  for (int flip = 0; flip < 300; ++flip) {
    std::string copy = bytes;
    for (int k = 0; k < 4; ++k)
      copy[random() % copy.size()] ^= static_cast<char>(1 + random() % 255);
    read(copy);
  }
  std::filesystem::remove(good);
  std::filesystem::remove(bad);
}

}  // namespace
}  // namespace drape::bake

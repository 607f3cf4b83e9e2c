// Import of every shared character, checked against assimp's node hierarchy evaluated here,
// independently of the importer: the runtime's skinned mesh at clip times on the resampling grid
// must match sum_j w_j * G_t(node_j) * Offset_j * x (skinned meshes) or G_t(node) * x (rigid
// meshes), mapped to the asset frame, within 1e-4 of the character's height.

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <gtest/gtest.h>

#include <assimp/Importer.hpp>
#include <cmath>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "drape/bake/importer.h"
#include "drape/formats/asset_file.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"
#include "test_support.h"

namespace drape {
namespace {

using bake::Character;
using bake::ImportCharacter;
using bake::ImportOptions;

// --- The independent reference: assimp scene graph, evaluated with assimp's own math.
struct Reference {
  Assimp::Importer importer;
  const aiScene* scene = nullptr;
  std::map<std::string, const aiNode*> node_by_name;  // prefers nodes without meshes

  void Index(const aiNode* n) {
    auto it = node_by_name.find(n->mName.C_Str());
    if (it == node_by_name.end() || (it->second->mNumMeshes > 0 && n->mNumMeshes == 0)) {
      node_by_name[n->mName.C_Str()] = n;
    }
    for (unsigned c = 0; c < n->mNumChildren; ++c) Index(n->mChildren[c]);
  }

  template <class Key>
  static const Key* Bracket(const Key* keys, unsigned count, double tick, float* alpha) {
    *alpha = 0.f;
    if (count == 1 || tick <= keys[0].mTime) return keys;
    if (tick >= keys[count - 1].mTime) return keys + count - 1;
    unsigned i = 0;
    while (keys[i + 1].mTime <= tick) ++i;
    *alpha = static_cast<float>((tick - keys[i].mTime) / (keys[i + 1].mTime - keys[i].mTime));
    return keys + i;
  }

  aiMatrix4x4 Local(const aiNode* node, const aiAnimation* anim, double tick) const {
    if (anim == nullptr) return node->mTransformation;
    for (unsigned c = 0; c < anim->mNumChannels; ++c) {
      const aiNodeAnim* ch = anim->mChannels[c];
      auto it = node_by_name.find(ch->mNodeName.C_Str());
      if (it == node_by_name.end() || it->second != node) continue;
      aiVector3D s, p;
      aiQuaternion r;
      node->mTransformation.Decompose(s, r, p);
      float a = 0.f;
      if (ch->mNumPositionKeys) {
        const aiVectorKey* k = Bracket(ch->mPositionKeys, ch->mNumPositionKeys, tick, &a);
        p = a > 0.f ? k[0].mValue + (k[1].mValue - k[0].mValue) * a : k[0].mValue;
      }
      if (ch->mNumRotationKeys) {
        const aiQuatKey* k = Bracket(ch->mRotationKeys, ch->mNumRotationKeys, tick, &a);
        if (a > 0.f) {
          aiQuaternion::Interpolate(r, k[0].mValue, k[1].mValue, a);
        } else {
          r = k[0].mValue;
        }
        r.Normalize();
      }
      if (ch->mNumScalingKeys) {
        const aiVectorKey* k = Bracket(ch->mScalingKeys, ch->mNumScalingKeys, tick, &a);
        s = a > 0.f ? k[0].mValue + (k[1].mValue - k[0].mValue) * a : k[0].mValue;
      }
      return aiMatrix4x4(s, r, p);
    }
    return node->mTransformation;
  }

  aiMatrix4x4 Global(const aiNode* node, const aiAnimation* anim, double tick) const {
    aiMatrix4x4 m = Local(node, anim, tick);
    for (const aiNode* p = node->mParent; p != nullptr; p = p->mParent)
      m = Local(p, anim, tick) * m;
    return m;
  }

  // World positions (source frame) of every vertex of every mesh instance.
  std::vector<aiVector3D> Posed(const aiAnimation* anim, double tick) const {
    std::vector<aiVector3D> out;
    std::vector<const aiNode*> stack{scene->mRootNode};
    while (!stack.empty()) {
      const aiNode* node = stack.back();
      stack.pop_back();
      for (unsigned c = 0; c < node->mNumChildren; ++c) stack.push_back(node->mChildren[c]);
      for (unsigned k = 0; k < node->mNumMeshes; ++k) {
        const aiMesh* m = scene->mMeshes[node->mMeshes[k]];
        if (m->mNumBones == 0) {
          const aiMatrix4x4 g = Global(node, anim, tick);
          for (unsigned v = 0; v < m->mNumVertices; ++v) out.push_back(g * m->mVertices[v]);
          continue;
        }
        std::vector<aiVector3D> sum(m->mNumVertices, aiVector3D(0, 0, 0));
        std::vector<float> weight(m->mNumVertices, 0.f);
        for (unsigned b = 0; b < m->mNumBones; ++b) {
          const aiBone* bone = m->mBones[b];
          const aiMatrix4x4 skin =
              Global(node_by_name.at(bone->mName.C_Str()), anim, tick) * bone->mOffsetMatrix;
          for (unsigned w = 0; w < bone->mNumWeights; ++w) {
            const aiVertexWeight& vw = bone->mWeights[w];
            sum[vw.mVertexId] += (skin * m->mVertices[vw.mVertexId]) * vw.mWeight;
            weight[vw.mVertexId] += vw.mWeight;
          }
        }
        for (unsigned v = 0; v < m->mNumVertices; ++v) {
          if (weight[v] > 0.f) out.push_back(sum[v] / weight[v]);  // renormalised, as drape does
        }
      }
    }
    return out;
  }
};

// Largest distance from any point of `a` to its nearest point of `b` (brute force).
double OneSidedHausdorff(const std::vector<Float3>& a, const std::vector<Float3>& b) {
  double worst = 0;
  for (const Float3& p : a) {
    double best = INFINITY;
    for (const Float3& q : b) {
      const double dx = p.x - q.x, dy = p.y - q.y, dz = p.z - q.z;
      best = std::min(best, dx * dx + dy * dy + dz * dz);
    }
    worst = std::max(worst, best);
  }
  return std::sqrt(worst);
}

struct CharacterCase {
  const char* path;  // relative to shared/assets/characters, or "" for the built-in mannequin
  uint32_t min_joints;
};

class ImportEveryCharacter : public ::testing::TestWithParam<CharacterCase> {};

TEST_P(ImportEveryCharacter, RuntimeSkinningMatchesAssimpHierarchy) {
  const std::string path =
      *GetParam().path ? test::CharacterPath(GetParam().path) : test::MannequinPath();
  DRAPE_REQUIRE_FILE(path);
  Character character;
  const Status status = ImportCharacter(path, ImportOptions{}, &character);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_GE(character.skeleton.joint_count(), GetParam().min_joints);
  CharacterAsset asset;
  asset.info = character.info;
  asset.skeleton = character.skeleton;
  asset.clips = character.clips;
  asset.mesh = character.mesh;
  ASSERT_TRUE(ValidateAsset(asset).ok()) << ValidateAsset(asset).message();

  Reference ref;
  ref.scene =
      ref.importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                      aiProcess_SortByPType | aiProcess_ValidateDataStructure);
  ASSERT_NE(ref.scene, nullptr);
  ref.Index(ref.scene->mRootNode);
  const Mat34& to_asset = character.info.source_to_asset;

  SkeletonPose pose;
  ASSERT_TRUE(pose.Init(asset.skeleton).ok());
  std::vector<Float3> posed(asset.mesh.vertex_count());
  float height = 0.f;
  {
    float lo = INFINITY, hi = -INFINITY;
    pose.SetRest();
    ASSERT_TRUE(SkinMesh(asset.mesh, pose.skinning(), posed).ok());
    for (const Float3& p : posed) lo = std::min(lo, p.y), hi = std::max(hi, p.y);
    height = hi - lo;
  }
  EXPECT_GT(height, 0.05f) << "the character should be taller than 5 cm in metres";
  EXPECT_LT(height, 10.f) << "the character should be shorter than 10 m in metres";
  const double tolerance = 1e-4 * height;

  // The rest pose, then every clip at a few times on its resampling grid.
  struct Sample {
    int clip;
    uint32_t frame;
  };
  std::vector<Sample> samples{{-1, 0}};
  for (int c = 0; c < static_cast<int>(asset.clips.size()) && c < 3; ++c) {
    const uint32_t frames = asset.clips[c].frame_count;
    for (uint32_t f : {0u, frames / 3, (2 * frames) / 3, frames - 1}) samples.push_back({c, f});
  }
  for (const Sample& s : samples) {
    const aiAnimation* anim = nullptr;
    double tick = 0;
    if (s.clip < 0) {
      pose.SetRest();
    } else {
      const ClipData& clip = asset.clips[s.clip];
      const float time = std::min(static_cast<float>(s.frame) / clip.sample_rate, clip.duration);
      ASSERT_TRUE(pose.SampleClip(clip, time, false).ok());
      anim = ref.scene->mAnimations[s.clip];
      const double tps = anim->mTicksPerSecond > 0 ? anim->mTicksPerSecond : 25.0;
      tick = std::min(static_cast<double>(s.frame) / clip.sample_rate,
                      static_cast<double>(clip.duration)) *
             tps;
    }
    ASSERT_TRUE(SkinMesh(asset.mesh, pose.skinning(), posed).ok());
    std::vector<Float3> expected;
    for (const aiVector3D& p : ref.Posed(anim, tick))
      expected.push_back(TransformPoint(to_asset, {p.x, p.y, p.z}));
    const double forward = OneSidedHausdorff(posed, expected);
    const double backward = OneSidedHausdorff(expected, posed);
    EXPECT_LT(forward, tolerance) << path << " clip " << s.clip << " frame " << s.frame;
    EXPECT_LT(backward, tolerance) << path << " clip " << s.clip << " frame " << s.frame;
  }
}

INSTANTIATE_TEST_SUITE_P(
    SharedCharacters, ImportEveryCharacter,
    ::testing::Values(CharacterCase{"", 17}, CharacterCase{"RiggedSimple/RiggedSimple.gltf", 2},
                      CharacterCase{"RiggedFigure/RiggedFigure.glb", 19},
                      CharacterCase{"CesiumMan/CesiumMan.glb", 19},
                      CharacterCase{"Fox/Fox.glb", 24},
                      CharacterCase{"RobotExpressive/RobotExpressive.glb", 43},
                      CharacterCase{"QuaterniusAnimatedHuman/Animated_Human.fbx", 41},
                      CharacterCase{"QuaterniusSpider/Spider.fbx", 39}),
    [](const auto& param_info) { return test::CharacterTestName(param_info.param.path); });

TEST(Importer, UnitsAndUpAxisDetected) {
  const std::string fox = test::CharacterPath("Fox/Fox.glb");
  DRAPE_REQUIRE_FILE(fox);
  Character character;
  ASSERT_TRUE(ImportCharacter(fox, ImportOptions{}, &character).ok());
  EXPECT_NEAR(character.info.unit_scale, 0.01f, 1e-6f) << "Fox is authored in centimetres";
  ImportOptions forced;
  forced.unit_scale = 0.5;
  forced.up_axis = "+Z";
  ASSERT_TRUE(ImportCharacter(fox, forced, &character).ok());
  EXPECT_FLOAT_EQ(character.info.unit_scale, 0.5f);
  EXPECT_EQ(character.info.up_axis, "+Z");
  // +Z up maps source z to asset y: row 1 of the 3x4 is (0, 0, s | 0).
  EXPECT_FLOAT_EQ(character.info.source_to_asset.m[6], 0.5f);
}

TEST(Importer, WeightsAreRenormalisedAndRigidPartsKept) {
  const std::string robot = test::CharacterPath("RobotExpressive/RobotExpressive.glb");
  DRAPE_REQUIRE_FILE(robot);
  Character character;
  ASSERT_TRUE(ImportCharacter(robot, ImportOptions{}, &character).ok());
  const MeshData& mesh = character.mesh;
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    float sum = 0.f;
    for (uint32_t k = mesh.influence_offsets[v]; k < mesh.influence_offsets[v + 1]; ++k)
      sum += mesh.influence_weights[k];
    ASSERT_NEAR(sum, 1.f, 1e-5f) << "vertex " << v;
  }
  bool warned = false;
  for (const std::string& w : character.warnings)
    warned |= w.find("weight sums outside") != std::string::npos;
  EXPECT_TRUE(warned) << "RobotExpressive's skinned hands have raw weight sums up to 1.755";
}

TEST(Importer, CharacterWithoutSkeletonIsOneRigidRoot) {
  const std::string path = ::testing::TempDir() + "/tetrahedron.obj";
  {
    std::ofstream obj(path);
    obj << "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  }
  Character character;
  const Status s = ImportCharacter(path, ImportOptions{}, &character);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(character.skeleton.joint_count(), 1u);
  EXPECT_EQ(character.skeleton.joint_names[0], "root");
  EXPECT_TRUE(character.clips.empty());
  EXPECT_EQ(character.mesh.triangle_count(), 4u);
  for (uint32_t v = 0; v < character.mesh.vertex_count(); ++v) {
    ASSERT_EQ(character.mesh.influence_offsets[v + 1] - character.mesh.influence_offsets[v], 1u);
    EXPECT_EQ(character.mesh.influence_weights[character.mesh.influence_offsets[v]], 1.f);
  }
}

TEST(Importer, InwardWoundComponentsAreFlipped) {
  // The same tetrahedron wound inward: the importer must orient it outward and say so.
  const std::string path = ::testing::TempDir() + "/inward.obj";
  {
    std::ofstream obj(path);
    obj << "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nf 1 2 3\nf 1 4 2\nf 1 3 4\nf 2 4 3\n";
  }
  Character character;
  ASSERT_TRUE(ImportCharacter(path, ImportOptions{}, &character).ok());
  double volume = 0;
  const MeshData& m = character.mesh;
  for (uint32_t t = 0; t < m.triangle_count(); ++t) {
    const Float3 a = m.positions[m.triangles[3 * t]], b = m.positions[m.triangles[3 * t + 1]],
                 c = m.positions[m.triangles[3 * t + 2]];
    volume += Dot(a, Cross(b, c)) / 6.0;
  }
  EXPECT_GT(volume, 0.0);
  bool reported = false;
  for (const std::string& w : character.warnings)
    reported |= w.find("wound inward") != std::string::npos;
  EXPECT_TRUE(reported);
}

TEST(Importer, BadInputsFailWithTheFileNamed) {
  Character character;
  const std::string missing = "/nonexistent/character.glb";
  Status s = ImportCharacter(missing, ImportOptions{}, &character);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find(missing), std::string::npos);
  EXPECT_NE(s.message().find("not found"), std::string::npos);
  ImportOptions bad_axis;
  bad_axis.up_axis = "up";
  s = ImportCharacter(test::MannequinPath(), bad_axis, &character);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("up_axis"), std::string::npos);
}

}  // namespace
}  // namespace drape

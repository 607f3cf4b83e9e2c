#include "import/scene_repair.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <set>
#include <utility>

#include "import/import_messages.h"

namespace drape::bake::detail {
namespace {

// A loader may leave a string without its terminator or with a wrong length.
void RepairString(aiString* s) {
  s->data[MAXLEN - 1] = '\0';
  s->length = static_cast<ai_uint32>(std::strlen(s->data));
}

std::string Name(const aiString& s) { return std::string(s.data, s.length); }

template <typename T>
void DeleteAll(T**& items, unsigned& count) {
  if (items != nullptr) {
    for (unsigned i = 0; i < count; ++i) delete items[i];
    delete[] items;
  }
  items = nullptr;
  count = 0;
}

// Keeps the items `keep` accepts, in order; the others are deleted. A pointer array left empty
// is freed, as validation refuses an empty array that is not null.
template <typename T, typename Keep>
void CompactPointers(T**& items, unsigned& count, Keep keep) {
  if (items == nullptr) {
    count = 0;
    return;
  }
  unsigned kept = 0;
  for (unsigned i = 0; i < count; ++i) {
    if (keep(items[i])) {
      items[kept++] = items[i];
    } else {
      delete items[i];
    }
  }
  count = kept;
  if (count == 0) {
    delete[] items;
    items = nullptr;
  }
}

// Lights, cameras and embedded textures: a character bake reads none of them, and each has
// checks of its own that would refuse the file.
void DropUnusedContent(aiScene* scene) {
  DeleteAll(scene->mLights, scene->mNumLights);
  DeleteAll(scene->mCameras, scene->mNumCameras);
  DeleteAll(scene->mTextures, scene->mNumTextures);
}

// Node links: every node reached once (a cycle or a shared child is cut and refused, as assimp
// would recurse forever or free the node twice), parents set, null children and missing or
// repeated mesh references removed.
Status RepairNodes(const std::string& path, aiScene* scene, std::vector<std::string>* warnings) {
  if (scene->mRootNode == nullptr) return SourceError(path, StatusCode::kCorrupt, "no root node");
  scene->mRootNode->mParent = nullptr;
  std::set<const aiNode*> seen{scene->mRootNode};
  std::vector<aiNode*> stack{scene->mRootNode};
  bool cut = false;
  size_t bad_mesh_references = 0;
  while (!stack.empty()) {
    aiNode* node = stack.back();
    stack.pop_back();
    RepairString(&node->mName);
    if (node->mChildren == nullptr) node->mNumChildren = 0;
    unsigned kept = 0;
    for (unsigned c = 0; c < node->mNumChildren; ++c) {
      aiNode* child = node->mChildren[c];
      if (child == nullptr) continue;
      if (!seen.insert(child).second) {
        cut = true;
        continue;
      }
      child->mParent = node;
      node->mChildren[kept++] = child;
      stack.push_back(child);
    }
    node->mNumChildren = kept;
    if (node->mMeshes == nullptr) node->mNumMeshes = 0;
    std::set<unsigned> meshes;
    kept = 0;
    for (unsigned m = 0; m < node->mNumMeshes; ++m) {
      const unsigned mesh = node->mMeshes[m];
      if (mesh >= scene->mNumMeshes || !meshes.insert(mesh).second) {
        ++bad_mesh_references;
        continue;
      }
      node->mMeshes[kept++] = mesh;
    }
    node->mNumMeshes = kept;
  }
  if (cut) {
    return SourceError(path, StatusCode::kCorrupt,
                       "the node hierarchy is cyclic or shares a node between parents");
  }
  if (bad_mesh_references > 0) {
    warnings->push_back(std::to_string(bad_mesh_references) +
                        " node references to missing or repeated meshes removed");
  }
  return Status::Ok();
}

// Faces with no corner, no index array or a corner past the vertices are dropped (in place: a
// dropped face keeps its own index array, which delete[] frees). Returns how many.
size_t DropBadFaces(aiMesh* mesh) {
  unsigned kept = 0;
  for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
    aiFace& face = mesh->mFaces[f];
    bool good =
        face.mIndices != nullptr && face.mNumIndices > 0 && face.mNumIndices <= AI_MAX_FACE_INDICES;
    for (unsigned k = 0; good && k < face.mNumIndices; ++k)
      good = face.mIndices[k] < mesh->mNumVertices;
    if (!good) continue;
    std::swap(mesh->mFaces[kept].mIndices, face.mIndices);
    std::swap(mesh->mFaces[kept].mNumIndices, face.mNumIndices);
    ++kept;
  }
  const size_t dropped = mesh->mNumFaces - kept;
  mesh->mNumFaces = kept;
  return dropped;
}

// The primitive-type flags exactly as the faces are (a loader that over-reports polygons makes
// assimp's triangulation assert).
void RecomputePrimitiveTypes(aiMesh* mesh) {
  unsigned types = 0;
  for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
    const unsigned n = mesh->mFaces[f].mNumIndices;
    types |= n == 1   ? aiPrimitiveType_POINT
             : n == 2 ? aiPrimitiveType_LINE
             : n == 3 ? aiPrimitiveType_TRIANGLE
                      : aiPrimitiveType_POLYGON;
  }
  mesh->mPrimitiveTypes = types;
}

// Texture-coordinate and colour channels moved down over gaps; tangents without bitangents (or
// the reverse) removed, as drape reads neither.
void RepairVertexChannels(aiMesh* mesh) {
  unsigned uv = 0;
  for (unsigned c = 0; c < AI_MAX_NUMBER_OF_TEXTURECOORDS; ++c) {
    if (mesh->mTextureCoords[c] == nullptr) continue;
    std::swap(mesh->mTextureCoords[uv], mesh->mTextureCoords[c]);
    std::swap(mesh->mNumUVComponents[uv], mesh->mNumUVComponents[c]);
    ++uv;
  }
  unsigned colour = 0;
  for (unsigned c = 0; c < AI_MAX_NUMBER_OF_COLOR_SETS; ++c) {
    if (mesh->mColors[c] != nullptr) std::swap(mesh->mColors[colour++], mesh->mColors[c]);
  }
  if ((mesh->mTangents == nullptr) != (mesh->mBitangents == nullptr)) {
    delete[] mesh->mTangents;
    delete[] mesh->mBitangents;
    mesh->mTangents = nullptr;
    mesh->mBitangents = nullptr;
  }
}

// Null bones removed; weight arrays that are missing, or weights on a vertex past the mesh or on
// a vertex no face uses, removed (JoinIdenticalVertices would otherwise leave the latter behind
// with stale vertex numbers). Returns how many weights named a missing vertex.
size_t RepairBones(aiMesh* mesh) {
  CompactPointers(mesh->mBones, mesh->mNumBones, [](const aiBone* b) { return b != nullptr; });
  std::vector<bool> used(mesh->mNumVertices, false);
  for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
    const aiFace& face = mesh->mFaces[f];
    for (unsigned k = 0; k < face.mNumIndices; ++k) used[face.mIndices[k]] = true;
  }
  size_t missing = 0;
  for (unsigned b = 0; b < mesh->mNumBones; ++b) {
    aiBone* bone = mesh->mBones[b];
    RepairString(&bone->mName);
    if (bone->mWeights == nullptr) bone->mNumWeights = 0;
    unsigned kept = 0;
    for (unsigned w = 0; w < bone->mNumWeights; ++w) {
      const aiVertexWeight weight = bone->mWeights[w];
      if (weight.mVertexId >= mesh->mNumVertices) ++missing;
      if (weight.mVertexId >= mesh->mNumVertices || !used[weight.mVertexId]) continue;
      bone->mWeights[kept++] = weight;
    }
    bone->mNumWeights = kept;
  }
  return missing;
}

// Meshes left without faces, removed, and the nodes' references renumbered.
void RemoveEmptyMeshes(aiScene* scene) {
  std::vector<unsigned> new_index(scene->mNumMeshes, ~0u);
  unsigned kept = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    if (scene->mMeshes[m]->mNumFaces == 0) {
      delete scene->mMeshes[m];
      continue;
    }
    new_index[m] = kept;
    scene->mMeshes[kept++] = scene->mMeshes[m];
  }
  if (kept == scene->mNumMeshes) return;
  scene->mNumMeshes = kept;
  std::vector<aiNode*> stack{scene->mRootNode};
  while (!stack.empty()) {
    aiNode* node = stack.back();
    stack.pop_back();
    unsigned refs = 0;
    for (unsigned r = 0; r < node->mNumMeshes; ++r) {
      if (new_index[node->mMeshes[r]] != ~0u) node->mMeshes[refs++] = new_index[node->mMeshes[r]];
    }
    node->mNumMeshes = refs;
    for (unsigned c = 0; c < node->mNumChildren; ++c) stack.push_back(node->mChildren[c]);
  }
}

Status RepairMeshes(const std::string& path, aiScene* scene, std::vector<std::string>* warnings) {
  if (scene->mMeshes == nullptr || scene->mNumMeshes == 0)
    return SourceError(path, StatusCode::kCorrupt, "the scene has no meshes");
  size_t dropped_faces = 0, missing_weights = 0, points_and_lines = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    aiMesh* mesh = scene->mMeshes[m];
    if (mesh == nullptr) return SourceError(path, StatusCode::kCorrupt, "a mesh is missing");
    RepairString(&mesh->mName);
    if (mesh->mVertices == nullptr || mesh->mNumVertices == 0 || mesh->mFaces == nullptr) {
      return SourceError(path, StatusCode::kCorrupt,
                         "mesh '" + Name(mesh->mName) + "' has no vertex or face array");
    }
    if (mesh->mNumBones > 0 && mesh->mBones == nullptr) {
      return SourceError(path, StatusCode::kCorrupt,
                         "mesh '" + Name(mesh->mName) + "' has bones but no bone array");
    }
    dropped_faces += DropBadFaces(mesh);
    for (unsigned f = 0; f < mesh->mNumFaces; ++f)
      points_and_lines += mesh->mFaces[f].mNumIndices < 3;
    RecomputePrimitiveTypes(mesh);
    RepairVertexChannels(mesh);
    missing_weights += RepairBones(mesh);
    if (scene->mNumMaterials > 0 && mesh->mMaterialIndex >= scene->mNumMaterials)
      mesh->mMaterialIndex = 0;
  }
  if (dropped_faces > 0) {
    warnings->push_back(std::to_string(dropped_faces) +
                        " faces dropped: no corners, or a corner past the mesh's vertices");
  }
  if (points_and_lines > 0) {
    warnings->push_back(std::to_string(points_and_lines) +
                        " faces with one or two corners (points and lines) dropped");
  }
  if (missing_weights > 0) {
    warnings->push_back(std::to_string(missing_weights) +
                        " bone weights dropped: they name a vertex the mesh does not have");
  }
  RemoveEmptyMeshes(scene);
  if (scene->mNumMeshes == 0)
    return SourceError(path, StatusCode::kCorrupt, "no mesh has a face with valid corners");
  return Status::Ok();
}

// A material with a missing property array or a null or empty property becomes an empty one
// (drape reads no material); an index past the materials, a missing array, likewise repaired.
void RepairMaterials(aiScene* scene) {
  if (scene->mNumMaterials == 0) {
    delete[] scene->mMaterials;
    scene->mMaterials = nullptr;
    return;
  }
  if (scene->mMaterials == nullptr) {
    scene->mMaterials = new aiMaterial*[scene->mNumMaterials]();
  }
  for (unsigned i = 0; i < scene->mNumMaterials; ++i) {
    aiMaterial*& material = scene->mMaterials[i];
    bool broken =
        material == nullptr || (material->mNumProperties > 0 && material->mProperties == nullptr);
    for (unsigned p = 0; !broken && p < material->mNumProperties; ++p) {
      const aiMaterialProperty* property = material->mProperties[p];
      broken = property == nullptr || property->mData == nullptr || property->mDataLength == 0;
    }
    if (!broken) continue;
    if (material != nullptr && material->mProperties == nullptr) material->mNumProperties = 0;
    delete material;
    material = new aiMaterial();
  }
}

// A key track as validation wants it: no key at a non-finite time, times increasing (sorted
// stably, so the last of several keys at one time is the one kept). Returns whether it changed
// the order or dropped a key; *last is the latest key time.
template <typename Key>
bool RepairKeyTrack(Key*& keys, unsigned& count, double* last) {
  if (keys == nullptr) count = 0;
  const unsigned original = count;
  count = static_cast<unsigned>(
      std::remove_if(keys, keys + count, [](const Key& k) { return !std::isfinite(k.mTime); }) -
      keys);
  const bool sorted = std::is_sorted(keys, keys + count,
                                     [](const Key& a, const Key& b) { return a.mTime < b.mTime; });
  std::stable_sort(keys, keys + count,
                   [](const Key& a, const Key& b) { return a.mTime < b.mTime; });
  unsigned kept = 0;
  for (unsigned i = 0; i < count; ++i) {
    if (kept > 0 && keys[kept - 1].mTime == keys[i].mTime) {
      keys[kept - 1] = keys[i];
    } else {
      keys[kept++] = keys[i];
    }
  }
  count = kept;
  if (count > 0) *last = std::max(*last, keys[count - 1].mTime);
  return !sorted || count != original;
}

// One clip: morph-target channels (unused) dropped, channels without keys dropped, keys sorted,
// then ticks per second and a duration that covers every key. False when no channel is left.
bool RepairAnimation(aiAnimation* anim, const std::string& name,
                     std::vector<std::string>* warnings) {
  DeleteAll(anim->mMorphMeshChannels, anim->mNumMorphMeshChannels);
  if (anim->mChannels == nullptr) anim->mNumChannels = 0;
  size_t reordered = 0;
  double last = 0.0;
  CompactPointers(anim->mChannels, anim->mNumChannels, [&](aiNodeAnim* channel) {
    if (channel == nullptr) return false;
    RepairString(&channel->mNodeName);
    bool changed = RepairKeyTrack(channel->mPositionKeys, channel->mNumPositionKeys, &last);
    changed |= RepairKeyTrack(channel->mRotationKeys, channel->mNumRotationKeys, &last);
    changed |= RepairKeyTrack(channel->mScalingKeys, channel->mNumScalingKeys, &last);
    reordered += changed;
    return channel->mNumPositionKeys + channel->mNumRotationKeys + channel->mNumScalingKeys > 0;
  });
  if (anim->mNumChannels == 0) {
    warnings->push_back("clip '" + name + "' skipped: it animates no node");
    return false;
  }
  if (reordered > 0) {
    warnings->push_back("clip '" + name + "': keys of " + std::to_string(reordered) +
                        " channels were out of order, repeated or at a non-finite time; sorted, "
                        "the last key of a time kept");
  }
  if (!(anim->mTicksPerSecond > 0.0 && std::isfinite(anim->mTicksPerSecond))) {
    warnings->push_back("clip '" + name + "': " + Fmt(anim->mTicksPerSecond) +
                        " ticks per second; 25 used");
    anim->mTicksPerSecond = 25.0;
  }
  if (!(anim->mDuration > 0.0 && std::isfinite(anim->mDuration))) {
    warnings->push_back("clip '" + name + "': duration " + Fmt(anim->mDuration) +
                        " ticks; the last key's time, " + Fmt(last) + ", used");
    anim->mDuration = last;
  } else if (last > anim->mDuration) {
    warnings->push_back("clip '" + name + "': keys run to tick " + Fmt(last) +
                        ", past its duration of " + Fmt(anim->mDuration) +
                        " ticks; the duration extended to the last key");
    anim->mDuration = last;
  }
  return true;
}

void RepairAnimations(aiScene* scene, std::vector<std::string>* warnings) {
  if (scene->mAnimations == nullptr) scene->mNumAnimations = 0;
  unsigned index = 0;
  CompactPointers(scene->mAnimations, scene->mNumAnimations, [&](aiAnimation* anim) {
    const unsigned a = index++;
    if (anim == nullptr) return false;
    RepairString(&anim->mName);
    const std::string name = anim->mName.length ? Name(anim->mName) : "clip" + std::to_string(a);
    return RepairAnimation(anim, name, warnings);
  });
}

}  // namespace

Status RepairLoadedScene(const std::string& path, aiScene* scene,
                         std::vector<std::string>* warnings) {
  DropUnusedContent(scene);
  if (Status s = RepairNodes(path, scene, warnings); !s.ok()) return s;
  if (Status s = RepairMeshes(path, scene, warnings); !s.ok()) return s;
  RepairMaterials(scene);
  RepairAnimations(scene, warnings);
  return Status::Ok();
}

void DropStaleWeights(aiScene* scene, std::vector<std::string>* warnings) {
  size_t dropped = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    aiMesh* mesh = scene->mMeshes[m];
    for (unsigned b = 0; b < mesh->mNumBones; ++b) {
      aiBone* bone = mesh->mBones[b];
      unsigned kept = 0;
      for (unsigned w = 0; w < bone->mNumWeights; ++w) {
        if (bone->mWeights[w].mVertexId < mesh->mNumVertices)
          bone->mWeights[kept++] = bone->mWeights[w];
      }
      dropped += bone->mNumWeights - kept;
      bone->mNumWeights = kept;
    }
  }
  if (dropped > 0) {
    warnings->push_back(std::to_string(dropped) +
                        " bone weights dropped after welding: they named removed vertices");
  }
}

}  // namespace drape::bake::detail

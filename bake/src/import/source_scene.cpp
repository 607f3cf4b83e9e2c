#include "import/source_scene.h"

#include <assimp/postprocess.h>

#include <algorithm>
#include <cstring>
#include <set>

#include "import/import_messages.h"
#include "import/scene_repair.h"

namespace drape::bake::detail {
namespace {

constexpr int kMaxNodeDepth = 4096;  // deeper hierarchies are treated as corrupt (cycles)
constexpr size_t kMaxNodes = 1u << 22;

// Pre-order flattening, so every ancestor precedes its descendants.
Status FlattenNodes(const aiNode* root, const std::string& path, std::vector<SourceNode>* nodes) {
  struct Item {
    const aiNode* node;
    int parent;
    int depth;
  };
  std::vector<Item> stack{{root, -1, 0}};
  std::set<const aiNode*> seen;
  while (!stack.empty()) {
    const Item item = stack.back();
    stack.pop_back();
    if (!seen.insert(item.node).second || item.depth > kMaxNodeDepth ||
        nodes->size() >= kMaxNodes) {
      return Status(StatusCode::kCorrupt, path + ": the node hierarchy is cyclic or too deep");
    }
    SourceNode n;
    n.node = item.node;
    n.parent = item.parent;
    n.local_rest = ToEigen(item.node->mTransformation);
    if (!AllFinite(n.local_rest)) {
      return Status(StatusCode::kCorrupt, path + ": node '" +
                                              std::string(item.node->mName.C_Str()) +
                                              "' has a non-finite transform");
    }
    n.global_rest =
        item.parent < 0 ? n.local_rest : Mat4((*nodes)[item.parent].global_rest * n.local_rest);
    const int index = static_cast<int>(nodes->size());
    nodes->push_back(n);
    for (unsigned c = item.node->mNumChildren; c-- > 0;) {
      if (item.node->mChildren[c] == nullptr) {
        return Status(StatusCode::kCorrupt, path + ": a node has a null child");
      }
      stack.push_back({item.node->mChildren[c], index, item.depth + 1});
    }
  }
  return Status::Ok();
}

// Node index by name. When names collide (RobotExpressive: joints share names with their mesh
// nodes), the first node in pre-order that carries no mesh wins.
std::map<std::string, int> IndexNodesByName(const std::vector<SourceNode>& nodes) {
  std::map<std::string, int> by_name;
  for (int i = 0; i < static_cast<int>(nodes.size()); ++i) {
    const std::string name = nodes[i].node->mName.C_Str();
    auto it = by_name.find(name);
    if (it == by_name.end()) {
      by_name.emplace(name, i);
    } else if (nodes[it->second].node->mNumMeshes > 0 && nodes[i].node->mNumMeshes == 0) {
      it->second = i;
    }
  }
  return by_name;
}

// Names a bone cannot be resolved by: more than one node without meshes carries the name, or
// several nodes carry it and all have meshes. assimp identifies bones by name only, so binding
// such a bone to the first node would silently skin a mesh to the wrong joint (two skins whose
// joints share a name; an unnamed glTF joint, called "nodes[<i>]" by assimp, next to a node
// literally named so). Value: how many nodes carry the name.
std::map<std::string, int> AmbiguousNodeNames(const std::vector<SourceNode>& nodes) {
  std::map<std::string, std::pair<int, int>> count;  // name -> (nodes without, with meshes)
  for (const SourceNode& n : nodes) {
    auto& c = count[n.node->mName.C_Str()];
    ++(n.node->mNumMeshes > 0 ? c.second : c.first);
  }
  std::map<std::string, int> ambiguous;
  for (const auto& [name, c] : count) {
    if (c.first > 1 || (c.first == 0 && c.second > 1)) ambiguous.emplace(name, c.first + c.second);
  }
  return ambiguous;
}

// Which node instances which mesh, in node order; refuses a reference to a missing mesh and a
// scene whose meshes have no triangle.
Status ListMeshInstances(const std::string& path, SourceScene* source) {
  const aiScene* scene = source->scene;
  const std::vector<SourceNode>& nodes = source->nodes;
  std::vector<std::pair<int, unsigned>>& mesh_instances = source->mesh_instances;
  for (int n = 0; n < static_cast<int>(nodes.size()); ++n) {
    for (unsigned k = 0; k < nodes[n].node->mNumMeshes; ++k) {
      const unsigned mesh = nodes[n].node->mMeshes[k];
      if (mesh >= scene->mNumMeshes)
        return SourceError(path, StatusCode::kCorrupt, "a node references a missing mesh");
      mesh_instances.emplace_back(n, mesh);
    }
  }
  size_t triangle_faces = 0;
  for (const auto& [node, mesh] : mesh_instances) {
    const aiMesh* m = scene->mMeshes[mesh];
    for (unsigned f = 0; f < m->mNumFaces; ++f) triangle_faces += m->mFaces[f].mNumIndices == 3;
  }
  if (mesh_instances.empty())
    return SourceError(path, StatusCode::kCorrupt, "no node instances a mesh");
  if (triangle_faces == 0)
    return SourceError(path, StatusCode::kCorrupt, "the meshes have no triangles");
  return Status::Ok();
}

// assimp's message, on one line.
std::string ImporterError(const Assimp::Importer& importer) {
  std::string why = importer.GetErrorString();
  std::replace(why.begin(), why.end(), '\n', ' ');
  return why;
}

}  // namespace

Status ReadSourceScene(const std::string& path, Assimp::Importer* importer, SourceScene* source,
                       std::vector<std::string>* warnings) {
  importer->SetPropertyBool(AI_CONFIG_IMPORT_FBX_PRESERVE_PIVOTS, false);
  importer->SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                               aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  // Read as the loader has it, repair what a viewer would forgive, then validate and
  // post-process: what the repair left is refused with assimp's own message.
  const aiScene* loaded = importer->ReadFile(path, 0);
  if (loaded == nullptr) {
    const std::string why = ImporterError(*importer);
    // assimp asks every reader whose extension or signature matches; none took the file.
    if (why.rfind("No suitable reader found", 0) == 0) {
      return SourceError(path, StatusCode::kCorrupt,
                         "unsupported or corrupt model: no reader accepts it (the file is "
                         "corrupt, or not the format its extension names; drape-bake --formats "
                         "lists what it reads)");
    }
    return SourceError(path, StatusCode::kCorrupt, "unsupported or corrupt model: " + why);
  }
  if (Status s = RepairLoadedScene(path, const_cast<aiScene*>(loaded), warnings); !s.ok()) return s;
  const aiScene* scene =
      importer->ApplyPostProcessing(aiProcess_ValidateDataStructure | aiProcess_Triangulate |
                                    aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
  if (scene == nullptr) {
    return SourceError(path, StatusCode::kCorrupt,
                       "unsupported or corrupt model: " + ImporterError(*importer));
  }
  DropStaleWeights(const_cast<aiScene*>(scene), warnings);
  if (scene->mRootNode == nullptr)
    return SourceError(path, StatusCode::kCorrupt, "the scene has no node hierarchy");
  if (scene->mNumMeshes == 0)
    return SourceError(path, StatusCode::kCorrupt, "the scene has no meshes");
  source->scene = scene;

  if (Status s = FlattenNodes(scene->mRootNode, path, &source->nodes); !s.ok()) return s;
  source->node_by_name = IndexNodesByName(source->nodes);
  source->ambiguous_names = AmbiguousNodeNames(source->nodes);
  return ListMeshInstances(path, source);
}

bool MetadataNumber(const aiScene* scene, const char* key, double* value) {
  if (scene->mMetaData == nullptr) return false;
  const aiMetadata* meta = scene->mMetaData;
  for (unsigned i = 0; i < meta->mNumProperties; ++i) {
    if (std::strcmp(meta->mKeys[i].C_Str(), key) != 0) continue;
    const aiMetadataEntry& e = meta->mValues[i];
    if (e.mData == nullptr) return false;
    switch (e.mType) {
      case AI_INT32:
        *value = *static_cast<const int32_t*>(e.mData);
        return true;
      case AI_UINT64:
        *value = static_cast<double>(*static_cast<const uint64_t*>(e.mData));
        return true;
      case AI_FLOAT:
        *value = *static_cast<const float*>(e.mData);
        return true;
      case AI_DOUBLE:
        *value = *static_cast<const double*>(e.mData);
        return true;
      default:
        return false;
    }
  }
  return false;
}

}  // namespace drape::bake::detail

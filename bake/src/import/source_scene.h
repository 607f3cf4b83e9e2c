#pragma once
// The source file as the import stages read it (header importer.h): assimp's scene, its node
// hierarchy flattened with rest transforms, the nodes by name, and which node instances which
// mesh.

#include <assimp/scene.h>

#include <assimp/Importer.hpp>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "drape/formats/status.h"
#include "import/import_transforms.h"

namespace drape::bake::detail {

struct SourceNode {
  const aiNode* node = nullptr;
  int parent = -1;
  Mat4 local_rest = Mat4::Identity();
  Mat4 global_rest = Mat4::Identity();
};

struct SourceScene {
  const aiScene* scene = nullptr;           // owned by the Assimp::Importer that read it
  std::vector<SourceNode> nodes;            // pre-order, so every ancestor precedes its descendants
  std::map<std::string, int> node_by_name;  // see IndexNodesByName in source_scene.cpp
  std::map<std::string, int> ambiguous_names;  // name -> how many nodes carry it
  // (node, mesh index): a mesh may be instanced more than once; each instance counts.
  std::vector<std::pair<int, unsigned>> mesh_instances;
};

// Reads `path` with assimp, repairs what a loader may leave that validation would refuse (see
// scene_repair.h; one line per repair appended to `warnings`), validates, then triangulates,
// joins identical vertices and drops points and lines; flattens the nodes and lists the mesh
// instances. Refuses a scene without nodes, meshes, mesh instances or triangles, and a corrupt
// hierarchy. `importer` owns the scene afterwards.
Status ReadSourceScene(const std::string& path, Assimp::Importer* importer, SourceScene* source,
                       std::vector<std::string>* warnings);

// A number of the scene's metadata (FBX: UpAxis, UpAxisSign, UnitScaleFactor).
bool MetadataNumber(const aiScene* scene, const char* key, double* value);

}  // namespace drape::bake::detail

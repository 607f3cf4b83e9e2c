#pragma once
// The skeleton of an import (header importer.h): which source nodes become joints, and the
// joints' names, parents, rest transforms and inverse bind matrices. Every rigid collider is
// baked from the inverse bind matrices alone (docs/ALGORITHMS.md §1.1).

#include <map>
#include <string>
#include <vector>

#include "drape/bake/character.h"
#include "drape/bake/importer.h"
#include "import/asset_frame.h"
#include "import/source_scene.h"

namespace drape::bake::detail {

struct JointNodes {
  bool synthetic_root = false;      // no bones in the file: one rigid root joint
  std::map<int, Mat4> bone_offset;  // node -> offset matrix of the first mesh that names it
  std::vector<char> is_joint;       // per node
  std::vector<int> joint_nodes;     // the joints' nodes in pre-order, so parents precede children
  std::vector<int> joint_of_node;   // per node: its joint index, -1 for a node that is no joint
};

// The nearest node at or above node n that is a joint, -1 if none.
int JointAncestor(const SourceScene& source, const JointNodes& joints, int n);

// Every bone's node, plus the nodes that carry unskinned meshes outside any joint. Refuses a bone
// without a node, a bone whose name several nodes carry, and a singular offset matrix.
Status SelectJointNodes(const std::string& path, const SourceScene& source, JointNodes* joints);

// character->skeleton in the asset frame, and per joint its inverse bind matrix in source units
// (the bone's offset matrix, or the inverse of its node's rest transform). Refuses unnamed and
// duplicate joint names unless the options allow renaming them, and more than 65535 joints.
Status BuildSkeleton(const std::string& path, const ImportOptions& options,
                     const SourceScene& source, const JointNodes& joints, const AssetFrame& frame,
                     Character* character, std::vector<Mat4>* inverse_bind_source);

}  // namespace drape::bake::detail

#include "import/skeleton_import.h"

#include <cmath>

#include "import/import_messages.h"

namespace drape::bake::detail {
namespace {

// Each bone's node and offset matrix; sets has_bones when any mesh instance is skinned.
Status GatherBoneNodes(const std::string& path, const SourceScene& source, JointNodes* joints,
                       bool* has_bones) {
  for (const auto& [node, mesh] : source.mesh_instances) {
    const aiMesh* m = source.scene->mMeshes[mesh];
    for (unsigned b = 0; b < m->mNumBones; ++b) {
      *has_bones = true;
      const std::string name = m->mBones[b]->mName.C_Str();
      auto it = source.node_by_name.find(name);
      if (it == source.node_by_name.end())
        return SourceError(path, StatusCode::kCorrupt, "bone '" + name + "' has no node");
      if (auto dup = source.ambiguous_names.find(name); dup != source.ambiguous_names.end()) {
        return SourceError(path, StatusCode::kCorrupt,
                           "duplicate joint name '" + name + "': " + std::to_string(dup->second) +
                               " nodes carry it and bones are matched to nodes by name, so the "
                               "skin cannot be bound (rename the nodes in the source; "
                               "import.rename_duplicate_joints cannot repair this)");
      }
      const Mat4 offset = ToEigen(m->mBones[b]->mOffsetMatrix);
      if (!AllFinite(offset) || std::fabs(offset.topLeftCorner<3, 3>().determinant()) < 1e-30) {
        return SourceError(path, StatusCode::kCorrupt,
                           "bone '" + name + "' has a singular or non-finite offset matrix");
      }
      joints->bone_offset.emplace(it->second, offset);
    }
  }
  return Status::Ok();
}

// The name joint j is stored under: its node's name, "joint_<j>" for an unnamed node and "#2",
// "#3" suffixes on repeated names when the options allow repairing them.
Status NameJoint(const std::string& path, const ImportOptions& options, int node, size_t j,
                 std::map<std::string, int>* name_count, std::vector<std::string>* warnings,
                 std::string* name) {
  if (name->empty()) {
    if (!options.rename_duplicate_joints) {
      return SourceError(path, StatusCode::kCorrupt,
                         "joint node #" + std::to_string(node) + " has no name");
    }
    *name = "joint_" + std::to_string(j);
  }
  const int seen = ++(*name_count)[*name];
  if (seen > 1) {
    if (!options.rename_duplicate_joints) {
      return SourceError(
          path, StatusCode::kCorrupt,
          "duplicate joint name '" + *name + "' (set import.rename_duplicate_joints to repair)");
    }
    warnings->push_back("renamed duplicate joint '" + *name + "' to '" + *name + "#" +
                        std::to_string(seen) + "'");
    *name += "#" + std::to_string(seen);
  }
  return Status::Ok();
}

}  // namespace

int JointAncestor(const SourceScene& source, const JointNodes& joints, int n) {
  for (; n >= 0; n = source.nodes[n].parent)
    if (joints.is_joint[n]) return n;
  return -1;
}

Status SelectJointNodes(const std::string& path, const SourceScene& source, JointNodes* joints) {
  const std::vector<SourceNode>& nodes = source.nodes;
  bool has_bones = false;
  if (Status s = GatherBoneNodes(path, source, joints, &has_bones); !s.ok()) return s;
  std::vector<char>& is_joint = joints->is_joint;
  is_joint.assign(nodes.size(), 0);
  for (const auto& [node, offset] : joints->bone_offset) is_joint[node] = 1;
  joints->synthetic_root = !has_bones;
  if (has_bones) {
    for (const auto& [node, mesh] : source.mesh_instances) {
      if (source.scene->mMeshes[mesh]->mNumBones == 0 && JointAncestor(source, *joints, node) < 0)
        is_joint[node] = 1;
    }
  }
  joints->joint_of_node.assign(nodes.size(), -1);
  for (int n = 0; n < static_cast<int>(nodes.size()); ++n) {
    if (is_joint[n]) {
      joints->joint_of_node[n] = static_cast<int>(joints->joint_nodes.size());
      joints->joint_nodes.push_back(n);
    }
  }
  return Status::Ok();
}

Status BuildSkeleton(const std::string& path, const ImportOptions& options,
                     const SourceScene& source, const JointNodes& joints, const AssetFrame& frame,
                     Character* character, std::vector<Mat4>* inverse_bind_source) {
  const std::vector<SourceNode>& nodes = source.nodes;
  SkeletonData& skeleton = character->skeleton;
  if (joints.synthetic_root) {
    skeleton.joint_names = {"root"};
    skeleton.parents = {-1};
    Transform root;
    Decompose(frame.to_asset, &root);
    skeleton.rest_local = {root};
    *inverse_bind_source = {Mat4::Identity()};
  } else {
    std::map<std::string, int> name_count;
    for (size_t j = 0; j < joints.joint_nodes.size(); ++j) {
      const SourceNode& n = nodes[joints.joint_nodes[j]];
      std::string name = n.node->mName.C_Str();
      if (Status s = NameJoint(path, options, joints.joint_nodes[j], j, &name_count,
                               &character->warnings, &name);
          !s.ok()) {
        return s;
      }
      const int parent_joint = JointAncestor(source, joints, n.parent);
      skeleton.joint_names.push_back(name);
      skeleton.parents.push_back(parent_joint < 0 ? -1 : joints.joint_of_node[parent_joint]);
      const Mat4 local = parent_joint < 0
                             ? Mat4(frame.to_asset * n.global_rest)
                             : Mat4(nodes[parent_joint].global_rest.inverse() * n.global_rest);
      Transform t;
      if (Decompose(local, &t) > 1e-3) {
        character->warnings.push_back("joint '" + name +
                                      "' rest transform has shear; stored without it");
      }
      skeleton.rest_local.push_back(t);
      auto offset = joints.bone_offset.find(joints.joint_nodes[j]);
      inverse_bind_source->push_back(
          offset != joints.bone_offset.end() ? offset->second : Mat4(n.global_rest.inverse()));
    }
  }
  const size_t joint_count = skeleton.joint_names.size();
  if (joint_count > 65535) return SourceError(path, StatusCode::kCorrupt, "more than 65535 joints");
  for (size_t j = 0; j < joint_count; ++j) {
    skeleton.inverse_bind.push_back(ToMat34((*inverse_bind_source)[j] * frame.from_asset));
  }
  return Status::Ok();
}

}  // namespace drape::bake::detail

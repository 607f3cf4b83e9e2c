#include "drape/bake/importer.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <Eigen/Dense>
#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>
#include <tuple>
#include <utility>

namespace drape::bake {
namespace {

using Mat4 = Eigen::Matrix4d;
using Vec3 = Eigen::Vector3d;

constexpr int kMaxNodeDepth = 4096;  // deeper hierarchies are treated as corrupt (cycles)
constexpr size_t kMaxNodes = 1u << 22;

Mat4 ToEigen(const aiMatrix4x4& m) {
  Mat4 r;
  r << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3,
      m.d4;
  return r;
}

Mat34 ToMat34(const Mat4& m) {
  Mat34 r;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) r.m[4 * row + col] = static_cast<float>(m(row, col));
  return r;
}

Vec3 TransformPoint(const Mat4& m, const Vec3& p) { return (m * p.homogeneous()).head<3>(); }

bool AllFinite(const Mat4& m) { return m.allFinite(); }

struct Node {
  const aiNode* node = nullptr;
  int parent = -1;
  Mat4 local_rest = Mat4::Identity();
  Mat4 global_rest = Mat4::Identity();
};

// Pre-order flattening, so every ancestor precedes its descendants.
Status FlattenNodes(const aiNode* root, const std::string& path, std::vector<Node>* nodes) {
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
    Node n;
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
std::map<std::string, int> IndexNodesByName(const std::vector<Node>& nodes) {
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
std::map<std::string, int> AmbiguousNodeNames(const std::vector<Node>& nodes) {
  std::map<std::string, std::pair<int, int>> count;  // name -> (nodes without, with meshes)
  for (const Node& n : nodes) {
    auto& c = count[n.node->mName.C_Str()];
    ++(n.node->mNumMeshes > 0 ? c.second : c.first);
  }
  std::map<std::string, int> ambiguous;
  for (const auto& [name, c] : count) {
    if (c.first > 1 || (c.first == 0 && c.second > 1)) ambiguous.emplace(name, c.first + c.second);
  }
  return ambiguous;
}

// Polar decomposition of an affine matrix into translation, rotation and per-axis scale.
// A reflection is carried by a negative scale on z. Returns the relative size of the shear that
// a TRS transform cannot represent (0 for a clean TRS matrix).
double Decompose(const Mat4& m, Transform* t) {
  const Eigen::Matrix3d linear = m.topLeftCorner<3, 3>();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(linear, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  const Eigen::Matrix3d v = svd.matrixV();
  Eigen::Vector3d sigma = svd.singularValues();
  if ((u * v.transpose()).determinant() < 0.0) {
    u.col(2) = -u.col(2);
    sigma(2) = -sigma(2);
  }
  const Eigen::Matrix3d rotation = u * v.transpose();
  const Eigen::Matrix3d stretch = v * sigma.asDiagonal() * v.transpose();
  const Eigen::Quaterniond q(rotation);
  t->translation = {static_cast<float>(m(0, 3)), static_cast<float>(m(1, 3)),
                    static_cast<float>(m(2, 3))};
  t->rotation = {static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()),
                 static_cast<float>(q.w())};
  t->scale = {static_cast<float>(stretch(0, 0)), static_cast<float>(stretch(1, 1)),
              static_cast<float>(stretch(2, 2))};
  const double off = std::fabs(stretch(0, 1)) + std::fabs(stretch(0, 2)) + std::fabs(stretch(1, 2));
  return off / std::max(1e-12, stretch.diagonal().cwiseAbs().maxCoeff());
}

// Rotation that maps the given source up axis onto +Y (and, for a Z-up source, -Y onto +Z,
// which turns Blender's "front = -Y" into our "front = +Z").
bool UpAxisRotation(const std::string& axis, Eigen::Matrix3d* r) {
  Eigen::Matrix3d m;
  if (axis == "+Y") {
    m.setIdentity();
  } else if (axis == "-Y") {
    m << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  } else if (axis == "+Z") {
    m << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  } else if (axis == "-Z") {
    m << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  } else if (axis == "+X") {
    m << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  } else if (axis == "-X") {
    m << 0, 1, 0, -1, 0, 0, 0, 0, 1;
  } else {
    return false;
  }
  *r = m;
  return true;
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

aiVector3D SampleVectorKeys(const aiVectorKey* keys, unsigned count, double tick) {
  if (count == 1 || tick <= keys[0].mTime) return keys[0].mValue;
  if (tick >= keys[count - 1].mTime) return keys[count - 1].mValue;
  const aiVectorKey* upper = std::upper_bound(
      keys, keys + count, tick, [](double t, const aiVectorKey& k) { return t < k.mTime; });
  const aiVectorKey& a = *(upper - 1);
  const aiVectorKey& b = *upper;
  const double span = b.mTime - a.mTime;
  const float alpha = span > 0.0 ? static_cast<float>((tick - a.mTime) / span) : 0.f;
  return a.mValue + (b.mValue - a.mValue) * alpha;
}

aiQuaternion SampleQuatKeys(const aiQuatKey* keys, unsigned count, double tick) {
  if (count == 1 || tick <= keys[0].mTime) return keys[0].mValue;
  if (tick >= keys[count - 1].mTime) return keys[count - 1].mValue;
  const aiQuatKey* upper = std::upper_bound(
      keys, keys + count, tick, [](double t, const aiQuatKey& k) { return t < k.mTime; });
  const aiQuatKey& a = *(upper - 1);
  const aiQuatKey& b = *upper;
  const double span = b.mTime - a.mTime;
  const float alpha = span > 0.0 ? static_cast<float>((tick - a.mTime) / span) : 0.f;
  aiQuaternion out;
  aiQuaternion::Interpolate(out, a.mValue, b.mValue, alpha);  // slerp on the shorter arc
  return out.Normalize();
}

Mat4 ChannelLocal(const aiNodeAnim& channel, const Mat4& rest, double tick) {
  // A channel without keys of one kind keeps that part of the rest transform.
  aiVector3D rest_scale, rest_position;
  aiQuaternion rest_rotation;
  aiMatrix4x4 rest_ai;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) rest_ai[r][c] = static_cast<ai_real>(rest(r, c));
  rest_ai.Decompose(rest_scale, rest_rotation, rest_position);
  const aiVector3D position =
      channel.mNumPositionKeys
          ? SampleVectorKeys(channel.mPositionKeys, channel.mNumPositionKeys, tick)
          : rest_position;
  const aiQuaternion rotation =
      channel.mNumRotationKeys
          ? SampleQuatKeys(channel.mRotationKeys, channel.mNumRotationKeys, tick)
          : rest_rotation;
  const aiVector3D scale = channel.mNumScalingKeys ? SampleVectorKeys(channel.mScalingKeys,
                                                                      channel.mNumScalingKeys, tick)
                                                   : rest_scale;
  return ToEigen(aiMatrix4x4(scale, rotation, position));
}

std::string Fmt(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.6g", v);
  return buffer;
}

// Closed character meshes can be wound inward (docs/ALGORITHMS.md §1.4: winding number -1 inside).
// Orients every connected component (triangles sharing vertices) so that its signed volume about
// its centroid is positive. Returns how many components were flipped.
size_t OrientComponentsOutward(MeshData* mesh) {
  const uint32_t vertex_count = mesh->vertex_count();
  std::vector<uint32_t> root(vertex_count);
  for (uint32_t v = 0; v < vertex_count; ++v) root[v] = v;
  auto find = [&](uint32_t v) {
    while (root[v] != v) v = root[v] = root[root[v]];
    return v;
  };
  const size_t triangles = mesh->triangles.size() / 3;
  for (size_t t = 0; t < triangles; ++t) {
    const uint32_t a = find(mesh->triangles[3 * t]);
    for (int k = 1; k < 3; ++k) {
      const uint32_t b = find(mesh->triangles[3 * t + k]);
      if (a != b) root[std::max(a, b)] = std::min(a, b);
    }
  }
  std::map<uint32_t, std::pair<Vec3, double>> centroid;  // component -> (sum, count)
  for (uint32_t v = 0; v < vertex_count; ++v) {
    auto& c = centroid.try_emplace(find(v), Vec3::Zero(), 0.0).first->second;
    c.first += Vec3(mesh->positions[v].x, mesh->positions[v].y, mesh->positions[v].z);
    c.second += 1.0;
  }
  std::map<uint32_t, double> volume;
  for (size_t t = 0; t < triangles; ++t) {
    const uint32_t component = find(mesh->triangles[3 * t]);
    const auto& c = centroid[component];
    const Vec3 origin = c.first / c.second;
    Vec3 p[3];
    for (int k = 0; k < 3; ++k) {
      const Float3 q = mesh->positions[mesh->triangles[3 * t + k]];
      p[k] = Vec3(q.x, q.y, q.z) - origin;
    }
    volume[component] += p[0].dot(p[1].cross(p[2])) / 6.0;
  }
  size_t flipped = 0;
  for (const auto& [component, v] : volume) flipped += v < 0.0;
  for (size_t t = 0; t < triangles; ++t) {
    if (volume[find(mesh->triangles[3 * t])] < 0.0)
      std::swap(mesh->triangles[3 * t + 1], mesh->triangles[3 * t + 2]);
  }
  return flipped;
}

}  // namespace

Status ImportCharacter(const std::string& path, const ImportOptions& options,
                       Character* character) {
  *character = Character{};
  auto fail = [&](StatusCode code, const std::string& reason) {
    return Status(code, path + ": " + reason);
  };
  std::error_code fs_error;
  if (!std::filesystem::exists(path, fs_error)) return fail(StatusCode::kIoError, "file not found");
  if (std::filesystem::is_directory(path, fs_error))
    return fail(StatusCode::kIoError, "is a directory");
  if (std::filesystem::file_size(path, fs_error) == 0)
    return fail(StatusCode::kCorrupt, "file is empty");
  if (!(options.clip_sample_rate > 0.f && options.clip_sample_rate <= 1000.f)) {
    return fail(StatusCode::kInvalidArgument, "clip_sample_rate must be in (0, 1000] Hz");
  }
  if (!(options.unit_scale >= 0.0 && std::isfinite(options.unit_scale))) {
    return fail(StatusCode::kInvalidArgument, "unit_scale must be >= 0 (0 = detect)");
  }

  Assimp::Importer importer;
  importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_PRESERVE_PIVOTS, false);
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene =
      importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                  aiProcess_SortByPType | aiProcess_ValidateDataStructure);
  if (scene == nullptr) {
    std::string why = importer.GetErrorString();
    std::replace(why.begin(), why.end(), '\n', ' ');
    return fail(StatusCode::kCorrupt, "unsupported or corrupt model: " + why);
  }
  if (scene->mRootNode == nullptr)
    return fail(StatusCode::kCorrupt, "the scene has no node hierarchy");
  if (scene->mNumMeshes == 0) return fail(StatusCode::kCorrupt, "the scene has no meshes");

  std::vector<Node> nodes;
  if (Status s = FlattenNodes(scene->mRootNode, path, &nodes); !s.ok()) return s;
  const std::map<std::string, int> node_by_name = IndexNodesByName(nodes);
  const std::map<std::string, int> ambiguous_names = AmbiguousNodeNames(nodes);

  // Which node instances which mesh (a mesh may be instanced more than once; each counts).
  std::vector<std::pair<int, unsigned>> mesh_instances;  // (node, mesh index)
  for (int n = 0; n < static_cast<int>(nodes.size()); ++n) {
    for (unsigned k = 0; k < nodes[n].node->mNumMeshes; ++k) {
      const unsigned mesh = nodes[n].node->mMeshes[k];
      if (mesh >= scene->mNumMeshes)
        return fail(StatusCode::kCorrupt, "a node references a missing mesh");
      mesh_instances.emplace_back(n, mesh);
    }
  }
  size_t triangle_faces = 0;
  for (const auto& [node, mesh] : mesh_instances) {
    const aiMesh* m = scene->mMeshes[mesh];
    for (unsigned f = 0; f < m->mNumFaces; ++f) triangle_faces += m->mFaces[f].mNumIndices == 3;
  }
  if (mesh_instances.empty()) return fail(StatusCode::kCorrupt, "no node instances a mesh");
  if (triangle_faces == 0) return fail(StatusCode::kCorrupt, "the meshes have no triangles");

  // --- Joints: every bone's node, plus the nodes that carry unskinned meshes outside any joint.
  std::map<int, Mat4> bone_offset;  // node -> offset matrix of the first mesh that names it
  bool has_bones = false;
  for (const auto& [node, mesh] : mesh_instances) {
    const aiMesh* m = scene->mMeshes[mesh];
    for (unsigned b = 0; b < m->mNumBones; ++b) {
      has_bones = true;
      const std::string name = m->mBones[b]->mName.C_Str();
      auto it = node_by_name.find(name);
      if (it == node_by_name.end())
        return fail(StatusCode::kCorrupt, "bone '" + name + "' has no node");
      if (auto dup = ambiguous_names.find(name); dup != ambiguous_names.end()) {
        return fail(StatusCode::kCorrupt,
                    "duplicate joint name '" + name + "': " + std::to_string(dup->second) +
                        " nodes carry it and bones are matched to nodes by name, so the skin "
                        "cannot be bound (rename the nodes in the source; "
                        "import.rename_duplicate_joints cannot repair this)");
      }
      const Mat4 offset = ToEigen(m->mBones[b]->mOffsetMatrix);
      if (!AllFinite(offset) || std::fabs(offset.topLeftCorner<3, 3>().determinant()) < 1e-30) {
        return fail(StatusCode::kCorrupt,
                    "bone '" + name + "' has a singular or non-finite offset matrix");
      }
      bone_offset.emplace(it->second, offset);
    }
  }
  std::vector<char> is_joint(nodes.size(), 0);
  for (const auto& [node, offset] : bone_offset) is_joint[node] = 1;
  auto joint_ancestor = [&](int n) {
    for (; n >= 0; n = nodes[n].parent)
      if (is_joint[n]) return n;
    return -1;
  };
  const bool synthetic_root = !has_bones;  // no skeleton: one rigid root joint
  if (has_bones) {
    for (const auto& [node, mesh] : mesh_instances) {
      if (scene->mMeshes[mesh]->mNumBones == 0 && joint_ancestor(node) < 0) is_joint[node] = 1;
    }
  }
  std::vector<int> joint_nodes;  // pre-order, so parents precede children
  std::vector<int> joint_of_node(nodes.size(), -1);
  for (int n = 0; n < static_cast<int>(nodes.size()); ++n) {
    if (is_joint[n]) {
      joint_of_node[n] = static_cast<int>(joint_nodes.size());
      joint_nodes.push_back(n);
    }
  }

  // --- Frame: unit scale and up axis. A = R_up * s maps the scene-root frame to the asset frame.
  std::string up = options.up_axis;
  std::string up_source = "config";
  if (up == "auto") {
    double axis = 1, sign = 1;
    if (MetadataNumber(scene, "UpAxis", &axis)) {
      MetadataNumber(scene, "UpAxisSign", &sign);
      const char* names[3] = {"X", "Y", "Z"};
      const int a = std::clamp(static_cast<int>(axis), 0, 2);
      up = std::string(sign < 0 ? "-" : "+") + names[a];
      up_source = "file metadata";
    } else {
      up = "+Y";
      up_source = "format default";
    }
  }
  Eigen::Matrix3d up_rotation;
  if (!UpAxisRotation(up, &up_rotation)) {
    return fail(StatusCode::kInvalidArgument,
                "up_axis '" + options.up_axis + "' is not auto, +X, -X, +Y, -Y, +Z or -Z");
  }

  // Rest-pose world positions of all vertices (source units) for the scale check.
  Eigen::AlignedBox3d rest_box;
  for (const auto& [node, mesh] : mesh_instances) {
    const aiMesh* m = scene->mMeshes[mesh];
    for (unsigned v = 0; v < m->mNumVertices; ++v) {
      const Vec3 p(m->mVertices[v].x, m->mVertices[v].y, m->mVertices[v].z);
      if (!p.allFinite()) {
        return fail(StatusCode::kCorrupt, "vertex " + std::to_string(v) + " of mesh '" +
                                              std::string(m->mName.C_Str()) + "' is not finite");
      }
      if (m->mNumBones == 0) rest_box.extend(TransformPoint(nodes[node].global_rest, p));
    }
    for (unsigned b = 0; b < m->mNumBones; ++b) {
      const aiBone* bone = m->mBones[b];
      const int bn = node_by_name.at(bone->mName.C_Str());
      const Mat4 skin = nodes[bn].global_rest * ToEigen(bone->mOffsetMatrix);
      for (unsigned w = 0; w < bone->mNumWeights; ++w) {
        const unsigned v = bone->mWeights[w].mVertexId;
        if (v >= m->mNumVertices)
          return fail(StatusCode::kCorrupt, "a bone weight names a missing vertex");
        if (bone->mWeights[w].mWeight > 0.5f) {
          rest_box.extend(
              TransformPoint(skin, Vec3(m->mVertices[v].x, m->mVertices[v].y, m->mVertices[v].z)));
        }
      }
    }
  }
  double scale = options.unit_scale;
  std::string scale_source = "config";
  if (scale == 0.0) {
    double factor = 0;
    if (MetadataNumber(scene, "UnitScaleFactor", &factor) && factor > 0 && std::isfinite(factor)) {
      scale = factor / 100.0;  // FBX: centimetres per unit
      scale_source = "file metadata (UnitScaleFactor " + Fmt(factor) + ")";
    } else {
      scale = 1.0;
      scale_source = "format default (metres)";
    }
    const double extent = rest_box.isEmpty() ? 0.0 : rest_box.sizes().maxCoeff() * scale;
    // A body beyond 20 m is taken to be in cm or mm: whichever brings it nearest (in ratio) to
    // a person's 1.7 m. Characters between 5 cm and 20 m are left as they are.
    if (extent > 20.0) {
      const double cm = extent * 0.01, mm = extent * 0.001;
      const bool millimetres = std::fabs(std::log(mm / 1.7)) < std::fabs(std::log(cm / 1.7));
      scale *= millimetres ? 0.001 : 0.01;
      scale_source += std::string(", then x") + (millimetres ? "0.001" : "0.01") +
                      ": the body would be " + Fmt(extent) + " m tall (taken as " +
                      (millimetres ? "mm" : "cm") + ")";
    }
  }
  const double extent_m = rest_box.isEmpty() ? 0.0 : rest_box.sizes().maxCoeff() * scale;
  if (extent_m < 0.02 || extent_m > 3.0) {
    character->warnings.push_back("the rest-pose body spans " + Fmt(extent_m) +
                                  " m after unit scaling; set import.unit_scale if that is wrong");
  }
  Mat4 to_asset = Mat4::Identity();
  to_asset.topLeftCorner<3, 3>() = up_rotation * scale;
  const Mat4 from_asset = to_asset.inverse();

  // --- Skeleton.
  SkeletonData& skeleton = character->skeleton;
  std::vector<Mat4> inverse_bind_source;  // per joint, source units
  if (synthetic_root) {
    skeleton.joint_names = {"root"};
    skeleton.parents = {-1};
    Transform root;
    Decompose(to_asset, &root);
    skeleton.rest_local = {root};
    inverse_bind_source = {Mat4::Identity()};
  } else {
    std::map<std::string, int> name_count;
    for (size_t j = 0; j < joint_nodes.size(); ++j) {
      const Node& n = nodes[joint_nodes[j]];
      std::string name = n.node->mName.C_Str();
      if (name.empty()) {
        if (!options.rename_duplicate_joints) {
          return fail(StatusCode::kCorrupt,
                      "joint node #" + std::to_string(joint_nodes[j]) + " has no name");
        }
        name = "joint_" + std::to_string(j);
      }
      const int seen = ++name_count[name];
      if (seen > 1) {
        if (!options.rename_duplicate_joints) {
          return fail(StatusCode::kCorrupt, "duplicate joint name '" + name +
                                                "' (set import.rename_duplicate_joints to repair)");
        }
        character->warnings.push_back("renamed duplicate joint '" + name + "' to '" + name + "#" +
                                      std::to_string(seen) + "'");
        name += "#" + std::to_string(seen);
      }
      const int parent_joint = joint_ancestor(n.parent);
      skeleton.joint_names.push_back(name);
      skeleton.parents.push_back(parent_joint < 0 ? -1 : joint_of_node[parent_joint]);
      const Mat4 local = parent_joint < 0
                             ? Mat4(to_asset * n.global_rest)
                             : Mat4(nodes[parent_joint].global_rest.inverse() * n.global_rest);
      Transform t;
      if (Decompose(local, &t) > 1e-3) {
        character->warnings.push_back("joint '" + name +
                                      "' rest transform has shear; stored without it");
      }
      skeleton.rest_local.push_back(t);
      auto offset = bone_offset.find(joint_nodes[j]);
      inverse_bind_source.push_back(offset != bone_offset.end() ? offset->second
                                                                : Mat4(n.global_rest.inverse()));
    }
  }
  const size_t joint_count = skeleton.joint_names.size();
  if (joint_count > 65535) return fail(StatusCode::kCorrupt, "more than 65535 joints");
  for (size_t j = 0; j < joint_count; ++j) {
    skeleton.inverse_bind.push_back(ToMat34(inverse_bind_source[j] * from_asset));
  }

  // --- Mesh: bind positions in the asset frame, welded per source mesh, weights renormalised.
  MeshData& out = character->mesh;
  out.influence_offsets.push_back(0);
  size_t weight_sum_warnings = 0, zero_weight_vertices = 0, degenerate_triangles = 0,
         weld_conflicts = 0;
  size_t mesh_space_mismatch = 0;
  for (const auto& [node, mesh_index] : mesh_instances) {
    const aiMesh* m = scene->mMeshes[mesh_index];
    // Source-space bind transform of this mesh's vertices (docs/ALGORITHMS.md §1.1).
    Mat4 to_bind = Mat4::Identity();
    int rigid_joint = -1;
    if (synthetic_root) {
      to_bind = nodes[node].global_rest;
      rigid_joint = 0;
    } else if (m->mNumBones == 0) {
      const int jn = joint_ancestor(node);
      rigid_joint = joint_of_node[jn];
      to_bind = inverse_bind_source[rigid_joint].inverse() * nodes[jn].global_rest.inverse() *
                nodes[node].global_rest;
    } else {
      // A mesh whose offset matrices differ from the first mesh's by a constant transform lives
      // in another mesh space: bring it into the shared one.
      bool first = true;
      for (unsigned b = 0; b < m->mNumBones; ++b) {
        const int jn = node_by_name.at(m->mBones[b]->mName.C_Str());
        const Mat4 correction =
            inverse_bind_source[joint_of_node[jn]].inverse() * ToEigen(m->mBones[b]->mOffsetMatrix);
        if (first) {
          to_bind = correction;
          first = false;
        } else if (!correction.isApprox(to_bind, 1e-4)) {
          ++mesh_space_mismatch;
        }
      }
    }
    const Mat4 vertex_to_asset = to_asset * to_bind;

    // Influences per source vertex.
    std::vector<std::vector<std::pair<int, float>>> influences(m->mNumVertices);
    for (unsigned b = 0; b < m->mNumBones; ++b) {
      const aiBone* bone = m->mBones[b];
      const int joint = joint_of_node[node_by_name.at(bone->mName.C_Str())];
      for (unsigned w = 0; w < bone->mNumWeights; ++w) {
        const float weight = bone->mWeights[w].mWeight;
        if (!std::isfinite(weight))
          return fail(StatusCode::kCorrupt,
                      "bone '" + std::string(bone->mName.C_Str()) + "' has a non-finite weight");
        if (weight > 0.f) influences[bone->mWeights[w].mVertexId].emplace_back(joint, weight);
      }
    }
    const int fallback_joint =
        rigid_joint >= 0 ? rigid_joint
                         : (joint_ancestor(node) >= 0 ? joint_of_node[joint_ancestor(node)] : 0);

    std::map<std::tuple<float, float, float>, uint32_t> welded;
    std::vector<uint32_t> remap(m->mNumVertices);
    // Per welded vertex of this mesh (from first_vertex on): its first copy's normalised skin,
    // and the normalised skins of all its copies, averaged once the mesh is read.
    const uint32_t first_vertex = out.vertex_count();
    std::vector<std::vector<std::pair<int, double>>> first_skin, all_skins;
    std::vector<uint32_t> copies;
    for (unsigned v = 0; v < m->mNumVertices; ++v) {
      const Vec3 p = TransformPoint(vertex_to_asset,
                                    Vec3(m->mVertices[v].x, m->mVertices[v].y, m->mVertices[v].z));
      const Float3 position{static_cast<float>(p.x()), static_cast<float>(p.y()),
                            static_cast<float>(p.z())};
      if (!std::isfinite(position.x) || !std::isfinite(position.y) || !std::isfinite(position.z)) {
        return fail(StatusCode::kCorrupt, "vertex " + std::to_string(v) + " of mesh '" +
                                              std::string(m->mName.C_Str()) +
                                              "' is not finite after transforming to metres");
      }
      std::vector<std::pair<int, float>> inf = influences[v];
      if (rigid_joint >= 0) inf = {{rigid_joint, 1.f}};
      std::sort(inf.begin(), inf.end());
      // Merge repeated joints, then renormalise.
      std::vector<std::pair<int, float>> merged;
      for (const auto& [joint, weight] : inf) {
        if (!merged.empty() && merged.back().first == joint) {
          merged.back().second += weight;
        } else {
          merged.emplace_back(joint, weight);
        }
      }
      double sum = 0;
      for (const auto& [joint, weight] : merged) sum += weight;
      if (sum <= 0.0) {
        ++zero_weight_vertices;
        merged = {{fallback_joint, 1.f}};
        sum = 1.0;
      } else if (sum < 0.9 || sum > 1.1) {
        ++weight_sum_warnings;
      }
      std::vector<std::pair<int, double>> skin;  // sorted by joint, sums to 1
      for (const auto& [joint, weight] : merged) skin.emplace_back(joint, weight / sum);
      auto key = std::make_tuple(position.x, position.y, position.z);
      auto [it, inserted] = welded.emplace(key, out.vertex_count());
      remap[v] = it->second;
      if (inserted) {
        out.positions.push_back(position);
        first_skin.push_back(skin);
        all_skins.push_back(std::move(skin));
        copies.push_back(1);
        continue;
      }
      // Same position: one vertex whose skin is the average of its copies' skins, which is what
      // assimp's JoinIdenticalVertices already does to copies that differ only in their skin
      // (it sums their weights); copies it keeps apart (other normals or UVs) get the same here.
      // Counted when the skins differ (a seam with split weights).
      const std::vector<std::pair<int, double>>& first = first_skin[it->second - first_vertex];
      bool same = first.size() == skin.size();
      for (size_t k = 0; same && k < skin.size(); ++k) {
        same =
            first[k].first == skin[k].first && std::fabs(first[k].second - skin[k].second) < 1e-4;
      }
      weld_conflicts += !same;
      auto& skins = all_skins[it->second - first_vertex];
      skins.insert(skins.end(), skin.begin(), skin.end());
      ++copies[it->second - first_vertex];
    }
    for (size_t w = 0; w < all_skins.size(); ++w) {
      std::vector<std::pair<int, double>>& skin = all_skins[w];
      std::sort(skin.begin(), skin.end());
      std::vector<std::pair<int, double>> averaged;
      double total = 0;
      for (const auto& [joint, weight] : skin) {
        total += weight;
        if (!averaged.empty() && averaged.back().first == joint) {
          averaged.back().second += weight;
        } else {
          averaged.emplace_back(joint, weight);
        }
      }
      for (const auto& [joint, weight] : averaged) {
        out.influence_joints.push_back(static_cast<uint16_t>(joint));
        // A single copy is stored as normalised above, bit for bit.
        out.influence_weights.push_back(
            static_cast<float>(copies[w] == 1 ? weight : weight / total));
      }
      out.influence_offsets.push_back(static_cast<uint32_t>(out.influence_joints.size()));
    }
    for (unsigned f = 0; f < m->mNumFaces; ++f) {
      const aiFace& face = m->mFaces[f];
      if (face.mNumIndices != 3) continue;
      uint32_t idx[3];
      for (int k = 0; k < 3; ++k) {
        if (face.mIndices[k] >= m->mNumVertices)
          return fail(StatusCode::kCorrupt, "a face names a missing vertex");
        idx[k] = remap[face.mIndices[k]];
      }
      const Float3 a = out.positions[idx[0]], b = out.positions[idx[1]], c = out.positions[idx[2]];
      const Vec3 e1(b.x - a.x, b.y - a.y, b.z - a.z), e2(c.x - a.x, c.y - a.y, c.z - a.z);
      if (idx[0] == idx[1] || idx[1] == idx[2] || idx[0] == idx[2] ||
          e1.cross(e2).squaredNorm() == 0.0) {
        ++degenerate_triangles;
        continue;
      }
      out.triangles.insert(out.triangles.end(), idx, idx + 3);
    }
  }
  if (out.triangles.empty()) return fail(StatusCode::kCorrupt, "every triangle is degenerate");
  const size_t flipped_components = OrientComponentsOutward(&out);
  if (flipped_components) {
    character->warnings.push_back(std::to_string(flipped_components) +
                                  " connected components were wound inward and have been flipped");
  }
  auto warn_count = [&](size_t count, const std::string& what) {
    if (count) character->warnings.push_back(std::to_string(count) + " " + what);
  };
  warn_count(weight_sum_warnings, "vertices had raw weight sums outside [0.9, 1.1] (renormalised)");
  warn_count(zero_weight_vertices, "vertices had no weight (made rigid to their mesh's joint)");
  warn_count(degenerate_triangles, "degenerate or zero-area triangles were dropped");
  warn_count(weld_conflicts, "welded vertices had differing weights (averaged)");
  warn_count(mesh_space_mismatch,
             "bones disagree on their mesh's bind space (blended skin may be off)");

  // --- Clips: every animation resampled at a fixed rate into joint-local transforms.
  if (!synthetic_root) {
    std::set<std::string> clip_names;
    for (unsigned a = 0; a < scene->mNumAnimations; ++a) {
      const aiAnimation* anim = scene->mAnimations[a];
      std::string name = anim->mName.length ? anim->mName.C_Str() : "clip" + std::to_string(a);
      while (!clip_names.insert(name).second) name += "_" + std::to_string(a);
      const double ticks_per_second = anim->mTicksPerSecond > 0 ? anim->mTicksPerSecond : 25.0;
      const double duration = anim->mDuration / ticks_per_second;
      if (!std::isfinite(duration) || duration < 0 || duration > 3600) {
        character->warnings.push_back("clip '" + name + "' skipped: duration " + Fmt(duration) +
                                      " s");
        continue;
      }
      std::vector<const aiNodeAnim*> channel_of_node(nodes.size(), nullptr);
      for (unsigned c = 0; c < anim->mNumChannels; ++c) {
        const aiNodeAnim* channel = anim->mChannels[c];
        auto it = node_by_name.find(channel->mNodeName.C_Str());
        if (it == node_by_name.end()) continue;  // a channel for a node that is not there
        channel_of_node[it->second] = channel;
      }
      ClipData clip;
      clip.name = name;
      clip.duration = static_cast<float>(duration);
      clip.sample_rate = options.clip_sample_rate;
      clip.frame_count = static_cast<uint32_t>(
          std::ceil(static_cast<double>(clip.duration) * clip.sample_rate - 1e-3) + 1);
      clip.keys.resize(static_cast<size_t>(clip.frame_count) * joint_count);
      std::vector<Mat4> global(nodes.size());
      bool shear = false;
      for (uint32_t f = 0; f < clip.frame_count; ++f) {
        const double seconds =
            std::min(static_cast<double>(f) / clip.sample_rate, static_cast<double>(clip.duration));
        const double tick = seconds * ticks_per_second;
        for (size_t n = 0; n < nodes.size(); ++n) {
          const Mat4 local = channel_of_node[n]
                                 ? ChannelLocal(*channel_of_node[n], nodes[n].local_rest, tick)
                                 : nodes[n].local_rest;
          global[n] = nodes[n].parent < 0 ? local : Mat4(global[nodes[n].parent] * local);
        }
        for (size_t j = 0; j < joint_count; ++j) {
          const int jn = joint_nodes[j];
          const int parent_joint = joint_ancestor(nodes[jn].parent);
          const Mat4 local = parent_joint < 0 ? Mat4(to_asset * global[jn])
                                              : Mat4(global[parent_joint].inverse() * global[jn]);
          if (!local.allFinite())
            return fail(StatusCode::kCorrupt,
                        "clip '" + name + "' produces a non-finite transform");
          shear |= Decompose(local, &clip.keys[static_cast<size_t>(f) * joint_count + j]) > 1e-3;
        }
      }
      if (shear)
        character->warnings.push_back("clip '" + name +
                                      "' has sheared joint transforms; stored without shear");
      character->clips.push_back(std::move(clip));
    }
  }

  // --- Info.
  character->info.source_name = std::filesystem::path(path).filename().string();
  character->info.tool_version = DRAPE_VERSION_STRING;
  character->info.unit_scale = static_cast<float>(scale);
  character->info.up_axis = up;
  character->info.source_to_asset = ToMat34(to_asset);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) character->source_to_asset[4 * r + c] = to_asset(r, c);
  character->warnings.insert(character->warnings.begin(),
                             "unit scale " + Fmt(scale) + " m/unit from " + scale_source +
                                 "; up axis " + up + " from " + up_source);
  return Status::Ok();
}

}  // namespace drape::bake

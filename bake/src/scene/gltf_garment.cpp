// glTF garments through tinygltf (the Debian package). Every accessor is checked against its
// buffer before it is read: a hostile file gets an error, never a read out of bounds.
#include "scene/gltf_garment.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <tuple>

#include "config/name_suggestions.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "scene/scene_messages.h"

namespace drape::bake::detail {
namespace {

constexpr size_t kMaxVertices = size_t{1} << 22;  // before welding; garments are far smaller

// The elements of one accessor, checked to lie inside their buffer.
struct Elements {
  const unsigned char* data = nullptr;
  size_t count = 0, stride = 0;
  int component = 0, components = 0;
  bool normalized = false;

  // Component c of element i; normalized integers mapped to [0, 1] ([-1, 1] signed).
  double Get(size_t i, int c) const {
    const unsigned char* p = data + i * stride;
    switch (component) {
      case TINYGLTF_COMPONENT_TYPE_FLOAT: {
        float v;
        std::memcpy(&v, p + 4 * c, 4);
        return v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        uint32_t v;
        std::memcpy(&v, p + 4 * c, 4);
        return normalized ? v / 4294967295.0 : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t v;
        std::memcpy(&v, p + 2 * c, 2);
        return normalized ? v / 65535.0 : v;
      }
      case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t v;
        std::memcpy(&v, p + 2 * c, 2);
        return normalized ? std::max(v / 32767.0, -1.0) : v;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return normalized ? p[c] / 255.0 : p[c];
      case TINYGLTF_COMPONENT_TYPE_BYTE: {
        const auto v = static_cast<int8_t>(p[c]);
        return normalized ? std::max(v / 127.0, -1.0) : v;
      }
    }
    return 0.0;
  }
};

// Accessor `index` as `what`, of one of `types` (TINYGLTF_TYPE_*) and `components`
// (TINYGLTF_COMPONENT_TYPE_*).
Status Access(const tinygltf::Model& model, int index, const std::string& what,
              std::initializer_list<int> types, std::initializer_list<int> component_types,
              Elements* out) {
  if (index < 0 || static_cast<size_t>(index) >= model.accessors.size())
    return Invalid(what + ": accessor " + std::to_string(index) + " does not exist");
  const tinygltf::Accessor& a = model.accessors[static_cast<size_t>(index)];
  const std::string name = what + " (accessor " + std::to_string(index) + ")";
  if (a.sparse.isSparse) return Invalid(name + ": sparse accessors are not supported");
  if (std::find(types.begin(), types.end(), a.type) == types.end())
    return Invalid(name + ": unexpected element type " + std::to_string(a.type));
  if (std::find(component_types.begin(), component_types.end(), a.componentType) ==
      component_types.end())
    return Invalid(name + ": unexpected component type " + std::to_string(a.componentType));
  if (a.bufferView < 0 || static_cast<size_t>(a.bufferView) >= model.bufferViews.size())
    return Invalid(name + ": has no buffer view");
  const tinygltf::BufferView& view = model.bufferViews[static_cast<size_t>(a.bufferView)];
  if (view.buffer < 0 || static_cast<size_t>(view.buffer) >= model.buffers.size())
    return Invalid(name + ": its buffer view names no buffer");
  const std::vector<unsigned char>& buffer = model.buffers[static_cast<size_t>(view.buffer)].data;
  const int component_bytes =
      tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(a.componentType));
  const int components = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(a.type));
  const int stride = a.ByteStride(view);
  const size_t element_bytes = static_cast<size_t>(component_bytes) * components;
  if (component_bytes <= 0 || components <= 0 || stride <= 0 ||
      static_cast<size_t>(stride) < element_bytes)
    return Invalid(name + ": bad element layout");
  if (a.count > kMaxVertices * 3) return Invalid(name + ": too many elements");
  const size_t end =
      a.count == 0 ? 0 : a.byteOffset + (a.count - 1) * static_cast<size_t>(stride) + element_bytes;
  if (view.byteOffset > buffer.size() || view.byteLength > buffer.size() - view.byteOffset ||
      a.byteOffset > view.byteLength || end > view.byteLength)
    return Invalid(name + ": lies beyond its buffer");
  out->data = buffer.data() + view.byteOffset + a.byteOffset;
  out->count = a.count;
  out->stride = static_cast<size_t>(stride);
  out->component = a.componentType;
  out->components = components;
  out->normalized = a.normalized;
  return Status::Ok();
}

Mat34 ColumnMajor(const double* m) {  // a glTF 4x4 (column-major) as a 3x4
  Mat34 out;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) out.m[r * 4 + c] = static_cast<float>(m[c * 4 + r]);
  return out;
}

Mat34 NodeLocal(const tinygltf::Node& node) {
  if (node.matrix.size() == 16) return ColumnMajor(node.matrix.data());
  Transform t;
  if (node.translation.size() == 3)
    t.translation = {static_cast<float>(node.translation[0]),
                     static_cast<float>(node.translation[1]),
                     static_cast<float>(node.translation[2])};
  if (node.rotation.size() == 4)
    t.rotation =
        Normalize(Quat{static_cast<float>(node.rotation[0]), static_cast<float>(node.rotation[1]),
                       static_cast<float>(node.rotation[2]), static_cast<float>(node.rotation[3])});
  if (node.scale.size() == 3)
    t.scale = {static_cast<float>(node.scale[0]), static_cast<float>(node.scale[1]),
               static_cast<float>(node.scale[2])};
  return ToMatrix(t);
}

// Every node's world matrix in the file's node pose; the hierarchy must be a tree.
Status NodeWorlds(const tinygltf::Model& model, const std::string& where,
                  std::vector<Mat34>* worlds) {
  const size_t n = model.nodes.size();
  std::vector<int> parent(n, -1);
  for (size_t i = 0; i < n; ++i) {
    for (const int child : model.nodes[i].children) {
      if (child < 0 || static_cast<size_t>(child) >= n || parent[static_cast<size_t>(child)] >= 0 ||
          static_cast<size_t>(child) == i)
        return Invalid(where + ": the node hierarchy is not a tree (node " + std::to_string(i) +
                       ")");
      parent[static_cast<size_t>(child)] = static_cast<int>(i);
    }
  }
  worlds->assign(n, Mat34{});
  for (size_t i = 0; i < n; ++i) {
    Mat34 world = NodeLocal(model.nodes[i]);
    size_t steps = 0;
    for (int p = parent[i]; p >= 0; p = parent[static_cast<size_t>(p)]) {
      if (++steps > n) return Invalid(where + ": the node hierarchy has a cycle");
      world = Multiply(NodeLocal(model.nodes[static_cast<size_t>(p)]), world);
    }
    if (!IsFinite(world)) return Invalid(where + ": node " + std::to_string(i) + " is not finite");
    (*worlds)[i] = world;
  }
  return Status::Ok();
}

std::string NodeName(const tinygltf::Model& model, int node) {
  const tinygltf::Node& n = model.nodes[static_cast<size_t>(node)];
  if (!n.name.empty() || n.mesh < 0) return n.name;
  return model.meshes[static_cast<size_t>(n.mesh)].name;
}

// The nodes of the default scene (every node when the file has no scene) that carry a mesh.
std::vector<int> MeshNodes(const tinygltf::Model& model) {
  std::vector<int> out, stack;
  const int scene = model.defaultScene >= 0 ? model.defaultScene : 0;
  if (static_cast<size_t>(scene) < model.scenes.size()) {
    stack = model.scenes[static_cast<size_t>(scene)].nodes;
  } else {
    for (size_t i = 0; i < model.nodes.size(); ++i) stack.push_back(static_cast<int>(i));
  }
  std::vector<char> seen(model.nodes.size(), 0);
  std::reverse(stack.begin(), stack.end());
  while (!stack.empty()) {
    const int node = stack.back();
    stack.pop_back();
    if (node < 0 || static_cast<size_t>(node) >= model.nodes.size() || seen[node]) continue;
    seen[node] = 1;
    const tinygltf::Node& n = model.nodes[static_cast<size_t>(node)];
    if (n.mesh >= 0 && static_cast<size_t>(n.mesh) < model.meshes.size()) out.push_back(node);
    for (auto it = n.children.rbegin(); it != n.children.rend(); ++it) stack.push_back(*it);
  }
  return out;
}

Status ChooseMeshNode(const tinygltf::Model& model, const std::string& where,
                      const std::string& wanted, int* node) {
  const std::vector<int> nodes = MeshNodes(model);
  std::vector<std::string> names;
  for (const int n : nodes) {
    names.push_back(Quote(NodeName(model, n)));
    const std::string& mesh_name =
        model.meshes[static_cast<size_t>(model.nodes[static_cast<size_t>(n)].mesh)].name;
    if (!wanted.empty() && (NodeName(model, n) == wanted || mesh_name == wanted)) {
      *node = n;
      return Status::Ok();
    }
  }
  if (nodes.empty()) return Invalid(where + ": the file's scene holds no mesh");
  const std::string list = JoinNames(names);
  if (wanted.empty() && nodes.size() == 1) {
    *node = nodes[0];
    return Status::Ok();
  }
  if (wanted.empty())
    return Invalid(where + ": the file holds several meshes (" + list + "); name one in `mesh`");
  return Invalid(where + ": no mesh named " + Quote(wanted) + " (the file's meshes: " + list + ")");
}

// The raw (unwelded) vertices of a mesh node's primitives.
struct RawMesh {
  std::vector<Float3> positions, colors;
  std::vector<float> max_distance, backstop;
  std::vector<std::array<uint16_t, 4>> joints;
  std::vector<std::array<float, 4>> weights;
  std::vector<uint32_t> triangles;
  bool all_colored = true, all_max_distance = true, all_backstop = true;
};

const int* FindAttribute(const tinygltf::Primitive& p, const char* name) {
  const auto it = p.attributes.find(name);
  return it == p.attributes.end() ? nullptr : &it->second;
}

Status ReadOptionalScalar(const tinygltf::Model& model, const tinygltf::Primitive& p,
                          const char* attribute, const std::string& what, size_t count,
                          bool* all_have, std::vector<float>* out) {
  const int* index = FindAttribute(p, attribute);
  if (index == nullptr) {
    *all_have = false;
    out->resize(out->size() + count, -1.f);
    return Status::Ok();
  }
  Elements e;
  if (Status s = Access(model, *index, what + "/" + attribute, {TINYGLTF_TYPE_SCALAR},
                        {TINYGLTF_COMPONENT_TYPE_FLOAT}, &e);
      !s.ok())
    return s;
  if (e.count != count) return Invalid(what + "/" + attribute + ": count differs from POSITION's");
  for (size_t i = 0; i < count; ++i) {
    const double v = e.Get(i, 0);
    if (!std::isfinite(v)) return Invalid(what + "/" + attribute + ": a value is not finite");
    out->push_back(static_cast<float>(v));
  }
  return Status::Ok();
}

Status ReadSkinAttributes(const tinygltf::Model& model, const tinygltf::Primitive& p,
                          const std::string& what, size_t count, size_t skin_joints, RawMesh* raw) {
  const int* joints = FindAttribute(p, "JOINTS_0");
  const int* weights = FindAttribute(p, "WEIGHTS_0");
  if (joints == nullptr || weights == nullptr)
    return Invalid(what + ": a skinned mesh's primitive needs JOINTS_0 and WEIGHTS_0");
  Elements j, w;
  if (Status s = Access(
          model, *joints, what + "/JOINTS_0", {TINYGLTF_TYPE_VEC4},
          {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT}, &j);
      !s.ok())
    return s;
  if (Status s = Access(model, *weights, what + "/WEIGHTS_0", {TINYGLTF_TYPE_VEC4},
                        {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                         TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT},
                        &w);
      !s.ok())
    return s;
  if (j.count != count || w.count != count)
    return Invalid(what + ": JOINTS_0 / WEIGHTS_0 counts differ from POSITION's");
  for (size_t i = 0; i < count; ++i) {
    std::array<uint16_t, 4> vj{};
    std::array<float, 4> vw{};
    for (int k = 0; k < 4; ++k) {
      const double weight = w.Get(i, k);
      if (!(weight >= 0.0 && weight <= 1e6))
        return Invalid(what + "/WEIGHTS_0: vertex " + std::to_string(i) + " has a bad weight");
      const double joint = j.Get(i, k);
      if (weight > 0.0 && joint >= static_cast<double>(skin_joints))
        return Invalid(what + "/JOINTS_0: vertex " + std::to_string(i) + " names joint " +
                       std::to_string(static_cast<long>(joint)) + " of a skin of " +
                       std::to_string(skin_joints));
      vj[k] = weight > 0.0 ? static_cast<uint16_t>(joint) : 0;
      vw[k] = static_cast<float>(weight);
    }
    raw->joints.push_back(vj);
    raw->weights.push_back(vw);
  }
  return Status::Ok();
}

Status ReadPrimitive(const tinygltf::Model& model, const tinygltf::Primitive& p,
                     const std::string& what, const Mat34* world, size_t skin_joints,
                     RawMesh* raw) {
  if (p.mode != TINYGLTF_MODE_TRIANGLES && p.mode != -1)
    return Invalid(what + ": mode " + std::to_string(p.mode) + " is not triangles");
  const int* position = FindAttribute(p, "POSITION");
  if (position == nullptr) return Invalid(what + ": no POSITION");
  Elements e;
  DRAPE_RETURN_IF_ERROR(Access(model, *position, what + "/POSITION", {TINYGLTF_TYPE_VEC3},
                               {TINYGLTF_COMPONENT_TYPE_FLOAT}, &e));
  const size_t base = raw->positions.size(), count = e.count;
  if (base + count > kMaxVertices) return Invalid(what + ": too many vertices");
  for (size_t i = 0; i < count; ++i) {
    Float3 v{static_cast<float>(e.Get(i, 0)), static_cast<float>(e.Get(i, 1)),
             static_cast<float>(e.Get(i, 2))};
    if (world != nullptr) v = TransformPoint(*world, v);
    if (!IsFinite(v))
      return Invalid(what + "/POSITION: vertex " + std::to_string(i) + " is not finite");
    raw->positions.push_back(v);
  }
  if (const int* color = FindAttribute(p, "COLOR_0")) {
    Elements c;
    DRAPE_RETURN_IF_ERROR(
        Access(model, *color, what + "/COLOR_0", {TINYGLTF_TYPE_VEC3, TINYGLTF_TYPE_VEC4},
               {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT},
               &c));
    if (c.count != count) return Invalid(what + "/COLOR_0: count differs from POSITION's");
    for (size_t i = 0; i < count; ++i) {
      const auto channel = [&](int k) {
        const double v = c.Get(i, k);
        return static_cast<float>(std::isfinite(v) ? std::clamp(v, 0.0, 1.0) : 0.0);
      };
      raw->colors.push_back({channel(0), channel(1), channel(2)});
    }
  } else {
    raw->all_colored = false;
    raw->colors.resize(raw->colors.size() + count);
  }
  DRAPE_RETURN_IF_ERROR(ReadOptionalScalar(model, p, kMaxDistanceAttribute, what, count,
                                           &raw->all_max_distance, &raw->max_distance));
  DRAPE_RETURN_IF_ERROR(ReadOptionalScalar(model, p, kBackstopAttribute, what, count,
                                           &raw->all_backstop, &raw->backstop));
  if (skin_joints > 0)
    DRAPE_RETURN_IF_ERROR(ReadSkinAttributes(model, p, what, count, skin_joints, raw));
  if (p.indices < 0) {  // not indexed: every three vertices
    for (size_t i = 0; i + 2 < count; i += 3)
      for (size_t k = 0; k < 3; ++k) raw->triangles.push_back(static_cast<uint32_t>(base + i + k));
    return Status::Ok();
  }
  Elements indices;
  DRAPE_RETURN_IF_ERROR(
      Access(model, p.indices, what + "/indices", {TINYGLTF_TYPE_SCALAR},
             {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
              TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT},
             &indices));
  for (size_t i = 0; i + 2 < indices.count; i += 3) {
    for (size_t k = 0; k < 3; ++k) {
      const double index = indices.Get(i + k, 0);
      if (index >= static_cast<double>(count))
        return Invalid(what + "/indices: index " + std::to_string(static_cast<uint64_t>(index)) +
                       " is beyond the " + std::to_string(count) + " vertices");
      raw->triangles.push_back(static_cast<uint32_t>(base + static_cast<size_t>(index)));
    }
  }
  return Status::Ok();
}

// One particle per distinct (position, skin): exporters split vertices at UV and normal seams,
// which would cut the cloth there. Welded indices follow the first occurrence (deterministic).
void Weld(const RawMesh& raw, GltfGarmentMesh* out) {
  using Key = std::tuple<std::array<uint32_t, 3>, std::array<uint16_t, 4>, std::array<uint32_t, 4>>;
  const auto bits = [](float v) {
    uint32_t b;
    v = v == 0.f ? 0.f : v;  // -0 and +0 weld
    std::memcpy(&b, &v, 4);
    return b;
  };
  const bool skinned = !raw.joints.empty();
  std::map<Key, uint32_t> index_of;
  std::vector<uint32_t> welded(raw.positions.size());
  for (size_t i = 0; i < raw.positions.size(); ++i) {
    const Float3 p = raw.positions[i];
    Key key{{bits(p.x), bits(p.y), bits(p.z)}, {}, {}};
    if (skinned) {
      std::get<1>(key) = raw.joints[i];
      for (int k = 0; k < 4; ++k) std::get<2>(key)[k] = bits(raw.weights[i][k]);
    }
    const auto [it, added] = index_of.emplace(key, static_cast<uint32_t>(out->positions.size()));
    welded[i] = it->second;
    if (!added) continue;
    out->positions.push_back(p);
    if (raw.all_colored) out->colors.push_back(raw.colors[i]);
    if (raw.all_max_distance) out->max_distance.push_back(raw.max_distance[i]);
    if (raw.all_backstop) out->backstop.push_back(raw.backstop[i]);
    if (skinned) {
      out->vertex_joints.push_back(raw.joints[i]);
      out->vertex_weights.push_back(raw.weights[i]);
    }
  }
  for (size_t t = 0; t + 2 < raw.triangles.size(); t += 3) {
    const uint32_t a = welded[raw.triangles[t]], b = welded[raw.triangles[t + 1]],
                   c = welded[raw.triangles[t + 2]];
    if (a == b || b == c || a == c) continue;  // collapsed by the weld
    out->triangles.insert(out->triangles.end(), {a, b, c});
  }
}

Status ReadSkin(const tinygltf::Model& model, int skin_index, const std::string& where,
                GltfGarmentMesh* out) {
  if (static_cast<size_t>(skin_index) >= model.skins.size())
    return Invalid(where + ": the mesh node's skin " + std::to_string(skin_index) +
                   " does not exist");
  const tinygltf::Skin& skin = model.skins[static_cast<size_t>(skin_index)];
  if (skin.joints.empty() || skin.joints.size() > 65536)
    return Invalid(where + ": the skin has " + std::to_string(skin.joints.size()) + " joints");
  for (const int node : skin.joints) {
    if (node < 0 || static_cast<size_t>(node) >= model.nodes.size())
      return Invalid(where + ": a skin joint names node " + std::to_string(node) +
                     ", which does not exist");
    const std::string& name = model.nodes[static_cast<size_t>(node)].name;
    if (name.empty())
      return Invalid(where + ": skin joint node " + std::to_string(node) +
                     " has no name (garments bind to the character's joints by name)");
    out->joint_names.push_back(name);
  }
  out->inverse_bind.assign(skin.joints.size(), Mat34{});
  if (skin.inverseBindMatrices < 0) return Status::Ok();  // identity, by the specification
  Elements e;
  DRAPE_RETURN_IF_ERROR(Access(model, skin.inverseBindMatrices, where + ": inverseBindMatrices",
                               {TINYGLTF_TYPE_MAT4}, {TINYGLTF_COMPONENT_TYPE_FLOAT}, &e));
  if (e.count < skin.joints.size())
    return Invalid(where + ": fewer inverse bind matrices than skin joints");
  for (size_t j = 0; j < skin.joints.size(); ++j) {
    double m[16];
    for (int k = 0; k < 16; ++k) m[k] = e.Get(j, k);
    out->inverse_bind[j] = ColumnMajor(m);
    if (!IsFinite(out->inverse_bind[j]))
      return Invalid(where + ": the inverse bind matrix of joint " + Quote(out->joint_names[j]) +
                     " is not finite");
  }
  return Status::Ok();
}

bool LoadModel(const std::string& file, tinygltf::Model* model, std::string* error) {
  tinygltf::TinyGLTF loader;
  // Garments need no pictures: images are neither decoded nor required.
  loader.SetImageLoader([](tinygltf::Image*, const int, std::string*, std::string*, int, int,
                           const unsigned char*, int, void*) { return true; },
                        nullptr);
  std::string warning;
  const bool binary = file.size() >= 4 && (file.compare(file.size() - 4, 4, ".glb") == 0 ||
                                           file.compare(file.size() - 4, 4, ".GLB") == 0);
  return binary ? loader.LoadBinaryFromFile(model, error, &warning, file)
                : loader.LoadASCIIFromFile(model, error, &warning, file);
}

}  // namespace

Status ReadGltfGarment(const std::string& file, const std::string& where, const std::string& mesh,
                       GltfGarmentMesh* out) {
  *out = GltfGarmentMesh{};
  const std::string at = where + ": " + file;
  tinygltf::Model model;
  std::string error;
  if (!LoadModel(file, &model, &error)) {
    while (!error.empty() && (error.back() == '\n' || error.back() == ' ')) error.pop_back();
    return Invalid(at + ": not a readable glTF 2.0 file (" + (error.empty() ? "?" : error) + ")");
  }
  int node = -1;
  DRAPE_RETURN_IF_ERROR(ChooseMeshNode(model, at, mesh, &node));
  std::vector<Mat34> worlds;
  DRAPE_RETURN_IF_ERROR(NodeWorlds(model, at, &worlds));
  const tinygltf::Node& n = model.nodes[static_cast<size_t>(node)];
  out->name = NodeName(model, node);
  const std::string what = at + ": mesh " + Quote(out->name);
  if (n.skin >= 0) DRAPE_RETURN_IF_ERROR(ReadSkin(model, n.skin, what, out));
  // A skinned mesh's vertices are in bind space: the node's own transform does not apply.
  const Mat34* world = n.skin >= 0 ? nullptr : &worlds[static_cast<size_t>(node)];
  RawMesh raw;
  const tinygltf::Mesh& m = model.meshes[static_cast<size_t>(n.mesh)];
  for (size_t i = 0; i < m.primitives.size(); ++i) {
    DRAPE_RETURN_IF_ERROR(ReadPrimitive(model, m.primitives[i],
                                        what + " primitive " + std::to_string(i), world,
                                        out->joint_names.size(), &raw));
  }
  Weld(raw, out);
  if (out->triangles.empty()) return Invalid(what + ": has no triangles");
  return Status::Ok();
}

Status BindGltfGarment(const GltfGarmentMesh& mesh, const SkeletonData& skeleton, float tolerance,
                       const std::string& where, GltfGarmentBinding* out) {
  *out = GltfGarmentBinding{};
  if (mesh.joint_names.empty()) return Invalid(where + ": the garment's mesh has no skin");
  // File joint -> skeleton joint and file bind space -> asset bind frame, for weighted joints.
  const size_t joints = mesh.joint_names.size();
  std::vector<int32_t> to_skeleton(joints, -1);
  std::vector<Mat34> to_bind(joints);
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    for (int k = 0; k < 4; ++k) {
      const uint16_t j = mesh.vertex_joints[v][k];
      if (!(mesh.vertex_weights[v][k] > 0.f) || to_skeleton[j] >= 0) continue;
      to_skeleton[j] = FindJoint(skeleton, mesh.joint_names[j]);
      if (to_skeleton[j] < 0) {
        const std::vector<std::string> near =
            NearestNames(mesh.joint_names[j], skeleton.joint_names, 4);
        return Invalid(where + ": the garment's skin joint " + Quote(mesh.joint_names[j]) +
                       " is not a joint of the character" +
                       (near.empty() ? "" : " (did you mean " + JoinNames(near) + "?)"));
      }
      Mat34 bind_world;
      if (!InverseAffine(skeleton.inverse_bind[static_cast<size_t>(to_skeleton[j])], &bind_world))
        bind_world = Mat34{};
      to_bind[j] = Multiply(bind_world, mesh.inverse_bind[j]);
    }
  }
  // The file's skeleton must be the character's up to one transform of the whole (units, an
  // armature's placement): every joint maps a vertex where the most weighted joint maps it.
  std::vector<float> joint_weight(joints, 0.f);
  for (size_t v = 0; v < mesh.positions.size(); ++v)
    for (int k = 0; k < 4; ++k)
      if (mesh.vertex_weights[v][k] > 0.f)
        joint_weight[mesh.vertex_joints[v][k]] += mesh.vertex_weights[v][k];
  const size_t reference = static_cast<size_t>(
      std::max_element(joint_weight.begin(), joint_weight.end()) - joint_weight.begin());
  out->scale = UniformScale(to_bind[reference]);
  out->skin.resize(mesh.positions.size());
  out->bind_positions.resize(mesh.positions.size());
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    // Weights summed per skeleton joint (two file joints may share a name), then normalised.
    std::map<uint32_t, float> by_joint;
    float total = 0.f;
    Float3 blended;
    const Float3 expected = TransformPoint(to_bind[reference], mesh.positions[v]);
    for (int k = 0; k < 4; ++k) {
      const float w = mesh.vertex_weights[v][k];
      if (!(w > 0.f)) continue;
      const uint16_t j = mesh.vertex_joints[v][k];
      by_joint[static_cast<uint32_t>(to_skeleton[j])] += w;
      total += w;
      const Float3 p = TransformPoint(to_bind[j], mesh.positions[v]);
      blended += p * w;
      const float apart = Length(p - expected);
      if (apart > tolerance)
        return Invalid(where + ": joint " + Quote(mesh.joint_names[j]) + " places vertex " +
                       std::to_string(v) + " " + std::to_string(apart * 1000.f) +
                       " mm from where joint " + Quote(mesh.joint_names[reference]) +
                       " does (more than " + std::to_string(tolerance * 1000.f) +
                       " mm): the file's skeleton at bind is not the character's (another rig or "
                       "another bind pose)");
    }
    if (!(total > 0.f))
      return Invalid(where + ": vertex " + std::to_string(v) + " has no skin weight");
    out->bind_positions[v] = blended * (1.f / total);
    ClothSkinWeights& w = out->skin[v];
    int k = 0;
    for (const auto& [joint, weight] : by_joint) {
      w.joints[k] = joint;
      w.weights[k] = weight / total;
      ++k;
    }
  }
  return Status::Ok();
}

}  // namespace drape::bake::detail

// glTF 2.0 through tinygltf (the Debian package): one buffer, one view per array, accessors
// with the bounds the specification requires; matrices turned from drape's row-major 3x4 to
// glTF's column-major 4x4.
#include "drape/bake/gltf_export.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "capsule/capsule_fit.h"
#include "drape/formats/asset_file.h"
#include "drape/runtime/math.h"
#include "import/import_transforms.h"

namespace drape::bake {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::vector<double> GltfMatrix(const Mat34& m) {  // column-major 4x4
  std::vector<double> out(16, 0.0);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 3; ++r) out[static_cast<size_t>(c * 4 + r)] = m.m[r * 4 + c];
  out[15] = 1.0;
  return out;
}

// The model under construction: one buffer that every view appends to.
class Builder {
 public:
  tinygltf::Model model;
  Builder() {
    model.asset.version = "2.0";
    model.asset.generator = "drape-bake";
    model.buffers.emplace_back();
  }

  int View(const void* data, size_t bytes, int target) {
    std::vector<unsigned char>& buffer = model.buffers[0].data;
    buffer.resize((buffer.size() + 3) / 4 * 4, 0);  // 4-byte aligned views
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = buffer.size();
    view.byteLength = bytes;
    view.target = target;
    const auto* p = static_cast<const unsigned char*>(data);
    buffer.insert(buffer.end(), p, p + bytes);
    model.bufferViews.push_back(view);
    return static_cast<int>(model.bufferViews.size()) - 1;
  }

  int Accessor(int view, int component, size_t count, int type, std::vector<double> min = {},
               std::vector<double> max = {}) {
    tinygltf::Accessor a;
    a.bufferView = view;
    a.componentType = component;
    a.count = count;
    a.type = type;
    a.minValues = std::move(min);
    a.maxValues = std::move(max);
    model.accessors.push_back(a);
    return static_cast<int>(model.accessors.size()) - 1;
  }

  int Positions(const std::vector<Float3>& p) {
    std::vector<double> lo(3, 1e300), hi(3, -1e300);
    for (const Float3& v : p) {
      const double c[3] = {v.x, v.y, v.z};
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], c[k]), hi[k] = std::max(hi[k], c[k]);
    }
    const int view = View(p.data(), p.size() * sizeof(Float3), TINYGLTF_TARGET_ARRAY_BUFFER);
    return Accessor(view, TINYGLTF_COMPONENT_TYPE_FLOAT, p.size(), TINYGLTF_TYPE_VEC3, lo, hi);
  }

  int Indices(const std::vector<uint32_t>& i) {
    const int view =
        View(i.data(), i.size() * sizeof(uint32_t), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    return Accessor(view, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, i.size(), TINYGLTF_TYPE_SCALAR);
  }

  int Material(const char* name, double r, double g, double b, double alpha) {
    tinygltf::Material m;
    m.name = name;
    m.pbrMetallicRoughness.baseColorFactor = {r, g, b, alpha};
    m.pbrMetallicRoughness.metallicFactor = 0.0;
    m.pbrMetallicRoughness.roughnessFactor = 0.8;
    if (alpha < 1.0) m.alphaMode = "BLEND";
    m.doubleSided = alpha < 1.0;
    model.materials.push_back(m);
    return static_cast<int>(model.materials.size()) - 1;
  }

  int Mesh(const std::string& name, int positions, int indices, int material,
           std::map<std::string, int> extra = {}) {
    tinygltf::Primitive primitive;
    primitive.attributes = std::move(extra);
    primitive.attributes["POSITION"] = positions;
    primitive.indices = indices;
    primitive.material = material;
    primitive.mode = TINYGLTF_MODE_TRIANGLES;
    tinygltf::Mesh mesh;
    mesh.name = name;
    mesh.primitives.push_back(primitive);
    model.meshes.push_back(mesh);
    return static_cast<int>(model.meshes.size()) - 1;
  }

  int Node(tinygltf::Node node, int parent) {
    model.nodes.push_back(std::move(node));
    const int index = static_cast<int>(model.nodes.size()) - 1;
    if (parent >= 0) model.nodes[static_cast<size_t>(parent)].children.push_back(index);
    return index;
  }
};

// The skeleton's nodes in the rest pose; joint j is node j.
void AddSkeleton(const SkeletonData& skeleton, Builder* b) {
  for (uint32_t j = 0; j < skeleton.joint_count(); ++j) {
    const Transform& t = skeleton.rest_local[j];
    const Quat q = Normalize(t.rotation);
    tinygltf::Node node;
    node.name = skeleton.joint_names[j];
    node.translation = {t.translation.x, t.translation.y, t.translation.z};
    node.rotation = {q.x, q.y, q.z, q.w};
    node.scale = {t.scale.x, t.scale.y, t.scale.z};
    b->Node(node, skeleton.parents[j]);
  }
}

int AddSkin(const SkeletonData& skeleton, Builder* b) {
  std::vector<float> matrices;
  for (const Mat34& m : skeleton.inverse_bind)
    for (const double v : GltfMatrix(m)) matrices.push_back(static_cast<float>(v));
  const int view = b->View(matrices.data(), matrices.size() * sizeof(float), 0);
  tinygltf::Skin skin;
  skin.inverseBindMatrices =
      b->Accessor(view, TINYGLTF_COMPONENT_TYPE_FLOAT, skeleton.joint_count(), TINYGLTF_TYPE_MAT4);
  for (uint32_t j = 0; j < skeleton.joint_count(); ++j) skin.joints.push_back(static_cast<int>(j));
  b->model.skins.push_back(skin);
  return static_cast<int>(b->model.skins.size()) - 1;
}

// JOINTS_0 and WEIGHTS_0 from four (joint, weight) pairs per vertex.
std::map<std::string, int> SkinAttributes(const std::vector<uint16_t>& joints,
                                          const std::vector<float>& weights, Builder* b) {
  const size_t n = joints.size() / 4;
  const int joints_view = b->View(joints.data(), joints.size() * 2, TINYGLTF_TARGET_ARRAY_BUFFER);
  const int weights_view =
      b->View(weights.data(), weights.size() * 4, TINYGLTF_TARGET_ARRAY_BUFFER);
  return {{"JOINTS_0",
           b->Accessor(joints_view, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, n, TINYGLTF_TYPE_VEC4)},
          {"WEIGHTS_0",
           b->Accessor(weights_view, TINYGLTF_COMPONENT_TYPE_FLOAT, n, TINYGLTF_TYPE_VEC4)}};
}

// The bind mesh skinned by its four strongest influences (renormalised).
int AddBody(const MeshData& mesh, int skin, Builder* b) {
  const size_t n = mesh.positions.size();
  std::vector<uint16_t> joints(4 * n, 0);
  std::vector<float> weights(4 * n, 0.f);
  for (size_t v = 0; v < n; ++v) {
    std::vector<std::pair<float, uint16_t>> influences;
    if (mesh.influence_offsets.size() == n + 1) {
      for (uint32_t k = mesh.influence_offsets[v]; k < mesh.influence_offsets[v + 1]; ++k)
        influences.emplace_back(mesh.influence_weights[k], mesh.influence_joints[k]);
    }
    std::sort(influences.begin(), influences.end(), std::greater<>());
    influences.resize(std::min<size_t>(4, influences.size()));
    float sum = 0.f;
    for (const auto& [w, j] : influences) sum += w;
    if (!(sum > 0.f)) influences = {{1.f, 0}}, sum = 1.f;  // unskinned: carried by the root
    for (size_t k = 0; k < influences.size(); ++k) {
      weights[4 * v + k] = influences[k].first / sum;
      joints[4 * v + k] = influences[k].second;
    }
  }
  const int mesh_index =
      b->Mesh("body", b->Positions(mesh.positions), b->Indices(mesh.triangles),
              b->Material("body", 0.7, 0.7, 0.7, 1.0), SkinAttributes(joints, weights, b));
  tinygltf::Node node;
  node.name = "body";
  node.mesh = mesh_index;
  node.skin = skin;
  return b->Node(node, -1);
}

// Joint j's frame at bind: a child node's local transform for something placed at bind in the
// asset frame is inverse_bind[j] times its asset-frame transform.
const Mat34& JointFromAsset(const SkeletonData& skeleton, int32_t joint) {
  static const Mat34 identity;
  return joint >= 0 ? skeleton.inverse_bind[static_cast<size_t>(joint)] : identity;
}

void AddHulls(const CharacterAsset& asset, Builder* b) {
  const int material = b->Material("hull", 0.1, 0.8, 0.3, 0.35);
  for (size_t h = 0; h < asset.hulls.size(); ++h) {
    const HullColliderData& hull = asset.hulls[h];
    const std::string name =
        "hull " +
        (hull.joint >= 0 ? asset.skeleton.joint_names[static_cast<size_t>(hull.joint)]
                         : std::string("root")) +
        " " + std::to_string(h);
    tinygltf::Node node;
    node.name = name;
    node.mesh = b->Mesh(name, b->Positions(hull.vertices), b->Indices(hull.triangles), material);
    node.matrix = GltfMatrix(Multiply(JointFromAsset(asset.skeleton, hull.joint), hull.bind_frame));
    b->Node(node, hull.joint);
  }
}

// A unit UV sphere, shared by every joint sphere (a node scale gives each its radius).
int UnitSphere(Builder* b, int material) {
  constexpr int kRings = 12, kSegments = 16;
  std::vector<Float3> p;
  std::vector<uint32_t> t;
  for (int r = 0; r <= kRings; ++r) {
    const double theta = kPi * r / kRings;
    for (int s = 0; s < kSegments; ++s) {
      const double phi = 2.0 * kPi * s / kSegments;
      p.push_back({static_cast<float>(std::sin(theta) * std::cos(phi)),
                   static_cast<float>(std::cos(theta)),
                   static_cast<float>(std::sin(theta) * std::sin(phi))});
    }
  }
  for (uint32_t r = 0; r < kRings; ++r) {
    for (uint32_t s = 0; s < kSegments; ++s) {
      const uint32_t a = r * kSegments + s, c = r * kSegments + (s + 1) % kSegments;
      t.insert(t.end(), {a, c, a + kSegments, c, c + kSegments, a + kSegments});
    }
  }
  return b->Mesh("joint sphere", b->Positions(p), b->Indices(t), material);
}

void AddJointSpheres(const CharacterAsset& asset, Builder* b) {
  if (asset.joint_spheres.empty()) return;
  const int mesh = UnitSphere(b, b->Material("joint sphere", 0.2, 0.4, 0.9, 0.35));
  for (size_t s = 0; s < asset.joint_spheres.size(); ++s) {
    const JointSphereData& sphere = asset.joint_spheres[s];
    const Mat34& local = JointFromAsset(asset.skeleton, sphere.joint);
    const Float3 c = TransformPoint(local, sphere.center);
    // The radius is in asset metres; the joint's frame may be scaled (a rig bound in cm).
    const double r = sphere.radius * UniformScale(local);
    tinygltf::Node node;
    node.name = "joint sphere " + std::to_string(s);
    node.mesh = mesh;
    node.translation = {c.x, c.y, c.z};
    node.scale = {r, r, r};
    b->Node(node, sphere.joint);
  }
}

// Every capsule as a translucent round cone on its joint, in the joint's frame (its radii scaled
// as the joint spheres' are).
void AddCapsules(const CharacterAsset& asset, Builder* b) {
  if (asset.capsules.empty()) return;
  const int material = b->Material("capsule", 0.9, 0.6, 0.1, 0.35);
  for (size_t c = 0; c < asset.capsules.size(); ++c) {
    const CapsuleColliderData& k = asset.capsules[c];
    const Mat34& local = JointFromAsset(asset.skeleton, k.joint);
    const double scale = UniformScale(local);
    const Float3 from = TransformPoint(local, k.from), to = TransformPoint(local, k.to);
    const double a[3] = {from.x, from.y, from.z}, e[3] = {to.x, to.y, to.z};
    std::vector<double> vertices;
    std::vector<uint32_t> triangles;
    RoundConeMesh(a, k.radius_from * scale, e, k.radius_to * scale, 16, 4, &vertices, &triangles);
    std::vector<Float3> positions(vertices.size() / 3);
    for (size_t v = 0; v < positions.size(); ++v)
      positions[v] = {static_cast<float>(vertices[3 * v]), static_cast<float>(vertices[3 * v + 1]),
                      static_cast<float>(vertices[3 * v + 2])};
    const std::string name = "capsule " + asset.skeleton.joint_names[static_cast<size_t>(k.joint)] +
                             " " + std::to_string(c);
    tinygltf::Node node;
    node.name = name;
    node.mesh = b->Mesh(name, b->Positions(positions), b->Indices(triangles), material);
    b->Node(node, k.joint);
  }
}

// The skeleton, skin and skinned body; returns the body's node.
int AddCharacter(const CharacterAsset& asset, Builder* b) {
  AddSkeleton(asset.skeleton, b);
  const int skin = AddSkin(asset.skeleton, b);
  return AddBody(asset.mesh, skin, b);
}

Status Write(const CharacterAsset& asset, const std::vector<int>& extra_roots,
             const std::string& path, Builder* b) {
  tinygltf::Scene scene;
  scene.name = asset.info.source_name;
  for (uint32_t j = 0; j < asset.skeleton.joint_count(); ++j)
    if (asset.skeleton.parents[j] < 0) scene.nodes.push_back(static_cast<int>(j));
  scene.nodes.insert(scene.nodes.end(), extra_roots.begin(), extra_roots.end());
  b->model.scenes.push_back(scene);
  b->model.defaultScene = 0;
  b->model.buffers[0].data.resize((b->model.buffers[0].data.size() + 3) / 4 * 4, 0);
  const bool binary = path.size() >= 4 && path.compare(path.size() - 4, 4, ".glb") == 0;
  std::ostringstream out;
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToStream(&b->model, out, /*prettyPrint=*/!binary, binary))
    return Status(StatusCode::kInvalidArgument, path + ": the glTF writer failed");
  return WriteFileAtomically(path, out.str());
}

// Per frame, each joint's local transform from the skinning matrices, in double: world =
// skinning * inverse(inverse bind), local = inverse(parent world) * world, decomposed as the
// import decomposes (import/import_transforms.h).
std::vector<Transform> LocalPoses(const SkeletonData& skeleton,
                                  const std::vector<std::vector<Mat34>>& skinning) {
  const uint32_t joints = skeleton.joint_count();
  std::vector<detail::Mat4> bind_world(joints), world(joints);
  for (uint32_t j = 0; j < joints; ++j)
    bind_world[j] = detail::ToEigen(skeleton.inverse_bind[j]).inverse();
  std::vector<Transform> local(skinning.size() * joints);
  for (size_t f = 0; f < skinning.size(); ++f) {
    for (uint32_t j = 0; j < joints; ++j) {
      world[j] = detail::ToEigen(skinning[f][j]) * bind_world[j];
      const int32_t p = skeleton.parents[j];
      const detail::Mat4 relative =
          p < 0 ? world[j] : detail::Mat4(world[static_cast<size_t>(p)].inverse() * world[j]);
      detail::Decompose(relative, &local[f * joints + j]);
    }
  }
  return local;
}

// Key times (seconds, strictly increasing) with their bounds.
int TimeAccessor(const std::vector<float>& times, Builder* b) {
  const int view = b->View(times.data(), times.size() * sizeof(float), 0);
  return b->Accessor(view, TINYGLTF_COMPONENT_TYPE_FLOAT, times.size(), TINYGLTF_TYPE_SCALAR,
                     {times.front()}, {times.back()});
}

tinygltf::AnimationSampler Sampler(int input, int output, const char* interpolation) {
  tinygltf::AnimationSampler sampler;
  sampler.input = input;
  sampler.output = output;
  sampler.interpolation = interpolation;
  return sampler;
}

// One channel per joint and path over the recorded frames.
void AddPoseChannels(const std::vector<Transform>& local, uint32_t joints, int input,
                     tinygltf::Animation* animation, Builder* b) {
  const size_t frames = local.size() / joints;
  for (uint32_t j = 0; j < joints; ++j) {
    std::vector<float> translation, rotation, scale;
    for (size_t f = 0; f < frames; ++f) {
      const Transform& k = local[f * joints + j];
      translation.insert(translation.end(), {k.translation.x, k.translation.y, k.translation.z});
      rotation.insert(rotation.end(), {k.rotation.x, k.rotation.y, k.rotation.z, k.rotation.w});
      scale.insert(scale.end(), {k.scale.x, k.scale.y, k.scale.z});
    }
    for (const auto& [path, values, type] :
         {std::tuple{"translation", &translation, TINYGLTF_TYPE_VEC3},
          std::tuple{"rotation", &rotation, TINYGLTF_TYPE_VEC4},
          std::tuple{"scale", &scale, TINYGLTF_TYPE_VEC3}}) {
      const int view = b->View(values->data(), values->size() * sizeof(float), 0);
      animation->samplers.push_back(
          Sampler(input, b->Accessor(view, TINYGLTF_COMPONENT_TYPE_FLOAT, frames, type), "LINEAR"));
      tinygltf::AnimationChannel channel;
      channel.sampler = static_cast<int>(animation->samplers.size()) - 1;
      channel.target_node = static_cast<int>(j);
      channel.target_path = path;
      animation->channels.push_back(channel);
    }
  }
}

// A clip as an animation of the joints' local transforms. Key times strictly increase: frames
// whose time does not advance past the previous one's are left out.
void AddClip(const ClipData& clip, uint32_t joint_count, Builder* b) {
  std::vector<float> times;
  std::vector<Transform> local;
  for (uint32_t f = 0; f < clip.frame_count; ++f) {
    const float t = std::min(static_cast<float>(f) / clip.sample_rate, clip.duration);
    if (!times.empty() && !(t > times.back())) continue;
    times.push_back(t);
    for (uint32_t j = 0; j < joint_count; ++j) {
      Transform k = clip.keys[static_cast<size_t>(f) * joint_count + j];
      k.rotation = Normalize(k.rotation);
      local.push_back(k);
    }
  }
  tinygltf::Animation animation;
  animation.name = clip.name;
  AddPoseChannels(local, joint_count, TimeAccessor(times, b), &animation, b);
  b->model.animations.push_back(animation);
}

// A garment: frame 0 as the mesh, frame k as morph target k - 1, and weights that switch to
// target k - 1 at frame k (STEP). Returns its node.
int AddGarment(const SimulationRecording::Garment& g, int input, tinygltf::Animation* animation,
               Builder* b) {
  const int material = b->Material("garment", 0.85, 0.35, 0.25, 1.0);
  const int mesh = b->Mesh(g.name, b->Positions(g.positions[0]), b->Indices(g.triangles), material);
  const size_t frames = g.positions.size();
  tinygltf::Primitive& primitive = b->model.meshes[static_cast<size_t>(mesh)].primitives[0];
  for (size_t f = 1; f < frames; ++f) {
    std::vector<Float3> delta(g.positions[f].size());
    for (size_t i = 0; i < delta.size(); ++i) delta[i] = g.positions[f][i] - g.positions[0][i];
    primitive.targets.push_back({{"POSITION", b->Positions(delta)}});
  }
  b->model.meshes[static_cast<size_t>(mesh)].weights.assign(frames - 1, 0.0);
  std::vector<float> weights(frames * (frames - 1), 0.f);
  for (size_t f = 1; f < frames; ++f) weights[f * (frames - 1) + (f - 1)] = 1.f;
  const int view = b->View(weights.data(), weights.size() * sizeof(float), 0);
  animation->samplers.push_back(Sampler(
      input, b->Accessor(view, TINYGLTF_COMPONENT_TYPE_FLOAT, weights.size(), TINYGLTF_TYPE_SCALAR),
      "STEP"));
  tinygltf::Node node;
  node.name = g.name;
  node.mesh = mesh;
  const int index = b->Node(node, -1);
  tinygltf::AnimationChannel channel;
  channel.sampler = static_cast<int>(animation->samplers.size()) - 1;
  channel.target_node = index;
  channel.target_path = "weights";
  animation->channels.push_back(channel);
  return index;
}

// A per-vertex distance as a SCALAR float attribute: metres, -1 for unlimited (+inf is not a
// value a glTF accessor may hold).
int DistanceAttribute(const std::vector<float>& metres, Builder* b) {
  std::vector<float> values(metres.size());
  for (size_t i = 0; i < metres.size(); ++i)
    values[i] = std::isfinite(metres[i]) ? metres[i] : -1.f;
  const int view =
      b->View(values.data(), values.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER);
  return b->Accessor(view, TINYGLTF_COMPONENT_TYPE_FLOAT, values.size(), TINYGLTF_TYPE_SCALAR);
}

int AddBoundGarment(const GarmentExport& g, int skin, Builder* b) {
  const size_t n = g.bind_positions.size();
  std::vector<uint16_t> joints(4 * n, 0);
  std::vector<float> weights(4 * n, 0.f);
  for (size_t v = 0; v < n; ++v) {
    for (int k = 0; k < 4; ++k) {
      joints[4 * v + k] = static_cast<uint16_t>(g.skin[v].joints[k]);
      weights[4 * v + k] = g.skin[v].weights[k];
    }
  }
  std::map<std::string, int> attributes = SkinAttributes(joints, weights, b);
  if (g.max_distance.size() == n)
    attributes[detail::kGltfMaxDistanceAttribute] = DistanceAttribute(g.max_distance, b);
  if (g.backstop.size() == n)
    attributes[detail::kGltfBackstopAttribute] = DistanceAttribute(g.backstop, b);
  tinygltf::Node node;
  node.name = g.name;
  node.mesh = b->Mesh(g.name, b->Positions(g.bind_positions), b->Indices(g.triangles),
                      b->Material("garment", 0.85, 0.35, 0.25, 1.0), std::move(attributes));
  node.skin = skin;
  return b->Node(node, -1);
}

}  // namespace

Status WriteGarmentGltf(const CharacterAsset& asset, const GarmentExport& garment,
                        const std::string& path) {
  const auto invalid = [&](const std::string& why) {
    return Status(StatusCode::kInvalidArgument, path + ": " + why);
  };
  const uint32_t joints = asset.skeleton.joint_count();
  const size_t n = garment.bind_positions.size();
  if (joints == 0) return invalid("the asset has no skeleton to bind the garment to");
  if (joints > 65535) return invalid("more joints than JOINTS_0 can name");
  if (garment.skin.size() != n || n == 0 || garment.triangles.size() % 3 != 0)
    return invalid("garment " + garment.name + ": no particles, or skin and positions differ");
  for (const ClothSkinWeights& w : garment.skin)
    for (int k = 0; k < 4; ++k)
      if (w.weights[k] > 0.f && w.joints[k] >= joints)
        return invalid("garment " + garment.name + ": a skin weight names no joint");
  for (const uint32_t t : garment.triangles)
    if (t >= n) return invalid("garment " + garment.name + ": a triangle names no particle");
  Builder b;
  const int body = AddCharacter(asset, &b);
  const int node = AddBoundGarment(garment, b.model.nodes[static_cast<size_t>(body)].skin, &b);
  return Write(asset, {body, node}, path, &b);
}

Status WriteAssetGltf(const CharacterAsset& asset, const std::string& path) {
  if (asset.skeleton.joint_count() == 0)
    return Status(StatusCode::kInvalidArgument, path + ": the asset has no skeleton to export");
  Builder b;
  const int body = AddCharacter(asset, &b);
  AddHulls(asset, &b);
  AddJointSpheres(asset, &b);
  AddCapsules(asset, &b);
  const uint32_t joints = asset.skeleton.joint_count();
  for (const ClipData& clip : asset.clips)
    if (clip.frame_count > 1 && clip.keys.size() == size_t{clip.frame_count} * joints)
      AddClip(clip, joints, &b);
  return Write(asset, {body}, path, &b);
}

Status WriteSimulationGltf(const CharacterAsset& asset, const SimulationRecording& recording,
                           const std::string& path) {
  const auto invalid = [&](const std::string& why) {
    return Status(StatusCode::kInvalidArgument, path + ": " + why);
  };
  const uint32_t joints = asset.skeleton.joint_count();
  const size_t frames = recording.skinning.size();
  if (joints == 0) return invalid("the asset has no skeleton to export");
  if (frames < 2 || !(recording.frame_seconds > 0.f))
    return invalid("a simulation of at least two recorded frames, frame_seconds > 0, is needed");
  for (const std::vector<Mat34>& frame : recording.skinning)
    if (frame.size() < joints) return invalid("a recorded frame has too few skinning matrices");
  for (const SimulationRecording::Garment& g : recording.garments)
    if (g.positions.size() != frames) return invalid("garment " + g.name + ": frames missing");
  Builder b;
  const int body = AddCharacter(asset, &b);
  std::vector<float> times(frames);
  for (size_t f = 0; f < frames; ++f) times[f] = static_cast<float>(f) * recording.frame_seconds;
  const int input = TimeAccessor(times, &b);
  tinygltf::Animation animation;
  animation.name = "simulation";
  AddPoseChannels(LocalPoses(asset.skeleton, recording.skinning), joints, input, &animation, &b);
  std::vector<int> roots = {body};
  for (const SimulationRecording::Garment& g : recording.garments)
    roots.push_back(AddGarment(g, input, &animation, &b));
  b.model.animations.push_back(animation);
  return Write(asset, roots, path, &b);
}

}  // namespace drape::bake

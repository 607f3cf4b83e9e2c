#include "import/mesh_import.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>
#include <utility>

#include "import/import_messages.h"
#include "import/orient_components.h"

namespace drape::bake::detail {
namespace {

using Vec3 = Eigen::Vector3d;
using Influences = std::vector<std::pair<int, float>>;  // (joint, weight) as the file gives them
using Skin = std::vector<std::pair<int, double>>;       // sorted by joint, sums to 1

// What the import repaired, counted over every mesh and reported once they are all read.
struct MeshRepairs {
  size_t weight_sum_warnings = 0, zero_weight_vertices = 0, degenerate_triangles = 0,
         weld_conflicts = 0;
  size_t mesh_space_mismatch = 0;
};

// The vertices of one source mesh welded by position. Per welded vertex of this mesh (from
// first_vertex on): its first copy's normalised skin, and the normalised skins of all its copies,
// averaged once the mesh is read.
struct WeldedMesh {
  std::map<std::tuple<float, float, float>, uint32_t> welded;
  std::vector<uint32_t> remap;  // source vertex -> welded vertex
  uint32_t first_vertex = 0;
  std::vector<Skin> first_skin, all_skins;
  std::vector<uint32_t> copies;
};

// Source-space bind transform of a mesh instance's vertices (docs/ALGORITHMS.md §1.1), and the
// joint an unskinned mesh is rigid to (left at -1 for a skinned mesh).
Mat4 BindTransform(const SourceScene& source, const JointNodes& joints,
                   const std::vector<Mat4>& inverse_bind_source, int node, const aiMesh* m,
                   int* rigid_joint, MeshRepairs* repairs) {
  const std::vector<SourceNode>& nodes = source.nodes;
  Mat4 to_bind = Mat4::Identity();
  if (joints.synthetic_root) {
    to_bind = nodes[node].global_rest;
    *rigid_joint = 0;
  } else if (m->mNumBones == 0) {
    const int jn = JointAncestor(source, joints, node);
    *rigid_joint = joints.joint_of_node[jn];
    to_bind = inverse_bind_source[*rigid_joint].inverse() * nodes[jn].global_rest.inverse() *
              nodes[node].global_rest;
  } else {
    // A mesh whose offset matrices differ from the first mesh's by a constant transform lives
    // in another mesh space: bring it into the shared one.
    bool first = true;
    for (unsigned b = 0; b < m->mNumBones; ++b) {
      const int jn = source.node_by_name.at(m->mBones[b]->mName.C_Str());
      const Mat4 correction = inverse_bind_source[joints.joint_of_node[jn]].inverse() *
                              ToEigen(m->mBones[b]->mOffsetMatrix);
      if (first) {
        to_bind = correction;
        first = false;
      } else if (!correction.isApprox(to_bind, 1e-4)) {
        ++repairs->mesh_space_mismatch;
      }
    }
  }
  return to_bind;
}

// Influences per source vertex, in bone order; weights that are not positive are left out.
Status GatherInfluences(const std::string& path, const SourceScene& source,
                        const JointNodes& joints, const aiMesh* m,
                        std::vector<Influences>* influences) {
  for (unsigned b = 0; b < m->mNumBones; ++b) {
    const aiBone* bone = m->mBones[b];
    const int joint = joints.joint_of_node[source.node_by_name.at(bone->mName.C_Str())];
    for (unsigned w = 0; w < bone->mNumWeights; ++w) {
      const float weight = bone->mWeights[w].mWeight;
      if (!std::isfinite(weight))
        return SourceError(
            path, StatusCode::kCorrupt,
            "bone '" + std::string(bone->mName.C_Str()) + "' has a non-finite weight");
      if (weight > 0.f) (*influences)[bone->mWeights[w].mVertexId].emplace_back(joint, weight);
    }
  }
  return Status::Ok();
}

// A vertex's skin: its influences (all on rigid_joint for a rigid mesh), repeated joints merged,
// renormalised. A vertex without weight becomes rigid to fallback_joint.
Skin NormalisedSkin(const Influences& influences, int rigid_joint, int fallback_joint,
                    MeshRepairs* repairs) {
  std::vector<std::pair<int, float>> inf = influences;
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
    ++repairs->zero_weight_vertices;
    merged = {{fallback_joint, 1.f}};
    sum = 1.0;
  } else if (sum < 0.9 || sum > 1.1) {
    ++repairs->weight_sum_warnings;
  }
  Skin skin;
  for (const auto& [joint, weight] : merged) skin.emplace_back(joint, weight / sum);
  return skin;
}

// Source vertex v at `position`: a new welded vertex, or one more copy of the vertex already
// there.
void WeldVertex(unsigned v, const Float3& position, Skin skin, MeshData* out, WeldedMesh* weld,
                MeshRepairs* repairs) {
  auto key = std::make_tuple(position.x, position.y, position.z);
  auto [it, inserted] = weld->welded.emplace(key, out->vertex_count());
  weld->remap[v] = it->second;
  if (inserted) {
    out->positions.push_back(position);
    weld->first_skin.push_back(skin);
    weld->all_skins.push_back(std::move(skin));
    weld->copies.push_back(1);
    return;
  }
  // Same position: one vertex whose skin is the average of its copies' skins, which is what
  // assimp's JoinIdenticalVertices already does to copies that differ only in their skin
  // (it sums their weights); copies it keeps apart (other normals or UVs) get the same here.
  // Counted when the skins differ (a seam with split weights).
  const Skin& first = weld->first_skin[it->second - weld->first_vertex];
  bool same = first.size() == skin.size();
  for (size_t k = 0; same && k < skin.size(); ++k) {
    same = first[k].first == skin[k].first && std::fabs(first[k].second - skin[k].second) < 1e-4;
  }
  repairs->weld_conflicts += !same;
  auto& skins = weld->all_skins[it->second - weld->first_vertex];
  skins.insert(skins.end(), skin.begin(), skin.end());
  ++weld->copies[it->second - weld->first_vertex];
}

// The welded vertices' influences: each copy's skin averaged, appended to out in vertex order.
void AppendAveragedSkins(WeldedMesh* weld, MeshData* out) {
  for (size_t w = 0; w < weld->all_skins.size(); ++w) {
    Skin& skin = weld->all_skins[w];
    std::sort(skin.begin(), skin.end());
    Skin averaged;
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
      out->influence_joints.push_back(static_cast<uint16_t>(joint));
      // A single copy is stored as normalised above, bit for bit.
      out->influence_weights.push_back(
          static_cast<float>(weld->copies[w] == 1 ? weight : weight / total));
    }
    out->influence_offsets.push_back(static_cast<uint32_t>(out->influence_joints.size()));
  }
}

// The mesh's triangles through the weld; degenerate and zero-area ones are dropped.
Status AppendTriangles(const std::string& path, const aiMesh* m, const std::vector<uint32_t>& remap,
                       MeshData* out, MeshRepairs* repairs) {
  for (unsigned f = 0; f < m->mNumFaces; ++f) {
    const aiFace& face = m->mFaces[f];
    if (face.mNumIndices != 3) continue;
    uint32_t idx[3];
    for (int k = 0; k < 3; ++k) {
      if (face.mIndices[k] >= m->mNumVertices)
        return SourceError(path, StatusCode::kCorrupt, "a face names a missing vertex");
      idx[k] = remap[face.mIndices[k]];
    }
    const Float3 a = out->positions[idx[0]], b = out->positions[idx[1]], c = out->positions[idx[2]];
    const Vec3 e1(b.x - a.x, b.y - a.y, b.z - a.z), e2(c.x - a.x, c.y - a.y, c.z - a.z);
    if (idx[0] == idx[1] || idx[1] == idx[2] || idx[0] == idx[2] ||
        e1.cross(e2).squaredNorm() == 0.0) {
      ++repairs->degenerate_triangles;
      continue;
    }
    out->triangles.insert(out->triangles.end(), idx, idx + 3);
  }
  return Status::Ok();
}

// One mesh instance: bind transform, influences, welded vertices with their skins, triangles.
Status ImportMeshInstance(const std::string& path, const SourceScene& source,
                          const JointNodes& joints, const AssetFrame& frame,
                          const std::vector<Mat4>& inverse_bind_source, int node,
                          unsigned mesh_index, MeshData* out, MeshRepairs* repairs) {
  const aiMesh* m = source.scene->mMeshes[mesh_index];
  int rigid_joint = -1;
  const Mat4 to_bind =
      BindTransform(source, joints, inverse_bind_source, node, m, &rigid_joint, repairs);
  const Mat4 vertex_to_asset = frame.to_asset * to_bind;

  std::vector<Influences> influences(m->mNumVertices);
  if (Status s = GatherInfluences(path, source, joints, m, &influences); !s.ok()) return s;
  const int ancestor = JointAncestor(source, joints, node);
  const int fallback_joint =
      rigid_joint >= 0 ? rigid_joint : (ancestor >= 0 ? joints.joint_of_node[ancestor] : 0);

  WeldedMesh weld;
  weld.remap.resize(m->mNumVertices);
  weld.first_vertex = out->vertex_count();
  for (unsigned v = 0; v < m->mNumVertices; ++v) {
    const Vec3 p = TransformPoint(vertex_to_asset,
                                  Vec3(m->mVertices[v].x, m->mVertices[v].y, m->mVertices[v].z));
    const Float3 position{static_cast<float>(p.x()), static_cast<float>(p.y()),
                          static_cast<float>(p.z())};
    if (!std::isfinite(position.x) || !std::isfinite(position.y) || !std::isfinite(position.z)) {
      return SourceError(path, StatusCode::kCorrupt,
                         "vertex " + std::to_string(v) + " of mesh '" +
                             std::string(m->mName.C_Str()) +
                             "' is not finite after transforming to metres");
    }
    WeldVertex(v, position, NormalisedSkin(influences[v], rigid_joint, fallback_joint, repairs),
               out, &weld, repairs);
  }
  AppendAveragedSkins(&weld, out);
  return AppendTriangles(path, m, weld.remap, out, repairs);
}

void WarnRepairs(const MeshRepairs& repairs, std::vector<std::string>* warnings) {
  auto warn_count = [&](size_t count, const std::string& what) {
    if (count) warnings->push_back(std::to_string(count) + " " + what);
  };
  warn_count(repairs.weight_sum_warnings,
             "vertices had raw weight sums outside [0.9, 1.1] (renormalised)");
  warn_count(repairs.zero_weight_vertices,
             "vertices had no weight (made rigid to their mesh's joint)");
  warn_count(repairs.degenerate_triangles, "degenerate or zero-area triangles were dropped");
  warn_count(repairs.weld_conflicts, "welded vertices had differing weights (averaged)");
  warn_count(repairs.mesh_space_mismatch,
             "bones disagree on their mesh's bind space (blended skin may be off)");
}

}  // namespace

Status ImportBindMesh(const std::string& path, const SourceScene& source, const JointNodes& joints,
                      const AssetFrame& frame, const std::vector<Mat4>& inverse_bind_source,
                      Character* character) {
  MeshData& out = character->mesh;
  out.influence_offsets.push_back(0);
  MeshRepairs repairs;
  for (const auto& [node, mesh_index] : source.mesh_instances) {
    if (Status s = ImportMeshInstance(path, source, joints, frame, inverse_bind_source, node,
                                      mesh_index, &out, &repairs);
        !s.ok()) {
      return s;
    }
  }
  if (out.triangles.empty())
    return SourceError(path, StatusCode::kCorrupt, "every triangle is degenerate");
  const size_t flipped_components = OrientComponentsOutward(&out);
  if (flipped_components) {
    character->warnings.push_back(std::to_string(flipped_components) +
                                  " connected components were wound inward and have been flipped");
  }
  WarnRepairs(repairs, &character->warnings);
  return Status::Ok();
}

}  // namespace drape::bake::detail

#include "import/asset_frame.h"

#include <algorithm>
#include <cmath>

#include "import/import_messages.h"

namespace drape::bake::detail {
namespace {

using Vec3 = Eigen::Vector3d;

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

// "auto" reads the FBX UpAxis / UpAxisSign metadata and falls back to +Y.
Status ChooseUpAxis(const std::string& path, const ImportOptions& options, const aiScene* scene,
                    AssetFrame* frame, Eigen::Matrix3d* up_rotation) {
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
  if (!UpAxisRotation(up, up_rotation)) {
    return SourceError(path, StatusCode::kInvalidArgument,
                       "up_axis '" + options.up_axis + "' is not auto, +X, -X, +Y, -Y, +Z or -Z");
  }
  frame->up = up;
  frame->up_source = up_source;
  return Status::Ok();
}

// Rest-pose world positions of the vertices (source units) for the scale check: every vertex of
// an unskinned mesh, and every vertex a bone weighs above 0.5 of a skinned one.
Status MeasureRestBox(const std::string& path, const SourceScene& source,
                      Eigen::AlignedBox3d* rest_box) {
  const std::vector<SourceNode>& nodes = source.nodes;
  for (const auto& [node, mesh] : source.mesh_instances) {
    const aiMesh* m = source.scene->mMeshes[mesh];
    for (unsigned v = 0; v < m->mNumVertices; ++v) {
      const Vec3 p(m->mVertices[v].x, m->mVertices[v].y, m->mVertices[v].z);
      if (!p.allFinite()) {
        return SourceError(path, StatusCode::kCorrupt,
                           "vertex " + std::to_string(v) + " of mesh '" +
                               std::string(m->mName.C_Str()) + "' is not finite");
      }
      if (m->mNumBones == 0) rest_box->extend(TransformPoint(nodes[node].global_rest, p));
    }
    for (unsigned b = 0; b < m->mNumBones; ++b) {
      const aiBone* bone = m->mBones[b];
      const int bn = source.node_by_name.at(bone->mName.C_Str());
      const Mat4 skin = nodes[bn].global_rest * ToEigen(bone->mOffsetMatrix);
      for (unsigned w = 0; w < bone->mNumWeights; ++w) {
        const unsigned v = bone->mWeights[w].mVertexId;
        if (v >= m->mNumVertices)
          return SourceError(path, StatusCode::kCorrupt, "a bone weight names a missing vertex");
        if (bone->mWeights[w].mWeight > 0.5f) {
          rest_box->extend(
              TransformPoint(skin, Vec3(m->mVertices[v].x, m->mVertices[v].y, m->mVertices[v].z)));
        }
      }
    }
  }
  return Status::Ok();
}

// unit_scale 0 reads the FBX UnitScaleFactor metadata (metres otherwise), then corrects a body
// that would be beyond 20 m tall.
void ChooseUnitScale(const ImportOptions& options, const aiScene* scene,
                     const Eigen::AlignedBox3d& rest_box, AssetFrame* frame) {
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
  frame->scale = scale;
  frame->scale_source = scale_source;
}

}  // namespace

Status ChooseAssetFrame(const std::string& path, const ImportOptions& options,
                        const SourceScene& source, AssetFrame* frame,
                        std::vector<std::string>* warnings) {
  Eigen::Matrix3d up_rotation;
  if (Status s = ChooseUpAxis(path, options, source.scene, frame, &up_rotation); !s.ok()) return s;
  Eigen::AlignedBox3d rest_box;
  if (Status s = MeasureRestBox(path, source, &rest_box); !s.ok()) return s;
  ChooseUnitScale(options, source.scene, rest_box, frame);
  const double scale = frame->scale;
  const double extent_m = rest_box.isEmpty() ? 0.0 : rest_box.sizes().maxCoeff() * scale;
  if (extent_m < 0.02 || extent_m > 3.0) {
    warnings->push_back("the rest-pose body spans " + Fmt(extent_m) +
                        " m after unit scaling; set import.unit_scale if that is wrong");
  }
  Mat4 to_asset = Mat4::Identity();
  to_asset.topLeftCorner<3, 3>() = up_rotation * scale;
  frame->to_asset = to_asset;
  frame->from_asset = to_asset.inverse();
  return Status::Ok();
}

}  // namespace drape::bake::detail

#include "import/clip_resampler.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include "import/import_messages.h"

namespace drape::bake::detail {
namespace {

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

// Each node's channel in the animation, nullptr for a node it does not move.
std::vector<const aiNodeAnim*> ChannelsByNode(const aiAnimation* anim, const SourceScene& source) {
  std::vector<const aiNodeAnim*> channel_of_node(source.nodes.size(), nullptr);
  for (unsigned c = 0; c < anim->mNumChannels; ++c) {
    const aiNodeAnim* channel = anim->mChannels[c];
    auto it = source.node_by_name.find(channel->mNodeName.C_Str());
    if (it == source.node_by_name.end()) continue;  // a channel for a node that is not there
    channel_of_node[it->second] = channel;
  }
  return channel_of_node;
}

// Every node's global transform at `tick` (source units, scene-root frame).
void PoseNodes(const std::vector<SourceNode>& nodes,
               const std::vector<const aiNodeAnim*>& channel_of_node, double tick,
               std::vector<Mat4>* global) {
  for (size_t n = 0; n < nodes.size(); ++n) {
    const Mat4 local = channel_of_node[n]
                           ? ChannelLocal(*channel_of_node[n], nodes[n].local_rest, tick)
                           : nodes[n].local_rest;
    (*global)[n] = nodes[n].parent < 0 ? local : Mat4((*global)[nodes[n].parent] * local);
  }
}

// The clip's frames: per frame, every joint's local transform. Sets *shear when a transform has
// shear the keys cannot store.
Status SampleFrames(const std::string& path, const SourceScene& source, const JointNodes& joints,
                    const AssetFrame& frame, const std::vector<const aiNodeAnim*>& channel_of_node,
                    double ticks_per_second, size_t joint_count, ClipData* clip, bool* shear) {
  const std::vector<SourceNode>& nodes = source.nodes;
  std::vector<Mat4> global(nodes.size());
  for (uint32_t f = 0; f < clip->frame_count; ++f) {
    const double seconds =
        std::min(static_cast<double>(f) / clip->sample_rate, static_cast<double>(clip->duration));
    const double tick = seconds * ticks_per_second;
    PoseNodes(nodes, channel_of_node, tick, &global);
    for (size_t j = 0; j < joint_count; ++j) {
      const int jn = joints.joint_nodes[j];
      const int parent_joint = JointAncestor(source, joints, nodes[jn].parent);
      const Mat4 local = parent_joint < 0 ? Mat4(frame.to_asset * global[jn])
                                          : Mat4(global[parent_joint].inverse() * global[jn]);
      if (!local.allFinite())
        return SourceError(path, StatusCode::kCorrupt,
                           "clip '" + clip->name + "' produces a non-finite transform");
      *shear |= Decompose(local, &clip->keys[static_cast<size_t>(f) * joint_count + j]) > 1e-3;
    }
  }
  return Status::Ok();
}

}  // namespace

Status ResampleClips(const std::string& path, const ImportOptions& options,
                     const SourceScene& source, const JointNodes& joints, const AssetFrame& frame,
                     Character* character) {
  const size_t joint_count = character->skeleton.joint_names.size();
  const aiScene* scene = source.scene;
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
    ClipData clip;
    clip.name = name;
    clip.duration = static_cast<float>(duration);
    clip.sample_rate = options.clip_sample_rate;
    clip.frame_count = static_cast<uint32_t>(
        std::ceil(static_cast<double>(clip.duration) * clip.sample_rate - 1e-3) + 1);
    clip.keys.resize(static_cast<size_t>(clip.frame_count) * joint_count);
    bool shear = false;
    if (Status s = SampleFrames(path, source, joints, frame, ChannelsByNode(anim, source),
                                ticks_per_second, joint_count, &clip, &shear);
        !s.ok()) {
      return s;
    }
    if (shear)
      character->warnings.push_back("clip '" + name +
                                    "' has sheared joint transforms; stored without shear");
    character->clips.push_back(std::move(clip));
  }
  return Status::Ok();
}

}  // namespace drape::bake::detail

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "drape/bake/scene.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "scene/scene_frames.h"
#include "scene/scene_garments.h"
#include "scene/scene_messages.h"

namespace drape::bake {
namespace {

using namespace detail;
using nlohmann::json;

constexpr float kInf = std::numeric_limits<float>::infinity();

// Distance from p to an oriented box (centre, orthonormal axes, half extents).
float DistanceToBox(Float3 p, Float3 center, const Float3 axes[3], Float3 half) {
  const Float3 d = p - center;
  const float h[3] = {half.x, half.y, half.z};
  float squared = 0.f;
  for (int k = 0; k < 3; ++k) {
    const float c = Dot(d, axes[k]);
    const float beyond = std::fabs(c) - h[k];
    if (beyond > 0.f) squared += beyond * beyond;
  }
  return std::sqrt(squared);
}

// A particle a garment holds (attached to a joint, or pinned in the world) and how far the
// garment reaches from it.
struct Held {
  int32_t joint;    // -1: pinned in the world
  Float3 position;  // bind frame (attached) or world (pinned)
  float radius;
};

// Each garment's reach (report) and held particles; *bounded is false when some garment has a
// particle no held one connects to (its reach is then unbounded).
Status GarmentReaches(const Scene& resolved, const CharacterAsset& asset, SceneReach* out,
                      std::vector<Held>* held, bool* bounded) {
  for (size_t g = 0; g < resolved.garments.size(); ++g) {
    ResolvedGarment garment;
    DRAPE_RETURN_IF_ERROR(ResolveGarment(resolved, g, asset.skeleton, &garment));
    const ClothDescription& d = garment.description;
    std::vector<float> distance;
    std::vector<uint32_t> nearest;
    NearestHeldParticles(d, &distance, &nearest);
    GarmentReach reach;
    reach.name = resolved.garments[g].name;
    reach.held_particles = static_cast<uint32_t>(d.attachments.size() + d.pinned.size());
    for (float x : distance) {
      if (std::isinf(x))
        reach.bounded = false;
      else
        reach.max_path = std::max(reach.max_path, x);
    }
    reach.radius = reach.bounded
                       ? (1.f + resolved.reach_stretch) * reach.max_path + resolved.reach_margin
                       : kInf;
    *bounded = *bounded && reach.bounded;
    for (const ClothAttachment& a : d.attachments)
      held->push_back({a.joint, a.bind_position, reach.radius});
    for (uint32_t p : d.pinned) held->push_back({-1, d.positions[p], reach.radius});
    out->garments.push_back(reach);
  }
  return Status::Ok();
}

// The asset's colliders as the runtime poses them, and one reach entry per collider: reachable
// with no bound to measure when a garment's reach is unbounded, else clearance to be measured.
Status ListColliders(const CharacterAsset& asset, bool bounded, HullColliderSet* colliders,
                     SceneReach* out) {
  if (Status s = colliders->Build(asset.hulls, asset.joint_spheres, asset.skeleton.joint_count());
      !s.ok()) {
    return Status(s.code(), asset.info.source_name + ": the asset's colliders: " + s.message());
  }
  const auto joint_name = [&](int32_t j) {
    return j >= 0 && static_cast<size_t>(j) < asset.skeleton.joint_names.size()
               ? asset.skeleton.joint_names[static_cast<size_t>(j)]
               : std::string("?");
  };
  for (const HullColliderData& h : asset.hulls)
    out->hulls.push_back({h.joint, joint_name(h.joint), !bounded, bounded ? kInf : -kInf});
  for (const JointSphereData& s : asset.joint_spheres)
    out->spheres.push_back({s.joint, joint_name(s.joint), !bounded, bounded ? kInf : -kInf});
  return Status::Ok();
}

// The poses played: the start (settle), then every substep boundary of every frame; a static
// pose is one pose.
std::vector<float> PlayedTimes(const Scene& resolved, int32_t clip) {
  const SceneAnimation& anim = resolved.animation;
  const uint32_t substeps = resolved.auto_substeps ? 4u : std::max(resolved.solver.substeps, 1u);
  std::vector<float> times;
  times.push_back(anim.start);
  for (uint32_t k = 0; k < resolved.frame_count; ++k) {
    for (uint32_t s = 1; s <= substeps; ++s) {
      times.push_back(anim.start + (static_cast<float>(k) +
                                    static_cast<float>(s) / static_cast<float>(substeps)) *
                                       resolved.dt);
    }
  }
  if (clip < 0) times.resize(1);  // a static pose is one pose
  return times;
}

// The root joint's bind position (asset frame); the origin when its bind matrix is singular.
Float3 RootBindPosition(const SkeletonData& skeleton) {
  Float3 root_bind;
  Mat34 m;
  if (!skeleton.inverse_bind.empty() && InverseAffine(skeleton.inverse_bind[0], &m))
    root_bind = Translation(m);
  return root_bind;
}

// Lowers each collider's clearance to the held particles' reach spheres at the current pose:
// hulls by their world OBB, joint spheres by their centre and radius.
void LowerClearances(const CharacterAsset& asset, const HullColliderSet& colliders,
                     const std::vector<Held>& held, const std::vector<Float3>& centers,
                     SceneReach* out) {
  for (uint32_t h = 0; h < colliders.hull_count(); ++h) {
    const Mat34 world = colliders.HullWorldTransform(h, 0.f);
    const Obb& obb = asset.hulls[h].obb;
    const Float3 center = TransformPoint(world, obb.center);
    const Float3 axes[3] = {NormalizeOr(TransformVector(world, obb.axes[0]), {1, 0, 0}),
                            NormalizeOr(TransformVector(world, obb.axes[1]), {0, 1, 0}),
                            NormalizeOr(TransformVector(world, obb.axes[2]), {0, 0, 1})};
    float& clearance = out->hulls[h].clearance;
    for (size_t i = 0; i < held.size(); ++i) {
      clearance = std::min(
          clearance, DistanceToBox(centers[i], center, axes, asset.hulls[h].obb.half_extents) -
                         held[i].radius);
    }
  }
  for (uint32_t s = 0; s < colliders.sphere_count(); ++s) {
    const Float3 center = colliders.SphereCenter(s, 0.f);
    float& clearance = out->spheres[s].clearance;
    for (size_t i = 0; i < held.size(); ++i) {
      clearance = std::min(
          clearance, Length(centers[i] - center) - asset.joint_spheres[s].radius - held[i].radius);
    }
  }
}

// Plays every time of `times`: the clip time range played, and (when the reach is bounded) each
// collider's clearance over all of them.
Status SweepPlayedPoses(const Scene& resolved, const CharacterAsset& asset,
                        const ClipData* clip_data, const std::vector<float>& times,
                        const std::vector<Held>& held, bool bounded, HullColliderSet* colliders,
                        SceneReach* out) {
  const SceneAnimation& anim = resolved.animation;
  SkeletonPose pose;
  DRAPE_RETURN_IF_ERROR(pose.Init(asset.skeleton));
  ScenePoser poser;
  const int32_t clip =
      clip_data != nullptr ? static_cast<int32_t>(clip_data - asset.clips.data()) : -1;
  DRAPE_RETURN_IF_ERROR(poser.Init(resolved, asset, clip));
  const int32_t root = 0;
  const Float3 root_bind = RootBindPosition(asset.skeleton);
  Float3 root_start;
  std::vector<Float3> centers(held.size());
  if (clip_data != nullptr) {
    out->clip_time_min = kInf;
    out->clip_time_max = -kInf;
  }
  for (size_t t = 0; t < times.size(); ++t) {
    DRAPE_RETURN_IF_ERROR(poser.Pose(times[t], &pose));
    if (clip_data != nullptr) {
      const float ct = ClipTime(*clip_data, times[t], anim.loop);
      out->clip_time_min = std::min(out->clip_time_min, ct);
      out->clip_time_max = std::max(out->clip_time_max, ct);
    }
    const std::span<const Mat34> skinning = pose.skinning();
    if (!bounded) continue;
    DRAPE_RETURN_IF_ERROR(colliders->SetPose(skinning, skinning));
    // Relative simulation carries pinned particles with the root's translation.
    const Float3 root_now = skinning.empty() ? Float3{} : TransformPoint(skinning[root], root_bind);
    if (t == 0) root_start = root_now;
    const Float3 root_shift = resolved.relative ? root_now - root_start : Float3{};
    for (size_t i = 0; i < held.size(); ++i) {
      centers[i] = held[i].joint >= 0 ? TransformPoint(skinning[static_cast<size_t>(held[i].joint)],
                                                       held[i].position)
                                      : held[i].position + root_shift;
    }
    LowerClearances(asset, *colliders, held, centers, out);
  }
  return Status::Ok();
}

// Body-map poses: those of the scene's clip (or the static poses) nearest to and bracketing
// the time at the end of each frame, where the solver reads them. Ascending indices.
std::vector<uint32_t> PlayedMapPoses(const Scene& resolved, const CharacterAsset& asset,
                                     int32_t clip, const ClipData* clip_data) {
  const SceneAnimation& anim = resolved.animation;
  std::vector<uint32_t> candidates;
  for (size_t p = 0; p < asset.body_maps.poses.size(); ++p) {
    if (asset.body_maps.poses[p].clip == clip) candidates.push_back(static_cast<uint32_t>(p));
  }
  std::vector<uint8_t> played(asset.body_maps.poses.size(), 0);
  if (clip_data == nullptr) {
    for (uint32_t p : candidates) played[p] = 1;
  } else if (!candidates.empty()) {
    std::vector<float> frame_ends = {ClipTime(*clip_data, anim.start, anim.loop)};
    for (uint32_t k = 0; k < resolved.frame_count; ++k) {
      frame_ends.push_back(
          ClipTime(*clip_data, anim.start + static_cast<float>(k + 1) * resolved.dt, anim.loop));
    }
    for (float t : frame_ends) {
      uint32_t best = candidates[0], below = UINT32_MAX, above = UINT32_MAX;
      for (uint32_t p : candidates) {
        const float pt = asset.body_maps.poses[p].time;
        if (std::fabs(pt - t) < std::fabs(asset.body_maps.poses[best].time - t)) best = p;
        if (pt <= t && (below == UINT32_MAX || pt > asset.body_maps.poses[below].time)) below = p;
        if (pt >= t && (above == UINT32_MAX || pt < asset.body_maps.poses[above].time)) above = p;
      }
      played[best] = 1;
      if (below != UINT32_MAX) played[below] = 1;
      if (above != UINT32_MAX) played[above] = 1;
    }
  }
  std::vector<uint32_t> indices;
  for (size_t p = 0; p < played.size(); ++p)
    if (played[p]) indices.push_back(static_cast<uint32_t>(p));
  return indices;
}

}  // namespace

Status AnalyzeSceneReach(const Scene& scene, const CharacterAsset& asset, SceneReach* out) {
  *out = SceneReach{};
  Scene resolved = scene;  // frame_count and the clip, without touching the caller's scene
  int32_t clip = -1;
  DRAPE_RETURN_IF_ERROR(ResolveSceneClip(asset, &resolved, &clip));
  out->clip = clip;

  std::vector<Held> held;
  bool bounded = true;
  DRAPE_RETURN_IF_ERROR(GarmentReaches(resolved, asset, out, &held, &bounded));
  HullColliderSet colliders;
  DRAPE_RETURN_IF_ERROR(ListColliders(asset, bounded, &colliders, out));

  const std::vector<float> times = PlayedTimes(resolved, clip);
  out->sampled_poses = static_cast<uint32_t>(times.size());
  const ClipData* clip_data = clip >= 0 ? &asset.clips[static_cast<size_t>(clip)] : nullptr;
  DRAPE_RETURN_IF_ERROR(
      SweepPlayedPoses(resolved, asset, clip_data, times, held, bounded, &colliders, out));
  for (ColliderReach& c : out->hulls) c.reachable = c.clearance <= 0.f;
  for (ColliderReach& c : out->spheres) c.reachable = c.clearance <= 0.f;

  if (clip_data != nullptr) {
    const SceneAnimation& anim = resolved.animation;
    const float end_time = anim.start + static_cast<float>(resolved.frame_count) * resolved.dt;
    out->whole_clip = (anim.loop && end_time - anim.start >= clip_data->duration) ||
                      (out->clip_time_min <= 0.f && out->clip_time_max >= clip_data->duration);
  }
  out->played_map_poses = PlayedMapPoses(resolved, asset, clip, clip_data);
  return Status::Ok();
}

json SceneReachToJson(const SceneReach& reach) {
  const auto number = [](float x) { return std::isfinite(x) ? json(x) : json(nullptr); };
  json garments = json::array();
  for (const GarmentReach& g : reach.garments) {
    garments.push_back({{"name", g.name},
                        {"held_particles", g.held_particles},
                        {"bounded", g.bounded},
                        {"max_path_m", g.max_path},
                        {"radius_m", number(g.radius)}});
  }
  json colliders = json::array();
  const auto add = [&](const std::vector<ColliderReach>& list, const char* kind) {
    for (const ColliderReach& c : list) {
      colliders.push_back({{"bone", c.joint_name},
                           {"kind", kind},
                           {"reachable", c.reachable},
                           {"clearance_m", number(c.clearance)}});
    }
  };
  add(reach.hulls, "hull");
  add(reach.spheres, "sphere");
  json out = {{"clip", reach.clip},
              {"sampled_poses", reach.sampled_poses},
              {"garments", garments},
              {"colliders", colliders},
              {"played_map_poses", reach.played_map_poses}};
  if (reach.clip >= 0) {
    out["clip_time_range_s"] = {reach.clip_time_min, reach.clip_time_max};
    out["whole_clip"] = reach.whole_clip;
  }
  return out;
}

void PruneUnreachable(const SceneReach& reach, CharacterAsset* asset, json* left_out) {
  if (!left_out->is_array()) *left_out = json::array();
  const auto why = [&](const ColliderReach& c) {
    char text[160];
    std::snprintf(text, sizeof(text),
                  "the garments cannot reach it: it stays %.3f m beyond their reach over the %u "
                  "poses the scene plays",
                  static_cast<double>(c.clearance), reach.sampled_poses);
    return std::string(text);
  };
  if (reach.hulls.size() == asset->hulls.size()) {
    std::vector<HullColliderData> kept;
    for (size_t h = 0; h < asset->hulls.size(); ++h) {
      if (reach.hulls[h].reachable) {
        kept.push_back(std::move(asset->hulls[h]));
      } else {
        left_out->push_back({{"bone", reach.hulls[h].joint_name},
                             {"kind", "hull"},
                             {"reason", why(reach.hulls[h])}});
      }
    }
    asset->hulls = std::move(kept);
  }
  if (reach.spheres.size() == asset->joint_spheres.size()) {
    std::vector<JointSphereData> kept;
    for (size_t s = 0; s < asset->joint_spheres.size(); ++s) {
      if (reach.spheres[s].reachable) {
        kept.push_back(asset->joint_spheres[s]);
      } else {
        left_out->push_back({{"bone", reach.spheres[s].joint_name},
                             {"kind", "joint_sphere"},
                             {"reason", why(reach.spheres[s])}});
      }
    }
    asset->joint_spheres = std::move(kept);
  }
  std::vector<BodyMapPose>& poses = asset->body_maps.poses;
  if (poses.empty()) return;
  if (reach.played_map_poses.empty()) {
    left_out->push_back({{"kind", "body_map_pose"},
                         {"reason", "kept all " + std::to_string(poses.size()) +
                                        " poses: none of them is a pose the scene plays"}});
    return;
  }
  std::vector<BodyMapPose> kept;
  size_t next = 0;
  for (size_t p = 0; p < poses.size(); ++p) {
    if (next < reach.played_map_poses.size() && reach.played_map_poses[next] == p) {
      kept.push_back(std::move(poses[p]));
      ++next;
      continue;
    }
    const std::string name = poses[p].clip < 0
                                 ? std::string("rest")
                                 : (static_cast<size_t>(poses[p].clip) < asset->clips.size()
                                        ? asset->clips[static_cast<size_t>(poses[p].clip)].name
                                        : std::string("?")) +
                                       "@" + std::to_string(poses[p].time);
    left_out->push_back(
        {{"pose", name}, {"kind", "body_map_pose"}, {"reason", "not played by the scene"}});
  }
  poses = std::move(kept);
}

}  // namespace drape::bake

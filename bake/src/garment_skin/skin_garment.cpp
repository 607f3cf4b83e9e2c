#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "drape/bake/scene.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"
#include "garment_skin/garment_skinning.h"

namespace drape::bake {
namespace {

Status Invalid(const std::string& message) { return Status(StatusCode::kInvalidArgument, message); }

// The body's vertices in the garment's frame: the bind positions, or skinned to the rest pose
// (SkinMesh, the runtime's linear blend skinning).
Status BodyInGarmentFrame(const SceneGarment& g, const SkeletonData& skeleton, const MeshData& body,
                          std::vector<Float3>* positions) {
  *positions = body.positions;
  if (g.frame != GarmentFrame::kRest) return Status::Ok();
  SkeletonPose rest;
  if (Status s = rest.Init(skeleton); !s.ok()) return s;
  rest.SetRest();
  return SkinMesh(body, rest.skinning(), *positions);
}

// The held particles: attached to a joint or pinned.
std::vector<uint32_t> HeldParticles(const ClothDescription& d) {
  std::vector<uint32_t> held(d.pinned.begin(), d.pinned.end());
  for (const ClothAttachment& a : d.attachments) held.push_back(a.particle);
  return held;
}

// Each particle takes the body weights of its nearest held particle along the garment (those
// d.skin holds, from the body's closest points); a part no edge path joins to a held one keeps
// its own.
Status TakeHeldWeights(ClothDescription* d) {
  const std::vector<uint32_t> held = HeldParticles(*d);
  if (held.empty())
    return Invalid(
        "\"held\" takes the weights of the held particles; the garment has none (add an "
        "attach or a pin)");
  std::vector<uint32_t> nearest;
  (void)detail::DistanceAlongEdges(d->triangles, d->positions, held, &nearest);
  const std::vector<ClothSkinWeights> body = d->skin;
  for (size_t i = 0; i < body.size(); ++i)
    if (nearest[i] != UINT32_MAX) d->skin[i] = body[held[nearest[i]]];
  return Status::Ok();
}

// max_distance grows linearly along the garment, from 0 at its held particles (attached or
// pinned) to `max_distance` at the particle farthest from them: a waistband follows the skin
// exactly and the hem may swing. A part no edge path joins to a held particle (a loose patch)
// gets the full max_distance.
Status PaintRamp(float max_distance, ClothDescription* d) {
  if (!std::isfinite(max_distance))
    return Invalid("\"ramp\" scales max_distance, which is \"none\" (give it in metres)");
  const std::vector<uint32_t> held = HeldParticles(*d);
  if (held.empty())
    return Invalid(
        "\"ramp\" grows from the held particles; the garment has none (add an attach "
        "or a pin)");
  const std::vector<float> from_held = detail::DistanceAlongEdges(d->triangles, d->positions, held);
  float farthest = 0.f;
  for (const float distance : from_held)
    if (std::isfinite(distance)) farthest = std::max(farthest, distance);
  for (size_t i = 0; i < from_held.size(); ++i) {
    const bool reached = std::isfinite(from_held[i]) && farthest > 0.f;
    d->max_distance[i] =
        reached ? max_distance * std::min(1.f, from_held[i] / farthest) : max_distance;
  }
  return Status::Ok();
}

}  // namespace

Status SkinGarment(const Scene& scene, size_t index, const SkeletonData& skeleton,
                   const MeshData& body, ResolvedGarment* garment) {
  const SceneGarment& g = scene.garments[index];
  if (!g.skinned) return Status::Ok();
  const std::string at = scene.source + ": " + g.path + "/skin";
  const bool file_skin = !garment->file_skin.empty();
  if (file_skin && !g.skin_weights_file.empty())
    return Invalid(at + "/weights_file: the glTF garment has its own skin; remove one of them");
  if (g.skin_transfer == SkinTransfer::kHeld && (file_skin || !g.skin_weights_file.empty()))
    return Invalid(at + "/transfer: \"held\" takes the body's weights; this garment's are " +
                   (file_skin ? "its glTF skin's" : "the weights_file's"));
  if (body.triangles.empty() && g.skin_weights_file.empty() && !file_skin)
    return Invalid(at + ": the asset has no body mesh to take weights from");
  ClothDescription& d = garment->description;
  if (file_skin) {  // a skinned glTF's own weights, as they are
    d.skin = garment->file_skin;
  } else if (!g.skin_weights_file.empty()) {  // authored weights, as they are
    if (Status s =
            detail::ReadSkinWeightsFile(g.skin_weights_file, skeleton, d.positions.size(), &d.skin);
        !s.ok())
      return Invalid(at + "/weights_file: " + s.message());
  } else {
    std::vector<Float3> body_positions;
    if (Status s = BodyInGarmentFrame(g, skeleton, body, &body_positions); !s.ok())
      return Invalid(at + ": the body at the rest pose: " + s.message());
    if (Status s = detail::TransferSkinWeights(body, body_positions, d.positions, &d.skin); !s.ok())
      return Invalid(at + ": " + s.message());
    if (g.skin_transfer == SkinTransfer::kHeld) {
      if (Status s = TakeHeldWeights(&d); !s.ok()) return Invalid(at + "/transfer: " + s.message());
    }
    detail::SmoothSkinWeights(d.triangles, g.skin_smoothing, &d.skin);
  }
  const size_t n = d.positions.size();
  if (file_skin) {
    d.skin_bind_positions = garment->file_bind_positions;  // exact, from the file's binding
  } else {  // each joint's frame -> bind, blended as the runtime skins
    d.skin_bind_positions.assign(n, Float3{});
    for (size_t i = 0; i < n; ++i) {
      const ClothSkinWeights& w = d.skin[i];
      for (int k = 0; k < 4; ++k)
        if (w.weights[k] > 0.f)
          d.skin_bind_positions[i] +=
              TransformPoint(garment->frame_to_bind[w.joints[k]], d.positions[i]) * w.weights[k];
    }
  }
  d.max_distance.assign(n, g.max_distance);
  d.backstop.assign(n, g.backstop);
  if (g.max_distance_channel == SceneGarment::kPaintAttribute) {  // painted in metres
    if (garment->painted_max_distance.size() != n)
      return Invalid(at +
                     "/paint: the glTF garment has no _MAX_DISTANCE attribute on every "
                     "primitive");
    d.max_distance = garment->painted_max_distance;
    if (garment->painted_backstop.size() == n) d.backstop = garment->painted_backstop;
  } else if (g.max_distance_channel == SceneGarment::kPaintRamp) {
    if (Status s = PaintRamp(g.max_distance, &d); !s.ok())
      return Invalid(at + "/paint: " + s.message());
  } else if (g.max_distance_channel >= 0) {  // painted: the channel scales max_distance
    if (garment->colors.size() != n)
      return Invalid(at +
                     "/paint: the garment has no vertex colours (an OBJ whose every `v` line has "
                     "r g b after x y z, a glTF whose every primitive has COLOR_0)");
    for (size_t i = 0; i < n; ++i) {
      const Float3 c = garment->colors[i];
      const float channel =
          g.max_distance_channel == 0 ? c.x : (g.max_distance_channel == 1 ? c.y : c.z);
      d.max_distance[i] = g.max_distance * channel;
    }
  }
  // Held by a joint or a pin: not the skin's.
  constexpr float kUnlimited = std::numeric_limits<float>::infinity();
  for (const ClothAttachment& a : d.attachments) d.max_distance[a.particle] = kUnlimited;
  for (const uint32_t p : d.pinned) d.max_distance[p] = kUnlimited;
  for (const ClothAttachment& a : d.attachments) d.backstop[a.particle] = kUnlimited;
  for (const uint32_t p : d.pinned) d.backstop[p] = kUnlimited;
  Cloth check;
  if (Status s = BuildCloth(d, &check); !s.ok()) return Invalid(at + ": " + s.message());
  return Status::Ok();
}

}  // namespace drape::bake

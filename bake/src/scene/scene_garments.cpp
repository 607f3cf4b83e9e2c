#include "scene/scene_garments.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <utility>

#include "config/name_suggestions.h"
#include "drape/bake/scene.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "scene/gltf_garment.h"
#include "scene/obj_reader.h"
#include "scene/scene_messages.h"

namespace drape::bake {
namespace {

using namespace detail;

constexpr uint32_t kMaxGarmentParticles = 1u << 20;  // per garment (a scene is a demo, not a film)
constexpr float kInf = std::numeric_limits<float>::infinity();

// The particles of a named ring of a generated garment, or empty when the name is unknown.
std::vector<uint32_t> RingParticles(const SceneGarment& g, const GarmentMesh& mesh,
                                    const std::string& name) {
  std::vector<uint32_t> out;
  if (name == "held") return mesh.held;
  const auto row = [&](uint32_t stride, uint32_t r) {
    for (uint32_t i = 0; i < stride; ++i) out.push_back(r * stride + i);
  };
  const auto column = [&](uint32_t stride, uint32_t rows, uint32_t c) {
    for (uint32_t j = 0; j <= rows; ++j) out.push_back(j * stride + c);
  };
  switch (g.type) {
    case GarmentType::kSheet:
      if (name == "top") row(g.sheet.columns + 1, g.sheet.rows);
      if (name == "bottom") row(g.sheet.columns + 1, 0);
      if (name == "left") column(g.sheet.columns + 1, g.sheet.rows, 0);
      if (name == "right") column(g.sheet.columns + 1, g.sheet.rows, g.sheet.columns);
      break;
    case GarmentType::kSkirt:
      if (name == "waist") row(g.skirt.segments, 0);
      if (name == "hem") row(g.skirt.segments, g.skirt.rings);
      break;
    case GarmentType::kCape:
      if (name == "top") row(g.cape.columns + 1, 0);
      if (name == "bottom") row(g.cape.columns + 1, g.cape.rows);
      if (name == "left") column(g.cape.columns + 1, g.cape.rows, 0);
      if (name == "right") column(g.cape.columns + 1, g.cape.rows, g.cape.columns);
      break;
    case GarmentType::kSleeve:
      if (name == "start") row(g.sleeve.segments, 0);
      if (name == "end") row(g.sleeve.segments, g.sleeve.rings);
      break;
    case GarmentType::kObj:
    case GarmentType::kGltf:
      break;
  }
  return out;
}

Status SelectParticles(const Scene& scene, const SceneGarment& g, const GarmentMesh& mesh,
                       const SceneSelection& sel, Float3 anchor, std::vector<uint32_t>* out) {
  const uint32_t count = static_cast<uint32_t>(mesh.positions.size());
  const std::string prefix = scene.source + ": ";
  if (!sel.ring.empty()) {
    std::vector<std::string> names = GarmentRingNames(g.type);
    if (!names.empty()) names.insert(names.begin(), "held");
    if (std::find(names.begin(), names.end(), sel.ring) == names.end()) {
      return Invalid(prefix + sel.path + "/ring: " +
                     (names.empty()
                          ? std::string(g.type == GarmentType::kObj ? "an OBJ" : "a glTF") +
                                " garment has no rings; use vertices or box"
                          : "no ring named " + Quote(sel.ring) + " on a " + ToString(g.type) +
                                " (rings: " + JoinNames(names) + ")"));
    }
    *out = RingParticles(g, mesh, sel.ring);
  } else if (!sel.vertices.empty()) {
    for (size_t i = 0; i < sel.vertices.size(); ++i) {
      if (sel.vertices[i] >= count) {
        return Invalid(prefix + sel.path + "/vertices/" + std::to_string(i) + ": particle " +
                       std::to_string(sel.vertices[i]) + " is out of range (the garment has " +
                       std::to_string(count) + " particles)");
      }
    }
    *out = sel.vertices;
  } else {
    const Float3 lo = sel.box_min + anchor, hi = sel.box_max + anchor;
    out->clear();
    for (uint32_t i = 0; i < count; ++i) {
      const Float3 p = mesh.positions[i];
      if (p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z)
        out->push_back(i);
    }
    if (out->empty()) return Invalid(prefix + sel.path + "/box: selects no particle");
  }
  std::sort(out->begin(), out->end());
  out->erase(std::unique(out->begin(), out->end()), out->end());
  return Status::Ok();
}

// Joint positions in the garment's frame (bind or rest), and each joint's frame -> bind matrix
// (identity in the bind frame).
Status JointFrames(const std::string& prefix, const SceneGarment& g, const SkeletonData& skeleton,
                   const SkeletonPose& rest, std::vector<Float3>* joint_positions,
                   std::vector<Mat34>* frame_to_bind) {
  const uint32_t joints = skeleton.joint_count();
  frame_to_bind->assign(joints, Mat34{});
  joint_positions->assign(joints, Float3{});
  for (uint32_t j = 0; j < joints; ++j) {
    Mat34 bind_world;
    if (!InverseAffine(skeleton.inverse_bind[j], &bind_world)) bind_world = Mat34{};
    if (g.frame == GarmentFrame::kBind) {
      (*joint_positions)[j] = Translation(bind_world);
    } else {
      (*joint_positions)[j] = Translation(rest.world()[j]);
      if (!InverseAffine(rest.skinning()[j], &(*frame_to_bind)[j])) {
        return Invalid(prefix + g.path + "/frame: the rest skinning matrix of joint " +
                       Quote(skeleton.joint_names[j]) + " is singular; use \"bind\"");
      }
    }
  }
  return Status::Ok();
}

// The joint named `name`; the refusal at `path` suggests the nearest joint names (case and the
// prefix all joints share, such as "mixamorig:", ignored), else says how many joints there are.
Status FindNamedJoint(const std::string& prefix, const SkeletonData& skeleton,
                      const std::string& name, const std::string& path, int32_t* j) {
  *j = FindJoint(skeleton, name);
  if (*j >= 0) return Status::Ok();
  const std::vector<std::string> similar = NearestNames(name, skeleton.joint_names, 4);
  return Invalid(prefix + path + ": no joint named " + Quote(name) +
                 (similar.empty() ? " (" + std::to_string(skeleton.joint_count()) + " joints)"
                                  : " (did you mean " + JoinNames(similar) + "?)"));
}

// The garment's particles and triangles: a generated shape placed at the anchor, or an OBJ file
// scaled, offset and placed at the anchor (with its vertex colours when every vertex has one).
Status MakeGarmentMesh(const std::string& prefix, const SceneGarment& g, Float3 anchor,
                       GarmentMesh* mesh, std::vector<Float3>* colors) {
  Status made;
  switch (g.type) {
    case GarmentType::kSheet: {
      SheetShape s = g.sheet;
      s.center += anchor;
      made = MakeSheet(s, mesh);
      break;
    }
    case GarmentType::kSkirt: {
      SkirtShape s = g.skirt;
      s.top_center += anchor;
      made = MakeSkirt(s, mesh);
      break;
    }
    case GarmentType::kCape: {
      CapeShape s = g.cape;
      s.top_center += anchor;
      made = MakeCape(s, mesh);
      break;
    }
    case GarmentType::kSleeve: {
      SleeveShape s = g.sleeve;
      s.start += anchor;
      made = MakeSleeve(s, mesh);
      break;
    }
    case GarmentType::kObj: {
      made = ReadObj(g.obj_file, prefix + g.path + "/shape/file", &mesh->positions,
                     &mesh->triangles, colors);
      if (!made.ok()) return made;
      for (Float3& p : mesh->positions) p = p * g.obj_scale + g.obj_offset + anchor;
      break;
    }
    case GarmentType::kGltf:  // MakeGltfGarment
      return Invalid(prefix + g.path + ": internal: a glTF garment has its own path");
  }
  if (!made.ok()) return Invalid(prefix + g.path + "/shape: " + made.message());
  if (mesh->positions.size() > kMaxGarmentParticles) {
    return Invalid(prefix + g.path + "/shape: " + std::to_string(mesh->positions.size()) +
                   " particles: at most " + std::to_string(kMaxGarmentParticles));
  }
  return Status::Ok();
}

// Metres a skinned glTF garment's joints may disagree on a vertex's bind position: 1 % of the
// skeleton's extent at bind, at least 5 mm (float rounding of a file written at another origin).
float GltfBindTolerance(const SkeletonData& skeleton) {
  Float3 lo{kInf, kInf, kInf}, hi{-kInf, -kInf, -kInf};
  for (const Mat34& inverse_bind : skeleton.inverse_bind) {
    Mat34 bind_world;
    if (!InverseAffine(inverse_bind, &bind_world)) continue;
    const Float3 p = Translation(bind_world);
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  const float extent = lo.x <= hi.x ? Length(hi - lo) : 0.f;
  return std::max(0.005f, 0.01f * extent);
}

// Painted distances in metres: file units times `scale`, negative values unlimited.
std::vector<float> PaintedMetres(const std::vector<float>& painted, float scale) {
  std::vector<float> out(painted.size());
  for (size_t i = 0; i < painted.size(); ++i) out[i] = painted[i] < 0.f ? kInf : painted[i] * scale;
  return out;
}

// A glTF garment's mesh in the garment's frame. With a skin: bound to the skeleton by joint name
// (its weights and bind positions kept in `out` for the skin stage), placed at bind or skinned
// to the rest pose; without: placed like an OBJ (scale, offset, anchor).
Status MakeGltfGarment(const std::string& prefix, const SceneGarment& g,
                       const SkeletonData& skeleton, const SkeletonPose& rest, Float3 anchor,
                       GarmentMesh* mesh, ResolvedGarment* out) {
  const std::string where = prefix + g.path + "/shape/file";
  GltfGarmentMesh file;
  DRAPE_RETURN_IF_ERROR(ReadGltfGarment(g.obj_file, where, g.gltf_mesh, &file));
  mesh->triangles = file.triangles;
  out->colors = file.colors;
  float scale = g.obj_scale;
  if (file.joint_names.empty()) {
    mesh->positions = file.positions;
    for (Float3& p : mesh->positions) p = p * g.obj_scale + g.obj_offset + anchor;
  } else {
    if (g.obj_scale != 1.f || Length(g.obj_offset) != 0.f || !g.anchor.empty())
      return Invalid(prefix + g.path +
                     ": a skinned glTF garment is placed by its skin; remove `shape/scale`, "
                     "`shape/offset` and `anchor`");
    GltfGarmentBinding binding;
    DRAPE_RETURN_IF_ERROR(
        BindGltfGarment(file, skeleton, GltfBindTolerance(skeleton), where, &binding));
    scale = binding.scale;
    mesh->positions = binding.bind_positions;
    if (g.frame == GarmentFrame::kRest) {  // linear blend skinning to the rest pose
      for (size_t i = 0; i < mesh->positions.size(); ++i) {
        Float3 p;
        for (int k = 0; k < 4; ++k)
          if (binding.skin[i].weights[k] > 0.f)
            p += TransformPoint(rest.skinning()[binding.skin[i].joints[k]],
                                binding.bind_positions[i]) *
                 binding.skin[i].weights[k];
        mesh->positions[i] = p;
      }
    }
    out->file_skin = std::move(binding.skin);
    out->file_bind_positions = std::move(binding.bind_positions);
  }
  out->painted_max_distance = PaintedMetres(file.max_distance, scale);
  out->painted_backstop = PaintedMetres(file.backstop, scale);
  if (mesh->positions.size() > kMaxGarmentParticles) {
    return Invalid(prefix + g.path + "/shape: " + std::to_string(mesh->positions.size()) +
                   " particles: at most " + std::to_string(kMaxGarmentParticles));
  }
  return Status::Ok();
}

// Which selection holds each particle (for messages about conflicts) and how: -2 free, -1 pinned,
// else the joint it is attached to.
struct Holds {
  std::vector<const std::string*> held_by;
  std::vector<int32_t> held_joint;
};

// The garment's attachments into d->attachments (bind-frame positions), then its pins into
// d->pinned. A particle held twice the same way is kept once; held two ways, refused.
Status HoldParticles(const Scene& scene, const std::string& prefix, const SceneGarment& g,
                     const SkeletonData& skeleton, const GarmentMesh& mesh, Float3 anchor,
                     const std::vector<Mat34>& frame_to_bind, ClothDescription* d, Holds* holds) {
  std::vector<const std::string*>& held_by = holds->held_by;
  std::vector<int32_t>& held_joint = holds->held_joint;
  held_by.assign(mesh.positions.size(), nullptr);
  held_joint.assign(mesh.positions.size(), -2);
  for (const SceneAttachment& a : g.attachments) {
    int32_t joint = -1;
    DRAPE_RETURN_IF_ERROR(
        FindNamedJoint(prefix, skeleton, a.joint, a.particles.path + "/joint", &joint));
    std::vector<uint32_t> particles;
    DRAPE_RETURN_IF_ERROR(SelectParticles(scene, g, mesh, a.particles, anchor, &particles));
    for (uint32_t p : particles) {
      if (held_by[p] != nullptr) {
        if (held_joint[p] == joint) continue;  // the same hold twice
        return Invalid(prefix + a.particles.path + ": particle " + std::to_string(p) +
                       " is already held by " + *held_by[p]);
      }
      held_by[p] = &a.particles.path;
      held_joint[p] = joint;
      d->attachments.push_back(
          {p, joint, TransformPoint(frame_to_bind[static_cast<size_t>(joint)], mesh.positions[p])});
    }
  }
  for (const SceneSelection& pin : g.pins) {
    std::vector<uint32_t> particles;
    DRAPE_RETURN_IF_ERROR(SelectParticles(scene, g, mesh, pin, anchor, &particles));
    for (uint32_t p : particles) {
      if (held_by[p] != nullptr) {
        if (held_joint[p] == -1) continue;
        return Invalid(prefix + pin.path + ": particle " + std::to_string(p) +
                       " is already held by " + *held_by[p]);
      }
      held_by[p] = &pin.path;
      held_joint[p] = -1;
      d->pinned.push_back(p);
    }
  }
  return Status::Ok();
}

// Each particle's carrier: the joint of its nearest held particle along the cloth (-1 for a pin
// or a particle no held one connects to).
std::vector<int32_t> CarrierJoints(const ClothDescription& d,
                                   const std::vector<int32_t>& held_joint) {
  std::vector<float> distance;
  std::vector<uint32_t> nearest;
  NearestHeldParticles(d, &distance, &nearest);
  std::vector<int32_t> carrier_joint(d.positions.size(), -1);
  for (size_t i = 0; i < d.positions.size(); ++i) {
    if (nearest[i] != UINT32_MAX) carrier_joint[i] = std::max(held_joint[nearest[i]], -1);
  }
  return carrier_joint;
}

}  // namespace

const char* ToString(GarmentType type) {
  switch (type) {
    case GarmentType::kSheet:
      return "sheet";
    case GarmentType::kSkirt:
      return "skirt";
    case GarmentType::kCape:
      return "cape";
    case GarmentType::kSleeve:
      return "sleeve";
    case GarmentType::kObj:
      return "obj";
    case GarmentType::kGltf:
      return "gltf";
  }
  return "?";
}

std::vector<std::string> GarmentRingNames(GarmentType type) {
  switch (type) {
    case GarmentType::kSheet:
      return {"top", "bottom", "left", "right"};
    case GarmentType::kSkirt:
      return {"waist", "hem"};
    case GarmentType::kCape:
      return {"top", "bottom", "left", "right"};
    case GarmentType::kSleeve:
      return {"start", "end"};
    case GarmentType::kObj:
    case GarmentType::kGltf:
      return {};
  }
  return {};
}

Status ResolveGarment(const Scene& scene, size_t index, const SkeletonData& skeleton,
                      ResolvedGarment* out) {
  *out = ResolvedGarment{};
  if (index >= scene.garments.size())
    return Invalid(scene.source + ": no garment " + std::to_string(index));
  const SceneGarment& g = scene.garments[index];
  const std::string prefix = scene.source + ": ";
  SkeletonPose rest;
  DRAPE_RETURN_IF_ERROR(rest.Init(skeleton));
  rest.SetRest();

  std::vector<Float3> joint_positions;
  DRAPE_RETURN_IF_ERROR(
      JointFrames(prefix, g, skeleton, rest, &joint_positions, &out->frame_to_bind));
  Float3 anchor;
  if (!g.anchor.empty()) {
    int32_t j = -1;
    DRAPE_RETURN_IF_ERROR(FindNamedJoint(prefix, skeleton, g.anchor, g.path + "/anchor", &j));
    anchor = joint_positions[static_cast<size_t>(j)];
  }
  GarmentMesh mesh;
  if (g.type == GarmentType::kGltf) {
    DRAPE_RETURN_IF_ERROR(MakeGltfGarment(prefix, g, skeleton, rest, anchor, &mesh, out));
  } else {
    DRAPE_RETURN_IF_ERROR(MakeGarmentMesh(prefix, g, anchor, &mesh, &out->colors));
  }

  ClothDescription& d = out->description;
  d.positions = mesh.positions;
  d.triangles = mesh.triangles;
  d.density = g.density;
  d.total_mass = g.total_mass;
  d.stretch = g.stretch;
  d.bend = g.bend;
  d.bend_springs = g.bend_springs;
  Holds holds;
  DRAPE_RETURN_IF_ERROR(
      HoldParticles(scene, prefix, g, skeleton, mesh, anchor, out->frame_to_bind, &d, &holds));
  d.tether_stretch = g.tether_stretch;

  // Validate the cloth now, so that a bad garment is refused with its path.
  Cloth check;
  if (Status s = BuildCloth(d, &check); !s.ok())
    return Invalid(prefix + g.path + ": " + s.message());
  out->carrier_joint = CarrierJoints(d, holds.held_joint);
  return Status::Ok();
}

void PlaceGarment(const ResolvedGarment& garment, std::span<const Mat34> skinning,
                  std::vector<Float3>* positions) {
  const std::vector<Float3>& rest = garment.description.positions;
  positions->resize(rest.size());
  for (size_t i = 0; i < rest.size(); ++i) {
    const int32_t j = garment.carrier_joint[i];
    if (j < 0 || static_cast<size_t>(j) >= skinning.size()) {
      (*positions)[i] = rest[i];
      continue;
    }
    const Mat34 m =
        Multiply(skinning[static_cast<size_t>(j)], garment.frame_to_bind[static_cast<size_t>(j)]);
    (*positions)[i] = TransformPoint(m, rest[i]);
  }
}

void NearestHeldParticles(const ClothDescription& cloth, std::vector<float>* distance,
                          std::vector<uint32_t>* nearest) {
  const size_t n = cloth.positions.size();
  distance->assign(n, kInf);
  nearest->assign(n, UINT32_MAX);
  // Undirected edge lists (compressed rows), from the triangles.
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  for (size_t t = 0; t + 2 < cloth.triangles.size(); t += 3) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = cloth.triangles[t + k], b = cloth.triangles[t + (k + 1) % 3];
      if (a >= n || b >= n || a == b) continue;
      edges.push_back({a, b});
      edges.push_back({b, a});
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  std::vector<uint32_t> offsets(n + 1, 0);
  for (const auto& e : edges) ++offsets[e.first + 1];
  for (size_t i = 0; i < n; ++i) offsets[i + 1] += offsets[i];

  // Dijkstra from every held particle at once; ties resolved by the smaller particle index, so
  // the result is a function of the description only.
  using Entry = std::pair<float, uint32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  const auto seed = [&](uint32_t p) {
    if (p >= n) return;
    (*distance)[p] = 0.f;
    (*nearest)[p] = p;
    queue.push({0.f, p});
  };
  for (const ClothAttachment& a : cloth.attachments) seed(a.particle);
  for (uint32_t p : cloth.pinned) seed(p);
  while (!queue.empty()) {
    const auto [d, p] = queue.top();
    queue.pop();
    if (d > (*distance)[p]) continue;
    for (uint32_t e = offsets[p]; e < offsets[p + 1]; ++e) {
      const uint32_t q = edges[e].second;
      const float candidate = d + Length(cloth.positions[q] - cloth.positions[p]);
      if (candidate < (*distance)[q] ||
          (candidate == (*distance)[q] && (*nearest)[p] < (*nearest)[q])) {
        (*distance)[q] = candidate;
        (*nearest)[q] = (*nearest)[p];
        queue.push({candidate, q});
      }
    }
  }
}

}  // namespace drape::bake

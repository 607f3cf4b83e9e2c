// drape-inspect FILE.drape [--json | --dump-json]
// What a .drape file holds, loaded through formats + runtime alone (no bake dependency).

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include "drape/formats/asset_file.h"
#include "drape/runtime/body_map_collider.h"
#include "drape/runtime/bone_map_collider.h"
#include "drape/runtime/capsule_colliders.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"
#include "tasks/passive_waits.h"

namespace {

int Usage() {
  std::fprintf(stderr,
               "usage: drape-inspect FILE.drape [--json | --dump-json]\n"
               "  --json       a JSON summary\n"
               "  --dump-json  the whole asset as JSON (large; for golden diffs)\n");
  return 2;
}

std::string Quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buffer[8];
      std::snprintf(buffer, sizeof(buffer), "\\u%04x", c);
      out += buffer;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

// The format version in the file's header (bytes 8-11, little-endian); the file has already been
// read and validated, so the header is there. 0 if it cannot be read again.
uint32_t FileFormatVersion(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char header[12] = {};
  if (!in.read(reinterpret_cast<char*>(header), sizeof(header))) return 0;
  return uint32_t{header[8]} | uint32_t{header[9]} << 8 | uint32_t{header[10]} << 16 |
         uint32_t{header[11]} << 24;
}

size_t PoseBytes(const drape::BodyMapPose& p) {
  size_t bytes = 0;
  for (int v = 0; v < 2; ++v) {
    bytes += p.depth_f32[v].size() * 4 + p.depth_u16[v].size() * 2 + p.normal_f32[v].size() * 4 +
             p.normal_oct16[v].size() * 2 + p.normal_rgb8[v].size();
  }
  // The row-span table of the sparse layout (empty for dense poses).
  return bytes + p.row_span_offsets.size() * 4 + p.span_begin.size() * 2 +
         p.span_texel_offsets.size() * 4;
}

const char* DepthName(drape::DepthEncoding e) {
  return e == drape::DepthEncoding::kFloat32 ? "float32" : "unorm16";
}
const char* NormalName(drape::NormalEncoding e) {
  switch (e) {
    case drape::NormalEncoding::kFloat32:
      return "float32";
    case drape::NormalEncoding::kOct16:
      return "oct16";
    case drape::NormalEncoding::kRgb8:
      return "rgb8";
  }
  return "?";
}

// Where a garment is placed: each joint's position and the body's box, at bind and at rest.
struct Placement {
  std::vector<drape::Float3> bind_joints, rest_joints;   // asset frame, metres
  drape::Float3 bind_min, bind_max, rest_min, rest_max;  // the skinned body's box
};

void BoundingBox(std::span<const drape::Float3> points, drape::Float3* lo, drape::Float3* hi) {
  *lo = {0.f, 0.f, 0.f};
  *hi = {0.f, 0.f, 0.f};
  for (size_t i = 0; i < points.size(); ++i) {
    const drape::Float3 p = points[i];
    *lo = i == 0 ? p
                 : drape::Float3{std::min(lo->x, p.x), std::min(lo->y, p.y), std::min(lo->z, p.z)};
    *hi = i == 0 ? p
                 : drape::Float3{std::max(hi->x, p.x), std::max(hi->y, p.y), std::max(hi->z, p.z)};
  }
}

drape::Status Place(const drape::CharacterAsset& a, Placement* out) {
  drape::SkeletonPose pose;
  if (drape::Status s = pose.Init(a.skeleton); !s.ok()) return s;
  std::vector<drape::Float3> skinned(a.mesh.vertex_count());
  for (const bool rest : {false, true}) {
    if (rest) {
      pose.SetRest();
    } else {
      pose.SetBind();
    }
    std::vector<drape::Float3>& joints = rest ? out->rest_joints : out->bind_joints;
    for (const drape::Mat34& m : pose.world()) joints.push_back({m.m[3], m.m[7], m.m[11]});
    if (drape::Status s = drape::SkinMesh(a.mesh, pose.skinning(), skinned); !s.ok()) return s;
    BoundingBox(skinned, rest ? &out->rest_min : &out->bind_min,
                rest ? &out->rest_max : &out->bind_max);
  }
  return drape::Status::Ok();
}

std::string Vec(drape::Float3 p) {
  std::ostringstream o;
  o << "[" << p.x << ", " << p.y << ", " << p.z << "]";
  return o.str();
}

std::string JsonSummary(const drape::CharacterAsset& a, const Placement& place,
                        const std::string& path) {
  std::ostringstream o;
  o << "{\n  \"file\": " << Quote(path) << ",\n  \"format_version\": " << FileFormatVersion(path)
    << ",\n  \"source\": " << Quote(a.info.source_name)
    << ",\n  \"tool_version\": " << Quote(a.info.tool_version)
    << ",\n  \"unit_scale\": " << a.info.unit_scale << ",\n  \"up_axis\": " << Quote(a.info.up_axis)
    << ",\n  \"joints\": [";
  for (size_t j = 0; j < a.skeleton.joint_names.size(); ++j) {
    o << (j ? ", " : "") << "{\"name\": " << Quote(a.skeleton.joint_names[j])
      << ", \"parent\": " << a.skeleton.parents[j]
      << ", \"bind_position\": " << Vec(place.bind_joints[j])
      << ", \"rest_position\": " << Vec(place.rest_joints[j]) << "}";
  }
  o << "],\n  \"body\": {\"bind_min\": " << Vec(place.bind_min)
    << ", \"bind_max\": " << Vec(place.bind_max)
    << ", \"bind_height\": " << place.bind_max.y - place.bind_min.y
    << ", \"rest_min\": " << Vec(place.rest_min) << ", \"rest_max\": " << Vec(place.rest_max)
    << ", \"rest_height\": " << place.rest_max.y - place.rest_min.y << "}";
  o << ",\n  \"clips\": [";
  for (size_t c = 0; c < a.clips.size(); ++c) {
    const auto& clip = a.clips[c];
    o << (c ? ", " : "") << "{\"name\": " << Quote(clip.name) << ", \"duration\": " << clip.duration
      << ", \"sample_rate\": " << clip.sample_rate << ", \"frames\": " << clip.frame_count << "}";
  }
  o << "],\n  \"mesh\": {\"vertices\": " << a.mesh.vertex_count()
    << ", \"triangles\": " << a.mesh.triangle_count()
    << ", \"influences\": " << a.mesh.influence_joints.size()
    << "},\n  \"render_mesh\": {\"vertices\": " << a.render_mesh.vertex_count()
    << ", \"triangles\": " << a.render_mesh.triangle_count()
    << "},\n  \"body_maps\": {\"epsilon\": " << a.body_maps.epsilon
    << ", \"resolution\": " << a.body_maps.resolution << ", \"poses\": [";
  for (size_t p = 0; p < a.body_maps.poses.size(); ++p) {
    const auto& pose = a.body_maps.poses[p];
    o << (p ? ", " : "") << "{\"clip\": " << pose.clip << ", \"time\": " << pose.time
      << ", \"width\": " << pose.width << ", \"height\": " << pose.height
      << ", \"texel_size_mm\": " << pose.texel_size * 1000.f << ", \"depth\": \""
      << DepthName(pose.depth_encoding) << "\", \"normal\": \"" << NormalName(pose.normal_encoding)
      << "\", \"layers\": " << int(pose.layers) << ", \"view_axis\": \""
      << BodyMapViewAxisName(pose.view_axis) << "\", \"bytes\": " << PoseBytes(pose) << "}";
  }
  o << "]},\n  \"hulls\": [";
  for (size_t h = 0; h < a.hulls.size(); ++h) {
    const auto& hull = a.hulls[h];
    o << (h ? ", " : "") << "{\"joint\": " << Quote(a.skeleton.joint_names[hull.joint])
      << ", \"triangles\": " << hull.triangles.size() / 3 << ", \"planes\": " << hull.planes.size()
      << ", \"map\": \"" << (hull.map.kind == drape::MapTableKind::kSphere ? "sphere" : "cylinder")
      << "\", \"map_cells\": " << hull.map.rows * hull.map.cols << "}";
  }
  o << "],\n  \"bone_maps\": [";
  for (size_t b = 0; b < a.bone_maps.maps.size(); ++b) {
    const auto& bone = a.bone_maps.maps[b];
    o << (b ? ", " : "") << "{\"joint\": " << Quote(a.skeleton.joint_names[bone.joint])
      << ", \"width\": " << bone.pose.width << ", \"height\": " << bone.pose.height
      << ", \"layers\": " << int(bone.pose.layers) << ", \"bytes\": " << PoseBytes(bone.pose)
      << "}";
  }
  o << "],\n  \"joint_spheres\": [";
  for (size_t s = 0; s < a.joint_spheres.size(); ++s) {
    const auto& sphere = a.joint_spheres[s];
    o << (s ? ", " : "") << "{\"joint\": " << Quote(a.skeleton.joint_names[sphere.joint])
      << ", \"radius\": " << sphere.radius << "}";
  }
  o << "],\n  \"capsules\": [";
  for (size_t c = 0; c < a.capsules.size(); ++c) {
    const auto& capsule = a.capsules[c];
    o << (c ? ", " : "") << "{\"joint\": " << Quote(a.skeleton.joint_names[capsule.joint])
      << ", \"radius_from\": " << capsule.radius_from << ", \"radius_to\": " << capsule.radius_to
      << "}";
  }
  o << "]\n}\n";
  return o.str();
}

void PrintText(const drape::CharacterAsset& a, const Placement& place, const std::string& path) {
  std::printf("%s: drape asset, format version %u, baked by drape %s from '%s'\n", path.c_str(),
              FileFormatVersion(path), a.info.tool_version.c_str(), a.info.source_name.c_str());
  std::printf("  units: %g m per source unit, source up axis %s\n", a.info.unit_scale,
              a.info.up_axis.c_str());
  const auto box = [](const char* name, drape::Float3 lo, drape::Float3 hi) {
    std::printf("  body at %s: x %.3f .. %.3f, y %.3f .. %.3f (height %.3f m), z %.3f .. %.3f\n",
                name, lo.x, hi.x, lo.y, hi.y, hi.y - lo.y, lo.z, hi.z);
  };
  box("bind", place.bind_min, place.bind_max);
  box("rest", place.rest_min, place.rest_max);
  std::printf("  skeleton: %u joints (positions in the asset frame, metres: bind / rest)\n",
              a.skeleton.joint_count());
  for (size_t j = 0; j < a.skeleton.joint_names.size(); ++j) {
    const int32_t parent = a.skeleton.parents[j];
    const drape::Float3 b = place.bind_joints[j], r = place.rest_joints[j];
    std::printf("    %3zu %-28s parent %-20s (%7.3f %7.3f %7.3f) / (%7.3f %7.3f %7.3f)\n", j,
                a.skeleton.joint_names[j].c_str(),
                parent < 0 ? "-" : a.skeleton.joint_names[parent].c_str(), b.x, b.y, b.z, r.x, r.y,
                r.z);
  }
  std::printf("  clips: %zu\n", a.clips.size());
  for (const auto& clip : a.clips) {
    std::printf("    %-28s %.3f s, %u frames at %g Hz\n", clip.name.c_str(), clip.duration,
                clip.frame_count, clip.sample_rate);
  }
  std::printf("  mesh: %u vertices, %u triangles, %zu influences\n", a.mesh.vertex_count(),
              a.mesh.triangle_count(), a.mesh.influence_joints.size());
  if (a.render_mesh.positions.empty()) {
    std::printf("  render mesh: none (body maps are rendered from the mesh)\n");
  } else {
    std::printf("  render mesh: %u vertices, %u triangles\n", a.render_mesh.vertex_count(),
                a.render_mesh.triangle_count());
  }
  std::printf("  body maps: %zu poses (epsilon %.1f mm)\n", a.body_maps.poses.size(),
              a.body_maps.epsilon * 1000.f);
  for (const auto& pose : a.body_maps.poses) {
    std::printf(
        "    clip %d t=%.3f s: %ux%u texels of %.2f mm along %s, depth %s, normals %s, %d "
        "layer(s), %zu bytes\n",
        pose.clip, pose.time, pose.width, pose.height, pose.texel_size * 1000.f,
        BodyMapViewAxisName(pose.view_axis), DepthName(pose.depth_encoding),
        NormalName(pose.normal_encoding), int(pose.layers), PoseBytes(pose));
  }
  std::printf("  bone maps: %zu (epsilon %.1f mm)\n", a.bone_maps.maps.size(),
              a.bone_maps.epsilon * 1000.f);
  for (const auto& bone : a.bone_maps.maps) {
    std::printf("    %-28s %ux%u texels of %.2f mm (bind frame), %d layer(s), %zu bytes\n",
                a.skeleton.joint_names[bone.joint].c_str(), bone.pose.width, bone.pose.height,
                bone.pose.texel_size * 1000.f, int(bone.pose.layers), PoseBytes(bone.pose));
  }
  std::printf("  hulls: %zu\n", a.hulls.size());
  for (const auto& hull : a.hulls) {
    std::printf("    %-28s %zu triangles, %zu planes, map %s %ux%u\n",
                a.skeleton.joint_names[hull.joint].c_str(), hull.triangles.size() / 3,
                hull.planes.size(),
                hull.map.kind == drape::MapTableKind::kSphere ? "sphere" : "cylinder",
                hull.map.rows, hull.map.cols);
  }
  std::printf("  joint spheres: %zu\n", a.joint_spheres.size());
  for (const auto& sphere : a.joint_spheres) {
    std::printf("    %-28s radius %.1f mm\n", a.skeleton.joint_names[sphere.joint].c_str(),
                sphere.radius * 1000.f);
  }
  std::printf("  capsules: %zu\n", a.capsules.size());
  for (const auto& capsule : a.capsules) {
    std::printf("    %-28s radius %.1f -> %.1f mm, %.1f mm between the centres (bind)\n",
                a.skeleton.joint_names[capsule.joint].c_str(), capsule.radius_from * 1000.f,
                capsule.radius_to * 1000.f, drape::Length(capsule.to - capsule.from) * 1000.f);
  }
}

}  // namespace

int main(int argc, char** argv) {
  drape::detail::PreferPassiveOpenMpWaits(argv);  // tasks/passive_waits.h: why
  std::string path;
  bool json = false, dump = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--json") == 0) {
      json = true;
    } else if (std::strcmp(argv[i], "--dump-json") == 0) {
      dump = true;
    } else if (std::strcmp(argv[i], "-h") == 0 || std::strcmp(argv[i], "--help") == 0) {
      Usage();
      return 0;
    } else if (argv[i][0] == '-' || !path.empty()) {
      return Usage();
    } else {
      path = argv[i];
    }
  }
  if (path.empty()) return Usage();
  drape::CharacterAsset asset;
  if (drape::Status status = drape::ReadAssetFile(path, &asset); !status.ok()) {
    std::fprintf(stderr, "drape-inspect: error: %s\n", status.message().c_str());
    return 1;
  }
  // Prove the runtime can use what it loaded: pose every clip's first frame...
  drape::SkeletonPose pose;
  if (drape::Status status = pose.Init(asset.skeleton); !status.ok()) {
    std::fprintf(stderr, "drape-inspect: error: %s: %s\n", path.c_str(), status.message().c_str());
    return 1;
  }
  for (const auto& clip : asset.clips) {
    if (drape::Status status = pose.SampleClip(clip, 0.f, false); !status.ok()) {
      std::fprintf(stderr, "drape-inspect: error: %s: %s\n", path.c_str(),
                   status.message().c_str());
      return 1;
    }
  }
  // And its colliders: a file that loads but that the runtime would refuse is reported here.
  for (size_t p = 0; p < asset.body_maps.poses.size(); ++p) {
    drape::BodyMapCollider maps;
    if (drape::Status status = maps.Build(asset.body_maps.poses[p]); !status.ok()) {
      std::fprintf(stderr, "drape-inspect: error: %s: body map pose %zu: %s\n", path.c_str(), p,
                   status.message().c_str());
      return 1;
    }
  }
  drape::BoneMapCollider bone_maps;
  if (drape::Status status = bone_maps.Build(asset.bone_maps, asset.skeleton.joint_count());
      !status.ok()) {
    std::fprintf(stderr, "drape-inspect: error: %s: %s\n", path.c_str(), status.message().c_str());
    return 1;
  }
  drape::HullColliderSet hulls;
  if (drape::Status status =
          hulls.Build(asset.hulls, asset.joint_spheres, asset.skeleton.joint_count());
      !status.ok()) {
    std::fprintf(stderr, "drape-inspect: error: %s: %s\n", path.c_str(), status.message().c_str());
    return 1;
  }
  drape::ShapeColliderSet capsules;  // the capsules at the bind pose, as the runtime adds them
  const std::vector<drape::Mat34> bind(asset.skeleton.joint_count());
  if (drape::Status status = drape::AddCapsuleColliders(asset.capsules, bind, bind, &capsules);
      !status.ok()) {
    std::fprintf(stderr, "drape-inspect: error: %s: %s\n", path.c_str(), status.message().c_str());
    return 1;
  }
  if (dump) {
    std::fputs(drape::AssetToJson(asset).c_str(), stdout);
    std::fputc('\n', stdout);
    return 0;
  }
  Placement place;
  if (drape::Status status = Place(asset, &place); !status.ok()) {
    std::fprintf(stderr, "drape-inspect: error: %s: %s\n", path.c_str(), status.message().c_str());
    return 1;
  }
  if (json) {
    std::fputs(JsonSummary(asset, place, path).c_str(), stdout);
  } else {
    PrintText(asset, place, path);
  }
  return 0;
}

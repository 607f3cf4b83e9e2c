// drape-query FILE.drape [--clip NAME --time T | --joint-matrices F] (--points F | --segments F)
//             [--method maps|bone_maps|hulls|spheres|capsules|all] [--mesh F.obj]
//             [--write-joint-matrices F]
// The runtime's collision answers from the command line, for pipeline checks and debugging.
// Input rows: "x y z" (points) or "x0 y0 z0 x1 y1 z1" (previous and current position), asset
// frame, metres; '#' starts a comment; "nan" and "inf" are read as such. Output: CSV on stdout,
// one row per input row and method, ending with the CollisionFlags bits. A row with a coordinate
// that is not finite, or beyond +-1e6 m (no body reaches there, and float positions that far are
// metres apart), is not queried: it gets kCollisionInvalidInput (128), no contact, the position
// unchanged, as the runtime's batch calls answer a non-finite particle.
// --joint-matrices: one 4x4 world matrix per joint, in joint order, asset frame, 16 numbers per
// line (row-major, last row 0 0 0 1). Every method answers for any pose: the body maps are the
// baked ones where the asset holds this very pose, else rendered from the skinned mesh
// (BodyMapRenderer) at the baked maps' texel size and epsilon, on their grid.
// --write-joint-matrices: the pose's joint world matrices in that format (9 significant digits,
// so reading them back gives the same floats).

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "drape/formats/asset_file.h"
#include "drape/runtime/body_map_collider.h"
#include "drape/runtime/body_map_renderer.h"
#include "drape/runtime/bone_map_collider.h"
#include "drape/runtime/capsule_colliders.h"
#include "drape/runtime/collision_types.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"
#include "tasks/passive_waits.h"

namespace {

int Usage() {
  std::fprintf(stderr,
               "usage: drape-query FILE.drape [--clip NAME --time T | --joint-matrices F]\n"
               "                   (--points F | --segments F)\n"
               "                   [--method maps|bone_maps|hulls|spheres|capsules|all] [--mesh "
               "F.obj]\n"
               "                   [--write-joint-matrices F]\n");
  return 2;
}

int Fail(const std::string& message) {
  std::fprintf(stderr, "drape-query: error: %s\n", message.c_str());
  return 1;
}

struct Segment {
  drape::Float3 p0, p1;
};

constexpr float kMaxCoordinate = 1e6f;  // metres

bool Usable(drape::Float3 p) {
  return drape::IsFinite(p) && std::fabs(p.x) <= kMaxCoordinate &&
         std::fabs(p.y) <= kMaxCoordinate && std::fabs(p.z) <= kMaxCoordinate;
}

// The numbers of one row: every token must be one whole number (strtod's syntax, which reads
// "nan" and "inf"); false names the first token that is not.
bool ParseNumbers(const std::string& line, std::vector<double>* values, std::string* bad) {
  std::istringstream tokens(line);
  for (std::string token; tokens >> token;) {
    char* end = nullptr;
    const double v = std::strtod(token.c_str(), &end);
    if (end == token.c_str() || *end != '\0') {
      *bad = token;
      return false;
    }
    values->push_back(v);
  }
  return true;
}

// Every row of numbers in a text file with its line number ('#' starts a comment, blank rows
// skipped), each row exactly `count` numbers; false names the file, the line and the reason.
struct NumberRow {
  int line;
  std::vector<double> values;
};
bool ReadNumberRows(const std::string& path, size_t count, const char* what,
                    std::vector<NumberRow>* rows, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = path + ": cannot open";
    return false;
  }
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (const size_t hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::vector<double> values;
    std::string bad;
    const std::string where = path + ":" + std::to_string(number) + ": ";
    if (!ParseNumbers(line, &values, &bad)) {
      *error = where + "'" + bad + "' is not a number";
      return false;
    }
    if (values.empty()) continue;
    if (values.size() != count) {
      *error = where + "expected " + std::to_string(count) + " numbers" + what + ", got " +
               std::to_string(values.size());
      return false;
    }
    rows->push_back({number, std::move(values)});
  }
  return true;
}

bool ReadRows(const std::string& path, bool segments, std::vector<Segment>* rows,
              std::string* error) {
  std::vector<NumberRow> numbers;
  if (!ReadNumberRows(path, segments ? 6 : 3, "", &numbers, error)) return false;
  for (const NumberRow& row : numbers) {
    auto f = [&](size_t k) { return static_cast<float>(row.values[k]); };
    Segment s{{f(0), f(1), f(2)}, {f(0), f(1), f(2)}};
    if (segments) s.p1 = {f(3), f(4), f(5)};
    rows->push_back(s);
  }
  return true;
}

// One affine 4x4 per line (row-major), exactly `joints` of them.
bool ReadJointMatrices(const std::string& path, uint32_t joints, std::vector<drape::Mat34>* out,
                       std::string* error) {
  std::vector<NumberRow> numbers;
  if (!ReadNumberRows(path, 16, " (a 4x4 matrix)", &numbers, error)) return false;
  for (const NumberRow& row : numbers) {
    const std::vector<double>& values = row.values;
    const std::string where = path + ":" + std::to_string(row.line) + ": ";
    drape::Mat34 m;
    for (int k = 0; k < 12; ++k) {
      if (!(std::fabs(values[k]) <= kMaxCoordinate)) {
        *error = where + "entry " + std::to_string(k) + " is not finite or beyond 1e6";
        return false;
      }
      m.m[k] = static_cast<float>(values[k]);
    }
    if (std::fabs(values[12]) > 1e-6 || std::fabs(values[13]) > 1e-6 ||
        std::fabs(values[14]) > 1e-6 || std::fabs(values[15] - 1.0) > 1e-6) {
      *error = where + "the last row is not 0 0 0 1 (not an affine matrix)";
      return false;
    }
    out->push_back(m);
  }
  if (out->size() != joints) {
    *error = path + ": " + std::to_string(out->size()) + " matrices, the skeleton has " +
             std::to_string(joints) + " joints";
    return false;
  }
  return true;
}

// The body maps of the pose: the baked ones when the asset holds this very pose (same clip and
// time, no engine matrices), else rendered from the skinned mesh on the baked maps' grid.
drape::Status PoseMaps(const drape::CharacterAsset& asset, const drape::SkeletonPose& pose,
                       int32_t clip_index, float time, bool engine_pose,
                       drape::BodyMapCollider* maps, bool* rendered) {
  *rendered = false;
  constexpr float kSameTime = 1e-4f;  // seconds
  for (const drape::BodyMapPose& p : asset.body_maps.poses) {
    const bool same_time = clip_index < 0 || std::fabs(p.time - time) <= kSameTime;
    if (!engine_pose && p.clip == clip_index && same_time) return maps->Build(p);
  }
  drape::BodyMapRenderOptions options;
  if (!asset.body_maps.poses.empty()) {
    const drape::BodyMapPose& baked = asset.body_maps.poses.front();
    options.texel_size = baked.texel_size;
    options.epsilon = asset.body_maps.epsilon;
    options.grid_x = baked.origin_x;
    options.grid_y = baked.origin_y;
    options.view_axis = baked.view_axis;
  }
  drape::BodyMapRenderer renderer;
  if (drape::Status s = renderer.Init(drape::RenderMeshOf(asset), options); !s.ok()) return s;
  *rendered = true;
  return renderer.Render(pose.skinning(), maps);
}

void PrintRow(size_t row, const char* method, const drape::ContactQuery& q, const Segment& s) {
  // Position after response: the particle moved p0 -> p1 with velocity (p1 - p0) per unit time.
  drape::Float3 position = s.p1;
  drape::Float3 velocity = s.p1 - s.p0;
  if (q.contact) drape::ApplyResponse(q, drape::ResponseParams{}, &position, &velocity);
  std::printf("%zu,%s,%d,%d,%.7g,%.7g,%.7g,%.7g,%.7g,%.7g,%.7g,%.7g,%.7g,%.7g,%.7g,%u\n", row,
              method, q.inside_end ? 1 : 0, q.contact ? 1 : 0, q.t, q.point.x, q.point.y, q.point.z,
              q.normal.x, q.normal.y, q.normal.z, q.depth, position.x, position.y, position.z,
              static_cast<unsigned>(q.flags));
}

// The collider's answer, or the invalid-input answer for a row no collider is asked about.
template <class Query>
drape::ContactQuery Answer(const Segment& s, const Query& query) {
  if (Usable(s.p0) && Usable(s.p1)) return query();
  drape::ContactQuery invalid;
  invalid.flags = drape::kCollisionInvalidInput;
  return invalid;
}

}  // namespace

int main(int argc, char** argv) {
  drape::detail::PreferPassiveOpenMpWaits(argv);  // tasks/passive_waits.h: why
  std::string path, clip_name, points_path, segments_path, method = "all", mesh_path;
  std::string matrices_path, write_matrices_path;
  float time = 0.f;
  bool time_given = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](std::string* out) {
      if (i + 1 >= argc) return false;
      *out = argv[++i];
      return true;
    };
    std::string v;
    if (a == "--clip") {
      if (!value(&clip_name)) return Usage();
    } else if (a == "--time") {
      if (!value(&v)) return Usage();
      char* end = nullptr;
      time = std::strtof(v.c_str(), &end);
      if (*end != '\0' || !std::isfinite(time)) return Fail("--time '" + v + "' is not a number");
      time_given = true;
    } else if (a == "--joint-matrices") {
      if (!value(&matrices_path)) return Usage();
    } else if (a == "--write-joint-matrices") {
      if (!value(&write_matrices_path)) return Usage();
    } else if (a == "--points") {
      if (!value(&points_path)) return Usage();
    } else if (a == "--segments") {
      if (!value(&segments_path)) return Usage();
    } else if (a == "--method") {
      if (!value(&method)) return Usage();
    } else if (a == "--mesh") {
      if (!value(&mesh_path)) return Usage();
    } else if (a == "-h" || a == "--help") {
      Usage();
      return 0;
    } else if (a[0] == '-' || !path.empty()) {
      return Usage();
    } else {
      path = a;
    }
  }
  if (path.empty() || (points_path.empty() == segments_path.empty() && mesh_path.empty() &&
                       write_matrices_path.empty())) {
    return Usage();
  }
  if (method != "maps" && method != "bone_maps" && method != "hulls" && method != "spheres" &&
      method != "capsules" && method != "all") {
    return Fail("--method '" + method +
                "' is not maps, bone_maps, hulls, spheres, capsules or all");
  }
  if (time_given && clip_name.empty()) return Fail("--time needs --clip");
  if (!matrices_path.empty() && !clip_name.empty()) {
    return Fail("--joint-matrices and --clip both give the pose: pass one");
  }

  drape::CharacterAsset asset;
  if (drape::Status s = drape::ReadAssetFile(path, &asset); !s.ok()) return Fail(s.message());
  drape::SkeletonPose pose;
  if (drape::Status s = pose.Init(asset.skeleton); !s.ok()) return Fail(path + ": " + s.message());
  int32_t clip_index = -1;
  if (!clip_name.empty()) {
    for (size_t c = 0; c < asset.clips.size(); ++c)
      if (asset.clips[c].name == clip_name) clip_index = static_cast<int32_t>(c);
    if (clip_index < 0) return Fail(path + ": no clip named '" + clip_name + "'");
    if (drape::Status s = pose.SampleClip(asset.clips[clip_index], time, false); !s.ok()) {
      return Fail(path + ": " + s.message());
    }
  }

  if (!matrices_path.empty()) {
    std::vector<drape::Mat34> world;
    std::string error;
    if (!ReadJointMatrices(matrices_path, asset.skeleton.joint_count(), &world, &error)) {
      return Fail(error);
    }
    if (drape::Status s = pose.SetJointWorldMatrices(world); !s.ok()) {
      return Fail(matrices_path + ": " + s.message());
    }
  }

  if (!write_matrices_path.empty()) {
    std::ostringstream text;
    text << "# joint world matrices of " << path << ", one 4x4 per joint (row-major)\n";
    char number[32];
    for (const drape::Mat34& m : pose.world()) {
      for (int k = 0; k < 12; ++k) {
        std::snprintf(number, sizeof(number), "%.9g ", static_cast<double>(m.m[k]));
        text << number;
      }
      text << "0 0 0 1\n";
    }
    if (drape::Status s = drape::WriteFileAtomically(write_matrices_path, text.str()); !s.ok())
      return Fail(s.message());
  }

  if (!mesh_path.empty()) {
    std::vector<drape::Float3> posed(asset.mesh.vertex_count());
    if (drape::Status s = drape::SkinMesh(asset.mesh, pose.skinning(), posed); !s.ok())
      return Fail(s.message());
    std::ostringstream obj;
    obj << "# posed body mesh of " << path
        << (!matrices_path.empty() ? " (joint matrices " + matrices_path + ")"
            : clip_name.empty()    ? " (rest pose)"
                                   : " clip " + clip_name)
        << "\n";
    for (const drape::Float3& p : posed) obj << "v " << p.x << ' ' << p.y << ' ' << p.z << '\n';
    for (size_t t = 0; t + 2 < asset.mesh.triangles.size(); t += 3) {
      obj << "f " << asset.mesh.triangles[t] + 1 << ' ' << asset.mesh.triangles[t + 1] + 1 << ' '
          << asset.mesh.triangles[t + 2] + 1 << '\n';
    }
    if (drape::Status s = drape::WriteFileAtomically(mesh_path, obj.str()); !s.ok())
      return Fail(s.message());
  }
  if (points_path.empty() && segments_path.empty()) return 0;

  std::vector<Segment> rows;
  std::string error;
  if (!ReadRows(points_path.empty() ? segments_path : points_path, !segments_path.empty(), &rows,
                &error)) {
    return Fail(error);
  }

  const bool want_maps = method == "maps" || method == "all";
  const bool want_hulls = method == "hulls" || method == "all";
  const bool want_spheres = method == "spheres" || method == "all";
  drape::BodyMapCollider maps;
  if (want_maps) {
    bool rendered = false;
    const drape::Status s =
        PoseMaps(asset, pose, clip_index, time, !matrices_path.empty(), &maps, &rendered);
    if (!s.ok()) {
      if (method == "maps") return Fail(path + ": no body maps for this pose: " + s.message());
      std::fprintf(stderr, "drape-query: note: no body maps for this pose: %s\n",
                   s.message().c_str());
    } else if (rendered) {
      std::fprintf(stderr, "drape-query: note: body maps rendered for this pose (%ux%u texels)\n",
                   maps.width(), maps.height());
    }
  }
  // Per-bone local maps, posed like the hulls; "all" includes them when the asset has them.
  drape::BoneMapCollider bone_maps;
  const bool want_bone_maps =
      method == "bone_maps" || (method == "all" && !asset.bone_maps.maps.empty());
  if (want_bone_maps) {
    if (asset.bone_maps.maps.empty()) {
      return Fail(path + ": no bone maps baked (drape-bake with bone_maps.enabled)");
    }
    if (drape::Status s = bone_maps.Build(asset.bone_maps, asset.skeleton.joint_count()); !s.ok()) {
      return Fail(path + ": " + s.message());
    }
    if (drape::Status s = bone_maps.SetPose(pose.skinning(), pose.skinning()); !s.ok())
      return Fail(path + ": " + s.message());
  }
  drape::HullColliderSet hulls;
  if (want_hulls || want_spheres) {
    if (drape::Status s =
            hulls.Build(asset.hulls, asset.joint_spheres, asset.skeleton.joint_count());
        !s.ok()) {
      return Fail(path + ": " + s.message());
    }
    if (drape::Status s = hulls.SetPose(pose.skinning(), pose.skinning()); !s.ok())
      return Fail(path + ": " + s.message());
  }

  drape::ShapeColliderSet capsules;  // the baked capsules at the pose, as an engine adds them
  const bool want_capsules = method == "capsules" || (method == "all" && !asset.capsules.empty());
  if (want_capsules) {
    if (asset.capsules.empty())
      return Fail(path + ": no capsules baked (format 6, capsules.enabled)");
    if (drape::Status s =
            drape::AddCapsuleColliders(asset.capsules, pose.skinning(), pose.skinning(), &capsules);
        !s.ok())
      return Fail(path + ": " + s.message());
  }

  std::printf(
      "row,method,inside,contact,t,px,py,pz,nx,ny,nz,depth,x_after,y_after,z_after,flags\n");
  for (size_t r = 0; r < rows.size(); ++r) {
    const Segment& s = rows[r];
    if (want_maps && !maps.empty())
      PrintRow(r, "maps", Answer(s, [&] { return maps.Query(s.p0, s.p1); }), s);
    if (want_bone_maps)
      PrintRow(r, "bone_maps", Answer(s, [&] { return bone_maps.Query(s.p0, s.p1); }), s);
    if (want_hulls)
      PrintRow(r, "hulls",
               Answer(s, [&] { return hulls.Query(s.p0, s.p1, drape::kColliderHulls); }), s);
    if (want_spheres) {
      PrintRow(r, "spheres",
               Answer(s, [&] { return hulls.Query(s.p0, s.p1, drape::kColliderSpheres); }), s);
    }
    if (want_capsules)
      PrintRow(r, "capsules", Answer(s, [&] { return capsules.Query(s.p0, s.p1, 0.f, 1.f); }), s);
  }
  return 0;
}

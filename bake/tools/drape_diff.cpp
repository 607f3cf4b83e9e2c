// drape-diff A.drape B.drape [--tolerance FILE.json] [--json]
// Compares two assets by meaning, for golden files: the skeleton and clips, the bind mesh and the
// render mesh, per hull its planes (normal angle, offset), vertices and OBB, per joint sphere its
// centre and radius, per body-map pose the texel depths (p99 and max) and coverage. Prints one line
// per difference ("hull 'spine_02': 3 planes moved up to 1.4 mm") and whether they are within the
// tolerance. Exit 0: within; 1: beyond; 2: a file could not be read or the arguments are wrong.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "body_map/body_map_collider_access.h"
#include "drape/formats/asset_file.h"
#include "drape/runtime/body_map_collider.h"
#include "tasks/passive_waits.h"

namespace {

using drape::CharacterAsset;
using drape::Float3;
using nlohmann::json;

// Limits, each in the unit its name ends with. A structural difference (a count, a name, a
// parent, a grid) is always beyond tolerance.
struct Tolerance {
  double joint_mm = 0.01;          // inverse bind and rest translations
  double joint_deg = 0.01;         // rest rotations, clip key rotations
  double clip_mm = 0.01;           // clip key translations
  double mesh_mm = 0.01;           // bind mesh and render mesh positions
  double plane_deg = 0.01;         // hull plane normals
  double plane_mm = 0.01;          // hull plane offsets
  double vertex_mm = 0.01;         // hull vertices
  double obb_mm = 0.01;            // OBB centre and half extents
  double sphere_mm = 0.01;         // joint sphere centres and radii
  double capsule_mm = 0.01;        // capsule end centres and radii
  double map_depth_p99_mm = 0.01;  // body-map texel depths over texels both cover
  double map_depth_max_mm = 0.1;
  double map_coverage_pct = 0.0;  // texels covered by one map and not the other, of either's
};

struct Finding {
  std::string what;  // "hull 'chest': 3 planes moved"
  double value = 0.0;
  double limit = 0.0;  // < 0: structural (any difference is beyond)
  std::string unit;
  bool beyond() const { return limit < 0.0 || value > limit; }
};

class Report {
 public:
  explicit Report(const Tolerance& t) : tolerance(t) {}
  void Structural(const std::string& what) { findings.push_back({what, 1.0, -1.0, ""}); }
  // Records a measured difference when it is not zero.
  void Measured(const std::string& what, double value, double limit, const std::string& unit) {
    if (value > 0.0 || !std::isfinite(value)) findings.push_back({what, value, limit, unit});
  }
  bool Within() const {
    return std::none_of(findings.begin(), findings.end(),
                        [](const Finding& f) { return f.beyond(); });
  }
  const Tolerance tolerance;
  std::vector<Finding> findings;
};

double Mm(double metres) { return metres * 1e3; }
double Distance(Float3 a, Float3 b) {
  const double dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}
constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;
// The angle between two directions, from atan2(|a x b|, a . b): exact 0 for equal vectors and
// well conditioned near 0, where acos of a rounded dot product reads hundredths of a degree.
double AngleDeg(Float3 a, Float3 b) {
  const double cx = double{a.y} * b.z - double{a.z} * b.y;
  const double cy = double{a.z} * b.x - double{a.x} * b.z;
  const double cz = double{a.x} * b.y - double{a.y} * b.x;
  const double dot = double{a.x} * b.x + double{a.y} * b.y + double{a.z} * b.z;
  return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), dot) * kDegreesPerRadian;
}
// The rotation between two orientations: 2 atan2(|v|, |w|) of conjugate(a) * b.
double QuatAngleDeg(const drape::Quat& a, const drape::Quat& b) {
  const double aw = a.w, ax = -double{a.x}, ay = -double{a.y}, az = -double{a.z};
  const double w = aw * b.w - ax * b.x - ay * b.y - az * b.z;
  const double x = aw * b.x + ax * b.w + ay * b.z - az * b.y;
  const double y = aw * b.y - ax * b.z + ay * b.w + az * b.x;
  const double z = aw * b.z + ax * b.y - ay * b.x + az * b.w;
  return 2.0 * std::atan2(std::sqrt(x * x + y * y + z * z), std::abs(w)) * kDegreesPerRadian;
}
double MatrixMm(const drape::Mat34& a, const drape::Mat34& b) {  // translation and 3x3, metres
  double worst = 0.0;
  for (int k = 0; k < 12; ++k) worst = std::max(worst, std::abs(double{a.m[k]} - b.m[k]));
  return Mm(worst);
}
std::string Quote(const std::string& s) { return "'" + s + "'"; }

void CompareSkeleton(const CharacterAsset& a, const CharacterAsset& b, Report* r) {
  const drape::SkeletonData &sa = a.skeleton, &sb = b.skeleton;
  if (sa.joint_names != sb.joint_names || sa.parents != sb.parents) {
    r->Structural("skeleton: joints differ (" + std::to_string(sa.joint_count()) + " vs " +
                  std::to_string(sb.joint_count()) + " joints, or names or parents)");
    return;
  }
  double bind = 0.0, rest_mm = 0.0, rest_deg = 0.0;
  for (size_t j = 0; j < sa.parents.size(); ++j) {
    bind = std::max(bind, MatrixMm(sa.inverse_bind[j], sb.inverse_bind[j]));
    rest_mm =
        std::max(rest_mm, Mm(Distance(sa.rest_local[j].translation, sb.rest_local[j].translation)));
    rest_deg =
        std::max(rest_deg, QuatAngleDeg(sa.rest_local[j].rotation, sb.rest_local[j].rotation));
  }
  r->Measured("skeleton: inverse bind matrices moved", bind, r->tolerance.joint_mm, "mm");
  r->Measured("skeleton: rest translations moved", rest_mm, r->tolerance.joint_mm, "mm");
  r->Measured("skeleton: rest rotations turned", rest_deg, r->tolerance.joint_deg, "deg");
}

void CompareClips(const CharacterAsset& a, const CharacterAsset& b, Report* r) {
  if (a.clips.size() != b.clips.size()) {
    r->Structural("clips: " + std::to_string(a.clips.size()) + " vs " +
                  std::to_string(b.clips.size()));
    return;
  }
  for (size_t c = 0; c < a.clips.size(); ++c) {
    const drape::ClipData &ca = a.clips[c], &cb = b.clips[c];
    const std::string name = "clip " + Quote(ca.name);
    if (ca.name != cb.name || ca.frame_count != cb.frame_count ||
        ca.keys.size() != cb.keys.size() || ca.duration != cb.duration) {
      r->Structural(name + ": name, duration or frame count differs (" + Quote(cb.name) + ", " +
                    std::to_string(cb.frame_count) + " frames)");
      continue;
    }
    double mm = 0.0, deg = 0.0;
    for (size_t k = 0; k < ca.keys.size(); ++k) {
      mm = std::max(mm, Mm(Distance(ca.keys[k].translation, cb.keys[k].translation)));
      deg = std::max(deg, QuatAngleDeg(ca.keys[k].rotation, cb.keys[k].rotation));
    }
    r->Measured(name + ": key translations moved", mm, r->tolerance.clip_mm, "mm");
    r->Measured(name + ": key rotations turned", deg, r->tolerance.joint_deg, "deg");
  }
}

// `name`: "mesh" or "render_mesh".
void CompareMesh(const std::string& name, const drape::MeshData& a, const drape::MeshData& b,
                 Report* r) {
  if (a.positions.size() != b.positions.size() || a.triangles != b.triangles) {
    r->Structural(name + ": " + std::to_string(a.positions.size()) + " vs " +
                  std::to_string(b.positions.size()) + " vertices, or other triangles");
    return;
  }
  double mm = 0.0;
  for (size_t v = 0; v < a.positions.size(); ++v)
    mm = std::max(mm, Mm(Distance(a.positions[v], b.positions[v])));
  r->Measured(name + ": vertices moved", mm, r->tolerance.mesh_mm, "mm");
}

// "hull 'chest'", "hull 'chest' #2" for a bone's second piece.
std::vector<std::string> HullNames(const CharacterAsset& asset) {
  std::vector<std::string> names;
  for (size_t h = 0; h < asset.hulls.size(); ++h) {
    const int32_t joint = asset.hulls[h].joint;
    const bool named = joint >= 0 && static_cast<size_t>(joint) < asset.skeleton.joint_names.size();
    std::string name = "hull " + Quote(named ? asset.skeleton.joint_names[joint] : "?");
    int piece = 1;
    for (size_t k = 0; k < h; ++k) piece += asset.hulls[k].joint == joint ? 1 : 0;
    names.push_back(piece > 1 ? name + " #" + std::to_string(piece) : name);
  }
  return names;
}

void CompareHull(const std::string& name, const drape::HullColliderData& a,
                 const drape::HullColliderData& b, Report* r) {
  if (a.joint != b.joint || a.planes.size() != b.planes.size() ||
      a.vertices.size() != b.vertices.size()) {
    r->Structural(name + ": " + std::to_string(a.planes.size()) + " vs " +
                  std::to_string(b.planes.size()) + " planes, " +
                  std::to_string(a.vertices.size()) + " vs " + std::to_string(b.vertices.size()) +
                  " vertices");
    return;
  }
  double deg = 0.0, mm = 0.0;
  int moved = 0;
  for (size_t p = 0; p < a.planes.size(); ++p) {
    const double d = AngleDeg(a.planes[p].normal, b.planes[p].normal);
    const double o = Mm(std::abs(double{a.planes[p].offset} - b.planes[p].offset));
    moved += d > 0.0 || o > 0.0 ? 1 : 0;
    deg = std::max(deg, d);
    mm = std::max(mm, o);
  }
  const std::string planes = std::to_string(moved) + (moved == 1 ? " plane" : " planes");
  r->Measured(name + ": " + planes + " turned", deg, r->tolerance.plane_deg, "deg");
  r->Measured(name + ": " + planes + " moved", mm, r->tolerance.plane_mm, "mm");
  double vertex = 0.0;
  for (size_t v = 0; v < a.vertices.size(); ++v)
    vertex = std::max(vertex, Mm(Distance(a.vertices[v], b.vertices[v])));
  r->Measured(name + ": vertices moved", vertex, r->tolerance.vertex_mm, "mm");
  const double obb = std::max({Mm(Distance(a.obb.center, b.obb.center)),
                               Mm(Distance(a.obb.half_extents, b.obb.half_extents)),
                               MatrixMm(a.bind_frame, b.bind_frame)});
  r->Measured(name + ": OBB or frame changed", obb, r->tolerance.obb_mm, "mm");
}

void CompareCapsules(const CharacterAsset& a, const CharacterAsset& b, Report* r) {
  if (a.capsules.size() != b.capsules.size()) {
    r->Structural("capsules: " + std::to_string(a.capsules.size()) + " vs " +
                  std::to_string(b.capsules.size()));
    return;
  }
  double mm = 0.0;
  int changed = 0;
  for (size_t c = 0; c < a.capsules.size(); ++c) {
    const drape::CapsuleColliderData &ca = a.capsules[c], &cb = b.capsules[c];
    if (ca.joint != cb.joint) {
      r->Structural("capsule " + std::to_string(c) + ": another joint");
      continue;
    }
    const double d = std::max({Mm(Distance(ca.from, cb.from)), Mm(Distance(ca.to, cb.to)),
                               Mm(std::abs(double{ca.radius_from} - cb.radius_from)),
                               Mm(std::abs(double{ca.radius_to} - cb.radius_to))});
    changed += d > 0.0 ? 1 : 0;
    mm = std::max(mm, d);
  }
  r->Measured("capsules: " + std::to_string(changed) + " moved or resized", mm,
              r->tolerance.capsule_mm, "mm");
}

void CompareColliders(const CharacterAsset& a, const CharacterAsset& b, Report* r) {
  if (a.hulls.size() != b.hulls.size()) {
    r->Structural("hulls: " + std::to_string(a.hulls.size()) + " vs " +
                  std::to_string(b.hulls.size()));
  } else {
    const std::vector<std::string> names = HullNames(a);
    for (size_t h = 0; h < a.hulls.size(); ++h) CompareHull(names[h], a.hulls[h], b.hulls[h], r);
  }
  if (a.joint_spheres.size() != b.joint_spheres.size()) {
    r->Structural("joint spheres: " + std::to_string(a.joint_spheres.size()) + " vs " +
                  std::to_string(b.joint_spheres.size()));
    return;
  }
  double mm = 0.0;
  int changed = 0;
  for (size_t s = 0; s < a.joint_spheres.size(); ++s) {
    const drape::JointSphereData &sa = a.joint_spheres[s], &sb = b.joint_spheres[s];
    if (sa.joint != sb.joint || sa.parent_joint != sb.parent_joint) {
      r->Structural("joint sphere " + std::to_string(s) + ": other joints");
      continue;
    }
    const double d =
        std::max(Mm(Distance(sa.center, sb.center)), Mm(std::abs(double{sa.radius} - sb.radius)));
    changed += d > 0.0 ? 1 : 0;
    mm = std::max(mm, d);
  }
  r->Measured("joint spheres: " + std::to_string(changed) + " moved or resized", mm,
              r->tolerance.sphere_mm, "mm");
  CompareCapsules(a, b, r);
}

// The slab of the texel of `c` whose square holds (x', y') (view frame, metres); false outside
// the grid or on background.
bool SlabAt(const drape::BodyMapCollider& c, double x, double y, float* top, float* bottom) {
  const double u = (x - c.origin_x()) / c.texel_size(), v = (y - c.origin_y()) / c.texel_size();
  if (!(u >= 0.0 && v >= 0.0 && u < c.width() && v < c.height())) return false;
  return drape::BodyMapColliderAccess::TexelSlab(c, static_cast<uint32_t>(u),
                                                 static_cast<uint32_t>(v), top, bottom);
}

// Over the texels of `from`, sampling `to` at each texel centre (the grids may differ: a window
// that moved or another resolution): the depth differences of the front and back surfaces where
// both cover (mm, appended), the texels `from` covers and `to` does not, and those `from` covers.
void SampleMaps(const drape::BodyMapCollider& from, const drape::BodyMapCollider& to,
                std::vector<double>* depth_mm, uint64_t* only_from, uint64_t* covered) {
  for (uint32_t j = 0; j < from.height(); ++j) {
    for (uint32_t i = 0; i < from.width(); ++i) {
      float top, bottom, other_top, other_bottom;
      if (!drape::BodyMapColliderAccess::TexelSlab(from, i, j, &top, &bottom)) continue;
      ++*covered;
      const double x = from.origin_x() + (i + 0.5) * double{from.texel_size()};
      const double y = from.origin_y() + (j + 0.5) * double{from.texel_size()};
      if (!SlabAt(to, x, y, &other_top, &other_bottom)) {
        ++*only_from;
        continue;
      }
      if (depth_mm != nullptr)
        depth_mm->push_back(Mm(
            std::max(std::abs(double{top} - other_top), std::abs(double{bottom} - other_bottom))));
    }
  }
}

// One pose: the front and back depths where both maps cover, and the coverage either has alone.
void CompareMapPose(const std::string& name, const drape::BodyMapPose& pa,
                    const drape::BodyMapPose& pb, Report* r) {
  if (pa.view_axis != pb.view_axis) {  // texels of different frames: nothing to sample
    r->Structural(name + ": seen along " + drape::BodyMapViewAxisName(pa.view_axis) + " vs " +
                  drape::BodyMapViewAxisName(pb.view_axis));
    return;
  }
  drape::BodyMapCollider a, b;
  if (!a.Build(pa).ok() || !b.Build(pb).ok()) {
    r->Structural(name + ": does not decode");
    return;
  }
  std::vector<double> depth_mm;
  uint64_t only_a = 0, only_b = 0, covered_a = 0, covered_b = 0;
  SampleMaps(a, b, &depth_mm, &only_a, &covered_a);
  SampleMaps(b, a, nullptr, &only_b, &covered_b);
  double p99 = 0.0, max = 0.0;
  if (!depth_mm.empty()) {
    std::sort(depth_mm.begin(), depth_mm.end());
    p99 = depth_mm[std::min(depth_mm.size() - 1, depth_mm.size() * 99 / 100)];
    max = depth_mm.back();
  }
  const bool same_grid = a.width() == b.width() && a.height() == b.height() &&
                         a.origin_x() == b.origin_x() && a.origin_y() == b.origin_y() &&
                         a.texel_size() == b.texel_size();
  const std::string label = name + (same_grid ? "" : " (grids differ: sampled at texel centres)");
  r->Measured(label + ": texel depths moved (p99)", p99, r->tolerance.map_depth_p99_mm, "mm");
  r->Measured(label + ": texel depths moved (max)", max, r->tolerance.map_depth_max_mm, "mm");
  const uint64_t covered = covered_a + covered_b;
  r->Measured(label + ": coverage changed",
              covered == 0
                  ? 0.0
                  : 100.0 * static_cast<double>(only_a + only_b) / static_cast<double>(covered),
              r->tolerance.map_coverage_pct, "%");
}

void CompareBodyMaps(const CharacterAsset& a, const CharacterAsset& b, Report* r) {
  const std::vector<drape::BodyMapPose>&pa = a.body_maps.poses, &pb = b.body_maps.poses;
  if (pa.size() != pb.size()) {
    r->Structural("body maps: " + std::to_string(pa.size()) + " vs " + std::to_string(pb.size()) +
                  " poses");
    return;
  }
  for (size_t p = 0; p < pa.size(); ++p) {
    const std::string name = "body map pose " + std::to_string(p) +
                             (pa[p].clip < 0 ? " (rest)"
                                             : " (clip " + std::to_string(pa[p].clip) + " at " +
                                                   std::to_string(pa[p].time) + " s)");
    if (pa[p].clip != pb[p].clip || pa[p].time != pb[p].time) {
      r->Structural(name + ": another clip or time");
      continue;
    }
    CompareMapPose(name, pa[p], pb[p], r);
  }
}

bool ReadTolerance(const std::string& path, Tolerance* t, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = path + ": cannot open the tolerance file";
    return false;
  }
  const json j = json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object()) {
    *error = path + ": not a JSON object";
    return false;
  }
  const std::pair<const char*, double*> fields[] = {{"joint_mm", &t->joint_mm},
                                                    {"joint_deg", &t->joint_deg},
                                                    {"clip_mm", &t->clip_mm},
                                                    {"mesh_mm", &t->mesh_mm},
                                                    {"plane_deg", &t->plane_deg},
                                                    {"plane_mm", &t->plane_mm},
                                                    {"vertex_mm", &t->vertex_mm},
                                                    {"obb_mm", &t->obb_mm},
                                                    {"sphere_mm", &t->sphere_mm},
                                                    {"capsule_mm", &t->capsule_mm},
                                                    {"map_depth_p99_mm", &t->map_depth_p99_mm},
                                                    {"map_depth_max_mm", &t->map_depth_max_mm},
                                                    {"map_coverage_pct", &t->map_coverage_pct}};
  for (const auto& [key, value] : j.items()) {
    const auto* field = std::find_if(std::begin(fields), std::end(fields),
                                     [&](const auto& f) { return key == f.first; });
    if (field == std::end(fields)) {
      *error = path + ": unknown key /" + key + " (drape-diff --help lists them)";
      return false;
    }
    if (!value.is_number() || !(value.get<double>() >= 0.0)) {
      *error = path + ": /" + key + " must be a number >= 0";
      return false;
    }
    *field->second = value.get<double>();
  }
  return true;
}

void Print(const Report& r, const std::string& a, const std::string& b, bool as_json) {
  if (as_json) {
    json findings = json::array();
    for (const Finding& f : r.findings)
      findings.push_back({{"what", f.what},
                          {"value", f.value},
                          {"unit", f.unit},
                          {"limit", f.limit < 0 ? json(nullptr) : json(f.limit)},
                          {"beyond_tolerance", f.beyond()}});
    std::printf("%s\n",
                json({{"a", a}, {"b", b}, {"within_tolerance", r.Within()}, {"findings", findings}})
                    .dump(2)
                    .c_str());
    return;
  }
  for (const Finding& f : r.findings) {
    if (f.limit < 0)
      std::printf("%s  (beyond tolerance)\n", f.what.c_str());
    else
      std::printf("%s up to %.4g %s (tolerance %.4g %s%s)\n", f.what.c_str(), f.value,
                  f.unit.c_str(), f.limit, f.unit.c_str(), f.beyond() ? ", beyond" : "");
  }
  const size_t beyond = static_cast<size_t>(std::count_if(
      r.findings.begin(), r.findings.end(), [](const Finding& f) { return f.beyond(); }));
  if (beyond == 0)
    std::printf("drape-diff: %s and %s agree within tolerance (%zu differences within it)\n",
                a.c_str(), b.c_str(), r.findings.size());
  else
    std::printf("drape-diff: %s and %s differ: %zu differences beyond tolerance\n", a.c_str(),
                b.c_str(), beyond);
}

}  // namespace

int main(int argc, char** argv) {
  drape::detail::PreferPassiveOpenMpWaits(argv);  // tasks/passive_waits.h: why
  CLI::App app{"drape-diff: compares two .drape assets by meaning (golden files)"};
  std::string path_a, path_b, tolerance_path;
  bool as_json = false;
  app.add_option("A", path_a, "the reference (golden) asset")->required();
  app.add_option("B", path_b, "the asset to check")->required();
  app.add_option("--tolerance", tolerance_path,
                 "JSON limits: joint_mm joint_deg clip_mm mesh_mm plane_deg plane_mm vertex_mm "
                 "obb_mm sphere_mm capsule_mm map_depth_p99_mm map_depth_max_mm "
                 "map_coverage_pct");
  app.add_flag("--json", as_json, "print the findings as JSON");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  Tolerance tolerance;
  std::string error;
  if (!tolerance_path.empty() && !ReadTolerance(tolerance_path, &tolerance, &error)) {
    std::fprintf(stderr, "drape-diff: error: %s\n", error.c_str());
    return 2;
  }
  CharacterAsset a, b;
  for (const auto& [path, asset] : {std::pair{&path_a, &a}, std::pair{&path_b, &b}}) {
    if (drape::Status s = drape::ReadAssetFile(*path, asset); !s.ok()) {
      std::fprintf(stderr, "drape-diff: error: %s\n", s.message().c_str());
      return 2;
    }
  }
  Report report(tolerance);
  CompareSkeleton(a, b, &report);
  CompareClips(a, b, &report);
  CompareMesh("mesh", a.mesh, b.mesh, &report);
  CompareMesh("render_mesh", a.render_mesh, b.render_mesh, &report);
  CompareColliders(a, b, &report);
  CompareBodyMaps(a, b, &report);
  Print(report, path_a, path_b, as_json);
  return report.Within() ? 0 : 1;
}

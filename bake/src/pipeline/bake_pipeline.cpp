#include "drape/bake/bake_pipeline.h"

#include "preview/collider_preview.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <span>

#include "config/clip_lookup.h"
#include "drape/bake/body_map_baker.h"
#include "drape/bake/bone_map_baker.h"
#include "drape/bake/capsule_fitter.h"
#include "drape/bake/hull_builder.h"
#include "drape/bake/importer.h"
#include "drape/bake/kirkpatrick_builder.h"
#include "drape/bake/map_table_builder.h"
#include "drape/bake/mesh_reference.h"
#include "drape/bake/regions.h"
#include "drape/formats/asset_file.h"
#include "drape/runtime/body_map_collider.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"
#include "fit/collider_fit.h"
#include "fit/fit_report.h"
#include "pipeline/map_stage.h"
#include "regions/convex_pieces.h"
#include "regions/interior_points.h"
#include "regions/surface_spheres.h"

namespace drape::bake {
namespace {

using Clock = std::chrono::steady_clock;
using nlohmann::json;

double MillisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

size_t HullBytes(const HullColliderData& h) {
  auto k = [](const KirkpatrickHierarchy& x) {
    return x.vertices_uv.size() * 4 + x.node_triangles.size() * 4 + x.child_offsets.size() * 4 +
           x.children.size() * 4 + x.leaf_planes.size() * 4;
  };
  return h.vertices.size() * 12 + h.triangles.size() * 4 + h.triangle_planes.size() * 4 +
         h.planes.size() * 16 + sizeof(Obb) + k(h.upper) + k(h.lower) +
         h.map.cell_offsets.size() * 4 + h.map.cell_triangles.size() * 4;
}

// One collider to build: a bone's region, or a convex piece of it (regions/convex_pieces.h).
struct HullJob {
  uint32_t joint = 0;
  uint32_t piece = 0, pieces = 1;
  std::vector<Float3> points;  // collider frame
  double piece_bloat = 0.0;    // metres, the piece's convex hull beyond the body (0: not split)
};

// Each bone's region (its rigid, then its shaping vertices, and its points inside the body,
// regions/interior_points.h), split into convex pieces that fit the body when hulls.max_pieces
// > 1, as collider points in the bone's collider frame.
std::vector<HullJob> HullJobs(const BakeConfig& config, const Regions& regions,
                              const MeshData& mesh, const MeshReference& body,
                              std::span<const int32_t> parents) {
  const std::span<const uint32_t> triangles = mesh.triangles;
  const uint32_t joints = static_cast<uint32_t>(regions.collider_frames.size());
  std::vector<std::vector<Float3>> interior =
      BoneInteriorPoints(regions, parents, body, config.hull.delta);
  const std::vector<std::vector<Float3>> grid = BodyInteriorPoints(
      regions.rest_positions, TriangleBones(mesh, joints), joints, body, config.hull.delta);
  for (uint32_t j = 0; j < joints && j < grid.size(); ++j)
    interior[j].insert(interior[j].end(), grid[j].begin(), grid[j].end());
  const auto region_of = [&](size_t j) {
    std::vector<uint32_t> region = regions.rigid_vertices[j];
    region.insert(region.end(), regions.shaping_vertices[j].begin(),
                  regions.shaping_vertices[j].end());
    return region;
  };
  std::vector<std::vector<ConvexPiece>> split(joints);
  if (config.hull_max_pieces > 1) {
    ConvexPieceOptions options;
    options.max_bloat = config.max_bloat;
    options.max_pieces = config.hull_max_pieces;
    // One bone per iteration, results in per-bone slots: identical at any thread count.
#pragma omp parallel for schedule(dynamic, 1)
    for (int64_t j = 0; j < static_cast<int64_t>(joints); ++j) {
      const std::vector<uint32_t> region = region_of(static_cast<size_t>(j));
      if (region.empty()) continue;
      split[j] = SplitIntoConvexPieces(regions.rest_positions, triangles, region, interior[j], body,
                                       options);
    }
  }
  std::vector<HullJob> jobs;
  for (uint32_t j = 0; j < joints; ++j) {
    const Mat34 to_collider = InverseRigid(regions.collider_frames[j]);
    const auto add = [&](std::span<const Float3> rest_points, uint32_t piece, uint32_t pieces,
                         double bloat) {
      HullJob job{j, piece, pieces, {}, bloat};
      for (const Float3& p : rest_points) job.points.push_back(TransformPoint(to_collider, p));
      jobs.push_back(std::move(job));
    };
    if (split[j].size() > 1) {
      const uint32_t n = static_cast<uint32_t>(split[j].size());
      for (uint32_t k = 0; k < n; ++k) add(split[j][k].points, k, n, split[j][k].bloat);
      continue;
    }
    std::vector<Float3> region;
    for (uint32_t v : region_of(j)) region.push_back(regions.rest_positions[v]);
    if (region.empty()) continue;  // no surface: no hull (its interior points alone are none)
    region.insert(region.end(), interior[j].begin(), interior[j].end());
    add(region, 0, 1, split[j].empty() ? 0.0 : split[j][0].bloat);
  }
  return jobs;
}

// One collider as built: the hull, its hierarchies and map table, or why it failed.
struct BoneHull {
  HullColliderData hull;
  HullStats stats;
  Status status;
  KirkpatrickStats kirkpatrick;
  // Why the hull has no Kirkpatrick hierarchies (empty: it has them). The hull is kept: the
  // default plane test does not need them, and a body part without a collider lets cloth in.
  std::string kirkpatrick_failure;
  MapTableStats table;
};

// Hull geometry, Kirkpatrick hierarchies and map table of every job.
std::vector<BoneHull> BuildBoneHulls(const BakeConfig& config, const std::vector<HullJob>& jobs) {
  std::vector<BoneHull> built(jobs.size());
  // One resolution setting for both shapes: rows x cols of whichever table a collider gets.
  MapTableOptions map_options = config.map_table;
  map_options.cylinder_rows = map_options.sphere_rows;
  map_options.cylinder_cols = map_options.sphere_cols;
  // One collider per iteration, results in per-job slots: identical output at any thread count.
#pragma omp parallel for schedule(dynamic, 1)
  for (int64_t i = 0; i < static_cast<int64_t>(jobs.size()); ++i) {
    BoneHull& b = built[i];
    b.status = BuildHullGeometry(jobs[i].points, config.hull, &b.hull, &b.stats);
    if (!b.status.ok()) continue;
    const Status kirkpatrick = BuildKirkpatrick(&b.hull, config.kirkpatrick, &b.kirkpatrick);
    if (!kirkpatrick.ok()) b.kirkpatrick_failure = kirkpatrick.message();
    b.status = BuildMapTable(&b.hull, map_options, &b.table);
  }
  return built;
}

// Whether `p` (collider frame) is inside `hull` with every plane at least `depth` metres away.
bool DeeperThan(const HullColliderData& hull, Float3 p, float depth) {
  return std::ranges::all_of(hull.planes, [&](const Plane& plane) {
    return Dot(plane.normal, p) - plane.offset <= -depth;
  });
}

// Per plane, the lowest index of the planes of its geometric plane (a face can be stored as
// several planes a rounding apart). Union-find over the pairs within tolerance (closeness is not
// transitive).
std::vector<size_t> GroupEqualPlanes(std::span<const Plane> planes) {
  constexpr float kSameNormal = 0.99999f;  // cosine: 0.26 degrees
  constexpr float kSameOffset = 1e-4f;     // metres
  std::vector<size_t> group(planes.size());
  for (size_t p = 0; p < planes.size(); ++p) group[p] = p;
  const auto root = [&](size_t p) {
    while (group[p] != p) p = group[p] = group[group[p]];
    return p;
  };
  for (size_t p = 0; p < planes.size(); ++p) {
    for (size_t q = 0; q < p; ++q) {
      const Plane& a = planes[p];
      const Plane& b = planes[q];
      if (Dot(a.normal, b.normal) > kSameNormal && std::fabs(a.offset - b.offset) < kSameOffset) {
        const size_t ra = root(p), rb = root(q);
        group[std::max(ra, rb)] = std::min(ra, rb);
      }
    }
  }
  for (size_t p = 0; p < planes.size(); ++p) group[p] = root(p);
  return group;
}

// A hull's faces that lie inside the body (a convex piece's cuts from the bone's other pieces, a
// bone's end buried in its neighbour): the runtime's push-out leaves through the nearest other
// face. A face is inside when a point 2 mm off its centroid is inside the body and farther than
// delta + 2 mm from its surface. Flagging buried ends too (not only cuts) left fewer particles
// inside the body after a static push-out on CesiumMan and Fox, at rest and posed (uniform
// set p99 60 -> 25 mm, 49 -> 17 mm posed on CesiumMan; no set worse). Faces of one geometric
// plane are judged together, by their joint centroid: judged alone, the parts along the cut's
// rim stayed outer, and the push-out, taking the first of the equal planes, left through the
// cut. A face is inside too when the point 2 mm off its centroid is 1 mm deep in another piece of
// the same bone, or those off most of its area are 2 mm deep (the pieces move as one): the sliver
// faces the inflation leaves along a cut's rim, nearly parallel to it, sit just outside the body
// but lead into the next piece, and a particle pushed out through one was pushed straight back
// (Animated_Human's chin: a fast particle left 68 mm inside the body).
void MarkInternalPlanes(const Mat34& collider_to_asset, const MeshReference& body, float delta,
                        std::span<const HullColliderData* const> same_bone,
                        HullColliderData* hull) {
  constexpr float kOff = 0.002f;  // metres off the face where its outside is judged
  const size_t planes = hull->planes.size();
  const std::vector<size_t> group = GroupEqualPlanes(hull->planes);
  std::vector<double> area(planes, 0.0), area_into_sibling(planes, 0.0);
  std::vector<Float3> centroid(planes, Float3{0.f, 0.f, 0.f});
  for (size_t t = 0; t < hull->triangle_planes.size(); ++t) {
    const Float3 a = hull->vertices[hull->triangles[3 * t]];
    const Float3 b = hull->vertices[hull->triangles[3 * t + 1]];
    const Float3 c = hull->vertices[hull->triangles[3 * t + 2]];
    const float w = 0.5f * Length(Cross(b - a, c - a));
    const size_t g = group[hull->triangle_planes[t]];
    const Float3 outside = (a + b + c) * (1.f / 3.f) + hull->planes[g].normal * kOff;
    const bool into_sibling = std::ranges::any_of(same_bone, [&](const HullColliderData* other) {
      return DeeperThan(*other, outside, kOff);
    });
    area[g] += w;
    area_into_sibling[g] += into_sibling ? w : 0.0;
    centroid[g] = centroid[g] + (a + b + c) * (w / 3.f);
  }
  hull->plane_internal.assign(planes, 0);
  for (size_t g = 0; g < planes; ++g) {
    if (group[g] != g || !(area[g] > 0.0)) continue;
    const Float3 local =
        centroid[g] * static_cast<float>(1.0 / area[g]) + hull->planes[g].normal * kOff;
    const Float3 at = TransformPoint(collider_to_asset, local);
    const double q[3] = {at.x, at.y, at.z};
    const bool centroid_into_sibling = std::ranges::any_of(
        same_bone,
        [&](const HullColliderData* other) { return DeeperThan(*other, local, kOff / 2.f); });
    const bool inside = centroid_into_sibling || 2.0 * area_into_sibling[g] > area[g] ||
                        (body.Distance(q) > delta + kOff && body.Inside(q));
    hull->plane_internal[g] = inside ? 1 : 0;
  }
  size_t internal = 0;
  for (size_t p = 0; p < planes; ++p) {
    hull->plane_internal[p] = hull->plane_internal[group[p]];
    internal += hull->plane_internal[p];
  }
  if (internal == 0 || internal == planes) hull->plane_internal.clear();
}

// Too few points for a solid: the joint sphere shared with the parent covers the rigid vertices
// (the shaping ones are in their joint spheres already). Returns where they went, for the report.
std::string LeaveToJointSphere(const SkeletonData& skeleton, uint32_t j, Regions& regions) {
  std::string where = "not covered (no parent joint)";
  for (JointRegion& region : regions.joints) {
    if (region.child == static_cast<int32_t>(j) || region.parent == static_cast<int32_t>(j)) {
      region.flexible_vertices.insert(region.flexible_vertices.end(),
                                      regions.rigid_vertices[j].begin(),
                                      regions.rigid_vertices[j].end());
      where = "left to the joint sphere of '" + skeleton.joint_names[region.child] + "'";
      break;
    }
  }
  return where;
}

json HullReport(const std::string& bone, const Regions& regions, uint32_t j, const BoneHull& b) {
  const HullStats& st = b.stats;
  const KirkpatrickStats& kirkpatrick = b.kirkpatrick;
  const MapTableStats& table = b.table;
  return {{"bone", bone},
          {"kind", "hull"},
          {"rigid_vertices", regions.rigid_vertices[j].size()},
          {"shaping_vertices", regions.shaping_vertices[j].size()},
          {"triangles_before", st.hull_triangles_before},
          {"triangles_after", st.triangles_after},
          {"planes_before", st.planes_before},
          {"planes_after", st.planes_after},
          {"budget_reached", st.budget_reached},
          {"growth_mm", st.growth_mm},
          {"kirkpatrick",
           b.kirkpatrick_failure.empty()
               ? json{{"axis", kirkpatrick.axis_index},
                      {"upper_nodes", kirkpatrick.upper.nodes},
                      {"lower_nodes", kirkpatrick.lower.nodes},
                      {"levels", std::max(kirkpatrick.upper.levels, kirkpatrick.lower.levels)},
                      {"mean_tests", kirkpatrick.mean_tests}}
               : json{{"not_built", b.kirkpatrick_failure}}},
          {"map_table",
           {{"kind", table.kind == MapTableKind::kSphere ? "sphere" : "cylinder"},
            {"rows", table.rows},
            {"cols", table.cols},
            {"entries", table.entries},
            {"max_list", table.max_list},
            {"empty_cells", table.empty_cells}}},
          {"bytes", HullBytes(b.hull)},
          {"ms", st.ms}};
}

// The fractions of the vertices that are rigid, and that shape a hull (rigid or shaping).
void ReportVertexFractions(const Regions& regions, json* report) {
  size_t rigid = 0, shaping = 0;
  for (const std::vector<uint32_t>& vertices : regions.rigid_vertices) rigid += vertices.size();
  for (const std::vector<uint32_t>& vertices : regions.shaping_vertices) shaping += vertices.size();
  const double vertices = static_cast<double>(std::max<size_t>(regions.rest_positions.size(), 1));
  (*report)["rigid_vertex_fraction"] = static_cast<double>(rigid) / vertices;
  (*report)["hull_vertex_fraction"] = static_cast<double>(rigid + shaping) / vertices;
}

// Every hull's internal faces, judged against the body and the other pieces of its bone (all of
// a bone's pieces share its collider frame).
void MarkAllInternalPlanes(const Regions& regions, const MeshReference& body, float delta,
                           std::vector<HullColliderData>* hulls) {
  std::vector<const HullColliderData*> same_bone;
  for (HullColliderData& hull : *hulls) {
    same_bone.clear();
    for (const HullColliderData& other : *hulls) {
      if (&other != &hull && other.joint == hull.joint) same_bone.push_back(&other);
    }
    const uint32_t j = static_cast<uint32_t>(hull.joint);
    MarkInternalPlanes(regions.collider_frames[j], body, delta, same_bone, &hull);
  }
}

Status BakeHulls(const BakeConfig& config, Regions& regions, const Character& character,
                 CharacterAsset* asset, json* report) {
  const SkeletonData& skeleton = character.skeleton;
  const MeshReference body(regions.rest_positions, character.mesh.triangles);
  const std::vector<HullJob> jobs =
      HullJobs(config, regions, character.mesh, body, skeleton.parents);
  std::vector<BoneHull> built = BuildBoneHulls(config, jobs);
  json colliders = json::array();
  json left_out = json::array();
  for (size_t i = 0; i < jobs.size(); ++i) {
    const uint32_t j = jobs[i].joint;
    const std::string& bone = skeleton.joint_names[j];
    if (!built[i].status.ok()) {
      // A whole bone too small for a solid: its joint sphere covers it. A piece: nothing does.
      const std::string where = jobs[i].pieces == 1 ? LeaveToJointSphere(skeleton, j, regions)
                                                    : std::string("not covered");
      left_out.push_back({{"bone", bone},
                          {"piece", jobs[i].piece},
                          {"rigid_vertices", regions.rigid_vertices[j].size()},
                          {"shaping_vertices", regions.shaping_vertices[j].size()},
                          {"reason", built[i].status.message()},
                          {"covered_by", where}});
      continue;
    }
    HullColliderData& hull = built[i].hull;
    hull.joint = static_cast<int32_t>(j);
    Mat34 rest_to_bind;
    if (!InverseAffine(regions.rest_skinning[j], &rest_to_bind)) {
      left_out.push_back({{"bone", bone}, {"reason", "singular skinning matrix"}});
      continue;
    }
    hull.bind_frame = Multiply(rest_to_bind, regions.collider_frames[j]);
    json entry = HullReport(bone, regions, j, built[i]);
    entry["piece"] = jobs[i].piece;
    entry["pieces"] = jobs[i].pieces;
    entry["points"] = jobs[i].points.size();
    // Before inflation and simplification: how far the piece's own convex hull leaves the body.
    if (jobs[i].pieces > 1) entry["piece_bloat_mm"] = jobs[i].piece_bloat * 1000.0;
    colliders.push_back(std::move(entry));
    asset->hulls.push_back(std::move(hull));
  }
  MarkAllInternalPlanes(regions, body, config.hull.delta, &asset->hulls);
  (*report)["colliders"] = colliders;
  (*report)["left_out"] = left_out;
  ReportVertexFractions(regions, report);
  return Status::Ok();
}

// Below this fraction of vertices shaping a hull (rigid, or shaping at hulls.shape_threshold)
// the hulls cover little of the body: smoothly weighted rigs, e.g. CesiumMan 13 % at the
// defaults, 5 hulls, 6 % of the speed-vs-error motions missed.
constexpr double kLowHullVertexFraction = 0.5;
// Warn when spheres.cover left_by_hulls would take more than a fifth off the joint spheres'
// radii (CesiumMan: 43 %; the mannequin: 14 %, RobotExpressive 5 %, the others under 3 %).
constexpr double kSphereShrinkWorthWarning = 0.8;

// The report's header: what was baked, by which tool, for which format, with which config.
void StartReport(const std::string& input, const BakeConfig& config, json* report) {
  *report = json::object();
  (*report)["input"] = input;
  (*report)["tool_version"] = DRAPE_VERSION_STRING;
  (*report)["format_version"] = kAssetFormatVersion;
  (*report)["config"] = BakeConfigToJson(config);
}

// The asset starts as the imported character; the report says what was imported.
void StartAsset(const Character& character, CharacterAsset* asset, json* report) {
  *asset = CharacterAsset{};
  asset->info = character.info;
  asset->skeleton = character.skeleton;
  asset->clips = character.clips;
  asset->mesh = character.mesh;

  (*report)["unit_scale"] = character.info.unit_scale;
  (*report)["frame"] = character.frame_provenance;
  (*report)["up_axis"] = character.info.up_axis;
  json matrix = json::array();
  for (int r = 0; r < 4; ++r) {
    matrix.push_back({character.source_to_asset[4 * r], character.source_to_asset[4 * r + 1],
                      character.source_to_asset[4 * r + 2], character.source_to_asset[4 * r + 3]});
  }
  (*report)["source_to_asset"] = matrix;
  (*report)["joint_count"] = asset->skeleton.joint_count();
  json clips = json::array();
  for (const ClipData& clip : asset->clips) {
    clips.push_back(
        {{"name", clip.name}, {"duration_s", clip.duration}, {"frames", clip.frame_count}});
  }
  (*report)["clips"] = clips;
  (*report)["mesh"] = {{"vertices", asset->mesh.vertex_count()},
                       {"triangles", asset->mesh.triangle_count()}};
}

// Hulls kept without Kirkpatrick hierarchies (their shadow boundary is not one simple cycle on
// any OBB axis): the default plane test covers them; the Kirkpatrick inside test refuses the asset.
void WarnAboutHullsWithoutKirkpatrick(const json& hulls, std::vector<std::string>* warnings) {
  std::string bones;
  size_t count = 0;
  for (const json& c : hulls["colliders"]) {
    if (!c["kirkpatrick"].contains("not_built")) continue;
    bones += (count++ == 0 ? "'" : ", '") + c["bone"].get<std::string>() + "'";
  }
  if (count == 0) return;
  warnings->push_back(std::to_string(count) + (count == 1 ? " hull has" : " hulls have") +
                      " no Kirkpatrick hierarchy (" + bones +
                      "; the report says why): the plane inside test covers them, and "
                      "HullColliderOptions::inside_test kKirkpatrick refuses this asset");
}

// A warning when the hulls shape less than kLowHullVertexFraction of the vertices, with advice.
void WarnIfHullsCoverLittle(const BakeConfig& config, double fraction, size_t hull_count,
                            std::vector<std::string>* warnings) {
  if (fraction >= kLowHullVertexFraction) return;
  const auto value = [](float v) { return std::to_string(v).substr(0, 4); };
  std::string advice =
      config.shape_threshold > 0.f
          ? "; hulls.shape_threshold 0 (the default; " + value(config.shape_threshold) +
                " here) lets every triangle shape the hull of the bone that carries most of it "
                "(docs/ALGORITHMS.md §2.1)"
          : "; most vertices are blended with no bone above half their weight, which no "
            "hull can follow: use the body maps for this character";
  warnings->push_back("only " + std::to_string(static_cast<int>(std::lround(fraction * 100.0))) +
                      " % of the vertices shape a hull at hulls.rigid_threshold " +
                      value(config.rigid_threshold) + " and hulls.shape_threshold " +
                      value(config.shape_threshold) + " (" + std::to_string(hull_count) +
                      " hulls): the skin weights are smooth and the joint spheres carry most of "
                      "the body" +
                      advice);
}

// Smoothly weighted rigs get spheres of a limb's size: a warning when spheres.cover
// left_by_hulls would shrink the paper's spheres by more than kSphereShrinkWorthWarning.
void AdviseSphereCover(const BakeConfig& config, const Regions& regions, const Character& character,
                       const CharacterAsset& asset, std::vector<std::string>* warnings) {
  const auto radius_sum = [](const std::vector<JointSphereData>& spheres) {
    double sum = 0.0;
    for (const JointSphereData& s : spheres) sum += s.radius;
    return sum;
  };
  const double paper_b = radius_sum(asset.joint_spheres);
  const double shrunk = radius_sum(
      BuildJointSpheres(regions, config.sphere_delta, asset.hulls, character.mesh.triangles));
  if (shrunk < kSphereShrinkWorthWarning * paper_b) {
    const auto metres = [](double m) {
      char text[32];
      std::snprintf(text, sizeof(text), "%.2f m", m);
      return std::string(text);
    };
    warnings->push_back(
        "the joint spheres reach every flexible vertex (paper B); their radii sum to " +
        metres(paper_b) + ", and spheres.cover left_by_hulls would shrink that to " +
        metres(shrunk) +
        " (CesiumMan: 66 -> 47 % false contacts, normals 43 -> 25 deg; docs/ALGORITHMS.md §9)");
  }
}

// The joint spheres (paper B's, or only what the hulls leave uncovered), and the report's list.
void BakeSpheres(const BakeConfig& config, const Regions& regions, Character& character,
                 CharacterAsset* asset, json* report) {
  const bool left_by_hulls = config.sphere_cover == SphereCover::kLeftByHulls;
  if (left_by_hulls && asset->hulls.empty()) {
    character.warnings.push_back(
        "spheres.cover is left_by_hulls but no hull was baked: the joint spheres cover every "
        "flexible vertex (paper B)");
  }
  json left_out = json::array();
  if (config.sphere_cover == SphereCover::kSurface) {
    const MeshReference body(regions.rest_positions, character.mesh.triangles);
    std::vector<SphereLeftOut> dropped;
    asset->joint_spheres = BuildSurfaceJointSpheres(regions, body, config.sphere_delta,
                                                    config.sphere_min_radius, &dropped);
    for (const SphereLeftOut& d : dropped) {
      left_out.push_back(
          {{"joint", asset->skeleton.joint_names[d.joint]},
           {"parent", d.parent_joint >= 0 ? asset->skeleton.joint_names[d.parent_joint] : ""},
           {"reason", d.reason}});
    }
  } else {
    asset->joint_spheres = left_by_hulls ? BuildJointSpheres(regions, config.sphere_delta,
                                                             asset->hulls, character.mesh.triangles)
                                         : BuildJointSpheres(regions, config.sphere_delta);
  }
  if (config.sphere_cover == SphereCover::kFlexible && !asset->hulls.empty()) {
    AdviseSphereCover(config, regions, character, *asset, &character.warnings);
  }
  json spheres = json::array();
  for (const JointSphereData& s : asset->joint_spheres) {
    spheres.push_back(
        {{"joint", asset->skeleton.joint_names[s.joint]},
         {"parent", s.parent_joint >= 0 ? asset->skeleton.joint_names[s.parent_joint] : ""},
         {"radius_mm", s.radius * 1000.f}});
  }
  (*report)["joint_spheres"] = spheres;
  (*report)["joint_spheres_left_out"] = left_out;
}

// The proxies' fit to the rest-pose body (fit/collider_fit.h): each collider's bloat on its
// report entry (report["hulls"]["colliders"] and report["joint_spheres"] list the colliders in
// the asset's order), the whole in report["fit"], and the warnings of fit/fit_report.h.
ColliderFit ReportFit(const BakeConfig& config, const Regions& regions, const CharacterAsset& asset,
                      json* report, std::vector<std::string>* warnings) {
  ColliderFitOptions options;
  options.hull_delta = config.hull.delta;
  options.sphere_delta = config.sphere_delta;
  const ColliderFit fit =
      MeasureColliderFit(regions.rest_positions, asset.mesh.triangles, asset.hulls,
                         asset.joint_spheres, {}, regions.rest_skinning, options);
  std::vector<std::string> hull_names, sphere_names;
  for (const HullColliderData& h : asset.hulls)
    hull_names.push_back(asset.skeleton.joint_names[h.joint]);
  for (const JointSphereData& s : asset.joint_spheres)
    sphere_names.push_back(asset.skeleton.joint_names[s.joint]);
  if (report->contains("hulls")) {
    json& entries = (*report)["hulls"]["colliders"];
    for (size_t h = 0; h < fit.hulls.size() && h < entries.size(); ++h)
      AddBloatToReport(fit.hulls[h], &entries[h]);
  }
  if (report->contains("joint_spheres")) {
    json& entries = (*report)["joint_spheres"];
    for (size_t s = 0; s < fit.spheres.size() && s < entries.size(); ++s)
      AddBloatToReport(fit.spheres[s], &entries[s]);
  }
  (*report)["fit"] = FitToJson(fit, options, config.max_bloat);
  for (std::string& w : FitWarnings(fit, options, hull_names, sphere_names, config.max_bloat))
    warnings->push_back(std::move(w));
  return fit;
}

// The tapered capsules, and the report's list with each one's fit and the fit of the capsules
// as a proxy set of their own (report["capsules"], report["fit_capsules"]).
void BakeCapsules(const BakeConfig& config, const Regions& regions, const MeshData& mesh,
                  CharacterAsset* asset, json* report) {
  asset->capsules = FitCapsules(regions, mesh, asset->skeleton.parents, config.capsules);
  ColliderFitOptions options;
  const ColliderFit fit = MeasureColliderFit(regions.rest_positions, mesh.triangles, {}, {},
                                             asset->capsules, regions.rest_skinning, options);
  json capsules = json::array();
  for (size_t c = 0; c < asset->capsules.size(); ++c) {
    const CapsuleColliderData& k = asset->capsules[c];
    const Float3 a = TransformPoint(regions.rest_skinning[k.joint], k.from);
    const Float3 b = TransformPoint(regions.rest_skinning[k.joint], k.to);
    json entry = {{"joint", asset->skeleton.joint_names[k.joint]},
                  {"length_mm", 1000.f * Length(b - a)},
                  {"radius_from_mm", 1000.f * k.radius_from},
                  {"radius_to_mm", 1000.f * k.radius_to}};
    if (c < fit.capsules.size()) AddBloatToReport(fit.capsules[c], &entry);
    capsules.push_back(entry);
  }
  (*report)["capsules"] = capsules;
  (*report)["fit_capsules"] = FitToJson(fit, options, config.max_bloat);
}

// The preview's colours: each collider's bloat max, red at hulls.max_bloat.
PreviewBloat PreviewBloatOf(const ColliderFit& fit, float max_bloat) {
  PreviewBloat bloat;
  for (const ColliderBloat& b : fit.hulls) bloat.hull_mm.push_back(b.max_mm);
  for (const ColliderBloat& b : fit.spheres) bloat.sphere_mm.push_back(b.max_mm);
  bloat.red_mm = 1000.0 * max_bloat;
  return bloat;
}

// What the scene's garment can reach; the rest is left out of the asset and the report says so.
Status ApplySceneReach(const Scene& scene, CharacterAsset* asset, json* report) {
  SceneReach reach;
  if (Status s = AnalyzeSceneReach(scene, *asset, &reach); !s.ok()) return s;
  json left_out = json::array();
  PruneUnreachable(reach, asset, &left_out);
  (*report)["scene"] = SceneReachToJson(reach);
  (*report)["scene"]["source"] = scene.source;
  (*report)["scene"]["left_out"] = left_out;
  return Status::Ok();
}

// The file validator, then the runtime's own builders: a bake the runtime would refuse fails
// here.
Status CheckRuntimeAccepts(const std::string& input, const CharacterAsset& asset) {
  if (Status s = ValidateAsset(asset); !s.ok()) {
    return Status(s.code(), input + ": the baked asset does not validate: " + s.message());
  }
  HullColliderSet hulls;
  if (Status s = hulls.Build(asset.hulls, asset.joint_spheres, asset.skeleton.joint_count());
      !s.ok()) {
    return Status(s.code(), input + ": the runtime refuses the baked colliders: " + s.message());
  }
  for (const BodyMapPose& pose : asset.body_maps.poses) {
    BodyMapCollider maps;
    if (Status s = maps.Build(pose); !s.ok()) {
      return Status(s.code(), input + ": the runtime refuses the baked body maps: " + s.message());
    }
  }
  return Status::Ok();
}

// Per-bone local maps, and per bone what the report lists: its part, axis choice, size.
Status BakeBoneMapStage(const BakeConfig& config, const Regions& regions,
                        const Character& character, CharacterAsset* asset, json* report) {
  std::vector<BoneMapStats> stats;
  BoneMapOptions options = config.bone_maps;
  if (options.texel_size == 0.f) options.texel_size = AutomaticBoneMapTexel(regions.rest_positions);
  if (Status s = BakeBoneMaps(character.mesh, character.skeleton, regions.rest_skinning, options,
                              &asset->bone_maps, &stats);
      !s.ok()) {
    return s;
  }
  json bones = json::array();
  size_t bytes = 0;
  for (const BoneMapStats& b : stats) {
    bones.push_back({{"bone", character.skeleton.joint_names[b.joint]},
                     {"triangles", b.triangles},
                     {"facing", b.facing},
                     {"width", b.width},
                     {"height", b.height},
                     {"bytes", b.bytes}});
    bytes += b.bytes;
  }
  *report = {{"count", stats.size()},
             {"bytes", bytes},
             {"texel_size_mm", options.texel_size * 1000.f},
             {"bones", bones}};
  return Status::Ok();
}

}  // namespace

Status BakeCharacter(const std::string& input, const BakeConfig& config, BakeResult* result,
                     const std::string& preview_dir, const Scene* scene) {
  json& report = result->report;
  StartReport(input, config, &report);
  json timings = json::object();
  // A stage's error, prefixed with the input's name.
  const auto failed = [&](const Status& s) { return Status(s.code(), input + ": " + s.message()); };

  auto start = Clock::now();
  Character character;
  if (Status s = ImportCharacter(input, config.import, &character); !s.ok()) return s;
  timings["import_ms"] = MillisecondsSince(start);
  result->input_files = character.source_files;
  if (scene != nullptr) {  // the scene's reach analysis reads its garment meshes
    for (const SceneGarment& g : scene->garments)
      if (g.type == GarmentType::kObj) result->input_files.push_back(g.obj_file);
  }
  std::vector<detail::MapPoseRequest> map_requests;
  if (config.maps_enabled) {
    if (Status s = detail::MapPoseRequests(input, config, character, &map_requests); !s.ok())
      return s;
  }
  CharacterAsset& asset = result->asset;
  StartAsset(character, &asset, &report);

  start = Clock::now();
  Regions regions;
  if (Status s = SplitRegions(character, config.rigid_threshold, &regions, config.shape_threshold);
      !s.ok()) {
    return failed(s);
  }
  timings["regions_ms"] = MillisecondsSince(start);

  if (config.maps_enabled) {
    start = Clock::now();
    json maps = {{"renderer", detail::RendererName(config.maps.renderer)},
                 {"poses", json::array()}};
    if (Status s = detail::BakeMapStage(config, map_requests, regions, character, preview_dir,
                                        &asset, &maps);
        !s.ok())
      return failed(s);
    report["body_maps"] = maps;
    timings["maps_ms"] = MillisecondsSince(start);
  }
  if (config.bone_maps_enabled) {
    start = Clock::now();
    json bone_maps;
    if (Status s = BakeBoneMapStage(config, regions, character, &asset, &bone_maps); !s.ok())
      return failed(s);
    report["bone_maps"] = bone_maps;
    timings["bone_maps_ms"] = MillisecondsSince(start);
  }
  if (config.hulls_enabled) {
    start = Clock::now();
    json hulls = json::object();
    if (Status s = BakeHulls(config, regions, character, &asset, &hulls); !s.ok()) return failed(s);
    report["hulls"] = hulls;
    timings["hulls_ms"] = MillisecondsSince(start);
    WarnIfHullsCoverLittle(config, hulls["hull_vertex_fraction"].get<double>(), asset.hulls.size(),
                           &character.warnings);
    WarnAboutHullsWithoutKirkpatrick(hulls, &character.warnings);
  }
  if (config.spheres_enabled) {
    start = Clock::now();
    BakeSpheres(config, regions, character, &asset, &report);
    timings["spheres_ms"] = MillisecondsSince(start);
  }
  if (config.capsules_enabled) {
    start = Clock::now();
    BakeCapsules(config, regions, character.mesh, &asset, &report);
    timings["capsules_ms"] = MillisecondsSince(start);
  }
  if (config.hulls_enabled || config.spheres_enabled) {
    start = Clock::now();
    const ColliderFit fit = ReportFit(config, regions, asset, &report, &character.warnings);
    timings["fit_ms"] = MillisecondsSince(start);
    if (!preview_dir.empty()) {
      const PreviewBloat bloat = PreviewBloatOf(fit, config.max_bloat);
      if (Status s = WriteColliderPreview(asset, regions.rest_positions, regions.rest_skinning,
                                          preview_dir, 800, &bloat);
          !s.ok()) {
        return failed(s);
      }
    }
  }
  if (scene != nullptr) {
    start = Clock::now();
    if (Status s = ApplySceneReach(*scene, &asset, &report); !s.ok()) return s;
    timings["reach_ms"] = MillisecondsSince(start);
  }
  report["warnings"] = character.warnings;

  start = Clock::now();
  if (Status s = CheckRuntimeAccepts(input, asset); !s.ok()) return s;
  timings["validate_ms"] = MillisecondsSince(start);
  report["timings"] = timings;
  return Status::Ok();
}

}  // namespace drape::bake

// The hull stage of the bake pipeline (hull_stage.h): the bones' regions split into convex
// pieces, each piece's hull with its Kirkpatrick hierarchies and map table, internal faces marked.
#include "pipeline/hull_stage.h"

#include <algorithm>
#include <cmath>
#include <span>

#include "drape/bake/hull_builder.h"
#include "drape/bake/kirkpatrick_builder.h"
#include "drape/bake/map_table_builder.h"
#include "drape/bake/mesh_reference.h"
#include "drape/runtime/math.h"
#include "regions/convex_pieces.h"
#include "regions/interior_points.h"

namespace drape::bake::detail {
namespace {

using nlohmann::json;

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
    options.max_bloat = config.max_bloat * config.hull_cut_fraction;
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

}  // namespace

Status BakeHullStage(const BakeConfig& config, Regions& regions, const Character& character,
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

}  // namespace drape::bake::detail

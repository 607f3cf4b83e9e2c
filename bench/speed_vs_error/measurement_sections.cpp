// The report's sections that are studies of their own: paper A's claim that the collision cost
// does not depend on the body's resolution, and drape's cloth beside Bullet's soft body.

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "cloth_peer_comparison.h"
#include "drape/bake/body_map_baker.h"
#include "measurement.h"

namespace drape::bench {
namespace {

// Four triangles per triangle (edge midpoints): the same surface with 4x the triangles.
void Subdivide(std::vector<Float3>* positions, std::vector<uint32_t>* triangles) {
  std::vector<uint32_t> out;
  out.reserve(triangles->size() * 4);
  std::unordered_map<uint64_t, uint32_t> midpoints;  // edge (low, high vertex) -> new vertex
  const auto midpoint = [&](uint32_t a, uint32_t b) {
    const uint64_t key = (uint64_t{std::min(a, b)} << 32) | std::max(a, b);
    const auto [it, added] = midpoints.try_emplace(key, static_cast<uint32_t>(positions->size()));
    if (added) positions->push_back(((*positions)[a] + (*positions)[b]) * 0.5f);
    return it->second;
  };
  for (size_t t = 0; t + 2 < triangles->size(); t += 3) {
    const uint32_t a = (*triangles)[t], b = (*triangles)[t + 1], c = (*triangles)[t + 2];
    const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
    out.insert(out.end(), {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca});
  }
  *triangles = std::move(out);
}

}  // namespace

// Paper A's claim: the cost of the collision test does not depend on the body's triangle
// count. The same surface subdivided to 4x and 16x the triangles, the same map settings, the
// same motions; the exact mesh query beside it.
void Measurement::ResolutionIndependence(const CharacterSpec& spec, const Context& base) {
  bake::Character character;
  std::string note;
  ImportFor(spec, &character, &note);
  bake::Regions regions;
  if (!bake::SplitRegions(character, 0.99f, &regions).ok()) return;
  std::vector<Float3> positions = regions.rest_positions;
  std::vector<uint32_t> triangles = character.mesh.triangles;
  std::ostringstream md;
  md << "The built-in mannequin's rest pose subdivided (each triangle into four at its edge "
        "midpoints: the same surface), the same "
     << base.sets.back().size()
     << " motions. Body-map cost stays flat; the exact query grows with the triangles.\n\n"
        "| triangles | maps N=1024 nearest ns | maps N=1024 bilinear ns | bake ms per view | "
        "exact mesh ns |\n|---:|---:|---:|---:|---:|\n";
  for (int level = 0; level < 3; ++level) {
    if (level > 0) Subdivide(&positions, &triangles);
    const bake::MeshReference reference(positions, triangles);
    bake::BodyMapOptions o;
    o.resolution = 1024;
    BodyMapPose pose;
    bake::BodyMapPoseStats stats;
    if (!bake::BakeBodyMapPose(positions, triangles, o, &pose, &stats).ok()) return;
    EvaluationOptions eo;
    eo.two_threads = false;
    eo.accuracy = false;
    const QuerySet& all = base.sets.back();
    const double nearest =
        Evaluate(*MakeBodyMapMethod(pose, DepthSampling::kNearest, "", 0), all, {}, reference, eo)
            .ns_one_thread;
    const double bilinear =
        Evaluate(*MakeBodyMapMethod(pose, DepthSampling::kBilinear, "", 0), all, {}, reference, eo)
            .ns_one_thread;
    // (The exact query's repetitions as the maps', above: the fastest of five.)
    const double exact =
        Evaluate(*MakeExactMeshPeer(reference), base.peer_subset, {}, reference, eo).ns_one_thread;
    char line[200];
    std::snprintf(line, sizeof(line), "| %zu | %.1f | %.1f | %.1f | %.0f |\n", triangles.size() / 3,
                  nearest, bilinear, 0.5 * (stats.render_ms_front + stats.render_ms_back), exact);
    md << line;
    std::printf("  resolution independence: %zu triangles: maps %.1f / %.1f ns, exact %.0f ns\n",
                triangles.size() / 3, nearest, bilinear, exact);
  }
  sections_.push_back({"Paper A's claim: collision cost independent of body resolution", md.str()});
}

// The simulation-level peer: drape's cloth solver and Bullet's soft body, same garment, same
// colliders, penetration measured against the exact posed body.
void Measurement::ClothSolvers(const CharacterSpec& spec, const bake::ImportOptions& import) {
  ClothComparisonOptions o;
  if (options_.quick) {
    o.settle_frames = 10;
    o.frames = 20;
    o.segments = 48;
    o.rings = 16;
  }
  std::string note;
  const std::vector<ClothComparisonRow> rows = CompareClothSolvers(spec.path, import, o, &note);
  if (rows.empty()) {
    std::printf("  cloth solvers: not compared (%s)\n", note.c_str());
    return;
  }
  std::ostringstream md;
  md << "The demo's skirt, finer (" << rows.front().particles << " particles, attached at the "
     << "hips), on the " << spec.label << " walking: " << o.settle_frames << " settle frames, then "
     << o.frames << " frames of 1/60 s, " << o.substeps << " substeps and " << o.iterations
     << " iterations, damping 0.2, friction 0.3, one "
     << "thread; the same baked hulls and joint spheres for both (Bullet: kinematic "
        "btConvexHullShape / btSphereShape). After every frame each particle is tested "
        "against the exact posed body (skinned original mesh, winding number).\n\n"
        "| solver | ms per frame (mean / max) | particle-frames inside | p99 penetration mm | "
        "max penetration mm | finite |\n|---|---:|---:|---:|---:|---|\n";
  for (const ClothComparisonRow& r : rows) {
    if (!r.error.empty()) {
      md << "| " << r.solver << " | failed: " << r.error << " | | | | |\n";
      continue;
    }
    char line[300];
    std::snprintf(line, sizeof(line), "| %s | %.2f / %.2f | %.2f %% | %.2f | %.1f | %s |\n",
                  r.solver.c_str(), r.ms_per_frame, r.ms_per_frame_max, 100.0 * r.inside_fraction,
                  r.penetration_p99_mm, r.penetration_max_mm, r.finite ? "yes" : "**no**");
    md << line;
    std::printf("  cloth: %-55s %7.2f ms/frame, inside %.2f %%, p99 %.2f mm\n", r.solver.c_str(),
                r.ms_per_frame, 100.0 * r.inside_fraction, r.penetration_p99_mm);
  }
  sections_.push_back({"Simulation level: drape's cloth against Bullet's soft body", md.str()});
}

}  // namespace drape::bench

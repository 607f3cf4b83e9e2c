#include "cloth_peer_comparison.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "bullet_cloth_peer.h"
#include "drape/bake/bake_pipeline.h"
#include "drape/bake/mesh_reference.h"
#include "drape/runtime/cloth.h"
#include "drape/runtime/cloth_solver.h"
#include "drape/runtime/garments.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"

namespace drape::bench {
namespace {

constexpr float kFrame = 1.f / 60.f;

using Clock = std::chrono::steady_clock;

// Penetration of every particle into the exact posed body, appended to *depths (metres, 0 when
// outside); returns the particles inside.
size_t MeasurePenetration(const bake::MeshReference& body, std::span<const Float3> particles,
                          std::vector<double>* depths) {
  const size_t first = depths->size();
  depths->resize(first + particles.size());
  const long count = static_cast<long>(particles.size());
  size_t inside = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : inside)
  for (long i = 0; i < count; ++i) {
    const Float3 p = particles[static_cast<size_t>(i)];
    const double q[3] = {p.x, p.y, p.z};
    const bool in = body.Inside(q);
    (*depths)[first + static_cast<size_t>(i)] = in ? body.Distance(q) : 0.0;
    inside += in;
  }
  return inside;
}

void Summarise(std::vector<double>& depths, size_t inside, ClothComparisonRow* row) {
  if (depths.empty()) return;
  std::sort(depths.begin(), depths.end());
  const size_t rank = static_cast<size_t>(std::ceil(0.99 * double(depths.size())));
  row->penetration_p99_mm = 1e3 * depths[std::min(depths.size() - 1, rank == 0 ? 0 : rank - 1)];
  row->penetration_max_mm = 1e3 * depths.back();
  row->inside_fraction = double(inside) / double(depths.size());
}

bool AllFinite(std::span<const Float3> points) {
  for (const Float3& p : points) {
    if (!IsFinite(p)) return false;
  }
  return true;
}

}  // namespace

std::vector<ClothComparisonRow> CompareClothSolvers(const std::string& path,
                                                    const bake::ImportOptions& import,
                                                    const ClothComparisonOptions& options,
                                                    std::string* note) {
  std::vector<ClothComparisonRow> rows;
  bake::BakeConfig config;
  config.import = import;
  config.maps_enabled = false;
  bake::BakeResult baked;
  if (Status s = bake::BakeCharacter(path, config, &baked); !s.ok()) {
    *note = "bake failed: " + s.message();
    return rows;
  }
  const CharacterAsset& asset = baked.asset;
  const int32_t hips = FindJoint(asset.skeleton, "hips");
  if (asset.clips.empty() || hips < 0) {
    *note = "needs a clip and a joint named hips";
    return rows;
  }
  const ClipData& clip = asset.clips.front();
  const uint32_t joints = asset.skeleton.joint_count();

  // The skinning matrices of every frame boundary: settle frames at the start pose, then the
  // clip looping from 0.
  SkeletonPose pose;
  if (!pose.Init(asset.skeleton).ok()) return rows;
  const uint32_t total = options.settle_frames + options.frames;
  std::vector<std::vector<Mat34>> skinning(total + 1);
  for (uint32_t f = 0; f <= total; ++f) {
    const float t = f <= options.settle_frames ? 0.f : float(f - options.settle_frames) * kFrame;
    if (!pose.SampleClip(clip, t, /*loop=*/true).ok()) return rows;
    skinning[f].assign(pose.skinning().begin(), pose.skinning().end());
  }

  // The garment at the start pose: the demo's skirt, finer. Placed at the hips joint of the bind
  // pose (attachments read bind-pose positions).
  SkeletonPose bind;
  if (!bind.Init(asset.skeleton).ok()) return rows;
  bind.SetBind();
  const Mat34& hips_world = bind.world()[static_cast<size_t>(hips)];
  SkirtShape shape;
  shape.top_center = {hips_world.m[3], hips_world.m[7] + 0.03f, hips_world.m[11]};
  shape.top_radius = 0.185f;
  shape.bottom_radius = 0.34f;
  shape.length = 0.42f;
  shape.segments = options.segments;
  shape.rings = options.rings;
  GarmentMesh mesh;
  if (!MakeSkirt(shape, &mesh).ok()) return rows;
  ClothDescription description = DescribeAttachedGarment(mesh, hips);
  Cloth cloth;
  if (Status s = BuildCloth(description, &cloth); !s.ok()) {
    *note = "cloth: " + s.message();
    return rows;
  }
  const size_t particles = cloth.particle_count();

  const int saved_threads = omp_get_max_threads();
  omp_set_num_threads(1);  // both solvers single-threaded (Bullet's soft body is)

  // drape.
  {
    ClothComparisonRow row;
    row.solver = "drape ClothSolver (Verlet, hulls + spheres, continuous)";
    row.particles = static_cast<uint32_t>(particles);
    HullColliderSet hulls;
    ClothSolverSettings settings = ClothSolverSettings::PaperB();
    settings.substeps = options.substeps;
    settings.iterations = options.iterations;
    settings.damping = 0.2f;
    ClothSolver solver;
    ClothState state;
    if (Status s = hulls.Build(asset.hulls, asset.joint_spheres, joints); !s.ok()) {
      row.error = s.message();
    } else if (Status i = solver.Init(cloth, settings); !i.ok()) {
      row.error = i.message();
    } else {
      state.Reset(cloth);
      ClothColliders colliders;
      colliders.hulls = &hulls;
      colliders.response.friction = 0.3f;
      colliders.response.separation = 0.002f;
      std::vector<double> depths;
      size_t inside = 0;
      double total_ms = 0.0;
      std::vector<Float3> posed(asset.mesh.positions.size());
      for (uint32_t f = 0; f < total && row.error.empty(); ++f) {
        ClothFrame frame;
        frame.dt = kFrame;
        frame.skinning_start = skinning[f];
        frame.skinning_end = skinning[f + 1];
        const auto begin = Clock::now();
        const Status stepped = solver.Step(&state, colliders, frame, nullptr);
        const double ms = std::chrono::duration<double, std::milli>(Clock::now() - begin).count();
        if (!stepped.ok()) row.error = stepped.message();
        if (f < options.settle_frames) continue;
        total_ms += ms;
        row.ms_per_frame_max = std::max(row.ms_per_frame_max, ms);
        row.finite = row.finite && AllFinite(state.positions);
        if (!SkinMesh(asset.mesh, skinning[f + 1], posed).ok()) row.error = "skinning failed";
        const bake::MeshReference body(posed, asset.mesh.triangles);
        inside += MeasurePenetration(body, state.positions, &depths);
        ++row.frames;
      }
      row.ms_per_frame = row.frames ? total_ms / row.frames : 0.0;
      Summarise(depths, inside, &row);
    }
    rows.push_back(row);
  }

  // Bullet, against the same hulls (collider-frame vertices, posed like drape's) and spheres.
  {
    ClothComparisonRow row;
    row.solver = "Bullet btSoftBody (SDF_RS, same hulls + spheres)";
    row.particles = static_cast<uint32_t>(particles);
    HullColliderSet poser;  // used only for the colliders' world transforms
    peers::BulletClothSetup setup;
    setup.positions.assign(cloth.rest_positions().begin(), cloth.rest_positions().end());
    setup.triangles.assign(cloth.triangles().begin(), cloth.triangles().end());
    setup.inverse_masses.assign(cloth.inverse_masses().begin(), cloth.inverse_masses().end());
    setup.iterations = options.iterations;
    setup.substeps = options.substeps;
    setup.damping = 0.2f;
    setup.friction = 0.3f;
    std::vector<peers::BulletHullShape> shapes(asset.hulls.size());
    for (size_t h = 0; h < asset.hulls.size(); ++h)
      shapes[h].local_vertices = asset.hulls[h].vertices;
    std::vector<float> radii;
    for (const JointSphereData& s : asset.joint_spheres) radii.push_back(s.radius);
    peers::BulletClothPeer bullet;
    std::vector<Mat34> hull_world(asset.hulls.size());
    std::vector<Float3> centres(asset.joint_spheres.size());
    const auto pose_colliders = [&](uint32_t f) {
      if (!poser.SetPose(skinning[f], skinning[f]).ok()) row.error = "posing the colliders failed";
      for (uint32_t h = 0; h < hull_world.size(); ++h)
        hull_world[h] = poser.HullWorldTransform(h, 1.f);
      for (uint32_t s = 0; s < centres.size(); ++s) centres[s] = poser.SphereCenter(s, 1.f);
    };
    std::vector<Float3> targets;
    const auto attach_targets = [&](uint32_t f) {
      targets.clear();
      for (const ClothAttachment& a : cloth.attachments()) {
        targets.push_back(
            TransformPoint(skinning[f][static_cast<size_t>(a.joint)], a.bind_position));
      }
    };
    if (Status s = poser.Build(asset.hulls, asset.joint_spheres, joints); !s.ok()) {
      row.error = s.message();
    } else if (Status b = bullet.Build(setup, shapes, radii); !b.ok()) {
      row.error = b.message();
    } else {
      pose_colliders(0);
      if (Status p = bullet.SetInitialPose(hull_world, centres); !p.ok()) row.error = p.message();
      std::vector<Float3> positions(particles);
      std::vector<double> depths;
      size_t inside = 0;
      double total_ms = 0.0;
      std::vector<Float3> posed(asset.mesh.positions.size());
      for (uint32_t f = 0; f < total && row.error.empty(); ++f) {
        pose_colliders(f + 1);
        attach_targets(f + 1);
        const auto begin = Clock::now();
        const Status stepped = bullet.Step(hull_world, centres, targets, kFrame);
        const double ms = std::chrono::duration<double, std::milli>(Clock::now() - begin).count();
        if (!stepped.ok()) row.error = stepped.message();
        if (f < options.settle_frames) continue;
        total_ms += ms;
        row.ms_per_frame_max = std::max(row.ms_per_frame_max, ms);
        bullet.CopyPositions(positions);
        row.finite = row.finite && AllFinite(positions);
        if (!SkinMesh(asset.mesh, skinning[f + 1], posed).ok()) row.error = "skinning failed";
        const bake::MeshReference body(posed, asset.mesh.triangles);
        inside += MeasurePenetration(body, positions, &depths);
        ++row.frames;
      }
      row.ms_per_frame = row.frames ? total_ms / row.frames : 0.0;
      Summarise(depths, inside, &row);
    }
    rows.push_back(row);
  }
  omp_set_num_threads(saved_threads);
  return rows;
}

}  // namespace drape::bench

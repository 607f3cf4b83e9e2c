// One 1/60 s frame of a 10 100-particle skirt (100 segments x 101 rings, waistband attached to
// the hips) on a walking pair of legs made of 20 colliders (4 box hulls: thighs and shins; 16
// joint spheres: hips, belly, thighs, knees, shins), with continuous collision and friction.
// Arguments: OpenMP threads, substeps, colliders on (1) or off (0: the solver alone, the skirt
// then falls freely below its waistband); 5 spring-correction iterations per substep (Verlet).
// BM_BulletSkirt is the peer: Bullet's soft body (bench/peers) on the same skirt
// mesh, masses and waistband, against the same 4 boxes (btConvexHullShape of their 8 corners)
// and 16 spheres posed by the same walk, 5 position iterations per substep, single-threaded.
// Both report the penetration of the particles into the boxes and spheres after each timed frame
// (measured outside the timed region): max_depth_mm over all frames, frame_max_depth_mm the mean
// of each frame's deepest particle, inside_per_frame the particles inside any collider.
// Run: build-<name>/bin/bench_cloth_step --benchmark_repetitions=5
//        --benchmark_report_aggregates_only=true

#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <span>
#include <vector>

#include "bullet_cloth_peer.h"

#include "drape/formats/hull_collider_data.h"
#include "drape/runtime/cloth.h"
#include "drape/runtime/cloth_solver.h"
#include "drape/runtime/garments.h"
#include "drape/runtime/hull_collider_set.h"
#include "drape/runtime/math.h"

namespace drape {
namespace {

constexpr float kFrame = 1.f / 60.f;
constexpr int kJoints = 5;  // 0 hips, 1 left thigh, 2 right thigh, 3 left shin, 4 right shin
constexpr float kHipY = 0.95f, kKneeY = 0.52f, kLegX = 0.09f;

// An axis-aligned box hull (bind frame = asset frame) carried by `joint`.
HullColliderData BoxHull(int32_t joint, Float3 center, Float3 half) {
  HullColliderData h;
  h.joint = joint;
  for (int k = 0; k < 8; ++k) {
    h.vertices.push_back({center.x + ((k & 1) ? half.x : -half.x),
                          center.y + ((k & 2) ? half.y : -half.y),
                          center.z + ((k & 4) ? half.z : -half.z)});
  }
  // Faces (-x, +x, -y, +y, -z, +z) as quads counter-clockwise seen from outside.
  const uint32_t quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  const Float3 normals[6] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
  for (uint32_t f = 0; f < 6; ++f) {
    const uint32_t* q = quads[f];
    h.triangles.insert(h.triangles.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
    h.triangle_planes.insert(h.triangle_planes.end(), {f, f});
    Plane plane;
    plane.normal = normals[f];
    plane.offset = Dot(plane.normal, h.vertices[q[0]]);
    h.planes.push_back(plane);
  }
  h.obb.center = center;
  h.obb.axes[0] = {1.f, 0.f, 0.f};
  h.obb.axes[1] = {0.f, 1.f, 0.f};
  h.obb.axes[2] = {0.f, 0.f, 1.f};
  h.obb.half_extents = half;
  h.projection_axis = {0.f, 1.f, 0.f};
  h.projection_u = {0.f, 0.f, 1.f};
  h.projection_v = {1.f, 0.f, 0.f};
  return h;
}

// Rotation about +x by `angle` radians about the point `pivot`.
Mat34 RotateXAbout(float angle, Float3 pivot) {
  Mat34 r;
  const float c = std::cos(angle), s = std::sin(angle);
  r.m[5] = c;
  r.m[6] = -s;
  r.m[9] = s;
  r.m[10] = c;
  const Float3 moved = TransformVector(r, pivot);
  r.m[3] = pivot.x - moved.x;
  r.m[7] = pivot.y - moved.y;
  r.m[11] = pivot.z - moved.z;
  return r;
}

// A walk cycle at 1 Hz: the thighs swing +-0.45 rad in antiphase, the shins bend back up to
// 0.6 rad; the hips move forward at 1.2 m/s and bob by 1 cm.
void WalkPose(float t, Mat34 skinning[kJoints]) {
  const float phase = 2.f * std::numbers::pi_v<float> * t;
  Mat34 hips;
  hips.m[7] = 0.01f * std::sin(2.f * phase);
  hips.m[11] = 1.2f * t;
  skinning[0] = hips;
  for (int side = 0; side < 2; ++side) {
    const float sign = side == 0 ? 1.f : -1.f;
    const float swing = 0.45f * sign * std::sin(phase);
    const float bend =
        0.3f * (1.f - std::cos(phase + (side == 0 ? 0.f : std::numbers::pi_v<float>)));
    const Float3 hip{sign * kLegX, kHipY, 0.f}, knee{sign * kLegX, kKneeY, 0.f};
    const Mat34 thigh = Multiply(hips, RotateXAbout(-swing, hip));
    skinning[1 + side] = thigh;
    skinning[3 + side] = Multiply(thigh, RotateXAbout(bend, knee));
  }
}

struct Scene {
  Cloth cloth;
  HullColliderSet hulls;
  size_t collider_count = 0;
  GarmentMesh mesh;                      // the skirt the cloth was built from (for the peer)
  std::vector<HullColliderData> boxes;   // the colliders in their bind frame (for the peer and
  std::vector<JointSphereData> spheres;  // the penetration measure)

  Scene() {
    const auto sphere = [&](int32_t joint, Float3 c, float r) {
      JointSphereData s;
      s.joint = joint;
      s.center = c;
      s.radius = r;
      spheres.push_back(s);
    };
    sphere(0, {0.f, kHipY, 0.f}, 0.15f);
    sphere(0, {0.f, kHipY + 0.12f, 0.03f}, 0.14f);
    for (int side = 0; side < 2; ++side) {
      const float x = (side == 0 ? 1.f : -1.f) * kLegX;
      boxes.push_back(BoxHull(1 + side, {x, (kHipY + kKneeY) * 0.5f, 0.f}, {0.06f, 0.2f, 0.06f}));
      boxes.push_back(BoxHull(3 + side, {x, kKneeY - 0.22f, 0.f}, {0.045f, 0.2f, 0.045f}));
      for (int k = 0; k < 3; ++k) {
        const float kf = static_cast<float>(k);
        const float f = (kf + 1.f) / 4.f;
        sphere(1 + side, {x, kHipY + (kKneeY - kHipY) * f, 0.f}, 0.085f - 0.01f * kf);
        sphere(3 + side, {x, kKneeY - 0.4f * f, 0.f}, 0.06f - 0.005f * kf);
      }
      sphere(3 + side, {x, kKneeY, 0.f}, 0.065f);
    }
    collider_count = boxes.size() + spheres.size();
    Status s = hulls.Build(boxes, spheres, kJoints);
    if (!s.ok()) {
      std::fprintf(stderr, "hulls: %s\n", s.message().c_str());
      std::abort();
    }
    SkirtShape shape;
    shape.top_center = {0.f, kHipY + 0.05f, 0.f};
    shape.top_radius = 0.17f;
    shape.bottom_radius = 0.36f;
    shape.length = 0.6f;
    shape.segments = 100;
    shape.rings = 100;
    if (!MakeSkirt(shape, &mesh).ok()) std::abort();
    ClothDescription d = DescribeAttachedGarment(mesh, 0);
    s = BuildCloth(d, &cloth);
    if (!s.ok()) {
      std::fprintf(stderr, "cloth: %s\n", s.message().c_str());
      std::abort();
    }
  }
};

Scene& GetScene() {
  static Scene scene;
  return scene;
}

// Penetration of the particles into the posed boxes and spheres (the colliders themselves, not
// the solvers' margins): the deepest particle (metres, 0 when none is inside) and how many are
// inside any collider. Brute force over particles x colliders (about 1 ms for the skirt).
struct Penetration {
  float max_depth = 0.f;
  uint32_t inside = 0;
};
Penetration MeasurePenetration(const Scene& scene, const Mat34 skinning[kJoints],
                               std::span<const Float3> positions) {
  std::vector<Mat34> box_inverse;  // world -> box frame
  for (const HullColliderData& box : scene.boxes)
    box_inverse.push_back(InverseRigid(Multiply(skinning[box.joint], box.bind_frame)));
  std::vector<Float3> sphere_centres;
  for (const JointSphereData& sphere : scene.spheres)
    sphere_centres.push_back(TransformPoint(skinning[sphere.joint], sphere.center));
  Penetration result;
  for (const Float3 p : positions) {
    float depth = 0.f;  // deepest over the colliders containing p
    for (size_t b = 0; b < scene.boxes.size(); ++b) {
      const Obb& obb = scene.boxes[b].obb;  // axis-aligned in the box frame (BoxHull)
      const Float3 q = TransformPoint(box_inverse[b], p) - obb.center;
      const float inside_by =
          std::min({obb.half_extents.x - std::abs(q.x), obb.half_extents.y - std::abs(q.y),
                    obb.half_extents.z - std::abs(q.z)});
      depth = std::max(depth, inside_by);
    }
    for (size_t s = 0; s < scene.spheres.size(); ++s)
      depth = std::max(depth, scene.spheres[s].radius - Length(p - sphere_centres[s]));
    if (depth > 0.f) {
      ++result.inside;
      result.max_depth = std::max(result.max_depth, depth);
    }
  }
  return result;
}

// Accumulates Penetration over the timed frames and writes the counters.
struct PenetrationCounters {
  float max_depth = 0.f;
  double sum_frame_max = 0.0, sum_inside = 0.0;
  int frames = 0;
  void Add(const Penetration& p) {
    max_depth = std::max(max_depth, p.max_depth);
    sum_frame_max += p.max_depth;
    sum_inside += p.inside;
    ++frames;
  }
  void Report(benchmark::State& state) const {
    const double n = frames > 0 ? frames : 1;
    state.counters["max_depth_mm"] = 1000.0 * max_depth;
    state.counters["frame_max_depth_mm"] = 1000.0 * sum_frame_max / n;
    state.counters["inside_per_frame"] = sum_inside / n;
  }
};

void BM_ClothStep(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  omp_set_num_threads(threads);
  Scene& scene = GetScene();
  ClothSolverSettings settings = ClothSolverSettings::PaperB();
  settings.iterations = 5;
  settings.substeps = static_cast<uint32_t>(state.range(1));
  settings.damping = 0.2f;
  ClothSolver solver;
  if (!solver.Init(scene.cloth, settings).ok()) std::abort();
  ClothState cloth_state;
  cloth_state.Reset(scene.cloth);
  ClothColliders colliders;
  if (state.range(2) != 0) colliders.hulls = &scene.hulls;
  colliders.response.friction = 0.3f;
  Mat34 start[kJoints], end[kJoints];
  ClothFrame frame;
  frame.dt = kFrame;
  frame.skinning_start = start;
  frame.skinning_end = end;
  int step = 0;
  uint64_t contacts = 0;
  const auto advance = [&]() {
    WalkPose(static_cast<float>(step) * kFrame, start);
    WalkPose(static_cast<float>(step + 1) * kFrame, end);
    ClothStepStats stats;
    const Status s = solver.Step(&cloth_state, colliders, frame, &stats);
    if (!s.ok()) {
      state.SkipWithError(s.message().c_str());
      return false;
    }
    contacts += stats.contacts;
    ++step;
    return true;
  };
  for (int warm = 0; warm < 60; ++warm)
    if (!advance()) return;  // one second: the skirt settles onto the legs
  contacts = 0;
  int timed = 0;
  PenetrationCounters penetration;
  for (auto _ : state) {
    if (!advance()) return;
    ++timed;
    state.PauseTiming();
    penetration.Add(MeasurePenetration(scene, end, cloth_state.positions));
    state.ResumeTiming();
  }
  state.counters["particles"] = static_cast<double>(scene.cloth.particle_count());
  state.counters["springs"] = static_cast<double>(scene.cloth.springs().size());
  state.counters["colliders"] = static_cast<double>(scene.collider_count);
  state.counters["contacts_per_frame"] = timed > 0 ? static_cast<double>(contacts) / timed : 0.0;
  penetration.Report(state);
}
BENCHMARK(BM_ClothStep)
    ->ArgNames({"omp_threads", "substeps", "colliders"})
    ->Args({1, 1, 1})
    ->Args({2, 1, 1})
    ->Args({1, 2, 1})
    ->Args({2, 2, 1})
    ->Args({1, 1, 0})
    ->Args({2, 1, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The same frame in Bullet. Mapping of the drape settings: the same particle masses (inverse
// mass 0 for the waistband, driven to hips * bind position), stretch links with full correction
// (kLST 1) and Bullet's distance-2 bending links with drape's bend correction (kLST 0.2), the
// velocity damping of 0.2 1/s as kDP = 1 - exp(-0.2 h) per substep of h seconds, friction 0.3
// (kDF), contact hardness 1 (kKHR: Bullet's 0.1 lets the cloth sink through), soft body margin
// 2 mm, a 5 mm SDF voxel. Argument: substeps.
void BM_BulletSkirt(benchmark::State& state) {
  Scene& scene = GetScene();
  const uint32_t substeps = static_cast<uint32_t>(state.range(0));
  peers::BulletClothSetup setup;
  setup.positions = scene.mesh.positions;
  setup.triangles = scene.mesh.triangles;
  const std::span<const float> inverse_masses = scene.cloth.inverse_masses();
  setup.inverse_masses.assign(inverse_masses.begin(), inverse_masses.end());
  setup.iterations = 5;
  setup.substeps = substeps;
  setup.damping = 1.f - std::exp(-0.2f * kFrame / static_cast<float>(substeps));
  setup.friction = 0.3f;
  setup.stretch_stiffness = scene.cloth.material(SpringKind::kStretch).correction;
  setup.bend_stiffness = scene.cloth.material(SpringKind::kBend).correction;
  std::vector<peers::BulletHullShape> hulls;
  for (const HullColliderData& box : scene.boxes) hulls.push_back({box.vertices});
  std::vector<float> radii;
  for (const JointSphereData& sphere : scene.spheres) radii.push_back(sphere.radius);
  peers::BulletClothPeer peer;
  Status s = peer.Build(setup, hulls, radii);
  if (!s.ok()) {
    state.SkipWithError(s.message().c_str());
    return;
  }
  // The attached particles in index order (Cloth::attachments() is sorted by particle) and
  // their bind positions: their targets are skinning(joint) * bind_position.
  const std::span<const ClothAttachment> attachments = scene.cloth.attachments();
  if (attachments.size() != peer.attached_count()) {
    state.SkipWithError("attachments and zero inverse masses differ");
    return;
  }
  Mat34 skinning[kJoints];
  std::vector<Mat34> hull_world(scene.boxes.size());
  std::vector<Float3> sphere_centres(scene.spheres.size()), targets(attachments.size());
  std::vector<Float3> positions(peer.particle_count());
  const auto pose = [&](int frame) {
    WalkPose(static_cast<float>(frame) * kFrame, skinning);
    for (size_t b = 0; b < scene.boxes.size(); ++b)
      hull_world[b] = Multiply(skinning[scene.boxes[b].joint], scene.boxes[b].bind_frame);
    for (size_t c = 0; c < scene.spheres.size(); ++c)
      sphere_centres[c] = TransformPoint(skinning[scene.spheres[c].joint], scene.spheres[c].center);
    for (size_t a = 0; a < attachments.size(); ++a)
      targets[a] = TransformPoint(skinning[attachments[a].joint], attachments[a].bind_position);
  };
  pose(0);
  s = peer.SetInitialPose(hull_world, sphere_centres);
  int step = 0;
  uint64_t contacts = 0;
  const auto advance = [&]() {
    pose(step + 1);  // the end of the frame
    const Status st = peer.Step(hull_world, sphere_centres, targets, kFrame);
    if (!st.ok()) {
      state.SkipWithError(st.message().c_str());
      return false;
    }
    contacts += peer.last_contact_count();
    ++step;
    return true;
  };
  if (!s.ok()) {
    state.SkipWithError(s.message().c_str());
    return;
  }
  for (int warm = 0; warm < 60; ++warm)
    if (!advance()) return;
  contacts = 0;
  int timed = 0;
  PenetrationCounters penetration;
  for (auto _ : state) {
    if (!advance()) return;
    ++timed;
    state.PauseTiming();
    peer.CopyPositions(positions);
    penetration.Add(MeasurePenetration(scene, skinning, positions));
    state.ResumeTiming();
  }
  state.counters["particles"] = static_cast<double>(peer.particle_count());
  state.counters["springs"] = static_cast<double>(peer.link_count());  // edge + bending links
  state.counters["colliders"] = static_cast<double>(scene.collider_count);
  // Bullet's node contacts of the last substep of each frame.
  state.counters["contacts_per_frame"] = timed > 0 ? static_cast<double>(contacts) / timed : 0.0;
  penetration.Report(state);
}
BENCHMARK(BM_BulletSkirt)
    ->ArgNames({"substeps"})
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace drape

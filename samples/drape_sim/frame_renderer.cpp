#include "frame_renderer.h"

#include <algorithm>
#include <cmath>

#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"

namespace drape::sim {
namespace {

// Edges between triangles of different planes: the hull's visible outline in a wireframe.
std::vector<std::pair<Float3, Float3>> FeatureEdges(const HullColliderData& hull) {
  struct Edge {
    uint32_t a, b, plane;
  };
  std::vector<Edge> edges;
  for (size_t t = 0; t * 3 + 2 < hull.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      uint32_t a = hull.triangles[t * 3 + k], b = hull.triangles[t * 3 + (k + 1) % 3];
      if (a > b) std::swap(a, b);
      edges.push_back({a, b, t < hull.triangle_planes.size() ? hull.triangle_planes[t] : 0u});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) {
    return x.a != y.a ? x.a < y.a : (x.b != y.b ? x.b < y.b : x.plane < y.plane);
  });
  std::vector<std::pair<Float3, Float3>> out;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    bool crease = false;
    while (j < edges.size() && edges[j].a == edges[i].a && edges[j].b == edges[i].b) {
      crease = crease || edges[j].plane != edges[i].plane;
      ++j;
    }
    if (crease || j - i == 1) out.push_back({hull.vertices[edges[i].a], hull.vertices[edges[i].b]});
    i = j;
  }
  return out;
}

}  // namespace

Status FrameRenderer::Frame(const bake::Scene& scene, const CharacterAsset& asset, int32_t clip,
                            const SceneSimulation& sim) {
  scene_ = &scene;
  asset_ = &asset;
  Float3 lo{1e30f, 1e30f, 1e30f}, hi{-1e30f, -1e30f, -1e30f};
  const auto grow = [&](std::span<const Float3> points) {
    for (const Float3& p : points) {
      lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
      hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
  };
  SkeletonPose pose;
  if (Status s = pose.Init(asset.skeleton); !s.ok()) return s;
  bake::ScenePoser poser;
  if (Status s = poser.Init(scene, asset, clip); !s.ok()) return s;
  std::vector<Float3> posed(asset.mesh.vertex_count());
  constexpr int kSamples = 8;
  for (int k = 0; k < kSamples; ++k) {
    const float t = scene.animation.start + static_cast<float>(scene.frame_count) * scene.dt *
                                                static_cast<float>(k) / (kSamples - 1);
    (void)poser.Pose(t, &pose);
    (void)SkinMesh(asset.mesh, pose.skinning(), posed);
    grow(posed);
  }
  for (size_t g = 0; g < sim.garment_count(); ++g) grow(sim.garment_start_positions(g));
  const bake::SceneOutput& out = scene.output;
  camera_ = FitCamera(lo, hi, out.camera_yaw_deg, out.camera_pitch_deg, out.camera_zoom,
                      static_cast<int>(out.width) * kSupersample,
                      static_cast<int>(out.height) * kSupersample);
  const Camera& c = camera_;
  light_.direction = NormalizeOr(-c.forward * 0.6f + Float3{0.f, 0.9f, 0.f} - c.right * 0.35f,
                                 Float3{0.f, 1.f, 0.f});
  floor_y_ = lo.y - 0.002f;
  floor_x_ = (lo.x + hi.x) * 0.5f;
  floor_z_ = (lo.z + hi.z) * 0.5f;
  return Status::Ok();
}

std::vector<uint8_t> FrameRenderer::Render(const SceneSimulation& sim) {
  const bake::SceneOutput& out = scene_->output;
  Canvas canvas(static_cast<int>(out.width), static_cast<int>(out.height), kSupersample);
  canvas.Clear({0.78f, 0.83f, 0.90f}, {0.95f, 0.95f, 0.96f});
  DrawFloor(&canvas, camera_, light_, floor_x_, floor_y_, floor_z_, 0.25f, 16);
  sim.SkinBody(&body_);
  const Rgb grey{0.55f, 0.55f, 0.56f};
  DrawMesh(&canvas, camera_, light_, body_, asset_->mesh.triangles, grey, false, grey);
  for (size_t g = 0; g < sim.garment_count(); ++g) {
    const auto& c = scene_->garments[g].color;
    const Rgb front{c[0], c[1], c[2]};
    const Rgb back{c[0] * 0.7f, c[1] * 0.7f, c[2] * 0.7f};
    DrawMesh(&canvas, camera_, light_, sim.garment_positions(g), sim.garment_triangles(g), front,
             true, back);
  }
  if (out.overlay_colliders && sim.hulls() != nullptr) DrawColliders(sim, &canvas);
  return canvas.Resolve();
}

void FrameRenderer::DrawColliders(const SceneSimulation& sim, Canvas* canvas) {
  const HullColliderSet& set = *sim.hulls();
  if (hull_edges_.empty()) {
    for (uint32_t h : sim.hull_indices()) hull_edges_.push_back(FeatureEdges(asset_->hulls[h]));
  }
  const Rgb hull_color{1.f, 0.8f, 0.1f}, sphere_color{0.1f, 0.85f, 1.f};
  for (uint32_t h = 0; h < set.hull_count(); ++h) {
    const Mat34 world = set.HullWorldTransform(h, 1.f);
    for (const auto& [a, b] : hull_edges_[h]) {
      canvas->DrawLine(camera_, TransformPoint(world, a), TransformPoint(world, b), hull_color,
                       0.12f, 1);
    }
  }
  for (uint32_t s = 0; s < set.sphere_count(); ++s) {
    const Float3 c = set.SphereCenter(s, 1.f);
    const float r = asset_->joint_spheres[sim.sphere_indices()[s]].radius;
    constexpr int kSegments = 36;
    for (int axis = 0; axis < 3; ++axis) {
      for (int k = 0; k < kSegments; ++k) {
        const auto point = [&](int i) {
          const float a = 2.f * 3.14159265f * static_cast<float>(i) / kSegments;
          const float u = r * std::cos(a), v = r * std::sin(a);
          return axis == 0 ? c + Float3{0.f, u, v}
                           : (axis == 1 ? c + Float3{u, 0.f, v} : c + Float3{u, v, 0.f});
        };
        canvas->DrawLine(camera_, point(k), point(k + 1), sphere_color, 0.12f, 1);
      }
    }
  }
}

}  // namespace drape::sim

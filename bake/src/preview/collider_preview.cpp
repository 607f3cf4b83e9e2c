#include "preview/collider_preview.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "body_map/cpu_rasterizer.h"
#include "capsule/capsule_fit.h"
#include "drape/runtime/math.h"
#include "preview/map_preview.h"

namespace drape::bake {
namespace {

// Flat-shaded triangle soup: every triangle has its own three vertices and its face normal.
struct Soup {
  std::vector<double> positions, normals;
  std::vector<uint32_t> triangles;
  std::vector<int32_t> owner;  // per triangle: -1 body, 0..H-1 hull, H.. sphere

  void Add(Float3 a, Float3 b, Float3 c, int32_t who) {
    const Float3 n = NormalizeOr(Cross(b - a, c - a), Float3{0, 0, 1});
    for (const Float3& p : {a, b, c}) {
      triangles.push_back(static_cast<uint32_t>(positions.size() / 3));
      positions.insert(positions.end(), {p.x, p.y, p.z});
      normals.insert(normals.end(), {n.x, n.y, n.z});
    }
    owner.push_back(who);
  }
};

// A unit sphere as a latitude-longitude mesh (12 x 24), enough for a preview.
void AddSphere(Soup* soup, Float3 center, float radius, int32_t who) {
  constexpr int kRings = 12, kSegments = 24;
  auto at = [&](int ring, int segment) {
    const float theta = static_cast<float>(M_PI) * static_cast<float>(ring) / kRings;
    const float phi = 2.f * static_cast<float>(M_PI) * static_cast<float>(segment) / kSegments;
    return center + Float3{std::sin(theta) * std::cos(phi), std::cos(theta),
                           std::sin(theta) * std::sin(phi)} *
                        radius;
  };
  for (int r = 0; r < kRings; ++r) {
    for (int s = 0; s < kSegments; ++s) {
      const Float3 a = at(r, s), b = at(r + 1, s), c = at(r + 1, s + 1), d = at(r, s + 1);
      if (r > 0) soup->Add(a, c, b, who);
      if (r + 1 < kRings) soup->Add(a, d, c, who);
    }
  }
}

// Green at no bloat, yellow at half of red_mm, red at red_mm and beyond.
void BloatColour(double mm, double red_mm, float rgb[3]) {
  constexpr float kGreen[3] = {0.2f, 0.8f, 0.25f};
  constexpr float kYellow[3] = {0.95f, 0.85f, 0.1f};
  constexpr float kRed[3] = {0.95f, 0.12f, 0.1f};
  const float t =
      red_mm > 0.0 ? static_cast<float>(std::clamp(mm / red_mm, 0.0, 1.0)) : (mm > 0.0 ? 1.f : 0.f);
  const float* from = t <= 0.5f ? kGreen : kYellow;
  const float* to = t <= 0.5f ? kYellow : kRed;
  const float f = t <= 0.5f ? 2.f * t : 2.f * t - 1.f;
  for (int k = 0; k < 3; ++k) rgb[k] = from[k] + (to[k] - from[k]) * f;
}

// Per-owner colour: grey for the body; by bloat when given; else a hue wheel for hulls and
// white for spheres.
void OwnerColour(int32_t owner, int32_t hull_count, const PreviewBloat* bloat, float rgb[3]) {
  if (owner < 0) {
    rgb[0] = rgb[1] = rgb[2] = 0.75f;
  } else if (bloat != nullptr) {
    const std::vector<double>& mm = owner < hull_count ? bloat->hull_mm : bloat->sphere_mm;
    const size_t index = static_cast<size_t>(owner < hull_count ? owner : owner - hull_count);
    BloatColour(index < mm.size() ? mm[index] : 0.0, bloat->red_mm, rgb);
  } else if (owner >= hull_count) {
    rgb[0] = rgb[1] = rgb[2] = 1.f;
  } else {
    const float h = std::fmod(static_cast<float>(owner) * 0.618034f, 1.f) * 6.f;
    const float x = 1.f - std::fabs(std::fmod(h, 2.f) - 1.f);
    const int sector = static_cast<int>(h);
    const float table[6][3] = {{1, x, 0}, {x, 1, 0}, {0, 1, x}, {0, x, 1}, {x, 0, 1}, {1, 0, x}};
    for (int k = 0; k < 3; ++k) rgb[k] = 0.25f + 0.75f * table[sector % 6][k];
  }
}

// Renders the soups looking along -axis (axis 2: front view along -z; axis 0: side view along -x):
// the body, the joint spheres translucent over it, the hulls over both (a hull inside a sphere
// stays visible).
Status RenderView(const Soup& body, const Soup& hulls, const Soup& spheres, int32_t hull_count,
                  const PreviewBloat* bloat, int axis, uint32_t height, const std::string& path) {
  // The picture plane: (u, v) = (x, y) for the front view, (-z, y) for the side view.
  auto project = [axis](const double* p, double* u, double* v, double* depth) {
    *u = axis == 2 ? p[0] : -p[2];
    *v = p[1];
    *depth = axis == 2 ? -p[2] : -p[0];
  };
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (const Soup* soup : {&body, &hulls, &spheres}) {
    for (size_t i = 0; i < soup->positions.size(); i += 3) {
      double c[3];
      project(&soup->positions[i], &c[0], &c[1], &c[2]);
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], c[k]), hi[k] = std::max(hi[k], c[k]);
    }
  }
  if (!(hi[1] > lo[1])) return Status(StatusCode::kInvalidArgument, path + ": nothing to draw");
  const double margin = 0.03 * (hi[1] - lo[1]);
  const double scale =
      static_cast<double>(height) / (hi[1] - lo[1] + 2 * margin);  // pixels per metre
  const uint32_t width = static_cast<uint32_t>(std::ceil((hi[0] - lo[0] + 2 * margin) * scale));

  struct Layer {
    MapViewImage image;
    std::vector<uint32_t> face;  // winning triangle per pixel, ~0u where none
  };
  auto render = [&](const Soup& soup, Layer* layer) {
    const size_t n = soup.positions.size() / 3;
    std::vector<double> wx(n), wy(n), depth(n), back(n);
    for (size_t i = 0; i < n; ++i) {
      double u, v, d;
      project(&soup.positions[3 * i], &u, &v, &d);
      wx[i] = (u - lo[0] + margin) * scale;
      wy[i] = (v - lo[1] + margin) * scale;
      depth[i] = d - lo[2] + 1.0;
      back[i] = 0.0;
    }
    MapRasterInput input;
    input.width = width;
    input.height = height;
    input.depth_range = hi[2] - lo[2] + 2.0;
    input.window_x = wx;
    input.window_y = wy;
    input.view_depth[0] = depth;
    input.view_depth[1] = back;
    input.normals = soup.normals;
    input.positions = soup.positions;
    input.triangles = soup.triangles;
    RasterizeViewCpu(input, 0, &layer->image, &layer->face);
  };
  Layer body_layer, hull_layer, sphere_layer;
  render(body, &body_layer);
  if (!hulls.triangles.empty()) render(hulls, &hull_layer);
  if (!spheres.triangles.empty()) render(spheres, &sphere_layer);

  const float light[3] = {0.35f, 0.45f, axis == 2 ? 0.82f : 0.f};
  const float side_light[3] = {axis == 0 ? 0.82f : 0.f, 0.45f, 0.35f};
  const float* l = axis == 2 ? light : side_light;
  std::vector<uint8_t> pixels(static_cast<size_t>(width) * height * 3, 40);
  for (size_t i = 0; i < static_cast<size_t>(width) * height; ++i) {
    float rgb[3] = {0.16f, 0.17f, 0.2f};
    auto shade = [&](const Layer& layer, const Soup& soup, float alpha) {
      if (layer.image.valid.empty() || !layer.image.valid[i]) return;
      const float* n = &layer.image.normal[3 * i];
      const float lambert = 0.35f + 0.65f * std::fabs(n[0] * l[0] + n[1] * l[1] + n[2] * l[2]);
      float colour[3];
      OwnerColour(soup.owner[layer.face[i]], hull_count, bloat, colour);
      for (int k = 0; k < 3; ++k) rgb[k] = (1.f - alpha) * rgb[k] + alpha * colour[k] * lambert;
    };
    shade(body_layer, body, 1.f);
    shade(sphere_layer, spheres, 0.3f);
    shade(hull_layer, hulls, 0.7f);
    for (int k = 0; k < 3; ++k)
      pixels[3 * i + k] = static_cast<uint8_t>(std::clamp(rgb[k], 0.f, 1.f) * 255.f);
  }
  return WritePreviewPng(path, width, height, 3, pixels);
}

}  // namespace

Status WriteColliderPreview(const CharacterAsset& asset, std::span<const Float3> rest_positions,
                            std::span<const Mat34> rest_skinning, const std::string& directory,
                            uint32_t height, const PreviewBloat* bloat) {
  Soup body, hulls, spheres;
  const auto& tris = asset.mesh.triangles;
  for (size_t t = 0; t + 2 < tris.size(); t += 3) {
    body.Add(rest_positions[tris[t]], rest_positions[tris[t + 1]], rest_positions[tris[t + 2]], -1);
  }
  const int32_t hull_count = static_cast<int32_t>(asset.hulls.size());
  for (int32_t h = 0; h < hull_count; ++h) {
    const HullColliderData& hull = asset.hulls[h];
    const Mat34 world = Multiply(rest_skinning[hull.joint], hull.bind_frame);
    for (size_t t = 0; t + 2 < hull.triangles.size(); t += 3) {
      hulls.Add(TransformPoint(world, hull.vertices[hull.triangles[t]]),
                TransformPoint(world, hull.vertices[hull.triangles[t + 1]]),
                TransformPoint(world, hull.vertices[hull.triangles[t + 2]]), h);
    }
  }
  for (size_t s = 0; s < asset.joint_spheres.size(); ++s) {
    const JointSphereData& sphere = asset.joint_spheres[s];
    AddSphere(&spheres, TransformPoint(rest_skinning[sphere.joint], sphere.center), sphere.radius,
              hull_count + static_cast<int32_t>(s));
  }
  if (Status s = RenderView(body, hulls, spheres, hull_count, bloat, 2, height,
                            directory + "/colliders_front.png");
      !s.ok()) {
    return s;
  }
  if (Status s = RenderView(body, hulls, spheres, hull_count, bloat, 0, height,
                            directory + "/colliders_side.png");
      !s.ok()) {
    return s;
  }
  if (asset.capsules.empty()) return Status::Ok();
  // The capsules over the body, one colour each (their fit is in the report's fit_capsules).
  Soup capsules;
  for (size_t c = 0; c < asset.capsules.size(); ++c) {
    const CapsuleColliderData& k = asset.capsules[c];
    const Float3 from = TransformPoint(rest_skinning[k.joint], k.from);
    const Float3 to = TransformPoint(rest_skinning[k.joint], k.to);
    const double a[3] = {from.x, from.y, from.z}, e[3] = {to.x, to.y, to.z};
    std::vector<double> v;
    std::vector<uint32_t> t;
    RoundConeMesh(a, k.radius_from, e, k.radius_to, 24, 6, &v, &t);
    const auto corner = [&](uint32_t i) {
      return Float3{static_cast<float>(v[3 * i]), static_cast<float>(v[3 * i + 1]),
                    static_cast<float>(v[3 * i + 2])};
    };
    for (size_t i = 0; i + 2 < t.size(); i += 3)
      capsules.Add(corner(t[i]), corner(t[i + 1]), corner(t[i + 2]), static_cast<int32_t>(c));
  }
  const Soup none;
  const int32_t capsule_count = static_cast<int32_t>(asset.capsules.size());
  if (Status s = RenderView(body, capsules, none, capsule_count, nullptr, 2, height,
                            directory + "/capsules_front.png");
      !s.ok()) {
    return s;
  }
  return RenderView(body, capsules, none, capsule_count, nullptr, 0, height,
                    directory + "/capsules_side.png");
}

}  // namespace drape::bake

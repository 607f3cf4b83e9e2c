// BodyMapRenderer: maps rendered from a skinned mesh follow the pose, agree with the offset
// surface, give the same bits at any thread count, stop allocating once the window fits, and
// reject hostile input with a message and an empty collider.

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <random>
#include <utility>
#include <vector>

#include "body_map/body_map_collider_access.h"
#include "drape/runtime/body_map_renderer.h"
#include "drape/runtime/math.h"
#include "skinned_spheres.h"
#include "workers.h"

namespace drape {
namespace {

constexpr float kRadius = 0.1f;     // metres
constexpr float kEpsilon = 0.005f;  // metres
constexpr float kTexel = 0.001f;    // metres

MeshData TwoSpheres() { return test::TwoSkinnedSpheres(kRadius); }

Mat34 Translation(float x, float y, float z) { return TranslationMatrix({x, y, z}); }

BodyMapRenderOptions Options() {
  BodyMapRenderOptions o;
  o.texel_size = kTexel;
  o.epsilon = kEpsilon;
  return o;
}

// Every texel's slab and normals, for bitwise comparisons.
std::vector<float> Texels(const BodyMapCollider& maps) {
  std::vector<float> out;
  for (uint32_t j = 0; j < maps.height(); ++j) {
    for (uint32_t i = 0; i < maps.width(); ++i) {
      float top = 0.f, bottom = 0.f;
      const bool valid = BodyMapColliderAccess::TexelSlab(maps, i, j, &top, &bottom);
      const Float3 f = BodyMapColliderAccess::TexelNormal(maps, i, j, false);
      const Float3 b = BodyMapColliderAccess::TexelNormal(maps, i, j, true);
      out.insert(out.end(), {valid ? 1.f : 0.f, top, bottom, f.x, f.y, f.z, b.x, b.y, b.z});
      float upper[3] = {}, lower[3] = {};
      const uint32_t gaps = BodyMapColliderAccess::TexelGaps(maps, i, j, upper, lower);
      out.push_back(static_cast<float>(gaps));
      out.insert(out.end(), upper, upper + gaps);
      out.insert(out.end(), lower, lower + gaps);
    }
  }
  return out;
}

TEST(BodyMapRenderer, TheSlabIsTheOffsetSphere) {
  const MeshData mesh = TwoSpheres();
  BodyMapRenderer renderer;
  ASSERT_TRUE(renderer.Init(mesh, Options()).ok());
  const Mat34 identity[2] = {Mat34{}, Mat34{}};
  BodyMapCollider maps;
  ASSERT_TRUE(renderer.Render(identity, &maps).ok());
  ASSERT_FALSE(maps.empty());
  EXPECT_EQ(renderer.stats().triangles_drawn, mesh.triangle_count());
  // Texel centres well inside the disk: top and bottom at +-sqrt((r + e)^2 - d^2) up to the
  // facets (1.2 mm at 4 subdivisions); normals point away from the centre.
  const float outer = kRadius + kEpsilon;
  int checked = 0;
  for (uint32_t j = 0; j < maps.height(); ++j) {
    for (uint32_t i = 0; i < maps.width(); ++i) {
      const float x = maps.origin_x() + (static_cast<float>(i) + 0.5f) * kTexel;
      const float y = maps.origin_y() + (static_cast<float>(j) + 0.5f) * kTexel;
      const float d = std::hypot(x, y);
      if (d > 0.8f * kRadius) continue;
      float top = 0.f, bottom = 0.f;
      ASSERT_TRUE(BodyMapColliderAccess::TexelSlab(maps, i, j, &top, &bottom)) << x << ", " << y;
      const float expected = std::sqrt(outer * outer - d * d);
      EXPECT_NEAR(top, expected, 1.5e-3f);
      EXPECT_NEAR(bottom, -expected, 1.5e-3f);
      const Float3 n = BodyMapColliderAccess::TexelNormal(maps, i, j, false);
      EXPECT_GT(Dot(n, NormalizeOr(Float3{x, y, top}, Float3{})), 0.99f);
      const Float3 nb = BodyMapColliderAccess::TexelNormal(maps, i, j, true);
      EXPECT_GT(Dot(nb, NormalizeOr(Float3{x, y, bottom}, Float3{})), 0.99f);
      ++checked;
    }
  }
  EXPECT_GT(checked, 20000);
  // Points: inside well within the offset sphere, outside beyond it.
  EXPECT_TRUE(maps.IsInside({0.f, 0.f, 0.f}));
  EXPECT_TRUE(maps.IsInside({0.5f, 0.f, 0.09f}));
  EXPECT_FALSE(maps.IsInside({0.f, 0.f, outer + 0.002f}));
  EXPECT_FALSE(maps.IsInside({0.25f, 0.f, 0.f}));  // between the spheres
}

TEST(BodyMapRenderer, TheMapsFollowTheJoints) {
  const MeshData mesh = TwoSpheres();
  BodyMapRenderer renderer;
  ASSERT_TRUE(renderer.Init(mesh, Options()).ok());
  // Joint 1 moves its sphere from (0.5, 0, 0) to (0.5, 0.6, 0.2).
  const Mat34 pose[2] = {Mat34{}, Translation(0.f, 0.6f, 0.2f)};
  BodyMapCollider maps;
  ASSERT_TRUE(renderer.Render(pose, &maps).ok());
  EXPECT_FALSE(maps.IsInside({0.5f, 0.f, 0.f}));
  EXPECT_TRUE(maps.IsInside({0.5f, 0.6f, 0.2f}));
  EXPECT_TRUE(maps.IsInside({0.5f, 0.6f, 0.2f + 0.09f}));
  EXPECT_FALSE(maps.IsInside({0.5f, 0.6f, 0.2f + kRadius + kEpsilon + 0.002f}));
  // A motion down onto the moved sphere stops on its offset surface.
  const ContactQuery c = maps.Query({0.5f, 0.6f, 0.5f}, {0.5f, 0.6f, 0.2f});
  ASSERT_TRUE(c.contact);
  EXPECT_NEAR(c.point.z, 0.2f + kRadius + kEpsilon, 1.5e-3f);
  EXPECT_GT(c.normal.z, 0.99f);
  EXPECT_EQ(renderer.posed_vertices()[mesh.vertex_count() - 1].y, mesh.positions.back().y + 0.6f);
}

TEST(BodyMapRenderer, TheRegionCutsTheWindowAndTheTriangles) {
  const MeshData mesh = TwoSpheres();
  BodyMapRenderer renderer;
  ASSERT_TRUE(renderer.Init(mesh, Options()).ok());
  const Mat34 identity[2] = {Mat34{}, Mat34{}};
  BodyMapCollider whole, cut;
  ASSERT_TRUE(renderer.Render(identity, &whole).ok());
  const uint32_t whole_width = renderer.stats().width;
  RenderRegion region;
  region.min = {0.35f, -0.2f, -0.2f};
  region.max = {0.7f, 0.2f, 0.2f};
  ASSERT_TRUE(renderer.Render(identity, &cut, &region).ok());
  EXPECT_EQ(renderer.stats().triangles_drawn, mesh.triangle_count() / 2);
  EXPECT_LT(renderer.stats().width, whole_width / 2);
  EXPECT_FALSE(cut.IsInside({0.f, 0.f, 0.f}));
  EXPECT_TRUE(cut.IsInside({0.5f, 0.f, 0.f}));
  // Inside the region both answer alike.
  for (float x = 0.36f; x < 0.64f; x += 0.0037f) {
    for (float z = -0.12f; z < 0.12f; z += 0.0041f) {
      EXPECT_EQ(whole.IsInside({x, 0.013f, z}), cut.IsInside({x, 0.013f, z})) << x << " " << z;
    }
  }
  // A region that cuts the body along the view axis (a blanket's box over a back) keeps whole
  // slabs: a point inside the body and the region is inside, not between two halves of a shell.
  region.min = {-0.2f, -0.2f, 0.06f};
  region.max = {0.2f, 0.2f, 0.3f};
  ASSERT_TRUE(renderer.Render(identity, &cut, &region).ok());
  for (float z = 0.065f; z < 0.1f; z += 0.005f) EXPECT_TRUE(cut.IsInside({0.f, 0.01f, z})) << z;
  // A region the body does not reach: an empty collider, not an error.
  region.min = {5.f, 5.f, 5.f};
  region.max = {6.f, 6.f, 6.f};
  ASSERT_TRUE(renderer.Render(identity, &cut, &region).ok());
  EXPECT_TRUE(cut.empty());
}

// Slabs, normals and gaps, bit for bit: two spheres turned and overlapping, and three where one
// sinks into another above the third (gaps found on later passes).
TEST(BodyMapRenderer, IdenticalBitsAtAnyThreadCount) {
  const MeshData two = TwoSpheres(), three = test::SkinnedSpheres(3, kRadius);
  const std::vector<Mat34> overlapping = {
      Mat34{}, Multiply(Translation(-0.3f, 0.05f, 0.04f),
                        Mat34{{0.8f, -0.6f, 0.f, 0.f, 0.6f, 0.8f, 0.f, 0.f, 0.f, 0.f, 1.f, 0.f}})};
  const std::vector<Mat34> sunk = {Mat34{}, Translation(-0.5f, 0.01f, 0.3f),
                                   Translation(-1.f, -0.02f, 0.38f)};
  for (const auto& [mesh, pose] : {std::pair{&two, &overlapping}, std::pair{&three, &sunk}}) {
    BodyMapRenderer renderer;
    ASSERT_TRUE(renderer.Init(*mesh, Options()).ok());
    std::vector<float> reference;
    for (int threads : {1, 2, 3, 4}) {
      test::UseWorkers(threads);
      BodyMapCollider maps;
      ASSERT_TRUE(renderer.Render(*pose, &maps).ok());
      const std::vector<float> texels = Texels(maps);
      if (reference.empty()) {
        reference = texels;
        continue;
      }
      ASSERT_EQ(texels.size(), reference.size());
      EXPECT_EQ(std::memcmp(texels.data(), reference.data(), texels.size() * sizeof(float)), 0)
          << threads << " threads";
    }
  }
  test::UseDefaultWorkers();
}

TEST(BodyMapRenderer, AllocatesOnlyWhenTheWindowGrows) {
  const MeshData mesh = TwoSpheres();
  BodyMapRenderer renderer;
  ASSERT_TRUE(renderer.Init(mesh, Options()).ok());
  const size_t renderer_bytes = renderer.memory_bytes();
  BodyMapCollider maps;
  const Mat34 identity[2] = {Mat34{}, Mat34{}};
  ASSERT_TRUE(renderer.Render(identity, &maps).ok());
  const size_t maps_bytes = maps.memory_bytes();
  EXPECT_EQ(renderer.stats().grew, 0u);
  for (float y = 0.f; y < 0.2f; y += 0.05f) {  // within 1.5x the bind pose's window
    const Mat34 pose[2] = {Mat34{}, Translation(0.f, y, 0.f)};
    ASSERT_TRUE(renderer.Render(pose, &maps).ok());
  }
  EXPECT_EQ(renderer.stats().grew, 0u);
  EXPECT_EQ(renderer.memory_bytes(), renderer_bytes);
  EXPECT_EQ(maps.memory_bytes(), maps_bytes);
  // Spread far apart: the window grows once, and is counted.
  const Mat34 far[2] = {Mat34{}, Translation(0.f, 1.f, 0.f)};
  ASSERT_TRUE(renderer.Render(far, &maps).ok());
  EXPECT_EQ(renderer.stats().grew, 1u);
  EXPECT_TRUE(maps.IsInside({0.5f, 1.f, 0.f}));
}

// A tetrahedron with a base near the origin and its apex far off along +x (faces
// counter-clockwise seen from outside), rigid on joint 0.
MeshData FarTetrahedron(Float3 apex) {
  MeshData mesh;
  mesh.positions = {{0.f, -0.1f, -0.1f}, {0.f, 0.1f, -0.1f}, {0.f, 0.f, 0.1f}, apex};
  const Float3 interior{0.05f, 0.f, -0.03f};
  for (const auto& face : {std::array<uint32_t, 3>{0, 1, 2}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}}) {
    const Float3 a = mesh.positions[face[0]], b = mesh.positions[face[1]];
    const Float3 c = mesh.positions[face[2]];
    const bool outward = Dot(Cross(b - a, c - a), a - interior) > 0.f;
    mesh.triangles.insert(mesh.triangles.end(),
                          {face[0], outward ? face[1] : face[2], outward ? face[2] : face[1]});
  }
  mesh.influence_offsets = {0, 1, 2, 3, 4};
  mesh.influence_joints = {0, 0, 0, 0};
  mesh.influence_weights = {1.f, 1.f, 1.f, 1.f};
  return mesh;
}

// The rasterizer works in fixed point on the finest grid its drawn corners allow (1/65536 texel
// for a body in its window). A triangle reaching 10^6 texels away coarsens it and keeps its shape
// (the apex's edges cross the region slanted); a corner 10^12 m off (10^15 texels) is clamped to
// 2^29 texels, here along the same direction. Either way the triangles near the region are drawn
// where they are.
TEST(BodyMapRenderer, ACornerFarAwayStillDrawsItsTriangles) {
  BodyMapRenderOptions options = Options();
  options.epsilon = 0.f;  // the slab is the tetrahedron itself
  RenderRegion region;
  region.min = {-0.05f, -0.2f, -0.2f};
  region.max = {0.25f, 0.2f, 0.2f};
  const Mat34 identity[1] = {Mat34{}};
  for (const Float3 apex : {Float3{1000.f, 600.f, 0.f}, Float3{1e12f, 0.f, 0.f}}) {
    const float far = apex.x;
    const MeshData mesh = FarTetrahedron(apex);
    BodyMapRenderer renderer;
    ASSERT_TRUE(renderer.Init(mesh, options).ok());
    BodyMapCollider maps;
    const Status status = renderer.Render(identity, &maps, &region);
    ASSERT_TRUE(status.ok()) << far << ": " << status.message();
    ASSERT_FALSE(maps.empty()) << far;
    // Inside where every face plane has the point behind it, by more than a few texels.
    size_t checked = 0;
    for (float x = 0.01f; x < 0.19f; x += 0.0131f) {
      for (float y = -0.1f; y < 0.1f; y += 0.0097f) {
        for (float z = -0.1f; z < 0.1f; z += 0.0093f) {
          const Float3 p{x, y, z};
          double nearest = 1e9;
          bool inside = true;
          for (size_t t = 0; t < mesh.triangles.size(); t += 3) {
            const Float3 a = mesh.positions[mesh.triangles[t]];
            const Float3 b = mesh.positions[mesh.triangles[t + 1]];
            const Float3 c = mesh.positions[mesh.triangles[t + 2]];
            const Float3 n = NormalizeOr(Cross(b - a, c - a), Float3{0.f, 0.f, 1.f});
            const double distance = double(Dot(n, p - a));
            inside = inside && distance < 0.0;
            nearest = std::min(nearest, std::fabs(distance));
          }
          if (nearest < 3.0 * kTexel) continue;
          ++checked;
          EXPECT_EQ(maps.IsInside(p), inside) << far << ": " << x << " " << y << " " << z;
        }
      }
    }
    EXPECT_GT(checked, 2000u);
  }
}

TEST(BodyMapRenderer, HostileInputIsAnErrorAndAnEmptyCollider) {
  const MeshData mesh = TwoSpheres();
  BodyMapRenderer renderer;
  ASSERT_TRUE(renderer.Init(mesh, Options()).ok());
  BodyMapCollider maps;
  const Mat34 identity[2] = {Mat34{}, Mat34{}};
  const auto fails = [&](std::span<const Mat34> pose, const RenderRegion* region,
                         const char* words) {
    ASSERT_TRUE(renderer.Render(identity, &maps).ok());
    ASSERT_FALSE(maps.empty());
    const Status s = renderer.Render(pose, &maps, region);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(s.message().find(words), std::string::npos) << s.message();
    EXPECT_TRUE(maps.empty());
    EXPECT_FALSE(maps.IsInside({0.f, 0.f, 0.f}));
  };
  Mat34 nan = Mat34{};
  nan.m[3] = std::nanf("");
  fails(std::vector<Mat34>{Mat34{}, nan}, nullptr, "not finite");
  fails(std::vector<Mat34>{Mat34{}, Translation(1e30f, 0.f, 0.f)}, nullptr, "beyond 1e15");
  fails(std::vector<Mat34>{Mat34{}, Translation(1e6f, 0.f, 0.f)}, nullptr, "max_side");
  fails(std::vector<Mat34>{Mat34{}}, nullptr, "2 joints");
  RenderRegion inverted;
  inverted.min = {1.f, 0.f, 0.f};
  inverted.max = {0.f, 1.f, 1.f};
  fails(identity, &inverted, "region");
  RenderRegion not_a_number;
  not_a_number.max.y = std::nanf("");
  fails(identity, &not_a_number, "region");

  // Init checks the mesh and the options.
  BodyMapRenderOptions bad = Options();
  bad.texel_size = 0.f;
  EXPECT_NE(renderer.Init(mesh, bad).message().find("texel_size"), std::string::npos);
  EXPECT_TRUE(renderer.empty());
  EXPECT_FALSE(renderer.Render(identity, &maps).ok());
  bad = Options();
  bad.epsilon = std::nanf("");
  EXPECT_NE(renderer.Init(mesh, bad).message().find("epsilon"), std::string::npos);
  MeshData broken = mesh;
  broken.triangles[7] = broken.vertex_count();
  EXPECT_NE(renderer.Init(broken, Options()).message().find("triangle index 7"), std::string::npos);
  broken = mesh;
  broken.positions[3].y = std::numeric_limits<float>::infinity();
  EXPECT_NE(renderer.Init(broken, Options()).message().find("vertex 3"), std::string::npos);
  broken = mesh;
  broken.triangles.pop_back();
  EXPECT_FALSE(renderer.Init(broken, Options()).ok());
}

// Maps an engine rendered on its GPU, loaded from the caller's arrays, answer as the maps they
// were read from; bad arrays are refused naming the reason, and the collider is left empty.
// One sphere above the other along the view axis: the air between them is a gap (outside),
// with air_gaps; without, the slab fills it. Spheres that overlap leave no gap inside their union.
TEST(BodyMapRenderer, TheAirBetweenPartsIsAGap) {
  const MeshData mesh = TwoSpheres();  // the second sphere's bind centre is (0.5, 0, 0)
  const Mat34 apart[2] = {Mat34{}, Translation(-0.5f, 0.f, 0.3f)};  // centre (0, 0, 0.3)
  const Mat34 overlapping[2] = {Mat34{}, Translation(-0.5f, 0.f, 0.12f)};
  BodyMapRenderer with_gaps, slab_only;
  BodyMapRenderOptions options = Options();
  ASSERT_TRUE(with_gaps.Init(mesh, options).ok());
  options.air_gaps = 0;
  ASSERT_TRUE(slab_only.Init(mesh, options).ok());
  BodyMapCollider gaps, slab;
  ASSERT_TRUE(with_gaps.Render(apart, &gaps).ok());
  ASSERT_TRUE(slab_only.Render(apart, &slab).ok());
  EXPECT_EQ(gaps.layers(), 2u);
  EXPECT_EQ(slab.layers(), 1u);
  const Float3 between{0.f, 0.f, 0.15f}, in_lower{0.f, 0.f, 0.05f}, in_upper{0.f, 0.f, 0.25f};
  EXPECT_FALSE(gaps.IsInside(between));
  EXPECT_TRUE(slab.IsInside(between));
  EXPECT_TRUE(gaps.IsInside(in_lower) && gaps.IsInside(in_upper));
  EXPECT_GT(with_gaps.stats().gap_texels, 1000u);
  EXPECT_EQ(slab_only.stats().gap_texels, 0u);
  // A motion down through the gap stops on the lower sphere's top, not the upper one's bottom.
  const ContactQuery q = gaps.Query(between, {0.f, 0.f, 0.f});
  ASSERT_TRUE(q.contact);
  EXPECT_NEAR(q.point.z, kRadius + kEpsilon, 2e-3f);
  EXPECT_GT(q.normal.z, 0.9f);
  // Overlapping (their offset surfaces overlap along the rays within 86 mm of the axis): the
  // union is solid there; only the rays beyond it pass air between the two.
  ASSERT_TRUE(with_gaps.Render(overlapping, &gaps).ok());
  for (float x : {0.f, 0.04f, 0.08f}) {
    const float h = std::sqrt((kRadius + kEpsilon) * (kRadius + kEpsilon) - x * x) - 2e-3f;
    for (float z = -h; z < 0.12f + h; z += 0.005f) {
      EXPECT_TRUE(gaps.IsInside({x, 0.f, z})) << x << ", " << z;
    }
  }
  EXPECT_FALSE(gaps.IsInside({0.1f, 0.f, 0.06f}));  // the air between them at 100 mm
}

// Four spheres stacked along the view axis with air between them: three gaps along the central
// rays, found top down as the bake's sweep finds them; air_gaps caps how many are kept.
TEST(BodyMapRenderer, StackedPartsKeepEveryGapUpToTheCap) {
  const MeshData mesh = test::SkinnedSpheres(4, kRadius);  // bind centres (0.5 s, 0, 0)
  Mat34 stack[4];
  for (int s = 0; s < 4; ++s) stack[s] = Translation(-0.5f * float(s), 0.f, 0.3f * float(s));
  const float between[3] = {0.15f, 0.45f, 0.75f};  // the air between sphere s and s + 1
  for (uint32_t cap : {1u, 2u, 3u}) {
    BodyMapRenderOptions options = Options();
    options.air_gaps = cap;
    BodyMapRenderer renderer;
    ASSERT_TRUE(renderer.Init(mesh, options).ok());
    BodyMapCollider maps;
    ASSERT_TRUE(renderer.Render(stack, &maps).ok());
    EXPECT_EQ(maps.layers(), cap + 1) << cap;
    for (int s = 0; s < 4; ++s) {
      EXPECT_TRUE(maps.IsInside({0.f, 0.f, 0.3f * float(s)})) << cap << ", sphere " << s;
    }
    // The cap keeps the upper gaps; the deeper air stays inside the slab.
    for (uint32_t g = 0; g < 3; ++g) {
      EXPECT_EQ(maps.IsInside({0.f, 0.f, between[2 - g]}), g >= cap) << cap << ", gap " << g;
    }
  }
  BodyMapRenderOptions too_many = Options();
  too_many.air_gaps = 4;
  BodyMapRenderer refused;
  const Status s = refused.Init(mesh, too_many);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("air_gaps 4"), std::string::npos) << s.message();
}

// Octahedra (radius 1 cm) stacked along the view axis 4 cm apart, all on joint 0: the central
// rays cross two surfaces per octahedron. Up to 1024 surfaces a ray's air gaps are searched;
// beyond, the texel keeps its slab (the bound that keeps a hostile mesh's search finite).
MeshData StackedOctahedra(int count) {
  const test::UnitSphereMesh unit = test::OctahedronSphere(0);
  MeshData mesh;
  for (int k = 0; k < count; ++k) {
    const uint32_t base = mesh.vertex_count();
    for (const auto& p : unit.positions) {
      mesh.positions.push_back({0.01f * static_cast<float>(p[0]), 0.01f * static_cast<float>(p[1]),
                                0.01f * static_cast<float>(p[2]) - 0.04f * static_cast<float>(k)});
    }
    for (const auto& t : unit.triangles)
      for (uint32_t v : t) mesh.triangles.push_back(base + v);
  }
  mesh.influence_offsets.push_back(0);
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v) {
    mesh.influence_joints.push_back(0);
    mesh.influence_weights.push_back(1.f);
    mesh.influence_offsets.push_back(v + 1);
  }
  return mesh;
}

TEST(BodyMapRenderer, ARayThroughTooManySurfacesKeepsItsSlab) {
  const Mat34 identity[1] = {Mat34{}};
  const Float3 first_air{0.f, 0.f, -0.02f};  // between the top two octahedra
  for (const int count : {300, 600}) {       // 600 and 1200 surfaces on the central rays
    const MeshData mesh = StackedOctahedra(count);
    BodyMapRenderer renderer;
    ASSERT_TRUE(renderer.Init(mesh, Options()).ok());
    BodyMapCollider maps;
    ASSERT_TRUE(renderer.Render(identity, &maps).ok());
    EXPECT_TRUE(maps.IsInside({0.f, 0.f, 0.f})) << count;
    if (count == 300) {
      EXPECT_EQ(maps.layers(), 4u);  // the slab and three gaps
      EXPECT_GT(renderer.stats().gap_texels, 0u);
      EXPECT_FALSE(maps.IsInside(first_air));
    } else {
      EXPECT_EQ(renderer.stats().gap_texels, 0u);  // no texel searched: the air stays inside
      EXPECT_TRUE(maps.IsInside(first_air));
    }
  }
}

// A part sunk into another (an arm into the torso) above a third with air between: the highest
// surface leaving the body along the central rays is the sunk part's, still inside the other, so
// the gap lies below the next leaving surface; the renderer searches on there, as the bake's
// sweep finds it.
TEST(BodyMapRenderer, AGapBelowPartsSunkIntoEachOther) {
  const MeshData mesh = test::SkinnedSpheres(3, kRadius);  // bind centres (0.5 s, 0, 0)
  const float centre_z[3] = {0.f, 0.3f, 0.38f};            // the third sunk into the second
  Mat34 pose[3];
  for (int s = 0; s < 3; ++s) pose[s] = Translation(-0.5f * float(s), 0.f, centre_z[s]);
  BodyMapRenderer renderer;
  ASSERT_TRUE(renderer.Init(mesh, Options()).ok());
  BodyMapCollider maps;
  ASSERT_TRUE(renderer.Render(pose, &maps).ok());
  EXPECT_FALSE(maps.IsInside({0.f, 0.f, 0.15f}));  // the air between the lowest and the others
  EXPECT_FALSE(maps.IsInside({0.03f, 0.02f, 0.15f}));
  for (const float z : {0.f, 0.25f, 0.3f, 0.4f, 0.45f}) {
    EXPECT_TRUE(maps.IsInside({0.f, 0.f, z})) << z;
  }
  // Seen from below it is the same body: one gap, found on the first pass.
  const Mat34 upside_down[3] = {Translation(0.f, 0.f, 0.38f), Translation(-0.5f, 0.f, 0.08f),
                                Translation(-1.f, 0.f, 0.f)};
  ASSERT_TRUE(renderer.Render(upside_down, &maps).ok());
  EXPECT_FALSE(maps.IsInside({0.f, 0.f, 0.23f}));
}

// A part seen edge-on at either end of the ray (a texel centre on the silhouette of an arm
// swinging back): its two sides meet at one depth, thinner than any gap. It is no body: the slab
// ends at the air next to it, instead of taking in the air between it and the rest of the body
// (a whole texel column called inside, up to 0.75 m from the body on a walking human).
TEST(BodyMapRenderer, APartSeenEdgeOnDoesNotFillTheAir) {
  for (const float sliver_z : {-0.3f, 0.3f}) {
    MeshData mesh = test::SkinnedSpheres(1, kRadius);
    // A square of zero thickness (both sides, sharing the vertices, so the vertex normals cancel
    // and the offset leaves it flat) over the sphere's central rays.
    const uint32_t base = mesh.vertex_count();
    for (const auto& [x, y] :
         {std::pair{-0.05f, -0.05f}, {0.05f, -0.05f}, {0.05f, 0.05f}, {-0.05f, 0.05f}}) {
      mesh.positions.push_back({x, y, sliver_z});
      mesh.influence_joints.push_back(0);
      mesh.influence_weights.push_back(1.f);
      mesh.influence_offsets.push_back(mesh.influence_offsets.back() + 1);
    }
    for (const uint32_t v : {0u, 1u, 2u, 0u, 2u, 3u, 0u, 2u, 1u, 0u, 3u, 2u}) {
      mesh.triangles.push_back(base + v);
    }
    BodyMapRenderer renderer;
    ASSERT_TRUE(renderer.Init(mesh, Options()).ok());
    BodyMapCollider maps;
    const Mat34 rest[1] = {Mat34{}};
    ASSERT_TRUE(renderer.Render(rest, &maps).ok());
    for (const float x : {0.f, 0.02f, -0.045f}) {
      EXPECT_TRUE(maps.IsInside({x, 0.01f, 0.f})) << sliver_z << ", " << x;
      EXPECT_FALSE(maps.IsInside({x, 0.01f, sliver_z / 2.f})) << sliver_z << ", " << x;
      EXPECT_FALSE(maps.IsInside({x, 0.01f, sliver_z * 0.9f})) << sliver_z << ", " << x;
    }
    // A motion from the air onto the sphere stops on the sphere's surface facing it.
    const float side = sliver_z > 0.f ? 1.f : -1.f;
    const ContactQuery q = maps.Query({0.f, 0.f, sliver_z / 2.f}, {0.f, 0.f, 0.f});
    ASSERT_TRUE(q.contact) << sliver_z;
    EXPECT_NEAR(q.point.z, side * (kRadius + kEpsilon), 2e-3f) << sliver_z;
    EXPECT_GT(q.normal.z * side, 0.9f) << sliver_z;
  }
}

TEST(BodyMapRenderer, LoadsMapsTheEngineRendered) {
  const MeshData mesh = TwoSpheres();
  BodyMapRenderer renderer;
  ASSERT_TRUE(renderer.Init(mesh, Options()).ok());
  const Mat34 identity[2] = {Mat34{}, Mat34{}};
  BodyMapCollider rendered;
  ASSERT_TRUE(renderer.Render(identity, &rendered).ok());
  // The engine's buffers: z of both surfaces (NaN on background) and outward normals.
  const uint32_t w = rendered.width(), h = rendered.height();
  std::vector<float> front_z(size_t{w} * h), back_z(front_z.size());
  std::vector<Float3> front_n(front_z.size()), back_n(front_z.size());
  for (uint32_t j = 0; j < h; ++j) {
    for (uint32_t i = 0; i < w; ++i) {
      const size_t k = size_t{j} * w + i;
      float top = 0.f, bottom = 0.f;
      const bool body = BodyMapColliderAccess::TexelSlab(rendered, i, j, &top, &bottom);
      front_z[k] = body ? top : std::nanf("");
      back_z[k] = body ? bottom : std::nanf("");
      front_n[k] = BodyMapColliderAccess::TexelNormal(rendered, i, j, false) * 3.f;  // any length
      back_n[k] = BodyMapColliderAccess::TexelNormal(rendered, i, j, true);
    }
  }
  RenderedMapsView view;
  view.width = w;
  view.height = h;
  view.origin_x = rendered.origin_x();
  view.origin_y = rendered.origin_y();
  view.texel_size = rendered.texel_size();
  view.front_z = front_z;
  view.back_z = back_z;
  view.front_normals = front_n;
  view.back_normals = back_n;
  BodyMapCollider loaded;
  ASSERT_TRUE(BodyMapRenderer::Load(view, &loaded).ok());
  EXPECT_EQ(loaded.stats().valid_texels, rendered.stats().valid_texels);
  std::mt19937 random(3);
  std::uniform_real_distribution<float> x(-0.2f, 0.7f), yz(-0.15f, 0.15f);
  for (int n = 0; n < 2000; ++n) {
    const Float3 p0{x(random), yz(random), yz(random)}, p1{x(random), yz(random), yz(random)};
    EXPECT_EQ(loaded.IsInside(p1), rendered.IsInside(p1));
    const ContactQuery a = loaded.Query(p0, p1), b = rendered.Query(p0, p1);
    ASSERT_EQ(a.contact, b.contact);
    EXPECT_EQ(a.t, b.t);
    if (a.contact) {
      EXPECT_GT(Dot(a.normal, b.normal), 0.9999f);
    }
  }
  const size_t capacity = loaded.memory_bytes();
  ASSERT_TRUE(BodyMapRenderer::Load(view, &loaded).ok());  // the same grid again: no allocation
  EXPECT_EQ(loaded.memory_bytes(), capacity);

  RenderedMapsView bad = view;
  bad.back_z = std::span<const float>(back_z).first(back_z.size() - 1);
  Status s = BodyMapRenderer::Load(bad, &loaded);
  EXPECT_NE(s.message().find("width * height"), std::string::npos) << s.message();
  EXPECT_TRUE(loaded.empty());
  bad = view;
  bad.texel_size = std::nanf("");
  EXPECT_NE(BodyMapRenderer::Load(bad, &loaded).message().find("texel size"), std::string::npos);
  bad = view;
  bad.width = 0;
  EXPECT_FALSE(BodyMapRenderer::Load(bad, &loaded).ok());
}

}  // namespace
}  // namespace drape

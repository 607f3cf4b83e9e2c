// The render mesh (drape/bake/render_mesh.h): the bind mesh simplified within a measured
// tolerance, keeping vertices and their influences, on the mannequin, the shared characters and
// generated variations (other units, a dense mesh); the maps the runtime renders from it at a
// pose no bake saw agree with the bind mesh's; bad input is refused.

#include "drape/bake/render_mesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "body_map/body_map_collider_access.h"
#include "drape/bake/importer.h"
#include "drape/bake/mesh_reference.h"
#include "drape/runtime/body_map_renderer.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "drape/runtime/skinning.h"
#include "subdivided_mesh.h"
#include "test_support.h"

namespace drape::bake {
namespace {

constexpr float kTolerance = 0.001f;  // metres: the bake's default

Character Import(const std::string& path) {
  Character c;
  const Status s = ImportCharacter(path, ImportOptions{}, &c);
  EXPECT_TRUE(s.ok()) << s.message();
  return c;
}

// The largest distance from `count` random points on `from`'s triangles (area-weighted, seeded)
// to the surface `to`: denser than the samples SimplifyRenderMesh checks.
double FarthestRandomSample(const MeshData& from, const MeshData& to, int count) {
  const MeshReference reference(to.positions, to.triangles);
  std::vector<double> areas;
  for (size_t t = 0; t < from.triangles.size(); t += 3) {
    const Float3 a = from.positions[from.triangles[t]], b = from.positions[from.triangles[t + 1]],
                 c = from.positions[from.triangles[t + 2]];
    areas.push_back(Length(Cross(b - a, c - a)));
  }
  std::mt19937 random(7);
  std::discrete_distribution<size_t> triangle(areas.begin(), areas.end());
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  double farthest = 0.0;
  for (int k = 0; k < count; ++k) {
    const size_t t = 3 * triangle(random);
    float u = unit(random), v = unit(random);
    if (u + v > 1.f) u = 1.f - u, v = 1.f - v;
    const Float3 a = from.positions[from.triangles[t]], b = from.positions[from.triangles[t + 1]],
                 c = from.positions[from.triangles[t + 2]];
    const Float3 p = a + (b - a) * u + (c - a) * v;
    const double q[3] = {p.x, p.y, p.z};
    farthest = std::max(farthest, reference.Distance(q));
  }
  return farthest;
}

// Every render-mesh vertex is a bind-mesh vertex (same position) with the same influences.
void ExpectKeptVertices(const MeshData& mesh, const MeshData& render) {
  std::map<std::tuple<float, float, float>, uint32_t> by_position;
  for (uint32_t v = 0; v < mesh.vertex_count(); ++v)
    by_position.emplace(
        std::make_tuple(mesh.positions[v].x, mesh.positions[v].y, mesh.positions[v].z), v);
  ASSERT_EQ(render.influence_offsets.size(), render.positions.size() + 1);
  for (uint32_t r = 0; r < render.vertex_count(); ++r) {
    const Float3 p = render.positions[r];
    const auto it = by_position.find(std::make_tuple(p.x, p.y, p.z));
    ASSERT_NE(it, by_position.end()) << "render vertex " << r << " is not a bind vertex";
    const uint32_t v = it->second;
    const uint32_t count = mesh.influence_offsets[v + 1] - mesh.influence_offsets[v];
    ASSERT_EQ(render.influence_offsets[r + 1] - render.influence_offsets[r], count) << r;
    for (uint32_t k = 0; k < count; ++k) {
      EXPECT_EQ(render.influence_joints[render.influence_offsets[r] + k],
                mesh.influence_joints[mesh.influence_offsets[v] + k]);
      EXPECT_EQ(render.influence_weights[render.influence_offsets[r] + k],
                mesh.influence_weights[mesh.influence_offsets[v] + k]);
    }
  }
}

// Kept, smaller, within the tolerance both ways at random points, vertices and influences kept.
void ExpectWithinTolerance(const MeshData& mesh, float tolerance, double max_share) {
  MeshData render;
  RenderMeshReport report;
  ASSERT_TRUE(SimplifyRenderMesh(mesh, tolerance, &render, &report).ok());
  ASSERT_TRUE(report.kept);
  EXPECT_EQ(report.triangles, mesh.triangle_count());
  EXPECT_EQ(report.kept_triangles, render.triangle_count());
  EXPECT_LE(render.triangle_count(), max_share * mesh.triangle_count());
  EXPECT_LE(report.error, tolerance);
  EXPECT_LE(report.turned_vertices, 0.002 * render.vertex_count());
  // Random points, not the samples the simplification checked: a little slack for the gaps
  // between them (a bind-mesh triangle's interior may lie a hair farther than its corners and
  // centre).
  EXPECT_LE(FarthestRandomSample(mesh, render, 20000), 1.25 * tolerance);
  EXPECT_LE(FarthestRandomSample(render, mesh, 20000), 1.25 * tolerance);
  ExpectKeptVertices(mesh, render);
}

TEST(RenderMesh, TheMannequinKeepsUnderTwoThirdsWithinTheTolerance) {
  const Character c = Import(test::MannequinPath());
  ExpectWithinTolerance(c.mesh, kTolerance, 0.67);
}

TEST(RenderMesh, SharedCharactersStayWithinTheTolerance) {
  const std::string path = test::CharacterPath("CesiumMan/CesiumMan.glb");
  DRAPE_REQUIRE_FILE(path);
  const Character c = Import(path);
  ExpectWithinTolerance(c.mesh, kTolerance, 0.7);
}

// A mesh that simplifies little keeps nothing: the Fox (576 triangles) would keep 458, and its
// maps at a pose between keys missed 0.34 % of the contacts instead of 0.01 %.
TEST(RenderMesh, LittleToGainKeepsNone) {
  const std::string path = test::CharacterPath("Fox/Fox.glb");
  DRAPE_REQUIRE_FILE(path);
  const Character c = Import(path);
  MeshData render;
  RenderMeshReport report;
  ASSERT_TRUE(SimplifyRenderMesh(c.mesh, kTolerance, &render, &report).ok());
  EXPECT_FALSE(report.kept);
  EXPECT_TRUE(render.positions.empty());
}

// Low-poly bodies of flat faces (Quaternius' Animated_Human, RobotExpressive, the Spider), at a
// person's size: collapses within 1 mm turn half the vertex normals by 20-160 degrees, and the
// maps drawn from such a mesh missed 23-43 % of the contacts. What the simplification keeps turns
// at most 0.2 % of its vertices' normals beyond 30 degrees, or it keeps nothing and the renderer
// draws the bind mesh.
TEST(RenderMesh, LowPolyBodiesKeepNoNormalTurnedInsideOut) {
  for (const auto& [relative, unit_scale] :
       {std::pair{"QuaterniusAnimatedHuman/Animated_Human.fbx", 0.0033273},
        std::pair{"RobotExpressive/RobotExpressive.glb", 0.39},
        std::pair{"QuaterniusSpider/Spider.fbx", 0.0}}) {
    const std::string path = test::CharacterPath(relative);
    DRAPE_REQUIRE_FILE(path);
    SCOPED_TRACE(relative);
    ImportOptions options;
    options.unit_scale = unit_scale;
    Character c;
    ASSERT_TRUE(ImportCharacter(path, options, &c).ok());
    MeshData render;
    RenderMeshReport report;
    ASSERT_TRUE(SimplifyRenderMesh(c.mesh, kTolerance, &render, &report).ok());
    if (!report.kept) {
      EXPECT_TRUE(render.triangles.empty());
      continue;
    }
    EXPECT_LE(report.turned_vertices, 0.002 * render.vertex_count());
    EXPECT_LE(report.error, kTolerance);
    ExpectKeptVertices(c.mesh, render);
  }
}

TEST(RenderMesh, OtherUnitsAndProportionsStayWithinTheTolerance) {
  // The mannequin in centimetres (tolerance in centimetres), and stretched to a 2.6 m giant with
  // thin limbs: each still simplifies within its tolerance. The simplifier is not scale-exact
  // (rounding moves collapses that tie), so the counts are compared loosely, not equal.
  const Character c = Import(test::MannequinPath());
  MeshData centimetres = c.mesh, giant = c.mesh;
  for (Float3& p : centimetres.positions) p = p * 100.f;
  for (Float3& p : giant.positions) p = Float3{0.7f * p.x, 1.5f * p.y, 0.7f * p.z};
  for (const auto& [mesh, tolerance] :
       {std::pair{&centimetres, 100.f * kTolerance}, std::pair{&giant, kTolerance}}) {
    MeshData render;
    RenderMeshReport report;
    ASSERT_TRUE(SimplifyRenderMesh(*mesh, tolerance, &render, &report).ok());
    ASSERT_TRUE(report.kept);
    EXPECT_LE(report.error, tolerance);
    EXPECT_LE(render.triangle_count(), 0.75 * mesh->triangle_count());
    EXPECT_LE(FarthestRandomSample(*mesh, render, 20000), 1.25 * tolerance);
  }
}

TEST(RenderMesh, ADenseMeshSimplifiesToAboutTheCoarseOnesSize) {
  // Each mannequin triangle into four at its midpoints: the same surface with 4x the triangles
  // (a densely meshed game character). Its render mesh needs about as few as the coarse one's.
  const Character c = Import(test::MannequinPath());
  const MeshData dense = test::SubdividedMesh(c.mesh);
  ExpectWithinTolerance(dense, kTolerance, 0.3);
}

TEST(RenderMesh, NothingToGainKeepsNone) {
  // A tetrahedron: no collapse stays within 1 mm, so the renderer draws the bind mesh.
  MeshData tetrahedron;
  tetrahedron.positions = {{0.f, 0.f, 0.f}, {0.1f, 0.f, 0.f}, {0.f, 0.1f, 0.f}, {0.f, 0.f, 0.1f}};
  tetrahedron.triangles = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  MeshData render;
  RenderMeshReport report;
  ASSERT_TRUE(SimplifyRenderMesh(tetrahedron, kTolerance, &render, &report).ok());
  EXPECT_FALSE(report.kept);
  EXPECT_TRUE(render.positions.empty());
  EXPECT_TRUE(render.triangles.empty());
  // No triangles at all: nothing kept, no error.
  ASSERT_TRUE(SimplifyRenderMesh(MeshData{}, kTolerance, &render, &report).ok());
  EXPECT_FALSE(report.kept);
}

TEST(RenderMesh, BadInputIsRefusedByName) {
  MeshData mesh;
  mesh.positions = {{0.f, 0.f, 0.f}, {1.f, 0.f, 0.f}, {0.f, 1.f, 0.f}};
  mesh.triangles = {0, 1, 2};
  MeshData render;
  RenderMeshReport report;
  for (const float bad : {0.f, -1.f, std::nanf(""), INFINITY}) {
    const Status s = SimplifyRenderMesh(mesh, bad, &render, &report);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << bad;
    EXPECT_NE(s.message().find("tolerance"), std::string::npos) << s.message();
  }
  mesh.triangles = {0, 1, 3};
  const Status s = SimplifyRenderMesh(mesh, kTolerance, &render, &report);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("out of range"), std::string::npos) << s.message();
}

// Maps rendered from the render mesh at a pose between the walk's keys (no bake saw it) are
// about as right as the bind mesh's: points near the posed body that either classifies wrongly
// against the exact epsilon shell, beyond two texels of it. (The render mesh's surface moves by
// up to the tolerance, and its epsilon offset follows its coarser vertex normals.)
TEST(RenderMesh, RenderedMapsClassifyLikeTheBindMeshs) {
  const Character c = Import(test::MannequinPath());
  MeshData render_mesh;
  RenderMeshReport report;
  ASSERT_TRUE(SimplifyRenderMesh(c.mesh, kTolerance, &render_mesh, &report).ok());
  ASSERT_TRUE(report.kept);
  SkeletonPose pose;
  ASSERT_TRUE(pose.Init(c.skeleton).ok());
  const ClipData& walk = c.clips.front();
  ASSERT_TRUE(pose.SampleClip(walk, 0.37f * walk.duration, false).ok());
  std::vector<Float3> posed(c.mesh.vertex_count());
  ASSERT_TRUE(SkinMesh(c.mesh, pose.skinning(), posed).ok());
  const MeshReference exact(posed, c.mesh.triangles);
  const float epsilon = BodyMapRenderOptions{}.epsilon;
  for (const float texel : {0.0017f, 0.007f}) {
    SCOPED_TRACE(texel);
    BodyMapRenderOptions options;
    options.texel_size = texel;
    BodyMapRenderer from_bind, from_render;
    ASSERT_TRUE(from_bind.Init(c.mesh, options).ok());
    ASSERT_TRUE(from_render.Init(render_mesh, options).ok());
    BodyMapCollider bind_maps, render_maps;
    ASSERT_TRUE(from_bind.Render(pose.skinning(), &bind_maps).ok());
    ASSERT_TRUE(from_render.Render(pose.skinning(), &render_maps).ok());
    // Points within epsilon + 4 texels of the posed surface, seeded.
    std::mt19937 random(3);
    std::uniform_int_distribution<size_t> vertex(0, posed.size() - 1);
    std::uniform_real_distribution<float> offset(-1.f, 1.f);
    const float reach = epsilon + 4.f * texel;
    std::vector<Float3> points(20000);
    for (Float3& p : points)
      p = posed[vertex(random)] + Float3{offset(random), offset(random), offset(random)} * reach;
    std::vector<uint8_t> bind_inside(points.size()), render_inside(points.size());
    ASSERT_TRUE(bind_maps.InsideBatch(points, bind_inside).ok());
    ASSERT_TRUE(render_maps.InsideBatch(points, render_inside).ok());
    // Against the exact shell (signed distance to the posed bind mesh below epsilon), beyond
    // the band a texel's depth resolves: the render mesh's maps miss about as few points as the
    // bind mesh's (both slabs fill concavities the same way).
    size_t bind_wrong = 0, render_wrong = 0, judged = 0;
    for (size_t k = 0; k < points.size(); ++k) {
      const double q[3] = {points[k].x, points[k].y, points[k].z};
      const double distance = exact.Inside(q) ? -exact.Distance(q) : exact.Distance(q);
      if (std::fabs(distance - epsilon) < 2.0 * texel) continue;
      ++judged;
      const bool inside = distance < epsilon;
      bind_wrong += (bind_inside[k] != 0) != inside;
      render_wrong += (render_inside[k] != 0) != inside;
    }
    ASSERT_GT(judged, points.size() / 5);
    EXPECT_LE(double(render_wrong), double(bind_wrong) + 0.002 * double(judged))
        << "of " << judged << " points, wrong: render mesh " << render_wrong << ", bind mesh "
        << bind_wrong;
  }
}

}  // namespace
}  // namespace drape::bake

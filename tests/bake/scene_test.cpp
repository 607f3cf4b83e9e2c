// Scenes: the JSON format (every refusal names the JSON path of the bad field), garment
// resolution against a skeleton, the bake configuration a scene implies, and the reach analysis
// ("model only what a scene needs") on the baked mannequin.

#include "drape/bake/scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "drape/bake/bake_pipeline.h"
#include "drape/runtime/math.h"
#include "drape/runtime/skeleton_pose.h"
#include "test_support.h"

namespace drape::bake {
namespace {

using nlohmann::json;

std::string DemoPath() { return test::SourceDir() + "/samples/scenes/demo.json"; }
std::string ScenesDir() { return test::SourceDir() + "/samples/scenes"; }

json DemoJson() {
  std::ifstream in(DemoPath());
  return json::parse(in);
}

// Parses `j` as if it were samples/scenes/scene.json.
Status Parse(const json& j, Scene* scene) {
  return ParseScene(j, "scene.json", ScenesDir(), scene);
}

// The mannequin baked once for the whole suite: hulls, spheres, and coarse maps of the walk at
// 10 Hz (11 poses), enough for the pose bookkeeping.
class SceneTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    BakeConfig config;
    config.maps.resolution = 64;
    config.maps_clip = "walk";
    config.maps_clip_rate = 10.f;
    BakeResult result;
    const Status s = BakeCharacter(test::MannequinPath(), config, &result);
    ASSERT_TRUE(s.ok()) << s.message();
    asset_ = new CharacterAsset(std::move(result.asset));
  }
  static void TearDownTestSuite() {
    delete asset_;
    asset_ = nullptr;
  }
  static const CharacterAsset& asset() { return *asset_; }

  // Garment 0 of the scene resolved and skinned to the mannequin's body.
  static Status ResolveSkinned(const Scene& scene, ResolvedGarment* garment) {
    if (Status s = ResolveGarment(scene, 0, asset().skeleton, garment); !s.ok()) return s;
    return SkinGarment(scene, 0, asset().skeleton, asset().mesh, garment);
  }

  // A mini skirt (25 cm) held at the hips, walking the whole clip.
  static json MiniSkirt() {
    json j = DemoJson();
    j["animation"] = {{"clip", "walk"}, {"start", 0.0}, {"duration", 1.0}, {"loop", true}};
    j["garments"][0]["shape"]["length"] = 0.25;
    j["garments"][0]["shape"]["bottom_radius"] = 0.3;
    j["collision"]["reach_margin"] = 0.02;
    j["collision"]["reach_stretch"] = 0.1;
    return j;
  }

 private:
  static CharacterAsset* asset_;
};
CharacterAsset* SceneTest::asset_ = nullptr;

TEST(SceneParse, DemoScene) {
  Scene scene;
  const Status s = LoadScene(DemoPath(), &scene);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(scene.source, DemoPath());
  EXPECT_TRUE(std::filesystem::equivalent(scene.character, test::MannequinPath()));
  EXPECT_EQ(scene.animation.clip, "walk");
  EXPECT_FLOAT_EQ(scene.animation.duration, 3.f);
  EXPECT_TRUE(scene.animation.loop);
  // 3 s at 1/60 s per frame (dt is written as 0.0166667: the count rounds to 180, not 181).
  EXPECT_EQ(scene.frame_count, 180u);
  ASSERT_EQ(scene.garments.size(), 1u);
  const SceneGarment& skirt = scene.garments[0];
  EXPECT_EQ(skirt.type, GarmentType::kSkirt);
  EXPECT_EQ(skirt.name, "skirt");
  EXPECT_EQ(skirt.anchor, "hips");
  EXPECT_EQ(skirt.skirt.segments, 64u);
  ASSERT_EQ(skirt.attachments.size(), 1u);
  EXPECT_EQ(skirt.attachments[0].joint, "hips");
  EXPECT_EQ(skirt.attachments[0].particles.ring, "waist");
  EXPECT_EQ(skirt.attachments[0].particles.path, "/garments/0/attach");
  EXPECT_TRUE(scene.use_hulls);
  EXPECT_TRUE(scene.use_spheres);
  EXPECT_FALSE(scene.use_maps);
  EXPECT_EQ(scene.solver.integrator, ClothIntegrator::kVerlet);
  EXPECT_EQ(scene.solver.substeps, 4u);
  EXPECT_EQ(scene.output.every, 2u);
}

// Every bad field is refused with "scene.json: <JSON path>: <reason>".
TEST(SceneParse, BadFieldsNameTheirPath) {
  struct Case {
    const char* name;
    std::function<void(json&)> mutate;
    const char* prefix;  // "scene.json: " + this
    const char* reason;  // must appear after the prefix
  };
  const std::vector<Case> cases = {
      {"missing character", [](json& j) { j.erase("character"); }, "/character: ", "missing"},
      {"character not found", [](json& j) { j["character"] = "nobody.glb"; },
       "/character: ", "not found"},
      {"unknown garment type", [](json& j) { j["garments"][0]["type"] = "dress"; },
       "/garments/0/type: ", "'dress' is not one of sheet | skirt | cape | sleeve | obj"},
      {"missing garment type", [](json& j) { j["garments"][0].erase("type"); },
       "/garments/0/type: ", "missing"},
      {"negative dt", [](json& j) { j["solver"]["dt"] = -0.01; }, "/solver/dt: ", "out of range"},
      {"zero dt", [](json& j) { j["solver"]["dt"] = 0; }, "/solver/dt: ", "out of range"},
      {"unknown collision method",
       [](json& j) {
         j["collision"]["methods"] = {"hulls", "lasers"};
       },
       "/collision/methods/1: ", "'lasers' is not a collision method"},
      {"methods not an array", [](json& j) { j["collision"]["methods"] = "hulls"; },
       "/collision/methods: ", "must be an array"},
      {"substeps as text", [](json& j) { j["solver"]["substeps"] = "four"; },
       "/solver/substeps: ", "integer"},
      {"width as fraction", [](json& j) { j["output"]["width"] = 12.5; },
       "/output/width: ", "must be an integer"},
      {"joint as number", [](json& j) { j["garments"][0]["attach"]["joint"] = 3; },
       "/garments/0/attach/joint: ", "must be a string"},
      {"attach without joint", [](json& j) { j["garments"][0]["attach"].erase("joint"); },
       "/garments/0/attach/joint: ", "missing"},
      {"gravity with text",
       [](json& j) {
         j["solver"]["gravity"] = {0, "down", 0};
       },
       "/solver/gravity/1: ", "must be a number"},
      {"garments as object", [](json& j) { j["garments"] = json::object(); },
       "/garments: ", "non-empty array"},
      {"unknown key", [](json& j) { j["solver"]["substepz"] = 2; }, "/solver/substepz: ",
       "unknown key: substepz is not a parameter of /solver (did you mean substeps? known here: "
       "integrator | dt | substeps |"},
      {"unknown garment key",
       [](json& j) {
         j["garments"][0]["colour"] = {1, 0, 0};
       },
       "/garments/0/colour: ", "did you mean color?"},
      {"missing attach box corner",
       [](json& j) {
         j["garments"][0]["attach"] = {{"joint", "hips"}, {"box", {{"min", {0, 0, 0}}}}};
       },
       "/garments/0/attach/box/max: ", "missing (required: an array of 3 numbers [x, y, z])"},
      {"auto substeps with verlet", [](json& j) { j["solver"]["substeps"] = "auto"; },
       "/solver/substeps: ", "\"auto\" is for the euler integrator only"},
      {"duplicate garment name", [](json& j) { j["garments"][1] = j["garments"][0]; },
       "/garments/1/name: ", "'skirt' is already the name of /garments/0"},
      {"negative radius", [](json& j) { j["garments"][0]["shape"]["top_radius"] = -0.1; },
       "/garments/0/shape/top_radius: ", "out of range"},
      {"selection with two kinds",
       [](json& j) {
         j["garments"][0]["attach"]["vertices"] = {0, 1};
       },
       "/garments/0/attach: ", "only one of"},
      {"bad bake override", [](json& j) { j["bake"]["maps"]["resolution"] = 3; },
       "/bake/maps/resolution: ", "must be in"},
      {"bake override of a kind",
       [](json& j) {
         j["bake"]["hulls"] = {{"enabled", false}};
       },
       "/bake/hulls/enabled: ", "/collision/methods"},
      {"clip and pose", [](json& j) { j["animation"]["pose"] = "rest"; },
       "/animation/pose: ", "not both"},
      {"friction above 1", [](json& j) { j["solver"]["friction"] = 1.5; },
       "/solver/friction: ", "out of range"},
      {"colour out of range",
       [](json& j) {
         j["garments"][0]["color"] = {1, 2, 0};
       },
       "/garments/0/color/1: ", "out of range"},
      {"baked maps of the bind pose",
       [](json& j) {
         j["animation"] = {{"pose", "bind"}};
         j["collision"]["methods"] = {"maps"};
         j["collision"]["maps_source"] = "baked";
       },
       "/animation/pose: ", "rest pose"},
      {"not an object", [](json& j) { j = json::array(); }, "", "must be a JSON object"},
      {"bake section not an object", [](json& j) { j["bake"]["maps"] = 3; },
       "/bake/maps: ", "must be an object, not a number"},
      {"unknown bake key",
       [](json& j) {
         j["bake"]["hulls"] = {{"deltaa", 0.01}};
       },
       "/bake/hulls/deltaa: ", "did you mean delta?"},
  };
  for (const Case& c : cases) {
    json j = DemoJson();
    c.mutate(j);
    Scene scene;
    const Status s = Parse(j, &scene);
    ASSERT_FALSE(s.ok()) << c.name;
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << c.name;
    const std::string expected_prefix = std::string("scene.json: ") + c.prefix;
    EXPECT_EQ(s.message().rfind(expected_prefix, 0), 0u)
        << c.name << ": " << s.message() << " should start with " << expected_prefix;
    EXPECT_NE(s.message().find(c.reason), std::string::npos)
        << c.name << ": " << s.message() << " should say " << c.reason;
    EXPECT_EQ(s.message().find('\n'), std::string::npos) << c.name << ": one line";
  }
}

TEST(SceneParse, LoadNamesTheFile) {
  Scene scene;
  Status s = LoadScene("/nonexistent/scene.json", &scene);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message().rfind("/nonexistent/scene.json: ", 0), 0u) << s.message();
  const std::string path = ::testing::TempDir() + "/broken_scene.json";
  std::ofstream(path) << "{\"character\": ";
  s = LoadScene(path, &scene);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message().rfind(path + ": not valid JSON", 0), 0u) << s.message();
}

// What drape-sim reads from a scene file's bytes: a number beyond a double and a key given twice
// are refused with the JSON path, never thrown or silently resolved.
TEST(SceneParse, FileBytesAreReadStrictly) {
  Scene scene;
  Status s = ParseSceneText(R"({"character": "a.glb", "garments": [{"type": "skirt",
      "shape": {"length": 1e400}}]})",
                            "s.json", "/nonexistent", &scene);
  EXPECT_EQ(s.message(),
            "s.json: /garments/0/shape/length: the number 1e400 is beyond what a double holds");
  s = ParseSceneText(R"({"character": "a.glb", "character": "b.glb", "garments": []})", "s.json",
                     "/nonexistent", &scene);
  EXPECT_EQ(s.message(), "s.json: /character: appears twice in its object");
  s = ParseSceneText(R"({"character": "a.glb", "solver": {"dt": 0.01, "dt": 0.02}})", "s.json",
                     "/nonexistent", &scene);
  EXPECT_EQ(s.message(), "s.json: /solver/dt: appears twice in its object");
}

TEST(SceneParse, BakeConfigFollowsTheScene) {
  Scene scene;
  ASSERT_TRUE(LoadScene(DemoPath(), &scene).ok());
  BakeConfig config;
  ASSERT_TRUE(ApplySceneToBakeConfig(scene, &config).ok());
  EXPECT_FALSE(config.maps_enabled);  // the demo uses hulls and spheres only
  EXPECT_TRUE(config.hulls_enabled);
  EXPECT_TRUE(config.spheres_enabled);
  EXPECT_EQ(config.maps.resolution, 512u);  // its /bake override
  EXPECT_EQ(config.maps_clip, "");

  json j = DemoJson();
  j["collision"]["methods"] = {"maps"};
  j["bake"]["maps"]["clip_rate"] = 15;
  ASSERT_TRUE(Parse(j, &scene).ok());
  config = BakeConfig{};
  ASSERT_TRUE(ApplySceneToBakeConfig(scene, &config).ok());
  EXPECT_TRUE(config.maps_enabled);
  EXPECT_FALSE(config.hulls_enabled);
  EXPECT_FALSE(config.spheres_enabled);
  EXPECT_EQ(config.maps_clip, "");  // rendered maps (the default) need the rest pose's alone
  j["collision"]["maps_source"] = "baked";
  ASSERT_TRUE(Parse(j, &scene).ok());
  config = BakeConfig{};
  ASSERT_TRUE(ApplySceneToBakeConfig(scene, &config).ok());
  EXPECT_EQ(config.maps_clip, "walk");  // baked maps: every pose of the clip
  EXPECT_FLOAT_EQ(config.maps_clip_rate, 15.f);
  // Rendered maps follow any pose, the bind pose too.
  j["animation"] = {{"pose", "bind"}};
  j["collision"]["maps_source"] = "rendered";
  EXPECT_TRUE(Parse(j, &scene).ok());
}

TEST_F(SceneTest, ResolutionErrorsNameTheirPath) {
  struct Case {
    const char* name;
    std::function<void(json&)> mutate;
    const char* expected;  // the message starts with "scene.json: " + this
  };
  const std::vector<Case> cases = {
      {"unknown joint", [](json& j) { j["garments"][0]["attach"]["joint"] = "hipz"; },
       "/garments/0/attach/joint: no joint named 'hipz'"},
      {"unknown anchor", [](json& j) { j["garments"][0]["anchor"] = "pelvis"; },
       "/garments/0/anchor: no joint named 'pelvis'"},
      {"unknown ring", [](json& j) { j["garments"][0]["attach"]["ring"] = "belt"; },
       "/garments/0/attach/ring: no ring named 'belt' on a skirt (rings: held | waist | hem)"},
      {"vertex out of range",
       [](json& j) {
         j["garments"][0]["attach"] = json::array({{{"joint", "hips"}, {"ring", "waist"}},
                                                   {{"joint", "hips"}, {"vertices", {5, 99999}}}});
       },
       "/garments/0/attach/1/vertices/1: particle 99999 is out of range"},
      {"empty box",
       [](json& j) {
         j["garments"][0]["attach"] = {{"joint", "hips"},
                                       {"box", {{"min", {5, 5, 5}}, {"max", {6, 6, 6}}}}};
       },
       "/garments/0/attach/box: selects no particle"},
      {"held twice",
       [](json& j) {
         j["garments"][0]["attach"] = json::array(
             {{{"joint", "hips"}, {"ring", "waist"}}, {{"joint", "spine"}, {"vertices", {3}}}});
       },
       "/garments/0/attach/1: particle 3 is already held by /garments/0/attach/0"},
  };
  for (const Case& c : cases) {
    json j = DemoJson();
    c.mutate(j);
    Scene scene;
    ASSERT_TRUE(Parse(j, &scene).ok()) << c.name;
    ResolvedGarment garment;
    const Status s = ResolveGarment(scene, 0, asset().skeleton, &garment);
    ASSERT_FALSE(s.ok()) << c.name;
    const std::string expected = std::string("scene.json: ") + c.expected;
    EXPECT_EQ(s.message().rfind(expected, 0), 0u) << c.name << ": " << s.message();
  }

  json j = DemoJson();
  j["animation"]["clip"] = "run";
  Scene scene;
  ASSERT_TRUE(Parse(j, &scene).ok());
  int32_t clip = 0;
  const Status s = ResolveSceneClip(asset(), &scene, &clip);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message().rfind("scene.json: /animation/clip: no clip named 'run'", 0), 0u)
      << s.message();
  EXPECT_NE(s.message().find("(clips: walk)"), std::string::npos) << s.message();
}

// A skinned skirt: weights from the mannequin's closest body points (smoothed), so at the bind
// pose every particle's skinned position is where it was authored, the waist stays attached, the
// free particles get the max distance and backstop, and the hem (between the legs) blends both
// thighs after smoothing. Without a body mesh the scene is refused with the garment's path.
TEST_F(SceneTest, SkinnedGarmentTakesItsWeightsFromTheBody) {
  json j = DemoJson();
  j["garments"][0]["skin"] = {{"max_distance", 0.06}, {"backstop", 0.01}};
  Scene scene;
  ASSERT_TRUE(Parse(j, &scene).ok());
  ResolvedGarment garment;
  Status s = ResolveSkinned(scene, &garment);
  ASSERT_TRUE(s.ok()) << s.message();
  const ClothDescription& d = garment.description;
  ASSERT_EQ(d.skin.size(), d.positions.size());
  ASSERT_EQ(d.attachments.size(), 64u);
  std::vector<Mat34> bind(asset().skeleton.joint_count());  // skinning = identity at the bind pose
  const int32_t left = FindJoint(asset().skeleton, "hip_l"),
                right = FindJoint(asset().skeleton, "hip_r");
  uint32_t hem_on_both_thighs = 0;
  for (size_t i = 0; i < d.positions.size(); ++i) {
    Float3 skinned;
    float sum = 0.f;
    float on_left = 0.f, on_right = 0.f;
    for (int k = 0; k < 4; ++k) {
      skinned += TransformPoint(bind[d.skin[i].joints[k]], d.skin_bind_positions[i]) *
                 d.skin[i].weights[k];
      sum += d.skin[i].weights[k];
      if (static_cast<int32_t>(d.skin[i].joints[k]) == left) on_left += d.skin[i].weights[k];
      if (static_cast<int32_t>(d.skin[i].joints[k]) == right) on_right += d.skin[i].weights[k];
    }
    ASSERT_NEAR(sum, 1.f, 1e-5f) << i;
    ASSERT_LT(Length(skinned - d.positions[i]), 1e-5f) << i;
    const bool held = i < 64;  // the waist ring
    EXPECT_EQ(d.max_distance[i], held ? std::numeric_limits<float>::infinity() : 0.06f) << i;
    EXPECT_EQ(d.backstop[i], held ? std::numeric_limits<float>::infinity() : 0.01f) << i;
    if (i >= d.positions.size() - 64 && on_left > 0.1f && on_right > 0.1f) ++hem_on_both_thighs;
  }
  EXPECT_GT(hem_on_both_thighs, 8u);
  Cloth cloth;
  EXPECT_TRUE(BuildCloth(d, &cloth).ok());
  ASSERT_TRUE(ResolveGarment(scene, 0, asset().skeleton, &garment).ok());
  s = SkinGarment(scene, 0, asset().skeleton, MeshData{}, &garment);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.message().rfind("scene.json: /garments/0/skin: the asset has no body mesh", 0), 0u)
      << s.message();
  j["garments"][0]["skin"] = {{"max_distance", -1}};
  EXPECT_FALSE(Parse(j, &scene).ok());
}

// A skirt skinned as a skirt: `transfer: held` gives every particle the body weights of its
// nearest held particle (its column's waist particle), so the legs do not drag the hem along;
// `paint: ramp` grows max_distance from 0 at the waist to max_distance at the hem. Both need a
// held part, and the ramp a finite max_distance.
TEST_F(SceneTest, SkirtFollowsItsWaistbandWithARampedMaxDistance) {
  json j = DemoJson();
  j["garments"][0]["skin"] = {{"max_distance", 0.2}, {"smoothing", 0}};
  Scene scene;
  ASSERT_TRUE(Parse(j, &scene).ok());
  ResolvedGarment closest;
  ASSERT_TRUE(ResolveSkinned(scene, &closest).ok());
  j["garments"][0]["skin"] = {
      {"max_distance", 0.2}, {"smoothing", 0}, {"transfer", "held"}, {"paint", "ramp"}};
  ASSERT_TRUE(Parse(j, &scene).ok());
  ResolvedGarment held;
  const Status s = ResolveSkinned(scene, &held);
  ASSERT_TRUE(s.ok()) << s.message();
  const ClothDescription& d = held.description;
  constexpr size_t kSegments = 64;  // the demo skirt's particles around; ring 0 is held
  const size_t rings = d.positions.size() / kSegments - 1;
  ASSERT_EQ(d.positions.size(), (rings + 1) * kSegments);
  std::vector<Mat34> bind(asset().skeleton.joint_count());
  uint32_t differs_from_closest = 0;
  for (size_t i = 0; i < d.positions.size(); ++i) {
    const ClothSkinWeights& waist = closest.description.skin[i % kSegments];
    Float3 skinned;
    for (int k = 0; k < 4; ++k) {
      ASSERT_EQ(d.skin[i].joints[k], waist.joints[k]) << i;
      ASSERT_EQ(d.skin[i].weights[k], waist.weights[k]) << i;
      skinned += TransformPoint(bind[d.skin[i].joints[k]], d.skin_bind_positions[i]) *
                 d.skin[i].weights[k];
    }
    ASSERT_LT(Length(skinned - d.positions[i]), 1e-5f) << i;
    const ClothSkinWeights& own = closest.description.skin[i];
    differs_from_closest += own.joints[0] != waist.joints[0] || own.weights[0] != waist.weights[0];
    const size_t ring = i / kSegments;
    if (ring == 0) {
      EXPECT_EQ(d.max_distance[i], std::numeric_limits<float>::infinity()) << i;
    } else {
      EXPECT_NEAR(d.max_distance[i], 0.2f * static_cast<float>(ring) / static_cast<float>(rings),
                  1e-5f)
          << i;
    }
  }
  EXPECT_GT(differs_from_closest, kSegments);  // the closest points of the hem are the legs'
  j["garments"][0]["skin"]["max_distance"] = "none";
  ASSERT_TRUE(Parse(j, &scene).ok());
  Status refused = ResolveSkinned(scene, &held);
  EXPECT_NE(refused.message().find("/garments/0/skin/paint: \"ramp\" scales max_distance"),
            std::string::npos)
      << refused.message();
  j["garments"][0]["skin"] = {{"transfer", "held"}};
  j["garments"][0].erase("attach");
  j["garments"][0]["pin"] = json::array();
  ASSERT_TRUE(Parse(j, &scene).ok()) << j.dump();
  refused = ResolveSkinned(scene, &held);
  EXPECT_NE(refused.message().find("/garments/0/skin/transfer: \"held\" takes the weights"),
            std::string::npos)
      << refused.message();
}

// An OBJ garment painted with vertex colours: the red channel scales max_distance per particle
// (black: the particle follows the skin exactly, as a held one). Without colours: refused.
TEST_F(SceneTest, SkinnedObjGarmentTakesItsPaintedMaxDistance) {
  const std::string obj = ::testing::TempDir() + "/painted_band.obj";
  {
    std::ofstream out(obj);
    // A band around the hips (the mannequin's hips at y = 0.95): 12 columns x 2 rows of quads,
    // red 0 on the top ring, 0.5 in the middle, 1 at the bottom.
    for (int row = 0; row < 3; ++row) {
      for (int c = 0; c < 12; ++c) {
        const double a = 2 * 3.14159265358979 * c / 12;
        out << "v " << 0.2 * std::sin(a) << " " << 1.0 - 0.1 * row << " " << 0.2 * std::cos(a)
            << " " << 0.5 * row << " 0 0\n";
      }
    }
    for (int row = 0; row < 2; ++row)
      for (int c = 0; c < 12; ++c)
        out << "f " << row * 12 + c + 1 << " " << (row + 1) * 12 + c + 1 << " "
            << (row + 1) * 12 + (c + 1) % 12 + 1 << " " << row * 12 + (c + 1) % 12 + 1 << "\n";
  }
  json j = DemoJson();
  j["garments"][0] = {{"type", "obj"},
                      {"shape", {{"file", obj}}},
                      {"skin", {{"max_distance", 0.1}, {"paint", "r"}}}};
  Scene scene;
  {
    const Status parsed = Parse(j, &scene);
    ASSERT_TRUE(parsed.ok()) << parsed.message();
  }
  ResolvedGarment garment;
  Status s = ResolveSkinned(scene, &garment);
  ASSERT_TRUE(s.ok()) << s.message();
  const ClothDescription& d = garment.description;
  ASSERT_EQ(d.max_distance.size(), 36u);
  for (size_t i = 0; i < 36; ++i)
    EXPECT_NEAR(d.max_distance[i], 0.05f * static_cast<float>(i / 12), 1e-6f) << i;
  Cloth cloth;
  ASSERT_TRUE(BuildCloth(d, &cloth).ok());
  EXPECT_EQ(cloth.kinematic_particles().size(), 12u);  // the black ring
  {
    std::ofstream out(obj);
    out << "v 0 1 0\nv 0.1 1 0\nv 0 1 0.1\nf 1 2 3\n";
  }
  s = ResolveSkinned(scene, &garment);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("/garments/0/skin/paint: the garment has no vertex colours"),
            std::string::npos)
      << s.message();
}

// Authored weights from a file (OBJ + weights): kept as written (no smoothing), the four heaviest
// renormalised; a file naming an unknown joint, or with the wrong line count, is refused naming
// the file and the line.
TEST_F(SceneTest, SkinnedGarmentTakesAuthoredWeightsFromAFile) {
  const std::string dir = ::testing::TempDir();
  {
    std::ofstream out(dir + "/triangle.obj");
    out << "v 0.1 0.9 0.1\nv 0.2 0.9 0.1\nv 0.1 0.8 0.1\nf 1 2 3\n";
    std::ofstream weights(dir + "/triangle.weights");
    weights << "# one line per vertex\nhips 1\nhips 0.5 hip_l 1.5\n"
            << "hip_l 1 hip_r 1 spine 1 chest 1 knee_l 0.5  # five: the lightest dropped\n";
  }
  json j = DemoJson();
  j["garments"][0] = {{"type", "obj"},
                      {"shape", {{"file", dir + "/triangle.obj"}}},
                      {"skin", {{"weights_file", dir + "/triangle.weights"}}}};
  Scene scene;
  ASSERT_TRUE(Parse(j, &scene).ok());
  ResolvedGarment garment;
  ASSERT_TRUE(ResolveGarment(scene, 0, asset().skeleton, &garment).ok());
  Status s = SkinGarment(scene, 0, asset().skeleton, asset().mesh, &garment);
  ASSERT_TRUE(s.ok()) << s.message();
  const std::vector<ClothSkinWeights>& w = garment.description.skin;
  ASSERT_EQ(w.size(), 3u);
  const auto joint = [&](const char* name) {
    return static_cast<uint32_t>(FindJoint(asset().skeleton, name));
  };
  EXPECT_EQ(w[0].joints[0], joint("hips"));
  EXPECT_FLOAT_EQ(w[0].weights[0], 1.f);
  EXPECT_EQ(w[1].joints[0], joint("hip_l"));
  EXPECT_FLOAT_EQ(w[1].weights[0], 0.75f);
  EXPECT_FLOAT_EQ(w[1].weights[1], 0.25f);
  EXPECT_FLOAT_EQ(w[2].weights[0] + w[2].weights[1] + w[2].weights[2] + w[2].weights[3], 1.f);
  for (int k = 0; k < 4; ++k) EXPECT_NE(w[2].joints[k], joint("knee_l"));
  {
    std::ofstream weights(dir + "/triangle.weights");
    weights << "hips 1\nhipz 1\nhips 1\n";
  }
  s = SkinGarment(scene, 0, asset().skeleton, asset().mesh, &garment);
  EXPECT_NE(s.message().find("triangle.weights': line 2: no joint named 'hipz' (did you mean"),
            std::string::npos)
      << s.message();
  {
    std::ofstream weights(dir + "/triangle.weights");
    weights << "hips 1\nhips 1\n";
  }
  s = SkinGarment(scene, 0, asset().skeleton, asset().mesh, &garment);
  EXPECT_NE(s.message().find("2 weighted vertices for the garment's 3"), std::string::npos)
      << s.message();
  // Authored weights are not the body's: taking a held particle's is refused, not ignored.
  j["garments"][0]["skin"]["transfer"] = "held";
  ASSERT_TRUE(Parse(j, &scene).ok());
  s = SkinGarment(scene, 0, asset().skeleton, asset().mesh, &garment);
  EXPECT_NE(s.message().find("/garments/0/skin/transfer: \"held\" takes the body's weights; "
                             "this garment's are the weights_file's"),
            std::string::npos)
      << s.message();
}

TEST_F(SceneTest, GarmentIsHeldInTheBindFrame) {
  Scene scene;
  ASSERT_TRUE(LoadScene(DemoPath(), &scene).ok());
  ResolvedGarment garment;
  const Status s = ResolveGarment(scene, 0, asset().skeleton, &garment);
  ASSERT_TRUE(s.ok()) << s.message();
  const ClothDescription& d = garment.description;
  ASSERT_EQ(d.positions.size(), 64u * 25u);
  ASSERT_EQ(d.attachments.size(), 64u);  // the waist ring
  const int32_t hips = FindJoint(asset().skeleton, "hips");
  // The skirt is anchored at the hips joint (bind position y = 0.95) + 0.03.
  for (const ClothAttachment& a : d.attachments) {
    EXPECT_EQ(a.joint, hips);
    EXPECT_LT(a.particle, 64u);
    EXPECT_NEAR(a.bind_position.y, 0.98f, 1e-5f);
    EXPECT_NEAR(std::hypot(a.bind_position.x, a.bind_position.z), 0.185f, 1e-5f);
  }
  // Every particle is carried by the hips; at a walk pose the placed waist is exactly where the
  // solver puts the attachments (S * bind position), and in the bind pose nothing moves.
  for (int32_t j : garment.carrier_joint) EXPECT_EQ(j, hips);
  SkeletonPose pose;
  ASSERT_TRUE(pose.Init(asset().skeleton).ok());
  pose.SetBind();
  std::vector<Float3> placed;
  PlaceGarment(garment, pose.skinning(), &placed);
  for (size_t i = 0; i < placed.size(); ++i) {
    EXPECT_NEAR(Length(placed[i] - d.positions[i]), 0.f, 1e-5f);
  }
  ASSERT_TRUE(pose.SampleClip(asset().clips[0], 0.3f, true).ok());
  PlaceGarment(garment, pose.skinning(), &placed);
  for (const ClothAttachment& a : d.attachments) {
    const Float3 target =
        TransformPoint(pose.skinning()[static_cast<size_t>(hips)], a.bind_position);
    EXPECT_NEAR(Length(placed[a.particle] - target), 0.f, 1e-5f);
  }
}

TEST_F(SceneTest, NearestHeldPathFollowsTheMesh) {
  json j = MiniSkirt();
  Scene scene;
  ASSERT_TRUE(Parse(j, &scene).ok());
  ResolvedGarment garment;
  ASSERT_TRUE(ResolveGarment(scene, 0, asset().skeleton, &garment).ok());
  std::vector<float> distance;
  std::vector<uint32_t> nearest;
  NearestHeldParticles(garment.description, &distance, &nearest);
  // The skirt's vertical edges run along the cone's generators: the hem is one slant height
  // from the waist particle straight above it, the shortest path there.
  const float slant = std::hypot(0.25f, 0.3f - 0.185f);
  const uint32_t segments = 64, rings = 24;
  for (uint32_t i = 0; i < segments; ++i) {
    const uint32_t hem = rings * segments + i;
    EXPECT_NEAR(distance[hem], slant, 1e-5f);
    EXPECT_EQ(nearest[hem], i);
  }
  for (uint32_t i = 0; i < segments; ++i) EXPECT_EQ(distance[i], 0.f);
  // An unheld part has no path.
  ClothDescription loose = garment.description;
  loose.attachments.clear();
  NearestHeldParticles(loose, &distance, &nearest);
  for (float d : distance) EXPECT_TRUE(std::isinf(d));
}

TEST_F(SceneTest, SkirtReachKeepsHipsAndDropsHeadAndWrists) {
  Scene scene;
  ASSERT_TRUE(Parse(MiniSkirt(), &scene).ok());
  SceneReach reach;
  const Status s = AnalyzeSceneReach(scene, asset(), &reach);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(reach.garments.size(), 1u);
  const float slant = std::hypot(0.25f, 0.3f - 0.185f);
  EXPECT_NEAR(reach.garments[0].max_path, slant, 1e-5f);
  EXPECT_NEAR(reach.garments[0].radius, 1.1f * slant + 0.02f, 1e-5f);
  EXPECT_TRUE(reach.garments[0].bounded);
  // 60 frames of 4 substeps, plus the start.
  EXPECT_EQ(reach.sampled_poses, 241u);
  EXPECT_TRUE(reach.whole_clip);
  ASSERT_EQ(reach.hulls.size(), asset().hulls.size());
  ASSERT_EQ(reach.spheres.size(), asset().joint_spheres.size());

  // By joint name (a bone may have several convex pieces, each its own hull), and counted.
  std::set<std::string> reachable_hulls, dropped_hulls, dropped_spheres;
  size_t reachable_hull_count = 0, dropped_hull_count = 0, dropped_sphere_count = 0;
  for (const ColliderReach& c : reach.hulls) {
    (c.reachable ? reachable_hulls : dropped_hulls).insert(c.joint_name);
    ++(c.reachable ? reachable_hull_count : dropped_hull_count);
    EXPECT_EQ(c.reachable, c.clearance <= 0.f);
  }
  for (const ColliderReach& c : reach.spheres) {
    if (!c.reachable) dropped_spheres.insert(c.joint_name);
    dropped_sphere_count += c.reachable ? 0 : 1;
  }
  for (const char* kept : {"hips", "hip_l", "hip_r", "spine"})
    EXPECT_TRUE(reachable_hulls.count(kept)) << kept << " should be reachable";
  for (const char* dropped : {"head", "wrist_l", "wrist_r", "ankle_l", "ankle_r"})
    EXPECT_TRUE(dropped_hulls.count(dropped)) << dropped << " should be out of reach";
  for (const char* dropped : {"head", "wrist_l", "wrist_r"})
    EXPECT_TRUE(dropped_spheres.count(dropped)) << dropped << " sphere should be out of reach";

  // Pruning leaves exactly the reachable colliders and says why for each of the others.
  CharacterAsset pruned = asset();
  json left_out = json::array();
  PruneUnreachable(reach, &pruned, &left_out);
  EXPECT_EQ(pruned.hulls.size(), reachable_hull_count);
  EXPECT_EQ(pruned.joint_spheres.size() + dropped_sphere_count, asset().joint_spheres.size());
  size_t dropped_entries = 0;
  for (const json& entry : left_out) {
    if (entry["kind"] == "hull" || entry["kind"] == "joint_sphere") {
      ++dropped_entries;
      EXPECT_NE(entry["reason"].get<std::string>().find("cannot reach"), std::string::npos);
    }
  }
  EXPECT_EQ(dropped_entries, dropped_hull_count + dropped_sphere_count);
  // The whole looping clip is played: every map pose stays.
  EXPECT_EQ(pruned.body_maps.poses.size(), asset().body_maps.poses.size());
}

TEST_F(SceneTest, ReachOfALooseGarmentIsEverything) {
  json j = MiniSkirt();
  j["garments"][0].erase("attach");
  Scene scene;
  ASSERT_TRUE(Parse(j, &scene).ok());
  SceneReach reach;
  ASSERT_TRUE(AnalyzeSceneReach(scene, asset(), &reach).ok());
  EXPECT_FALSE(reach.garments[0].bounded);
  for (const ColliderReach& c : reach.hulls) EXPECT_TRUE(c.reachable) << c.joint_name;
  for (const ColliderReach& c : reach.spheres) EXPECT_TRUE(c.reachable) << c.joint_name;
}

TEST_F(SceneTest, PlayedMapPosesAreThoseOfThePlayedTimes) {
  json j = MiniSkirt();
  // 8 frames of 1/32 s (exact in float, so no frame end lands a rounding away from a pose).
  j["animation"] = {{"clip", "walk"}, {"start", 0.2}, {"duration", 0.25}, {"loop", false}};
  j["solver"]["dt"] = 0.03125;
  Scene scene;
  ASSERT_TRUE(Parse(j, &scene).ok());
  SceneReach reach;
  ASSERT_TRUE(AnalyzeSceneReach(scene, asset(), &reach).ok());
  EXPECT_FALSE(reach.whole_clip);
  EXPECT_NEAR(reach.clip_time_min, 0.2f, 1e-6f);
  EXPECT_NEAR(reach.clip_time_max, 0.45f, 1e-6f);
  // Poses at 0, 0.1, ..., 1.0 s: the frames end in [0.2, 0.45], so 0.2 .. 0.5 are read (a frame
  // end between two poses reads both with kBracket).
  ASSERT_EQ(asset().body_maps.poses.size(), 11u);
  std::vector<float> times;
  for (uint32_t p : reach.played_map_poses) times.push_back(asset().body_maps.poses[p].time);
  ASSERT_EQ(times.size(), 4u);
  for (size_t k = 0; k < times.size(); ++k)
    EXPECT_NEAR(times[k], 0.2f + 0.1f * static_cast<float>(k), 1e-5f);
  CharacterAsset pruned = asset();
  json left_out = json::array();
  PruneUnreachable(reach, &pruned, &left_out);
  EXPECT_EQ(pruned.body_maps.poses.size(), 4u);
}

// docs/SCENES.md is generated from the schema the parser reads with; a changed field, range or
// default changes the document.
// Poses no bake saw: a blend with a second clip and fixed random joint rotations. The
// perturbation is the same for a seed, turns every joint by at most its angle, and the poser
// plays it on top of the clip; the scene refuses a blend without a clip, baked maps with a
// perturbation, and a blend clip the character lacks, naming the path.
TEST_F(SceneTest, PosesBeyondTheClip) {
  const SkeletonData& skeleton = asset().skeleton;
  std::vector<Transform> a(skeleton.rest_local.begin(), skeleton.rest_local.end()), b = a;
  PerturbJointRotations(a, 30.f, 7);
  PerturbJointRotations(b, 30.f, 7);
  double largest = 0.0;
  for (size_t j = 0; j < a.size(); ++j) {
    EXPECT_EQ(std::memcmp(&a[j], &b[j], sizeof(Transform)), 0) << j;
    const Quat r = skeleton.rest_local[j].rotation, p = a[j].rotation;
    const double dot =
        std::fabs(double(r.x) * p.x + double(r.y) * p.y + double(r.z) * p.z + double(r.w) * p.w);
    const double angle = 2.0 * std::acos(std::min(dot, 1.0)) * 180.0 / 3.14159265358979;
    EXPECT_LE(angle, 30.01) << j;
    largest = std::max(largest, angle);
  }
  EXPECT_GT(largest, 15.0);  // not the identity

  json j = MiniSkirt();
  j["collision"]["methods"] = {"maps", "hulls"};
  j["animation"]["perturb_degrees"] = 20;
  j["animation"]["blend_clip"] = "walk";
  j["animation"]["blend_weight"] = 0.25;
  Scene scene;
  ASSERT_TRUE(Parse(j, &scene).ok());
  int32_t clip = -1;
  ASSERT_TRUE(ResolveSceneClip(asset(), &scene, &clip).ok());
  ScenePoser poser;
  ASSERT_TRUE(poser.Init(scene, asset(), clip).ok());
  SkeletonPose perturbed, plain;
  ASSERT_TRUE(perturbed.Init(skeleton).ok() && plain.Init(skeleton).ok());
  ASSERT_TRUE(poser.Pose(0.3f, &perturbed).ok());
  ASSERT_TRUE(plain.SampleClip(asset().clips[0], 0.3f, true).ok());
  float moved = 0.f;
  for (size_t k = 0; k < plain.world().size(); ++k) {
    const Mat34 &p = plain.world()[k], &q = perturbed.world()[k];
    moved = std::max(moved, Length(Float3{p.m[3] - q.m[3], p.m[7] - q.m[7], p.m[11] - q.m[11]}));
  }
  EXPECT_GT(moved, 0.05f);  // metres: the joints moved off the clip's pose

  j["animation"]["blend_clip"] = "run";
  ASSERT_TRUE(Parse(j, &scene).ok());
  ASSERT_TRUE(ResolveSceneClip(asset(), &scene, &clip).ok());
  const Status unknown = poser.Init(scene, asset(), clip);
  EXPECT_EQ(unknown.message().rfind("scene.json: /animation/blend_clip: no clip named 'run'", 0),
            0u)
      << unknown.message();
  j["animation"]["blend_clip"] = "walk";
  j["collision"]["maps_source"] = "baked";
  Status s = Parse(j, &scene);
  EXPECT_EQ(s.message().rfind("scene.json: /collision/maps_source: baked maps hold", 0), 0u)
      << s.message();
  json still = DemoJson();
  still["animation"] = {{"blend_clip", "walk"}};
  s = Parse(still, &scene);
  EXPECT_EQ(s.message().rfind("scene.json: /animation/blend_clip: blends with `clip`", 0), 0u)
      << s.message();
}

TEST(SceneReference, DocumentIsTheGeneratedOne) {
  const std::string path = test::SourceDir() + "/docs/SCENES.md";
  std::ifstream in(path);
  ASSERT_TRUE(in) << path << " is missing; generate it with: " << test::BinDir()
                  << "/drape-sim --dump-scene-reference > docs/SCENES.md";
  const std::string committed((std::istreambuf_iterator<char>(in)),
                              std::istreambuf_iterator<char>());
  const std::string generated = SceneReferenceMarkdown();
  if (committed == generated) return;
  // The first line that differs, for the message.
  std::istringstream a(committed), b(generated);
  std::string line_a, line_b;
  int line = 0;
  while (true) {
    ++line;
    const bool more_a = static_cast<bool>(std::getline(a, line_a));
    const bool more_b = static_cast<bool>(std::getline(b, line_b));
    if (!more_a || !more_b || line_a != line_b) break;
  }
  ADD_FAILURE() << "docs/SCENES.md differs from the generated reference at line " << line
                << ":\n  committed: " << line_a << "\n  generated: " << line_b
                << "\nRegenerate it with: " << test::BinDir()
                << "/drape-sim --dump-scene-reference > docs/SCENES.md";
}

// Every scene in samples/scenes is in the reference's table of sample scenes, and parses (a scene
// whose character is a shared asset is skipped when that asset is absent).
TEST(SceneReference, ListsAndParsesEverySampleScene) {
  const std::string reference = SceneReferenceMarkdown();
  std::vector<std::string> absent;
  size_t scenes = 0;
  for (const auto& entry : std::filesystem::directory_iterator(ScenesDir())) {
    if (entry.path().extension() != ".json") continue;
    ++scenes;
    const std::string name = entry.path().filename().string();
    EXPECT_NE(reference.find("| `" + name + "` |"), std::string::npos)
        << name << " is not in the sample scenes of docs/SCENES.md (scene_reference.cpp)";
    std::ifstream in(entry.path());
    const json j = json::parse(in);
    const std::string character = ScenesDir() + "/" + j.value("character", std::string());
    if (character.find("/shared/assets/") != std::string::npos &&
        !std::filesystem::exists(character)) {
      absent.push_back(name);
      continue;
    }
    Scene scene;
    const Status s = LoadScene(entry.path().string(), &scene);
    EXPECT_TRUE(s.ok()) << s.message();
  }
  EXPECT_GE(scenes, 5u);
  for (const std::string& name : absent)
    std::printf("skipped %s: shared asset absent\n", name.c_str());
}

}  // namespace
}  // namespace drape::bake

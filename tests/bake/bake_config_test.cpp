// The bake config: JSON-path errors, the reference's numbers, and a config written back out reads
// in again unchanged, including float values at the bounds of their ranges (0.1 m is stored as
// the float 0.100000001 m, which must not be refused as above the 0.1 m bound when read again).

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "config/json_schema.h"
#include "config/name_suggestions.h"
#include "drape/bake/bake_config.h"

namespace drape::bake {
namespace {

TEST(BakeConfig, FloatsAtTheirBoundsRoundTrip) {
  BakeConfig config;
  const nlohmann::json bounds = {
      {"hulls", {{"delta", 0.1}, {"max_growth", 1.0}}},
      {"maps",
       {{"epsilon", 0.1}, {"margin", 1.0}, {"clip_rate", 1000.0}, {"render_tolerance", 0.1}}},
      {"spheres", {{"delta", 0.1}}}};
  const Status first = ApplyBakeConfig(bounds, "bounds.json", &config);
  ASSERT_TRUE(first.ok()) << first.message();
  BakeConfig again;
  const Status second = ApplyBakeConfig(BakeConfigToJson(config), "again.json", &again);
  ASSERT_TRUE(second.ok()) << second.message();
  EXPECT_EQ(BakeConfigToJson(again), BakeConfigToJson(config));
}

TEST(BakeConfig, OutOfRangeAndUnknownKeysNameTheirPath) {
  BakeConfig config;
  Status s = ApplyBakeConfig({{"hulls", {{"delta", 0.2}}}}, "c.json", &config);
  EXPECT_EQ(s.message(), "c.json: /hulls/delta: 0.2 is out of range: must be in [0, 0.1]");
  s = ApplyBakeConfig({{"maps", {{"renderer", "vulkan"}}}}, "c.json", &config);
  EXPECT_EQ(s.message(), "c.json: /maps/renderer: 'vulkan' is not one of cpu | osmesa");
  s = ApplyBakeConfig({{"spheres", {{"cover", "all"}}}}, "c.json", &config);
  EXPECT_EQ(s.message(),
            "c.json: /spheres/cover: 'all' is not one of flexible | left_by_hulls | surface");
  s = ApplyBakeConfig({{"maps", {{"enabled", "yes"}}}}, "c.json", &config);
  EXPECT_EQ(s.message(), "c.json: /maps/enabled: must be true or false, not a string");
  // An unknown key names the keys known where it stands, and the nearest of them.
  s = ApplyBakeConfig({{"hull", {{"delta", 0.01}}}}, "c.json", &config);
  EXPECT_EQ(s.message(),
            "c.json: /hull: unknown key: hull is not a parameter of the top level (did you mean "
            "hulls? known here: import | maps | bone_maps | hulls | spheres | capsules)");
  s = ApplyBakeConfig({{"import", {{"no_such_key", 1}}}}, "c.json", &config);
  EXPECT_EQ(s.message(),
            "c.json: /import/no_such_key: unknown key: no_such_key is not a parameter of /import "
            "(known here: unit_scale | up_axis | clip_sample_rate | rename_duplicate_joints | "
            "memory_limit_mb | time_limit_s)");
  s = ApplyBakeConfig({{"hulls", 3}}, "c.json", &config);
  EXPECT_EQ(s.message(), "c.json: /hulls: must be an object, not a number");
  s = ApplyBakeConfig(nlohmann::json::array(), "c.json", &config);
  EXPECT_EQ(s.message(), "c.json: the config must be a JSON object");
  EXPECT_EQ(BakeConfigToJson(config), BakeConfigToJson(BakeConfig{})) << "refusals change nothing";
}

// The reference prints every float as the shortest decimal that reads back as it (0.005, not
// 0.004999999888241291), and ranges the same way.
// What drape-bake reads from a --config file's bytes: a number beyond a double, a key given
// twice, an unknown section and a config that leaves nothing to bake are refused with the JSON
// path, never thrown or silently resolved.
TEST(BakeConfig, FileBytesAreReadStrictly) {
  BakeConfig config;
  Status s = ParseBakeConfig(R"({"maps": {"resolution": 1e400}})", "c.json", &config);
  EXPECT_EQ(s.message(),
            "c.json: /maps/resolution: the number 1e400 is beyond what a double holds");
  s = ParseBakeConfig(R"({"maps": {"epsilon": [1, -1e999]}})", "c.json", &config);
  EXPECT_EQ(s.message(),
            "c.json: /maps/epsilon/1: the number -1e999 is beyond what a double holds");
  s = ParseBakeConfig(R"({"maps": {"resolution": 64, "resolution": 128}})", "c.json", &config);
  EXPECT_EQ(s.message(), "c.json: /maps/resolution: appears twice in its object");
  s = ParseBakeConfig(R"({"maps": {}, "maps": {}})", "c.json", &config);
  EXPECT_EQ(s.message(), "c.json: /maps: appears twice in its object");
  s = ParseBakeConfig(R"({"mapz": {}})", "c.json", &config);
  EXPECT_EQ(s.message().rfind("c.json: /mapz: unknown key: mapz is not a parameter of the top "
                              "level (did you mean maps?",
                              0),
            0u)
      << s.message();
  s = ParseBakeConfig(
      R"({"maps": {"enabled": false}, "hulls": {"enabled": false}, "spheres": {"enabled": false},
          "capsules": {"enabled": false}})",
      "c.json", &config);
  EXPECT_EQ(s.message(),
            "c.json: /: maps.enabled, bone_maps.enabled, hulls.enabled, spheres.enabled and "
            "capsules.enabled are all false: the asset would hold no collider");
  s = ParseBakeConfig("{\"maps\": ", "c.json", &config);
  EXPECT_EQ(s.message().rfind("c.json: not valid JSON: ", 0), 0u) << s.message();
  EXPECT_EQ(config.maps.resolution, BakeConfig{}.maps.resolution);  // untouched by the failures
  s = ParseBakeConfig(R"({"maps": {"resolution": 64}})", "c.json", &config);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(config.maps.resolution, 64u);
}

TEST(BakeConfig, ReferenceNumbersAreTheShortestDecimals) {
  const nlohmann::json reference = BakeConfigReference();
  EXPECT_EQ(reference["hulls"]["delta"]["default"].dump(), "0.005");
  EXPECT_EQ(reference["hulls"]["delta"]["range"], "[0, 0.1]");
  EXPECT_EQ(reference["hulls"]["delta"]["unit"], "m");
  EXPECT_EQ(reference["hulls"]["rigid_threshold"]["default"].dump(), "0.99");
  EXPECT_EQ(reference["hulls"]["rigid_threshold"]["range"], "(0.5, 1]");
  EXPECT_EQ(reference["import"]["unit_scale"]["range"], "[0, 1e6]");
  EXPECT_EQ(reference["maps"]["renderer"]["range"], "cpu | osmesa");
  EXPECT_EQ(reference["maps"]["enabled"]["range"], "true | false");
  EXPECT_EQ(BakeConfigToJson(BakeConfig{})["spheres"]["delta"].dump(), "0.005");
}

// FloatJson's decimal is read back as a double, then rounded to float: x itself for every float.
TEST(BakeConfig, FloatJsonReadsBackAsTheSameFloat) {
  uint32_t state = 12345;
  for (int i = 0; i < 200000; ++i) {
    state = state * 1664525u + 1013904223u;
    float x = 0.f;
    std::memcpy(&x, &state, sizeof(x));
    if (!std::isfinite(x)) continue;
    const nlohmann::json written = FloatJson(x);
    const float read = static_cast<float>(nlohmann::json::parse(written.dump()).get<double>());
    ASSERT_EQ(read, x) << written.dump();
  }
  EXPECT_EQ(FloatJson(0.1f).dump(), "0.1");
  EXPECT_EQ(FloatJson(1.f / 60.f).dump(), "0.016666668");
  EXPECT_EQ(FormatNumber(1e5), "1e5");
  EXPECT_EQ(FormatNumber(1e-7), "1e-7");
  EXPECT_EQ(FormatNumber(8192), "8192");
  EXPECT_EQ(FormatNumber(-9.81), "-9.81");
}

TEST(BakeConfig, ReferenceListsEveryParameterWithItsDefault) {
  const nlohmann::json reference = BakeConfigReference();
  const nlohmann::json defaults = BakeConfigToJson(BakeConfig{});
  for (const auto& [section, keys] : defaults.items()) {
    for (const auto& [key, value] : keys.items()) {
      ASSERT_TRUE(reference.contains(section) && reference[section].contains(key))
          << section << "." << key;
      EXPECT_EQ(reference[section][key]["default"], value) << section << "." << key;
      EXPECT_FALSE(reference[section][key]["range"].get<std::string>().empty());
    }
  }
}

TEST(BakeConfig, MapsLayersIsACountFromOneToFour) {
  BakeConfig config;
  EXPECT_EQ(config.maps.layers, 4) << "the slab and up to three air gaps by default";
  EXPECT_EQ(BakeConfigReference()["maps"]["layers"]["range"], "[1, 4]");
  Status s = ApplyBakeConfig({{"maps", {{"layers", 3}}}}, "c.json", &config);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(config.maps.layers, 3);
  EXPECT_EQ(BakeConfigToJson(config)["maps"]["layers"], 3);
  for (const nlohmann::json& bad :
       {nlohmann::json(0), nlohmann::json(5), nlohmann::json(-1), nlohmann::json(256),
        nlohmann::json(2.5), nlohmann::json("two")}) {
    s = ApplyBakeConfig({{"maps", {{"layers", bad}}}}, "c.json", &config);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << bad.dump();
    EXPECT_EQ(s.message().rfind("c.json: /maps/layers: ", 0), 0u) << s.message();
    EXPECT_NE(s.message().find("[1, 4]"), std::string::npos) << s.message();
    EXPECT_EQ(config.maps.layers, 3) << "a refused config changes nothing";
  }
}

TEST(BakeConfig, MapsViewAxisAndMaxError) {
  BakeConfig config;
  EXPECT_EQ(config.maps_view_axis, BakeConfig::MapViewAxis::kAuto);
  EXPECT_EQ(config.maps_max_error_mm, 0.f) << "off: maps.resolution and maps.layers as given";
  Status s =
      ApplyBakeConfig({{"maps", {{"view_axis", "y"}, {"max_error", 1.5}}}}, "c.json", &config);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(config.maps_view_axis, BakeConfig::MapViewAxis::kY);
  EXPECT_EQ(config.maps_max_error_mm, 1.5f);
  EXPECT_EQ(BakeConfigToJson(config)["maps"]["view_axis"], "y");
  s = ApplyBakeConfig({{"maps", {{"view_axis", "w"}}}}, "c.json", &config);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(s.message().rfind("c.json: /maps/view_axis: ", 0), 0u) << s.message();
  s = ApplyBakeConfig({{"maps", {{"max_error", -1}}}}, "c.json", &config);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(s.message().rfind("c.json: /maps/max_error: ", 0), 0u) << s.message();
  EXPECT_EQ(config.maps_view_axis, BakeConfig::MapViewAxis::kY) << "refused: nothing changes";
  EXPECT_EQ(config.maps_max_error_mm, 1.5f);
}

TEST(BakeConfig, MapsRenderTolerance) {
  BakeConfig config;
  EXPECT_EQ(config.maps_render_tolerance, 0.001f) << "1 mm by default";
  ASSERT_TRUE(ApplyBakeConfig({{"maps", {{"render_tolerance", 0}}}}, "c.json", &config).ok());
  EXPECT_EQ(config.maps_render_tolerance, 0.f) << "0: no render mesh";
  const Status s = ApplyBakeConfig({{"maps", {{"render_tolerance", 0.5}}}}, "c.json", &config);
  EXPECT_EQ(s.message(),
            "c.json: /maps/render_tolerance: 0.5 is out of range: must be in [0, 0.1]");
  EXPECT_EQ(config.maps_render_tolerance, 0.f) << "refused: nothing changes";
}

TEST(BakeConfig, MapsAssetBudget) {
  BakeConfig config;
  EXPECT_EQ(config.maps_asset_budget_mb, 8.f) << "8 MB by default";
  ASSERT_TRUE(ApplyBakeConfig({{"maps", {{"asset_budget_mb", 0}}}}, "c.json", &config).ok());
  EXPECT_EQ(config.maps_asset_budget_mb, 0.f) << "0: none";
  const Status s = ApplyBakeConfig({{"maps", {{"asset_budget_mb", -2}}}}, "c.json", &config);
  EXPECT_EQ(s.message().rfind("c.json: /maps/asset_budget_mb: -2 is out of range", 0), 0u)
      << s.message();
}

TEST(NameSuggestions, IgnoreCaseAndThePrefixEveryNameShares) {
  using detail::NearestNames;
  // Game rigs prefix every joint: the prefix does not count, and neither does case.
  const std::vector<std::string> mixamo = {
      "mixamorig:Hips",    "mixamorig:Spine",       "mixamorig:Spine1", "mixamorig:Spine2",
      "mixamorig:LeftArm", "mixamorig:LeftForeArm", "mixamorig:Head"};
  EXPECT_EQ(NearestNames("spine", mixamo, 4),
            (std::vector<std::string>{"mixamorig:Spine", "mixamorig:Spine1", "mixamorig:Spine2"}));
  EXPECT_EQ(NearestNames("LeftArm", mixamo, 4), (std::vector<std::string>{"mixamorig:LeftArm"}));
  EXPECT_EQ(NearestNames("mixamorig:leftarm", mixamo, 4),
            (std::vector<std::string>{"mixamorig:LeftArm"}));
  const std::vector<std::string> prefixed = {"B_Hip", "B_Spine", "B_Spine1", "B_Head", "B_L_Thigh"};
  EXPECT_EQ(NearestNames("hips", prefixed, 4), (std::vector<std::string>{"B_Hip"}));
  EXPECT_EQ(NearestNames("B_Spien", prefixed, 1), (std::vector<std::string>{"B_Spine"}));
  // Nothing near: no suggestion rather than a random one.
  EXPECT_TRUE(NearestNames("tail", prefixed, 4).empty());
  EXPECT_TRUE(NearestNames("x", {}, 4).empty());
}

TEST(BakeConfig, AClipNamedInAConfigIsRefusedWhereItWasNamed) {
  BakeConfig config;
  EXPECT_EQ(config.maps_clip_origin, "");
  ASSERT_TRUE(ParseBakeConfig(R"({"maps": {"clip": "walk"}})", "c.json", &config).ok());
  EXPECT_EQ(config.maps_clip, "walk");
  EXPECT_EQ(config.maps_clip_origin, "c.json: /maps/clip");
}

}  // namespace
}  // namespace drape::bake

// The bake config: JSON-path errors, and a config written back out reads in again unchanged,
// including float values at the bounds of their ranges (a fuzzer-found regression: 0.1 m became
// 0.100000001 m in float and was then refused as above the 0.1 m bound).

#include <gtest/gtest.h>

#include "drape/bake/bake_config.h"

namespace drape::bake {
namespace {

TEST(BakeConfig, FloatsAtTheirBoundsRoundTrip) {
  BakeConfig config;
  const nlohmann::json bounds = {
      {"hulls", {{"delta", 0.1}, {"max_growth", 1.0}}},
      {"maps", {{"epsilon", 0.1}, {"margin", 1.0}, {"clip_rate", 1000.0}}},
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
  EXPECT_EQ(s.message(), "c.json: /hulls/delta must be in [0.0, 0.1]");
  s = ApplyBakeConfig({{"maps", {{"renderer", "vulkan"}}}}, "c.json", &config);
  EXPECT_NE(s.message().find("c.json: /maps/renderer 'vulkan' is not one of cpu | osmesa"),
            std::string::npos)
      << s.message();
  s = ApplyBakeConfig({{"spheres", {{"cover", "all"}}}}, "c.json", &config);
  EXPECT_NE(s.message().find("c.json: /spheres/cover 'all' is not one of flexible | left_by_hulls"),
            std::string::npos)
      << s.message();
  s = ApplyBakeConfig({{"hull", {{"delta", 0.01}}}}, "c.json", &config);
  EXPECT_NE(s.message().find("/hull/delta is not a parameter"), std::string::npos) << s.message();
  s = ApplyBakeConfig({{"hulls", 3}}, "c.json", &config);
  EXPECT_NE(s.message().find("/hulls must be an object"), std::string::npos) << s.message();
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
  EXPECT_EQ(config.maps.layers, 1) << "paper A's slab alone by default";
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
    EXPECT_NE(s.message().find("c.json: /maps/layers must be"), std::string::npos) << s.message();
    EXPECT_NE(s.message().find("[1, 4]"), std::string::npos) << s.message();
    EXPECT_EQ(config.maps.layers, 3) << "a refused config changes nothing";
  }
}

}  // namespace
}  // namespace drape::bake

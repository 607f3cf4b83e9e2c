#pragma once
// The proxy colliders' fit targets, as docs/PERFORMANCE.md states them ("Proxy colliders"): bloat
// p99 <= 10 mm and max <= 30 mm beyond delta, coverage >= 99 %, checked on a bake report's "fit".

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

namespace drape::test {

inline void ExpectFitTargets(const nlohmann::json& fit) {
  EXPECT_LE(fit["bloat_p99_mm"].get<double>(), 10.0);
  EXPECT_LE(fit["bloat_max_mm"].get<double>(), 30.0);
  EXPECT_GE(fit["coverage"].get<double>(), 0.99);
}

}  // namespace drape::test

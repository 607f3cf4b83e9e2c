// The body maps' normal encodings (drape/runtime/normal_encoding.h): oct16's round trip and the
// colour encoding's decode.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "body_map_test_fixtures.h"
#include "workers.h"

namespace drape {
namespace {

using namespace test;

TEST(Oct16, RoundTripErrorBelowFiveThousandthsOfADegree) {
  std::mt19937 rng(7);
  std::normal_distribution<float> gauss;
  double worst = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const Float3 n = NormalizeOr({gauss(rng), gauss(rng), gauss(rng)}, {0.f, 0.f, 1.f});
    const std::array<uint16_t, 2> q = EncodeOct16(n);
    worst = std::max(worst, AngleDegrees(n, DecodeOct16(q[0], q[1])));
  }
  EXPECT_LT(worst, 0.005);  // measured: 0.0037 degrees at most
  const Float3 axes[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const Float3& a : axes) {
    const std::array<uint16_t, 2> q = EncodeOct16(a);
    EXPECT_LT(AngleDegrees(a, DecodeOct16(q[0], q[1])), 0.005);
  }
  EXPECT_LT(AngleDegrees(DecodeRgb8(128, 128, 255), {0.f, 0.f, 1.f}), 0.5);
}

}  // namespace
}  // namespace drape

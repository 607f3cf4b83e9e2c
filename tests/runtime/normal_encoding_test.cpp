// The body maps' normal encodings (drape/runtime/normal_encoding.h): oct16's round trip, the
// renderer's four-lane encoder against the scalar one, and the colour encoding's decode.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "body_map/texel_normal_lanes.h"
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

#if defined(__SSE2__)
// The renderer encodes four texel normals at a time; each lane must be EncodeOct16 bit for bit,
// rounding ties, the fold of the lower hemisphere, signed zeros and unusable input included.
TEST(Oct16, FourLanesEncodeAsTheScalar) {
  std::mt19937 rng(11);
  std::normal_distribution<float> gauss;
  std::uniform_int_distribution<int> pick(0, 11);
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float specials[12] = {0.f,   -0.f, 1.f,  -1.f, 1e-31f, -1e-31f,
                              1e30f, inf,  -inf, nan,  0.5f,   -0.25f};
  // Components that land exactly on a quantisation half step: (q + 1/2) / 65535 * 2 - 1.
  const auto half_step = [](int q) { return (float(q) + 0.5f) / 65535.f * 2.f - 1.f; };
  uint64_t compared = 0;
  for (int round = 0; round < 20000; ++round) {
    Float3 n[4];
    for (Float3& v : n) {
      v = {gauss(rng), gauss(rng), gauss(rng)};
      if (round % 4 == 1) v.x = specials[pick(rng)];
      if (round % 4 == 2) v = {half_step(pick(rng) * 5000), half_step(pick(rng) * 4000), 0.1f};
      if (round % 4 == 3) v.z = -std::fabs(v.z);
    }
    detail::NormalLanes lanes{_mm_setr_ps(n[0].x, n[1].x, n[2].x, n[3].x),
                              _mm_setr_ps(n[0].y, n[1].y, n[2].y, n[3].y),
                              _mm_setr_ps(n[0].z, n[1].z, n[2].z, n[3].z)};
    uint32_t codes[4];
    detail::EncodeOct16Lanes(lanes, codes);
    for (int l = 0; l < 4; ++l) {
      const std::array<uint16_t, 2> q = EncodeOct16(n[l]);
      ASSERT_EQ(codes[l], uint32_t{q[0]} | uint32_t{q[1]} << 16)
          << n[l].x << " " << n[l].y << " " << n[l].z;
      ++compared;
    }
  }
  EXPECT_EQ(compared, 80000u);
}
#endif

}  // namespace
}  // namespace drape

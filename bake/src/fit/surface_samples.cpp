#include "fit/surface_samples.h"

#include <algorithm>
#include <cmath>

namespace drape::bake {

void SampleTriangles(std::span<const double> positions, std::span<const uint32_t> triangles,
                     uint32_t count, uint64_t seed, std::vector<double>* points) {
  const size_t triangle_count = triangles.size() / 3;
  // Running sum of the areas (twice the area: the cross product's length); a triangle owns the
  // interval (cumulative[t - 1], cumulative[t]].
  std::vector<double> cumulative(triangle_count);
  double total = 0.0;
  for (size_t t = 0; t < triangle_count; ++t) {
    const double* a = &positions[3 * size_t{triangles[3 * t]}];
    const double* b = &positions[3 * size_t{triangles[3 * t + 1]}];
    const double* c = &positions[3 * size_t{triangles[3 * t + 2]}];
    const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                         e1[0] * e2[1] - e1[1] * e2[0]};
    total += std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    cumulative[t] = total;
  }
  if (!(total > 0.0) || !std::isfinite(total)) return;
  SplitMix64 random(seed);
  points->reserve(points->size() + 3 * size_t{count});
  for (uint32_t i = 0; i < count; ++i) {
    const double pick = random.Uniform() * total;
    // The first triangle whose running sum exceeds the pick: never a zero-area one.
    const size_t t = std::min<size_t>(
        std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin(),
        triangle_count - 1);
    // Uniform in the triangle: barycentrics (1 - sqrt(u), sqrt(u) (1 - v), sqrt(u) v).
    const double root = std::sqrt(random.Uniform());
    const double v = random.Uniform();
    const double wa = 1.0 - root, wb = root * (1.0 - v), wc = root * v;
    const double* a = &positions[3 * size_t{triangles[3 * t]}];
    const double* b = &positions[3 * size_t{triangles[3 * t + 1]}];
    const double* c = &positions[3 * size_t{triangles[3 * t + 2]}];
    for (int k = 0; k < 3; ++k) points->push_back(wa * a[k] + wb * b[k] + wc * c[k]);
  }
}

void SampleSphere(const double centre[3], double radius, uint32_t count,
                  std::vector<double>* points) {
  const double golden_angle = M_PI * (3.0 - std::sqrt(5.0));
  points->reserve(points->size() + 3 * size_t{count});
  for (uint32_t i = 0; i < count; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / count;
    const double ring = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double longitude = golden_angle * i;
    points->push_back(centre[0] + radius * ring * std::cos(longitude));
    points->push_back(centre[1] + radius * z);
    points->push_back(centre[2] + radius * ring * std::sin(longitude));
  }
}

}  // namespace drape::bake

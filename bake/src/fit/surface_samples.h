#pragma once
// Deterministic points on surfaces, for the fit measure (fit/collider_fit.h): the same points on
// every platform and at any thread count. The generator is our own (SplitMix64) and so is the
// mapping to [0, 1): the standard library's distributions give different numbers in different
// library implementations.

#include <cstdint>
#include <span>
#include <vector>

namespace drape::bake {

// Steele, Lea and Flood's SplitMix64: a 64-bit state advanced by a constant, mixed on output.
class SplitMix64 {
 public:
  explicit SplitMix64(uint64_t seed) : state_(seed) {}
  uint64_t Next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1): the top 53 bits as a double.
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }

 private:
  uint64_t state_;
};

// Appends `count` points (3 doubles each, metres) uniformly distributed over the area of the
// triangles: a triangle is chosen with probability proportional to its area, the point uniformly
// inside it. positions: 3 doubles per vertex; triangles: index triples into it (every index in
// range). Zero-area triangles get no point; a surface of zero area gets none at all.
void SampleTriangles(std::span<const double> positions, std::span<const uint32_t> triangles,
                     uint32_t count, uint64_t seed, std::vector<double>* points);

// Appends `count` points spread evenly over the sphere (a Fibonacci lattice: equal-area bands in
// z, golden-angle steps in longitude; the first and last within 1/count of the poles).
void SampleSphere(const double centre[3], double radius, uint32_t count,
                  std::vector<double>* points);

}  // namespace drape::bake

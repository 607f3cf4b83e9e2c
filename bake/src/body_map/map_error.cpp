#include "body_map/map_error.h"

#include <algorithm>
#include <cmath>
#include <span>

#include "drape/bake/mesh_reference.h"
#include "drape/runtime/body_map_collider.h"
#include "fit/surface_samples.h"

namespace drape::bake {
namespace {

constexpr double kShellMetres = 0.01;  // surface samples move up to this far
constexpr double kBoxGrowth = 0.1;     // the box samples' box, widened by this of its size
constexpr uint64_t kSurfaceSeed = 0x6d61705f65727231ull, kBoxSeed = 0x6d61705f65727232ull;
// The winding number's accuracy: as the fit measure's (fit/collider_fit.h), right on every point
// whose exact winding number is farther than 0.1 from 1/2.
constexpr double kWindingBeta = 2.0;

// A direction uniform on the sphere (Archimedes: z uniform, longitude uniform).
void RandomDirection(SplitMix64& rng, double d[3]) {
  const double z = 2.0 * rng.Uniform() - 1.0, phi = 2.0 * 3.14159265358979323846 * rng.Uniform();
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  d[0] = r * std::cos(phi);
  d[1] = r * std::sin(phi);
  d[2] = z;
}

}  // namespace

MapErrorSamples SampleMapError(std::span<const Float3> positions,
                               std::span<const uint32_t> triangles, uint32_t count) {
  MapErrorSamples out;
  std::vector<double> vertices;
  vertices.reserve(3 * positions.size());
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  for (const Float3& p : positions) {
    const double c[3] = {p.x, p.y, p.z};
    for (int k = 0; k < 3; ++k) {
      vertices.push_back(c[k]);
      lo[k] = std::min(lo[k], c[k]);
      hi[k] = std::max(hi[k], c[k]);
    }
  }
  std::vector<double> surface;
  SampleTriangles(vertices, triangles, count / 2, kSurfaceSeed, &surface);
  SplitMix64 shell(kSurfaceSeed);
  for (size_t s = 0; s + 2 < surface.size(); s += 3) {
    double d[3];
    RandomDirection(shell, d);
    const double r = kShellMetres * shell.Uniform();
    out.points.push_back({static_cast<float>(surface[s] + r * d[0]),
                          static_cast<float>(surface[s + 1] + r * d[1]),
                          static_cast<float>(surface[s + 2] + r * d[2])});
  }
  out.shell_count = out.points.size();
  SplitMix64 box(kBoxSeed);
  const uint32_t box_count = count - static_cast<uint32_t>(out.points.size());
  for (uint32_t s = 0; s < box_count && !positions.empty(); ++s) {
    double c[3];
    for (int k = 0; k < 3; ++k) {
      const double grow = kBoxGrowth * (hi[k] - lo[k]);
      c[k] = lo[k] - grow + (hi[k] - lo[k] + 2.0 * grow) * box.Uniform();
    }
    out.points.push_back(
        {static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2])});
  }
  WindingNumberOptions winding;
  winding.beta = kWindingBeta;
  const MeshReference body(positions, triangles, winding);
  out.inside.resize(out.points.size());
  out.distance.resize(out.points.size());
#pragma omp parallel for schedule(dynamic, 256)
  for (int64_t i = 0; i < static_cast<int64_t>(out.points.size()); ++i) {
    const double q[3] = {out.points[i].x, out.points[i].y, out.points[i].z};
    out.inside[i] = body.Inside(q) ? 1 : 0;
    out.distance[i] = body.Distance(q);
  }
  return out;
}

MapError MeasureMapError(const BodyMapPose& pose, float epsilon, const MapErrorSamples& samples) {
  MapError error;
  BodyMapCollider maps;
  if (!maps.Build(pose).ok()) return error;
  const double band = static_cast<double>(epsilon) + 2.0 * pose.texel_size;
  std::vector<double> errors(samples.points.size(), 0.0);
  size_t beyond = 0, beyond_wrong = 0;
  for (size_t i = 0; i < samples.points.size(); ++i) {
    const bool maps_inside = maps.IsInside(samples.points[i]);
    const bool inside = samples.inside[i] != 0;
    const double d = samples.distance[i];
    // Against the surface the maps stand for, the body offset by epsilon: signed distance s
    // (negative inside the body), inside it where s < epsilon.
    const double s = inside ? -d : d;
    if (maps_inside != (s < epsilon)) errors[i] = std::fabs(s - epsilon);
    if (d > band) {
      ++beyond;
      beyond_wrong += maps_inside != inside ? 1 : 0;
    }
  }
  error.samples = static_cast<uint32_t>(errors.size());
  // The larger p99 of the two kinds of sample: near the surface, where texels decide, and in
  // the box, where air a slab fills does.
  const auto p99 = [](std::span<double> part) {
    if (part.empty()) return 0.0;
    std::sort(part.begin(), part.end());
    return part[std::min(part.size() - 1, (part.size() * 99 + 99) / 100 - 1)];
  };
  const std::span<double> all(errors);
  const size_t shell = std::min<size_t>(samples.shell_count, errors.size());
  error.max_mm = errors.empty() ? 0.0 : *std::max_element(errors.begin(), errors.end()) * 1e3;
  error.p99_mm = std::max(p99(all.first(shell)), p99(all.subspan(shell))) * 1e3;
  error.misclassified_beyond_band =
      beyond == 0 ? 0.0 : static_cast<double>(beyond_wrong) / static_cast<double>(beyond);
  return error;
}

Status ChooseMapSetting(std::span<const Float3> positions, std::span<const uint32_t> triangles,
                        const BodyMapOptions& options, double max_error_mm,
                        MapSettingChoice* choice) {
  const MapErrorSamples samples = SampleMapError(positions, triangles);
  MapSettingChoice result;
  size_t best = 0;  // index into result.tried
  for (uint32_t resolution : {256u, 512u, 1024u, 2048u}) {
    for (uint8_t layers : {uint8_t{1}, kMaxBodyMapLayers}) {
      BodyMapOptions o = options;
      o.resolution = resolution;
      o.layers = layers;
      BodyMapPose pose;
      BodyMapPoseStats stats;
      if (Status s = BakeBodyMapPose(positions, triangles, o, &pose, &stats); !s.ok()) return s;
      result.tried.push_back(
          {resolution, layers, MeasureMapError(pose, o.epsilon, samples), stats.bytes});
      const MapSettingTried& tried = result.tried.back();
      if (tried.error.p99_mm < result.tried[best].error.p99_mm) best = result.tried.size() - 1;
      if (tried.error.p99_mm <= max_error_mm) {
        result.resolution = resolution;
        result.layers = layers;
        result.error = tried.error;
        result.within_budget = true;
        *choice = std::move(result);
        return Status::Ok();
      }
    }
  }
  result.resolution = result.tried[best].resolution;
  result.layers = result.tried[best].layers;
  result.error = result.tried[best].error;
  *choice = std::move(result);
  return Status::Ok();
}

}  // namespace drape::bake

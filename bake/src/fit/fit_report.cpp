#include "fit/fit_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace drape::bake {
namespace {

// A config value (metres, read as a float) in millimetres to the micrometre: 5, not 4.99999989.
double ConfigMillimetres(double metres) { return std::round(1e6 * metres) / 1e3; }

std::string Millimetres(double mm) {
  char text[32];
  std::snprintf(text, sizeof(text), mm >= 10.0 ? "%.0f mm" : "%.1f mm", mm);
  return text;
}

}  // namespace

void AddBloatToReport(const ColliderBloat& bloat, nlohmann::json* collider) {
  (*collider)["bloat_p99_mm"] = bloat.p99_mm;
  (*collider)["bloat_max_mm"] = bloat.max_mm;
}

nlohmann::json FitToJson(const ColliderFit& fit, const ColliderFitOptions& options,
                         double max_bloat) {
  return {{"coverage", fit.coverage},
          {"bloat_p99_mm", fit.bloat_p99_mm},
          {"bloat_max_mm", fit.bloat_max_mm},
          {"body_samples", fit.body_samples},
          {"collider_samples", fit.collider_samples},
          {"hull_delta_mm", ConfigMillimetres(options.hull_delta)},
          {"sphere_delta_mm", ConfigMillimetres(options.sphere_delta)},
          {"coverage_tolerance_mm", ConfigMillimetres(options.coverage_tolerance)},
          {"max_bloat_mm", ConfigMillimetres(max_bloat)}};
}

std::vector<std::string> FitWarnings(const ColliderFit& fit, const ColliderFitOptions& options,
                                     std::span<const std::string> hull_names,
                                     std::span<const std::string> sphere_names, double max_bloat) {
  struct Bulge {
    double mm;
    std::string what;
  };
  std::vector<Bulge> bulges;
  const double limit_mm = 1000.0 * max_bloat;
  for (size_t h = 0; h < fit.hulls.size() && h < hull_names.size(); ++h) {
    if (fit.hulls[h].max_mm > limit_mm)
      bulges.push_back({fit.hulls[h].max_mm, "hull '" + hull_names[h] + "'"});
  }
  for (size_t s = 0; s < fit.spheres.size() && s < sphere_names.size(); ++s) {
    if (fit.spheres[s].max_mm > limit_mm)
      bulges.push_back({fit.spheres[s].max_mm, "joint sphere '" + sphere_names[s] + "'"});
  }
  // Worst first; equal bloats keep the hulls-then-spheres order.
  std::stable_sort(bulges.begin(), bulges.end(),
                   [](const Bulge& a, const Bulge& b) { return a.mm > b.mm; });
  std::vector<std::string> warnings;
  if (!bulges.empty()) {
    const bool one = bulges.size() == 1;
    std::string line = std::to_string(bulges.size()) +
                       (one ? " collider bulges" : " colliders bulge") +
                       " outside the body by more than hulls.max_bloat (" + Millimetres(limit_mm) +
                       (one ? ", beyond its delta): " : ", beyond their delta): ");
    for (size_t k = 0; k < bulges.size(); ++k) {
      line += (k > 0 ? ", " : "") + bulges[k].what + " up to " + Millimetres(bulges[k].mm);
    }
    warnings.push_back(line);
  }
  if (fit.coverage < kMinCoverage) {
    char text[256];
    std::snprintf(text, sizeof(text),
                  "the colliders cover %.1f %% of the body's surface (%.0f %% expected; a point "
                  "counts inside a collider or within its delta + %.0f mm): cloth reaches the "
                  "body through the rest",
                  100.0 * fit.coverage, 100.0 * kMinCoverage, 1000.0 * options.coverage_tolerance);
    warnings.push_back(text);
  }
  return warnings;
}

}  // namespace drape::bake

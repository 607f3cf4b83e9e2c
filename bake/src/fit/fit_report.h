#pragma once
// The proxies' fit (fit/collider_fit.h) in the bake report, and the warnings it raises: a
// collider that bulges out of the body beyond hulls.max_bloat, and a body the colliders do not
// cover.

#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "fit/collider_fit.h"

namespace drape::bake {

// Below this coverage the report warns: cloth reaches the body through what is not covered.
inline constexpr double kMinCoverage = 0.99;

// {"bloat_p99_mm", "bloat_max_mm"} set on one collider's report entry.
void AddBloatToReport(const ColliderBloat& bloat, nlohmann::json* collider);

// The report's "fit" object: coverage, bloat over all colliders, the samples and the deltas it
// was measured with, and the max_bloat the warnings compare against (metres in, mm out).
nlohmann::json FitToJson(const ColliderFit& fit, const ColliderFitOptions& options,
                         double max_bloat);

// One line naming every collider whose bloat max exceeds max_bloat (metres), worst first, and
// one when the coverage is under kMinCoverage; nothing when the fit is good. hull_names and
// sphere_names: the bone of each hull and the joint of each sphere, in the fit's order.
std::vector<std::string> FitWarnings(const ColliderFit& fit, const ColliderFitOptions& options,
                                     std::span<const std::string> hull_names,
                                     std::span<const std::string> sphere_names, double max_bloat);

}  // namespace drape::bake

#include "checks.h"

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

namespace drape::bench {

bool CheckAccuracyClaims(const std::vector<Row>& rows, const std::vector<std::string>& violations) {
  bool ok = true;
  std::vector<std::string> humans_without_maps;
  for (const Row& r : rows) {
    if (r.query_set == "all" && r.human &&
        std::find(humans_without_maps.begin(), humans_without_maps.end(), r.character) ==
            humans_without_maps.end()) {
      humans_without_maps.push_back(r.character);
    }
  }
  for (const Row& r : rows) {
    if (r.query_set != "all") continue;
    const Metrics& m = r.metrics;
    if (m.own_surface_misses > 0 && r.setting.find("discrete") == std::string::npos) {
      std::fprintf(stderr, "check: %s %s missed its own surface %ld times\n", r.character.c_str(),
                   r.setting.c_str(), m.own_surface_misses);
      ok = false;
    }
    if (m.batch_mismatches > 0) {
      std::fprintf(stderr,
                   "check: %s %s: the batch differs from one-by-one answers for %ld "
                   "of %zu motions\n",
                   r.character.c_str(), r.setting.c_str(), m.batch_mismatches, m.queries);
      ok = false;
    }
    // Detection only: its response (the entry point, or the nearest surface point for a
    // particle that ends inside) is naive on a self-overlapping mesh: the nearest surface of a
    // point inside a limb sunk into the torso is the limb's, and leaving it lands in the torso.
    if (r.peer && m.has_accuracy && m.missed > 0) {
      std::fprintf(stderr, "check: %s %s missed %zu contacts\n", r.character.c_str(),
                   r.setting.c_str(), m.missed);
      ok = false;
    }
    if (r.family == "maps" && m.has_accuracy && m.penetration_p99_mm <= 2.0 &&
        m.missed_rate <= 0.001) {
      std::erase(humans_without_maps, r.character);
    }
  }
  for (const std::string& v : violations) {
    std::fprintf(stderr, "check: %s\n", v.c_str());
    ok = false;
  }
  for (const std::string& c : humans_without_maps) {
    std::fprintf(stderr, "check: %s: no body-map setting with p99 <= 2 mm and missed <= 0.1 %%\n",
                 c.c_str());
    ok = false;
  }
  return ok;
}

}  // namespace drape::bench

#pragma once
// The accuracy claims drape-speed-vs-error --check holds. They do not depend on the machine or
// its load: timings never fail a check (speed targets live in the report).

#include <string>
#include <vector>

#include "report.h"

namespace drape::bench {

// Every continuous hull setting catches every motion into its own surface; a body-map batch
// answers every motion bit for bit as its Query and response one at a time do; the exact peer,
// measured like a method, misses nothing (the metrics are consistent with their reference); each
// human character has a body-map setting with p99 penetration <= 2 mm and missed rate <= 0.1 %,
// measured on a body no taller than kTallestHuman. `violations` are the query-set contracts the
// mesh did not confirm and the humans measured taller than that. Prints each failed claim on
// stderr; false when any failed.
bool CheckAccuracyClaims(const std::vector<Row>& rows, const std::vector<std::string>& violations);

}  // namespace drape::bench

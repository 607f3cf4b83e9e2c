// drape-speed-vs-error: what each microsecond buys. Every collision method and setting of drape
// (paper A's body maps, paper B's hulls and joint spheres, their combination) and the peers (the
// exact mesh query, FCL) on the same particle motions of real characters, measured against the
// exact posed mesh. Writes speed_vs_error.csv, speed_vs_error.md and PNG charts.
//
//   drape-speed-vs-error --out DIR [--character builtin|all|PATH]... [--queries N] [--quick]
//                        [--check] [--dump-maps]
//
// --check exits 1 when an accuracy claim fails (checks.h); timings never fail it.
//
// The recipe: options.h reads the command line, characters.h finds and imports the characters,
// sweep.h lists the settings, measurement.h measures each setting and the peers on each
// character's query sets (query_sets.h) against the exact mesh (evaluation.h, methods.h),
// report.h writes the tables and charts, checks.h holds the accuracy claims and map_dump.h
// writes drape-replay-maps' inputs.

#include <filesystem>
#include <system_error>

#include "characters.h"
#include "measurement.h"
#include "options.h"

int main(int argc, char** argv) {
  using namespace drape::bench;
  const Options options = ParseOptions(argc, argv);
  std::error_code ec;
  std::filesystem::create_directories(options.out_dir, ec);
  if (ec) Fail(options.out_dir + ": " + ec.message());
  Measurement measurement(options);
  for (const CharacterSpec& spec : ResolveCharacters(options.characters)) {
    measurement.RunCharacter(spec);
  }
  measurement.Finish();
  if (options.check && !measurement.Check()) return 1;
  return 0;
}

#pragma once
// The command line of drape-speed-vs-error:
//
//   drape-speed-vs-error --out DIR [--character builtin|all|PATH]... [--queries N] [--quick]
//                        [--posed] [--check] [--dump-maps]

#include <cstdint>
#include <string>
#include <vector>

namespace drape::bench {

struct Options {
  std::string out_dir;
  std::vector<std::string> characters;  // builtin, all, or paths
  uint32_t queries = 4000;
  bool quick = false;
  bool check = false;
  bool posed = false;      // --posed: the posed bodies in a --quick run too
  bool dump_maps = false;  // --dump-maps: each rest-pose body-map setting and the mix, for replays
};

// Prints `message` after the tool's name on stderr and exits with code 2.
[[noreturn]] void Fail(const std::string& message);

// Exits through Fail on a bad option, with code 0 after --help.
Options ParseOptions(int argc, char** argv);

}  // namespace drape::bench

#include "options.h"

#include <cstdio>
#include <cstdlib>
#include <string>

namespace drape::bench {

void Fail(const std::string& message) {
  std::fprintf(stderr, "drape-speed-vs-error: %s\n", message.c_str());
  std::exit(2);
}

Options ParseOptions(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) Fail(arg + ": needs a value");
      return argv[++i];
    };
    if (arg == "--out") {
      o.out_dir = value();
    } else if (arg == "--character") {
      o.characters.push_back(value());
    } else if (arg == "--queries") {
      const std::string v = value();
      char* end = nullptr;
      const unsigned long n = std::strtoul(v.c_str(), &end, 10);
      if (*end != '\0' || n == 0 || n > 1000000) Fail("--queries " + v + ": not in [1, 1000000]");
      o.queries = static_cast<uint32_t>(n);
    } else if (arg == "--quick") {
      o.quick = true;
    } else if (arg == "--posed") {
      o.posed = true;
    } else if (arg == "--check") {
      o.check = true;
    } else if (arg == "--dump-maps") {
      o.dump_maps = true;
    } else if (arg == "--help" || arg == "-h") {
      std::printf(
          "drape-speed-vs-error --out DIR [--character builtin|all|PATH]... [--queries N] "
          "[--quick] [--posed] [--check] [--dump-maps]\n"
          "  --posed      the posed bodies (two clip times) in a --quick run too\n"
          "  --dump-maps  also write DIR/replay/<character>_mix.motions and, per rest-pose "
          "body-map\n"
          "               setting, <character>_<setting>.drape: drape-replay-maps runs them "
          "alone\n");
      std::exit(0);
    } else {
      Fail(arg + ": unknown option (see --help)");
    }
  }
  if (o.out_dir.empty()) Fail("--out DIR is required");
  if (o.characters.empty()) o.characters.push_back("all");
  return o;
}

}  // namespace drape::bench

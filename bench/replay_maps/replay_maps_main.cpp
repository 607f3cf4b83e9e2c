// drape-replay-maps: one baked body-map pose against one file of motions, through
// BodyMapCollider::CollideBatch and nothing else, so that a profiler or a simulator (perf,
// callgrind --branch-sim=yes) sees only the collider. drape-speed-vs-error --dump-maps writes
// both inputs. Prints the best time per particle over the repetitions and a hash of every
// output bit (positions, velocities, flags), so that two builds can be checked to agree.
//
//   drape-replay-maps ASSET.drape MOTIONS [--repetitions N] [--lanes scalar|sse2|avx2]
//                     [--bilinear] [--threads N] [--check]
//
// --lanes caps the batch's lanes (BodyMapCollider::LimitInstructionSet); by default they are the
// widest the CPU has. --check also answers the motions with every other lane pack the CPU runs
// and one by one (Query, then ApplyResponse), and exits 1 unless every way gives the same bits.
//
// Sampling and lanes are the runtime's choices, not the asset's: a dumped setting named
// "bilinear" or "SSE2 lanes" replays as such with --bilinear or --lanes sse2.

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "drape/formats/asset_file.h"
#include "drape/runtime/body_map_collider.h"
#include "motions_file.h"

namespace {

using namespace drape;

[[noreturn]] void Fail(const std::string& message) {
  std::fprintf(stderr, "drape-replay-maps: %s\n", message.c_str());
  std::exit(2);
}

// The lanes a collider may take, capped at `lanes` ("scalar", "sse2", "avx2").
void CapLanes(BodyMapCollider* collider, const std::string& lanes) {
  collider->LimitInstructionSet(lanes == "scalar" ? InstructionSet::kScalar
                                : lanes == "sse2" ? InstructionSet::kSse2
                                                  : InstructionSet::kAvx2);
}

// What the batch of `collider` takes.
const char* LanesName(const BodyMapCollider& collider, bool bilinear) {
  if (bilinear) return "no";
  switch (collider.instruction_set()) {
    case InstructionSet::kAvx2:
      return "eight AVX2";
    case InstructionSet::kSse2:
      return "four SSE2";
    case InstructionSet::kScalar:
      return "four scalar";
  }
  return "unknown";
}

uint32_t ParseCount(const std::string& option, const std::string& text, uint32_t limit) {
  char* end = nullptr;
  const unsigned long n = std::strtoul(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || n == 0 || n > limit) {
    Fail(option + " " + text + ": not in [1, " + std::to_string(limit) + "]");
  }
  return static_cast<uint32_t>(n);
}

// FNV-1a over bytes.
uint64_t Hash(uint64_t h, const void* data, size_t size) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < size; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

// Every output bit of one pass: positions, velocities, flags.
uint64_t HashOutputs(const std::vector<Float3>& positions, const std::vector<Float3>& velocities,
                     const std::vector<uint8_t>& flags) {
  uint64_t h = 1469598103934665603ull;
  h = Hash(h, positions.data(), positions.size() * sizeof(Float3));
  h = Hash(h, velocities.data(), velocities.size() * sizeof(Float3));
  return Hash(h, flags.data(), flags.size());
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> paths;
  uint32_t repetitions = 5, threads = 1;
  std::string lanes = "avx2";
  bool bilinear = false, check = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) Fail(arg + ": needs a value");
      return argv[++i];
    };
    if (arg == "--repetitions") {
      repetitions = ParseCount(arg, value(), 1000000);
    } else if (arg == "--threads") {
      threads = ParseCount(arg, value(), 256);
    } else if (arg == "--lanes") {
      lanes = value();
      if (lanes != "scalar" && lanes != "sse2" && lanes != "avx2") {
        Fail("--lanes " + lanes + ": not scalar, sse2 or avx2");
      }
    } else if (arg == "--bilinear") {
      bilinear = true;
    } else if (arg == "--check") {
      check = true;
    } else if (arg == "--help" || arg == "-h") {
      std::printf(
          "drape-replay-maps ASSET.drape MOTIONS [--repetitions N] [--lanes scalar|sse2|avx2] "
          "[--bilinear] [--threads N] [--check]\n");
      return 0;
    } else if (!arg.empty() && arg[0] == '-') {
      Fail(arg + ": unknown option (see --help)");
    } else {
      paths.push_back(arg);
    }
  }
  if (paths.size() != 2) Fail("needs ASSET.drape and MOTIONS (see --help)");

  CharacterAsset asset;
  if (const Status s = ReadAssetFile(paths[0], &asset); !s.ok()) Fail(s.message());
  if (asset.body_maps.poses.empty()) Fail(paths[0] + ": holds no body-map pose");
  BodyMapCollider collider;
  CapLanes(&collider, lanes);
  if (const Status s = collider.Build(
          asset.body_maps.poses[0], bilinear ? DepthSampling::kBilinear : DepthSampling::kNearest);
      !s.ok()) {
    Fail(paths[0] + ": " + s.message());
  }

  std::ifstream in(paths[1], std::ios::binary);
  if (!in) Fail(paths[1] + ": cannot open (missing or unreadable)");
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  bench::Motions motions;
  if (const std::string why = bench::DecodeMotions(bytes, &motions); !why.empty()) {
    Fail(paths[1] + ": " + why);
  }

  // The step and the response the motions were measured with (the file holds them).
  const size_t count = motions.current.size();
  std::vector<Float3> start_velocities(count), positions(count), velocities(count);
  for (size_t k = 0; k < count; ++k) {
    start_velocities[k] = (motions.current[k] - motions.previous[k]) * (1.f / motions.step_seconds);
  }
  std::vector<uint8_t> flags(count);
  const ResponseParams params = motions.response;
  omp_set_num_threads(static_cast<int>(threads));
  double best = std::numeric_limits<double>::infinity();
  uint64_t hash = 0;
  for (uint32_t r = 0; r <= repetitions; ++r) {  // the first run warms caches, not counted
    positions = motions.current;
    velocities = start_velocities;
    const auto begin = std::chrono::steady_clock::now();
    if (const Status s =
            collider.CollideBatch(motions.previous, positions, velocities, flags, params);
        !s.ok()) {
      Fail(s.message());
    }
    const auto end = std::chrono::steady_clock::now();
    if (r > 0) best = std::min(best, std::chrono::duration<double, std::nano>(end - begin).count());
    if (r == 0) hash = HashOutputs(positions, velocities, flags);
  }
  size_t contacts = 0;
  for (uint8_t f : flags) contacts += (f & kCollisionContact) != 0;
  std::printf(
      "%zu motions, %zu contacts, %.2f ns per particle (best of %u, %s lanes, %u thread%s), "
      "output hash %016llx\n",
      count, contacts, best / static_cast<double>(count), repetitions,
      LanesName(collider, bilinear), threads, threads == 1 ? "" : "s",
      static_cast<unsigned long long>(hash));
  if (!check) return 0;

  // The same motions the other ways: every lane pack the CPU runs, and one by one.
  bool agree = true;
  for (const char* other_lanes : {"scalar", "sse2", "avx2"}) {
    if (bilinear) break;
    BodyMapCollider other;
    CapLanes(&other, other_lanes);
    if (const Status s = other.Build(asset.body_maps.poses[0], DepthSampling::kNearest); !s.ok()) {
      Fail(paths[0] + ": " + s.message());
    }
    positions = motions.current;
    velocities = start_velocities;
    if (const Status s = other.CollideBatch(motions.previous, positions, velocities, flags, params);
        !s.ok()) {
      Fail(s.message());
    }
    const uint64_t other_hash = HashOutputs(positions, velocities, flags);
    std::printf("check: %s lanes %016llx\n", LanesName(other, false),
                static_cast<unsigned long long>(other_hash));
    agree = agree && other_hash == hash;
  }
  positions = motions.current;
  velocities = start_velocities;
  for (size_t k = 0; k < count; ++k) {
    if (!IsFinite(motions.previous[k]) || !IsFinite(positions[k]) || !IsFinite(velocities[k])) {
      flags[k] = kCollisionInvalidInput;
      continue;
    }
    const ContactQuery c = collider.Query(motions.previous[k], positions[k]);
    flags[k] = c.contact ? static_cast<uint8_t>(kCollisionContact | c.flags)
                         : static_cast<uint8_t>(kCollisionNone);
    if (c.contact) ApplyResponse(c, params, &positions[k], &velocities[k]);
  }
  const uint64_t one_by_one = HashOutputs(positions, velocities, flags);
  std::printf("check: one by one %016llx\n", static_cast<unsigned long long>(one_by_one));
  if (!agree || one_by_one != hash) {
    std::fprintf(stderr, "drape-replay-maps: %s: the answers differ between the ways\n",
                 paths[0].c_str());
    return 1;
  }
  return 0;
}

#pragma once
// A file of particle motions (previous -> current positions, metres, asset frame) with the step
// and the response they were measured with, for replays: drape-speed-vs-error --dump-maps writes
// its mix, drape-replay-maps reads it and runs exactly what the tool timed.
//
// Layout, little-endian: "DRAPEMOT" (8 bytes), uint32 version (1), uint32 zero, uint64 count,
// float step_seconds, friction, restitution, separation, then count float triples of previous
// positions and count of current ones.

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "drape/formats/types.h"
#include "drape/runtime/collision_types.h"

namespace drape::bench {

struct Motions {
  std::vector<Float3> previous, current;
  float step_seconds = 0.f;  // the velocities are (current - previous) / step_seconds; > 0
  ResponseParams response;
};

inline constexpr char kMotionsMagic[8] = {'D', 'R', 'A', 'P', 'E', 'M', 'O', 'T'};
inline constexpr uint32_t kMotionsVersion = 1;
inline constexpr size_t kMotionsHeaderBytes = 8 + 4 + 4 + 8 + 4 * 4;

template <class Set>
std::string EncodeMotions(const Set& set, float step_seconds, const ResponseParams& response) {
  static_assert(sizeof(Float3) == 12, "packed float triples");
  const uint64_t count = set.current.size();
  std::string bytes(kMotionsHeaderBytes + 2 * count * sizeof(Float3), '\0');
  char* out = bytes.data();
  const uint32_t version = kMotionsVersion, zero = 0;
  const float step[4] = {step_seconds, response.friction, response.restitution,
                         response.separation};
  std::memcpy(out, kMotionsMagic, 8);
  std::memcpy(out + 8, &version, 4);
  std::memcpy(out + 12, &zero, 4);
  std::memcpy(out + 16, &count, 8);
  std::memcpy(out + 24, step, sizeof(step));
  std::memcpy(out + kMotionsHeaderBytes, set.previous.data(), count * sizeof(Float3));
  std::memcpy(out + kMotionsHeaderBytes + count * sizeof(Float3), set.current.data(),
              count * sizeof(Float3));
  return bytes;
}

// Empty string on success, else why `bytes` is not a motions file.
inline std::string DecodeMotions(const std::string& bytes, Motions* out) {
  if (bytes.size() < kMotionsHeaderBytes || std::memcmp(bytes.data(), kMotionsMagic, 8) != 0) {
    return "not a motions file (no DRAPEMOT header)";
  }
  uint32_t version = 0;
  uint64_t count = 0;
  float step[4] = {};
  std::memcpy(&version, bytes.data() + 8, 4);
  std::memcpy(&count, bytes.data() + 16, 8);
  std::memcpy(step, bytes.data() + 24, sizeof(step));
  if (version != kMotionsVersion) return "motions file version " + std::to_string(version);
  const uint64_t payload = bytes.size() - kMotionsHeaderBytes;
  if (count == 0 || count > payload / (2 * sizeof(Float3)) ||
      payload != 2 * count * sizeof(Float3)) {
    return "the count (" + std::to_string(count) + ") does not match the file's size";
  }
  const auto in_unit = [](float x) { return x >= 0.f && x <= 1.f; };  // false for NaN
  if (!(std::isfinite(step[0]) && step[0] > 0.f) || !in_unit(step[1]) || !in_unit(step[2]) ||
      !(std::isfinite(step[3]) && step[3] >= 0.f)) {
    return "the step (> 0 s) or the response (friction and restitution in [0, 1], separation "
           ">= 0) is out of range";
  }
  out->step_seconds = step[0];
  out->response = {step[1], step[2], step[3]};
  out->previous.resize(count);
  out->current.resize(count);
  std::memcpy(out->previous.data(), bytes.data() + kMotionsHeaderBytes, count * sizeof(Float3));
  std::memcpy(out->current.data(), bytes.data() + kMotionsHeaderBytes + count * sizeof(Float3),
              count * sizeof(Float3));
  return {};
}

}  // namespace drape::bench

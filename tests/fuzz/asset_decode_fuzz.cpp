// libFuzzer target: DecodeAsset on arbitrary bytes must return a status, never crash, hang or
// leak, and a successful decode must re-encode to the same bytes (the writer is deterministic)
// when the input is in the format version the writer writes; an older version (still read)
// re-encodes in the current one, which must decode and re-encode to itself.
// Each input is decoded twice: as it is (the header and checksum checks), and with its two
// checksums recomputed, so that mutations reach the payload decoder and ValidateAsset instead
// of stopping at the CRC. Every body-map pose of a decoded asset is also built into the runtime
// collider (which checks what the validator leaves to it, e.g. the depth order of air gaps) and
// queried once: a file the loader accepts must not crash the runtime either.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "drape/formats/asset_file.h"
#include "drape/runtime/body_map_collider.h"

namespace {

void DecodeAndCheck(const uint8_t* data, size_t size) {
  drape::CharacterAsset asset;
  const drape::Status status = drape::DecodeAsset({data, size}, "fuzz", &asset);
  if (status.ok()) {
    for (const drape::BodyMapPose& pose : asset.body_maps.poses) {
      // Small rectangles only (the seeds' are 17 x 17): Build expands row spans into the dense
      // rectangle, and a few large ones would eat the fixed run's time budget.
      if (static_cast<uint64_t>(pose.width) * pose.height > 4096) continue;
      drape::BodyMapCollider collider;
      if (collider.Build(pose).ok()) {
        const drape::Float3 lo = collider.bounds_min(), hi = collider.bounds_max();
        const drape::Float3 mid{0.5f * (lo.x + hi.x), 0.5f * (lo.y + hi.y), 0.5f * (lo.z + hi.z)};
        (void)collider.Query({lo.x - 0.01f, mid.y, hi.z + 0.01f}, {hi.x + 0.01f, mid.y, lo.z});
        (void)collider.IsInside(mid);
      }
    }
    std::vector<uint8_t> again;
    if (!drape::EncodeAsset(asset, &again).ok()) std::abort();
    const uint32_t version = static_cast<uint32_t>(data[8]) | static_cast<uint32_t>(data[9]) << 8 |
                             static_cast<uint32_t>(data[10]) << 16 |
                             static_cast<uint32_t>(data[11]) << 24;  // header checked: size >= 32
    if (version == drape::kAssetFormatVersion) {
      if (again.size() != size || !std::equal(again.begin(), again.end(), data)) std::abort();
    } else {
      drape::CharacterAsset upgraded;
      std::vector<uint8_t> twice;
      if (!drape::DecodeAsset(again, "fuzz", &upgraded).ok()) std::abort();
      if (!drape::EncodeAsset(upgraded, &twice).ok() || twice != again) std::abort();
    }
  } else if (status.message().rfind("fuzz: ", 0) != 0) {
    std::abort();  // every message names the input
  }
}

void PutU32(uint8_t* out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out[i] = static_cast<uint8_t>(v >> (8 * i));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  DecodeAndCheck(data, size);
  if (size >= drape::kAssetHeaderSize) {
    std::vector<uint8_t> fixed(data, data + size);
    PutU32(&fixed[24],
           drape::Crc32({fixed.data() + drape::kAssetHeaderSize, size - drape::kAssetHeaderSize}));
    PutU32(&fixed[28], drape::Crc32({fixed.data(), 28}));
    DecodeAndCheck(fixed.data(), fixed.size());
  }
  return 0;
}

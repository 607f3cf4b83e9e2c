// libFuzzer target: DecodeAsset on arbitrary bytes must return a status, never crash, hang or
// leak, and a successful decode must re-encode to the same bytes (the writer is deterministic).
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "drape/formats/asset_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  drape::CharacterAsset asset;
  const drape::Status status = drape::DecodeAsset({data, size}, "fuzz", &asset);
  if (status.ok()) {
    std::vector<uint8_t> again;
    if (!drape::EncodeAsset(asset, &again).ok()) std::abort();
    if (again.size() != size || !std::equal(again.begin(), again.end(), data)) std::abort();
  } else if (status.message().rfind("fuzz: ", 0) != 0) {
    std::abort();  // every message names the input
  }
  return 0;
}

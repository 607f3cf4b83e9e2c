// A damaged .drape file is refused whole: every truncation, every single-byte flip, trailing
// bytes, the wrong magic and a count larger than the bytes left give a status naming the file
// and the reason; nothing crashes or half-loads.

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "asset_fixtures.h"
#include "drape/formats/asset_file.h"

namespace drape {
namespace {

using test::Encode;
using test::FixChecksums;
using test::SmallAsset;

TEST(AssetFile, EveryTruncationFailsCleanly) {
  const std::vector<uint8_t> bytes = Encode(SmallAsset());
  for (size_t length = 0; length < bytes.size(); ++length) {
    CharacterAsset out;
    const Status s = DecodeAsset({bytes.data(), length}, "cut.drape", &out);
    ASSERT_FALSE(s.ok()) << "length " << length;
    EXPECT_EQ(s.message().rfind("cut.drape: ", 0), 0u) << s.message();
    EXPECT_TRUE(out.skeleton.joint_names.empty()) << "half-loaded at length " << length;
  }
}

TEST(AssetFile, EverySingleByteFlipIsDetected) {
  const std::vector<uint8_t> bytes = Encode(SmallAsset());
  for (size_t at = 0; at < bytes.size(); ++at) {
    for (uint8_t flip : {uint8_t{0x01}, uint8_t{0x80}, uint8_t{0xFF}}) {
      std::vector<uint8_t> bad = bytes;
      bad[at] ^= flip;
      CharacterAsset out;
      const Status s = DecodeAsset(bad, "flip.drape", &out);
      ASSERT_FALSE(s.ok()) << "byte " << at << " ^ " << int(flip);
    }
  }
}

TEST(AssetFile, TrailingBytesAreRefused) {
  std::vector<uint8_t> bytes = Encode(SmallAsset());
  bytes.push_back(0);
  CharacterAsset out;
  const Status s = DecodeAsset(bytes, "long.drape", &out);
  EXPECT_EQ(s.code(), StatusCode::kTrailingBytes);
  EXPECT_NE(s.message().find("1 bytes after the payload"), std::string::npos) << s.message();
}

TEST(AssetFile, WrongMagicIsRefused) {
  const std::string text = "{\"asset\": {\"version\": \"2.0\"}}";
  CharacterAsset out;
  const Status s =
      DecodeAsset({reinterpret_cast<const uint8_t*>(text.data()), text.size()}, "model.gltf", &out);
  EXPECT_EQ(s.code(), StatusCode::kBadMagic);
  EXPECT_EQ(s.message(), "model.gltf: not a .drape file (wrong magic bytes)");
}

TEST(AssetFile, HugeCountWithValidChecksumDoesNotAllocate) {
  std::vector<uint8_t> bytes = Encode(SmallAsset());
  // The first array in the payload is info.source_name (a string); its uint64 size follows the
  // endianness byte and two uint32 class versions (CharacterAsset, AssetInfo).
  const size_t at = kAssetHeaderSize + 1 + 4 + 4;
  ASSERT_EQ(bytes[at], 10);  // strlen("small.gltf")
  // Lengths a resize would accept (16 GiB, 1 GiB) and one it would refuse (2^64 - 1): each must
  // be refused by the bound on the bytes left, before anything is allocated.
  for (uint64_t length : {uint64_t{1} << 34, uint64_t{1} << 30, ~uint64_t{0}}) {
    std::vector<uint8_t> bad = bytes;
    for (int i = 0; i < 8; ++i) bad[at + i] = static_cast<uint8_t>(length >> (8 * i));
    FixChecksums(bad);
    CharacterAsset out;
    const Status s = DecodeAsset(bad, "huge.drape", &out);
    EXPECT_EQ(s.code(), StatusCode::kCorrupt) << length;
    EXPECT_NE(s.message().find("payload bytes left"), std::string::npos) << s.message();
  }
}

}  // namespace
}  // namespace drape

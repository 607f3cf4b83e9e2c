#pragma once
// The .drape container: a fixed 32-byte header read before any decoding, then a cereal
// portable-binary payload. See docs/FORMAT.md.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "drape/formats/character_asset.h"
#include "drape/formats/status.h"

namespace drape {

// The version the writer writes. 2: BodyMapPose class version 2 (layout and row spans).
// 3: BodyMapPose class version 3 (depth layers: the slab and up to three air gaps per texel).
// 4: HullColliderData class version 2 (internal planes). 5: CharacterAsset class version 2
// (per-bone local maps). 6: CharacterAsset class version 3 (tapered capsules). 7: BodyMapPose
// class version 4 (the view axis). 8: CharacterAsset class version 4 (the render mesh).
inline constexpr uint32_t kAssetFormatVersion = 8;
// The oldest version the loader still reads (1: every class at version 1, body maps dense; the
// loader reads every version from this one to kAssetFormatVersion).
inline constexpr uint32_t kOldestAssetFormatVersion = 1;
inline constexpr size_t kAssetHeaderSize = 32;

// Serialises the asset into the bytes of a .drape file. Fails if the asset does not validate.
Status EncodeAsset(const CharacterAsset& asset, std::vector<uint8_t>* bytes);

// Decodes and validates the bytes of a .drape file. `name` is used in messages (usually the
// path). On failure `asset` is left empty and the message says which check failed and why.
Status DecodeAsset(std::span<const uint8_t> bytes, const std::string& name, CharacterAsset* asset);

// Whether `head`, the first bytes of a file, starts as a .drape file does.
bool LooksLikeAssetFile(std::span<const uint8_t> head);

// Writes to "path.tmp-<pid>" and renames, so a failed write leaves no partial file at `path`.
Status WriteAssetFile(const std::string& path, const CharacterAsset& asset);
// The same for any bytes (reports, meshes, keys): all or nothing at `path`.
Status WriteFileAtomically(const std::string& path, std::string_view bytes);
Status ReadAssetFile(const std::string& path, CharacterAsset* asset);

// Checks every count, index and value range the runtime relies on. Returns a message naming the
// first offending field, e.g. "skeleton.parents[3] = 7 is not smaller than 3".
Status ValidateAsset(const CharacterAsset& asset);

// The whole asset as JSON (cereal's JSON archive), for people and golden-file diffs.
std::string AssetToJson(const CharacterAsset& asset);

// CRC-32 (IEEE 802.3, the zlib polynomial) of the bytes.
uint32_t Crc32(std::span<const uint8_t> bytes);

}  // namespace drape

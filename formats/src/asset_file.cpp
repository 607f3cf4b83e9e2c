#include "drape/formats/asset_file.h"

#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <istream>
#include <new>
#include <sstream>
#include <streambuf>

#include "schema_archive.h"

namespace drape {
namespace {

// Bytes 0-7 of every .drape file. The high first byte and the CR LF catch files that went
// through a text-mode transfer, as PNG's signature does.
constexpr std::array<uint8_t, 8> kMagic = {0x89, 'D', 'R', 'A', 'P', 'E', '\r', '\n'};
constexpr uint32_t kFlagLittleEndian = 1u << 0;
constexpr uint32_t kFlagFloatSizeShift = 8;  // bits 8-15: sizeof(float) of the payload
constexpr uint32_t kCurrentFlags =
    kFlagLittleEndian | (uint32_t{sizeof(float)} << kFlagFloatSizeShift);

void PutU32(uint8_t* out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out[i] = static_cast<uint8_t>(v >> (8 * i));
}
void PutU64(uint8_t* out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out[i] = static_cast<uint8_t>(v >> (8 * i));
}
uint32_t GetU32(const uint8_t* in) {
  uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | in[i];
  return v;
}
uint64_t GetU64(const uint8_t* in) {
  uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | in[i];
  return v;
}

Status Error(StatusCode code, const std::string& name, const std::string& reason) {
  return Status(code, name + ": " + reason);
}

}  // namespace

const char* ToString(StatusCode code) {
  switch (code) {
    case StatusCode::kOk:
      return "ok";
    case StatusCode::kIoError:
      return "I/O error";
    case StatusCode::kBadMagic:
      return "not a .drape file";
    case StatusCode::kUnsupportedVersion:
      return "unsupported version";
    case StatusCode::kTruncated:
      return "truncated";
    case StatusCode::kTrailingBytes:
      return "trailing bytes";
    case StatusCode::kChecksumMismatch:
      return "checksum mismatch";
    case StatusCode::kCorrupt:
      return "corrupt";
    case StatusCode::kInvalidArgument:
      return "invalid argument";
    case StatusCode::kInvalidState:
      return "invalid state";
  }
  return "unknown";
}

uint32_t Crc32(std::span<const uint8_t> bytes) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  uint32_t crc = 0xFFFFFFFFu;
  for (uint8_t b : bytes) crc = table[(crc ^ b) & 0xFFu] ^ (crc >> 8);
  return crc ^ 0xFFFFFFFFu;
}

Status EncodeAsset(const CharacterAsset& asset, std::vector<uint8_t>* bytes) {
  if (Status valid = ValidateAsset(asset); !valid.ok()) return valid;
  std::ostringstream payload_stream(std::ios::binary);
  {
    cereal::PortableBinaryOutputArchive archive(
        payload_stream, cereal::PortableBinaryOutputArchive::Options::LittleEndian());
    archive(const_cast<CharacterAsset&>(asset));
  }
  const std::string payload = std::move(payload_stream).str();
  bytes->assign(kAssetHeaderSize + payload.size(), 0);
  uint8_t* header = bytes->data();
  std::memcpy(header, kMagic.data(), kMagic.size());
  PutU32(header + 8, kAssetFormatVersion);
  PutU32(header + 12, kCurrentFlags);
  PutU64(header + 16, payload.size());
  std::memcpy(header + kAssetHeaderSize, payload.data(), payload.size());
  PutU32(header + 24, Crc32({header + kAssetHeaderSize, payload.size()}));
  PutU32(header + 28, Crc32({header, 28}));
  return Status::Ok();
}

bool LooksLikeAssetFile(std::span<const uint8_t> head) {
  return head.size() >= kMagic.size() &&
         std::memcmp(head.data(), kMagic.data(), kMagic.size()) == 0;
}

Status DecodeAsset(std::span<const uint8_t> bytes, const std::string& name, CharacterAsset* asset) {
  *asset = CharacterAsset{};
  const size_t magic_bytes = std::min(bytes.size(), kMagic.size());
  if (bytes.empty() || std::memcmp(bytes.data(), kMagic.data(), magic_bytes) != 0) {
    return Error(StatusCode::kBadMagic, name, "not a .drape file (wrong magic bytes)");
  }
  if (bytes.size() < kAssetHeaderSize) {
    return Error(StatusCode::kTruncated, name,
                 "truncated header: " + std::to_string(bytes.size()) + " of " +
                     std::to_string(kAssetHeaderSize) + " bytes");
  }
  const uint8_t* header = bytes.data();
  if (GetU32(header + 28) != Crc32({header, 28})) {
    return Error(StatusCode::kChecksumMismatch, name, "header checksum mismatch (corrupt header)");
  }
  const uint32_t version = GetU32(header + 8);
  if (version < kOldestAssetFormatVersion || version > kAssetFormatVersion) {
    return Error(StatusCode::kUnsupportedVersion, name,
                 "format version " + std::to_string(version) + " is " +
                     (version > kAssetFormatVersion ? "newer" : "older") +
                     " than the versions this build reads (" +
                     std::to_string(kOldestAssetFormatVersion) + " to " +
                     std::to_string(kAssetFormatVersion) + ")");
  }
  const uint32_t flags = GetU32(header + 12);
  if (flags != kCurrentFlags) {
    return Error(
        StatusCode::kUnsupportedVersion, name, "unsupported flags 0x" + [&] {
          char buffer[16];
          std::snprintf(buffer, sizeof(buffer), "%08x", flags);
          return std::string(buffer);
        }() + " (expected little-endian payload with 4-byte floats)");
  }
  const uint64_t payload_size = GetU64(header + 16);
  const uint64_t available = bytes.size() - kAssetHeaderSize;
  if (available < payload_size) {
    return Error(StatusCode::kTruncated, name,
                 "truncated payload: " + std::to_string(available) + " of " +
                     std::to_string(payload_size) + " bytes");
  }
  if (available > payload_size) {
    return Error(StatusCode::kTrailingBytes, name,
                 std::to_string(available - payload_size) + " bytes after the payload");
  }
  const std::span<const uint8_t> payload = bytes.subspan(kAssetHeaderSize);
  if (GetU32(header + 24) != Crc32(payload)) {
    return Error(StatusCode::kChecksumMismatch, name, "payload checksum mismatch (corrupt data)");
  }

  CharacterAsset decoded;
  detail::SpanBuffer buffer(payload.data(), payload.size());
  std::istream stream(&buffer);
  detail::g_decoding = &buffer;
  detail::g_format_version = version;
  std::string failure;
  try {
    cereal::PortableBinaryInputArchive archive(
        stream, cereal::PortableBinaryInputArchive::Options::LittleEndian());
    archive(decoded);
  } catch (const DecodeError& e) {
    failure = e.what();
  } catch (const cereal::Exception& e) {
    failure = std::string("payload does not decode: ") + e.what();
  } catch (const std::bad_alloc&) {
    failure = "payload does not decode: a count is too large to allocate";
  } catch (const std::length_error&) {
    failure = "payload does not decode: a count is too large";
  }
  detail::g_decoding = nullptr;
  detail::g_format_version = 0;
  if (!failure.empty()) return Error(StatusCode::kCorrupt, name, failure);
  if (buffer.consumed() != payload.size()) {
    return Error(StatusCode::kCorrupt, name,
                 std::to_string(payload.size() - buffer.consumed()) +
                     " payload bytes left over after decoding");
  }
  if (Status valid = ValidateAsset(decoded); !valid.ok()) {
    return Error(StatusCode::kCorrupt, name, valid.message());
  }
  *asset = std::move(decoded);
  return Status::Ok();
}

Status WriteFileAtomically(const std::string& path, std::string_view bytes) {
  const std::string temporary = path + ".tmp-" + std::to_string(::getpid());
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) return Error(StatusCode::kIoError, path, "cannot open for writing");
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.flush();
    if (!out) {
      out.close();
      std::remove(temporary.c_str());
      return Error(StatusCode::kIoError, path, "write failed (disk full?)");
    }
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) {
    std::remove(temporary.c_str());
    return Error(StatusCode::kIoError, path,
                 "cannot rename the temporary file: " + error.message());
  }
  return Status::Ok();
}

Status WriteAssetFile(const std::string& path, const CharacterAsset& asset) {
  std::vector<uint8_t> bytes;
  if (Status encoded = EncodeAsset(asset, &bytes); !encoded.ok()) {
    return Error(encoded.code(), path, encoded.message());
  }
  return WriteFileAtomically(path, {reinterpret_cast<const char*>(bytes.data()), bytes.size()});
}

Status ReadAssetFile(const std::string& path, CharacterAsset* asset) {
  *asset = CharacterAsset{};
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) {
    return Error(StatusCode::kIoError, path, "is a directory");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error(StatusCode::kIoError, path, "cannot open (missing or unreadable)");
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                             std::istreambuf_iterator<char>());
  if (in.bad()) return Error(StatusCode::kIoError, path, "read failed");
  return DecodeAsset(bytes, path, asset);
}

std::string AssetToJson(const CharacterAsset& asset) {
  std::ostringstream out;
  {
    cereal::JSONOutputArchive archive(out, cereal::JSONOutputArchive::Options::Default());
    archive(cereal::make_nvp("drape_asset", const_cast<CharacterAsset&>(asset)));
  }
  return out.str();
}

}  // namespace drape

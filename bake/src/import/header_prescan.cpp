#include "import/header_prescan.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

#include "drape/formats/asset_file.h"
#include "import/import_messages.h"

namespace drape::bake::detail {
namespace {

constexpr uint64_t kMaxCount = 0xffffffffu;  // assimp keeps counts in 32 bits

// The file's bytes, mapped read-only for the scan.
class MappedFile {
 public:
  explicit MappedFile(const std::string& path) {
    const int fd = open(path.c_str(), O_RDONLY);
    if (fd < 0) return;
    struct stat info {};
    if (fstat(fd, &info) == 0 && info.st_size > 0) {
      void* p = mmap(nullptr, static_cast<size_t>(info.st_size), PROT_READ, MAP_PRIVATE, fd, 0);
      if (p != MAP_FAILED) {
        data_ = static_cast<const char*>(p);
        size_ = static_cast<size_t>(info.st_size);
      }
    }
    close(fd);
  }
  ~MappedFile() {
    if (data_ != nullptr) munmap(const_cast<char*>(data_), size_);
  }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  std::string_view bytes() const { return {data_, size_}; }

 private:
  const char* data_ = nullptr;
  size_t size_ = 0;
};

// Whitespace-separated tokens of a text, '#' comments skipped.
class Tokens {
 public:
  Tokens(std::string_view text, size_t at) : text_(text), at_(at) {}
  std::string_view Next() {
    for (;;) {
      while (at_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[at_]))) ++at_;
      if (at_ < text_.size() && text_[at_] == '#') {
        while (at_ < text_.size() && text_[at_] != '\n') ++at_;
        continue;
      }
      break;
    }
    const size_t begin = at_;
    while (at_ < text_.size() && !std::isspace(static_cast<unsigned char>(text_[at_]))) ++at_;
    return text_.substr(begin, at_ - begin);
  }
  size_t at() const { return at_; }
  size_t left() const { return text_.size() - at_; }

 private:
  std::string_view text_;
  size_t at_;
};

// A decimal count; false for anything else. Counts past 2^64 saturate.
bool ParseCount(std::string_view token, uint64_t* count) {
  if (token.empty()) return false;
  uint64_t value = 0;
  for (char c : token) {
    if (c < '0' || c > '9') return false;
    value =
        value > (UINT64_MAX - 9) / 10 ? UINT64_MAX : value * 10 + static_cast<uint64_t>(c - '0');
  }
  *count = value;
  return true;
}

Status TooMany(const std::string& path, uint64_t count, const std::string& what, uint64_t bytes) {
  return SourceError(path, StatusCode::kCorrupt,
                     "the header declares " + std::to_string(count) + " " + what +
                         ", more than its " + std::to_string(bytes) +
                         " bytes of data can hold (a corrupt or hostile header)");
}

// OFF: [ST][C][N][4][n]OFF, [dimension], vertex and face counts, then one record per line.
Status PrescanOff(const std::string& path, std::string_view text) {
  size_t line_start = 0;
  for (size_t i = 0; i <= text.size(); ++i) {
    if (i == text.size() || text[i] == '\n') {
      if (i - line_start >= 4096) {
        return SourceError(path, StatusCode::kCorrupt,
                           "a line of " + std::to_string(i - line_start) +
                               " bytes; assimp's OFF reader takes lines of at most 4095");
      }
      line_start = i + 1;
    }
  }
  Tokens tokens(text, 0);
  std::string_view token = tokens.Next();
  const bool keyword = token.size() >= 3 && token.substr(token.size() - 3) == "OFF";
  if (keyword) {
    if (token.size() >= 4 && token[token.size() - 4] == 'n') tokens.Next();  // dimension
    token = tokens.Next();
  }
  uint64_t vertices = 0, faces = 0;
  if (!ParseCount(token, &vertices) || !ParseCount(tokens.Next(), &faces)) return Status::Ok();
  const uint64_t bytes = tokens.left();
  if (vertices > kMaxCount) return TooMany(path, vertices, "vertices", bytes);
  if (faces > kMaxCount) return TooMany(path, faces, "faces", bytes);
  // Each record is a line: at least one character and a line end (the last may lack it).
  if (2 * (vertices + faces) > bytes + 1)
    return TooMany(path, vertices + faces, "vertex and face records", bytes);
  return Status::Ok();
}

// PLY header: elements with their counts and properties.
struct PlyProperty {
  int scalar_bytes = 0;  // the value's size; for a list, its count's
  int item_bytes = 0;    // > 0 for a list: each item's size
};
struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
};
struct PlyHeader {
  enum class Format { kAscii, kLittleEndian, kBigEndian } format = Format::kAscii;
  std::vector<PlyElement> elements;
  size_t data_begin = 0;
};

int PlyTypeBytes(std::string_view type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "int32" || type == "uint32" || type == "float" ||
      type == "float32")
    return 4;
  if (type == "double" || type == "float64" || type == "double64") return 8;
  return 0;
}

// False when the header is not one this scan understands (assimp then judges it alone).
bool ParsePlyHeader(std::string_view text, PlyHeader* header) {
  size_t at = 0;
  while (at < text.size()) {
    size_t end = text.find('\n', at);
    if (end == std::string_view::npos) return false;
    std::string_view line = text.substr(at, end - at);
    at = end + 1;
    Tokens tokens(line, 0);
    const std::string_view word = tokens.Next();
    if (word == "end_header") {
      header->data_begin = at;
      return true;
    }
    if (word == "format") {
      const std::string_view f = tokens.Next();
      header->format = f == "binary_little_endian" ? PlyHeader::Format::kLittleEndian
                       : f == "binary_big_endian"  ? PlyHeader::Format::kBigEndian
                                                   : PlyHeader::Format::kAscii;
    } else if (word == "element") {
      PlyElement element;
      element.name = std::string(tokens.Next());
      if (!ParseCount(tokens.Next(), &element.count)) return false;
      header->elements.push_back(std::move(element));
    } else if (word == "property" && !header->elements.empty()) {
      PlyProperty property;
      std::string_view type = tokens.Next();
      if (type == "list") {
        property.scalar_bytes = PlyTypeBytes(tokens.Next());
        property.item_bytes = PlyTypeBytes(tokens.Next());
        if (property.item_bytes == 0) return false;
      } else {
        property.scalar_bytes = PlyTypeBytes(type);
      }
      if (property.scalar_bytes == 0) return false;
      header->elements.back().properties.push_back(property);
    }
  }
  return false;
}

uint64_t ReadUnsigned(const char* p, int bytes, bool big_endian) {
  uint64_t value = 0;
  for (int i = 0; i < bytes; ++i) {
    const uint64_t byte = static_cast<unsigned char>(p[big_endian ? i : bytes - 1 - i]);
    value = (value << 8) | byte;
  }
  return value;
}

// Binary data: every element and every list's items lie inside the file.
Status WalkPlyBinary(const std::string& path, std::string_view text, const PlyHeader& header) {
  const bool big = header.format == PlyHeader::Format::kBigEndian;
  uint64_t at = header.data_begin;
  for (const PlyElement& element : header.elements) {
    for (uint64_t i = 0; i < element.count; ++i) {
      for (const PlyProperty& p : element.properties) {
        if (at + static_cast<uint64_t>(p.scalar_bytes) > text.size()) {
          return SourceError(path, StatusCode::kCorrupt,
                             "element '" + element.name + "' " + std::to_string(i) +
                                 " runs past the end of the file");
        }
        if (p.item_bytes > 0) {
          const uint64_t items = ReadUnsigned(text.data() + at, p.scalar_bytes, big);
          at += static_cast<uint64_t>(p.scalar_bytes);
          if (items > (text.size() - at) / static_cast<uint64_t>(p.item_bytes))
            return TooMany(path, items, "items in a list of '" + element.name + "'",
                           text.size() - at);
          at += items * static_cast<uint64_t>(p.item_bytes);
        } else {
          at += static_cast<uint64_t>(p.scalar_bytes);
        }
      }
    }
  }
  return Status::Ok();
}

// ASCII data: every list's length fits in the tokens left.
Status WalkPlyAscii(const std::string& path, std::string_view text, const PlyHeader& header) {
  Tokens tokens(text, header.data_begin);
  for (const PlyElement& element : header.elements) {
    for (uint64_t i = 0; i < element.count; ++i) {
      for (const PlyProperty& p : element.properties) {
        const std::string_view token = tokens.Next();
        if (token.empty()) return Status::Ok();  // short data: assimp's to judge
        uint64_t items = 0;
        if (p.item_bytes == 0 || !ParseCount(token, &items)) continue;
        if (items > tokens.left() / 2 + 1)
          return TooMany(path, items, "items in a list of '" + element.name + "'", tokens.left());
        for (uint64_t k = 0; k < items; ++k) tokens.Next();
      }
    }
  }
  return Status::Ok();
}

Status PrescanPly(const std::string& path, std::string_view text) {
  PlyHeader header;
  if (!ParsePlyHeader(text, &header)) return Status::Ok();
  const uint64_t bytes = text.size() - header.data_begin;
  const bool binary = header.format != PlyHeader::Format::kAscii;
  // The fewest bytes an element can take: its scalars and list counts in binary, one token and
  // a separator per property in text.
  uint64_t needed = 0;
  for (const PlyElement& element : header.elements) {
    if (element.count > kMaxCount) return TooMany(path, element.count, element.name, bytes);
    uint64_t least = 0;
    for (const PlyProperty& p : element.properties)
      least += binary ? static_cast<uint64_t>(p.scalar_bytes) : 2;
    needed += element.count * std::max<uint64_t>(least, binary ? 0 : 1);
    if (needed > bytes + 1)
      return TooMany(path, element.count, "'" + element.name + "' elements", bytes);
  }
  return binary ? WalkPlyBinary(path, text, header) : WalkPlyAscii(path, text, header);
}

// B3D: chunks of a 4-byte tag and a 32-bit size, each inside its parent.
Status PrescanB3d(const std::string& path, std::string_view data) {
  struct Range {
    uint64_t begin, end;
  };
  std::vector<Range> stack;
  auto chunk_at = [&](uint64_t at, uint64_t parent_end, std::string* tag, uint64_t* end) {
    if (at + 8 > parent_end) return false;
    *tag = std::string(data.substr(at, 4));
    *end = at + 8 + ReadUnsigned(data.data() + at + 4, 4, false);
    return true;
  };
  std::string tag;
  uint64_t end = 0;
  if (!chunk_at(0, data.size(), &tag, &end) || tag != "BB3D") return Status::Ok();
  if (end > data.size()) {
    return SourceError(path, StatusCode::kCorrupt,
                       "the BB3D chunk claims " + std::to_string(end) + " bytes; the file has " +
                           std::to_string(data.size()));
  }
  stack.push_back({12, end});  // after the version
  while (!stack.empty()) {
    Range& parent = stack.back();
    if (!chunk_at(parent.begin, parent.end, &tag, &end)) {
      stack.pop_back();
      continue;
    }
    const uint64_t at = parent.begin;
    if (end > parent.end) {
      return SourceError(path, StatusCode::kCorrupt,
                         "chunk '" + tag + "' at byte " + std::to_string(at) + " claims " +
                             std::to_string(end - at - 8) + " bytes, past the end of its parent");
    }
    parent.begin = end;
    uint64_t children = at + 8;
    if (tag == "MESH") children += 4;  // brush id
    if (tag == "NODE") {               // name, position, scale, rotation
      const size_t name_end = data.find('\0', children);
      if (name_end == std::string_view::npos) continue;
      children = name_end + 1 + 40;
    }
    if (tag == "MESH" || tag == "NODE") stack.push_back({children, end});
  }
  return Status::Ok();
}

// OBJ: `f` lines without a corner, which assimp's reader skips without a word.
size_t CountEmptyObjFaces(std::string_view text) {
  size_t empty = 0;
  size_t at = 0;
  while (at < text.size()) {
    size_t end = text.find('\n', at);
    if (end == std::string_view::npos) end = text.size();
    Tokens tokens(text.substr(at, end - at), 0);
    if (tokens.Next() == "f" && tokens.Next().empty()) ++empty;
    at = end + 1;
  }
  return empty;
}

std::string LowercaseExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

Status PrescanModelFile(const std::string& path, std::vector<std::string>* warnings) {
  const MappedFile file(path);
  const std::string_view data = file.bytes();
  const std::span<const uint8_t> head(reinterpret_cast<const uint8_t*>(data.data()),
                                      std::min<size_t>(data.size(), 64));
  if (LooksLikeAssetFile(head)) {
    return SourceError(path, StatusCode::kInvalidArgument,
                       "is a baked drape asset, not a character model (drape-inspect and "
                       "drape-sim read assets; drape-bake reads glTF, FBX, COLLADA, .X and the "
                       "other formats assimp reads)");
  }
  const std::string ext = LowercaseExtension(path);
  Tokens first(data.substr(0, std::min<size_t>(data.size(), 4096)), 0);
  const std::string_view word = first.Next();
  if (ext == ".off" || (word.size() >= 3 && word.size() <= 9 && word.ends_with("OFF")))
    return PrescanOff(path, data);
  if (ext == ".ply" || data.starts_with("ply")) return PrescanPly(path, data);
  if (ext == ".b3d" || data.starts_with("BB3D")) return PrescanB3d(path, data);
  if (ext == ".obj") {
    if (const size_t empty = CountEmptyObjFaces(data); empty > 0)
      warnings->push_back(std::to_string(empty) + " 'f' lines without a corner skipped");
  }
  return Status::Ok();
}

}  // namespace drape::bake::detail

#pragma once
// Status values: how every fallible formats/runtime call reports failure (no exceptions cross the
// API).

#include <cstdint>
#include <string>
#include <utility>

namespace drape {

enum class StatusCode : uint32_t {
  kOk = 0,
  kIoError,             // the file could not be opened, read, written or renamed
  kBadMagic,            // not a .drape file
  kUnsupportedVersion,  // a format or type version this build does not know (older or newer)
  kTruncated,           // fewer bytes than the header promises
  kTrailingBytes,       // more bytes than the header promises
  kChecksumMismatch,    // payload bytes do not match the header checksum
  kCorrupt,             // the payload does not decode, or a count or index is out of range
  kInvalidArgument,     // a caller-supplied value is out of its documented range
  kInvalidState,        // e.g. a NaN position handed to the solver
};

const char* ToString(StatusCode code);

// A status is ok, or an error code plus a one-line message that names the input and the reason.
class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}
  static Status Ok() { return Status(); }

  bool ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }

 private:
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

}  // namespace drape

#pragma once
// How the import words its refusals and warnings: every refusal starts with the source file's
// path, numbers are written with six significant digits.

#include <cstdio>
#include <string>

#include "drape/formats/status.h"

namespace drape::bake::detail {

// "path: reason" with `code`.
inline Status SourceError(const std::string& path, StatusCode code, const std::string& reason) {
  return Status(code, path + ": " + reason);
}

// %.6g
inline std::string Fmt(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.6g", v);
  return buffer;
}

}  // namespace drape::bake::detail

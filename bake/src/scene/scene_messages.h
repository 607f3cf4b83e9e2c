#pragma once
// How the scene code words its refusals: one line, the file, the JSON path, the reason.

#include <string>
#include <vector>

#include "drape/formats/status.h"

namespace drape::bake::detail {

// kInvalidArgument with `message`.
Status Invalid(const std::string& message);
// 'name'
std::string Quote(const std::string& s);
// "a | b | c"
std::string JoinNames(const std::vector<std::string>& names);

}  // namespace drape::bake::detail

#define DRAPE_RETURN_IF_ERROR(expr)     \
  do {                                  \
    if (Status _s = (expr); !_s.ok()) { \
      return _s;                        \
    }                                   \
  } while (0)

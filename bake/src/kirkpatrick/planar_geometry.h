#pragma once
// Private to the Kirkpatrick builder (drape/bake/kirkpatrick_builder.h): points of the projection
// plane as the runtime stores them (floats), the exact orientation test every topological
// decision uses, directed-edge keys, and how the builder words its refusals.

#include <array>
#include <cstdint>
#include <string>

#include "drape/formats/status.h"
#include "drape/runtime/exact_orientation.h"

namespace drape::bake::detail {

// kInvalidArgument, "Kirkpatrick: <what>".
inline Status Fail(const std::string& what) {
  return Status(StatusCode::kInvalidArgument, "Kirkpatrick: " + what);
}

struct Point {
  float u = 0.f, v = 0.f;
};
// Sign of the signed area of (a, b, c): > 0 counter-clockwise.
inline int Orient(const Point& a, const Point& b, const Point& c) {
  return Orient2dExact(a.u, a.v, b.u, b.v, c.u, c.v);
}
inline double Area2(const Point& a, const Point& b, const Point& c) {  // approximate, for ranking
  return (double(b.u) - a.u) * (double(c.v) - a.v) - (double(b.v) - a.v) * (double(c.u) - a.u);
}

using Tri = std::array<uint32_t, 3>;

// Directed-edge key.
inline uint64_t EdgeKey(uint32_t a, uint32_t b) { return (uint64_t(a) << 32) | b; }

}  // namespace drape::bake::detail

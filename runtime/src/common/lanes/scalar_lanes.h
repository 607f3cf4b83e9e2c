#pragma once
// Private to the runtime: the lane operations of sse2_lanes.h in plain C++, four lanes wide.
//
// The reference pack. Every kernel written in the lane operations (the body-map lanes, the hull
// plane kernels and broad phase) is instantiated for it as well as for the SSE2 and AVX2 packs,
// and the tests hold the SIMD instantiations to its bits. It is also the path of CPUs without
// SSE2 and of InstructionSet::kScalar. Each operation gives, lane by lane, exactly what the SSE2
// instruction it stands for gives: comparisons are ordered (false on NaN) and return all-ones
// masks, min/max keep the SSE operand order, float-to-int truncation returns INT32_MIN where
// cvttps does (NaN, out of range).

#include <bit>
#include <cmath>
#include <cstdint>

// Every operation is forced inline: the lane kernels are large, and an operation left out of line
// passes its 16-byte lanes through memory.
#if defined(__GNUC__)
#define DRAPE_LANE_INLINE [[gnu::always_inline]] inline
#else
#define DRAPE_LANE_INLINE inline
#endif

namespace drape::detail {

struct ScalarF {  // 16 bytes: four float lanes (a mask lane is all ones or all zeros)
  float v[4];
};
struct ScalarI {  // 16 bytes: four int32 lanes
  int32_t v[4];
};

namespace scalar_lanes {

DRAPE_LANE_INLINE uint32_t Bits(float x) { return std::bit_cast<uint32_t>(x); }
DRAPE_LANE_INLINE float FromBits(uint32_t x) { return std::bit_cast<float>(x); }
DRAPE_LANE_INLINE float Mask(bool condition) { return FromBits(condition ? ~0u : 0u); }
DRAPE_LANE_INLINE int32_t MaskI(bool condition) { return condition ? -1 : 0; }

template <class Op>
DRAPE_LANE_INLINE ScalarF Map(ScalarF a, Op op) {
  ScalarF r;
  for (int l = 0; l < 4; ++l) r.v[l] = op(a.v[l]);
  return r;
}
template <class Op>
DRAPE_LANE_INLINE ScalarF Map(ScalarF a, ScalarF b, Op op) {
  ScalarF r;
  for (int l = 0; l < 4; ++l) r.v[l] = op(a.v[l], b.v[l]);
  return r;
}
template <class Op>
DRAPE_LANE_INLINE ScalarI MapI(ScalarI a, ScalarI b, Op op) {
  ScalarI r;
  for (int l = 0; l < 4; ++l) r.v[l] = op(a.v[l], b.v[l]);
  return r;
}
// Bitwise operations on the float lanes' bits.
template <class Op>
DRAPE_LANE_INLINE ScalarF MapBits(ScalarF a, ScalarF b, Op op) {
  return Map(a, b, [&](float x, float y) { return FromBits(op(Bits(x), Bits(y))); });
}

}  // namespace scalar_lanes

// mask ? a : b per lane, by bits (SSE2's and / andnot / or).
DRAPE_LANE_INLINE ScalarF SelectLanes(ScalarF mask, ScalarF a, ScalarF b) {
  ScalarF r;
  for (int l = 0; l < 4; ++l) {
    const uint32_t m = scalar_lanes::Bits(mask.v[l]);
    r.v[l] = scalar_lanes::FromBits((m & scalar_lanes::Bits(a.v[l])) |
                                    (~m & scalar_lanes::Bits(b.v[l])));
  }
  return r;
}
// minps / maxps with the SSE operand order: StdMin(a, b) = b < a ? b : a (a on ties and NaN).
DRAPE_LANE_INLINE ScalarF StdMin(ScalarF a, ScalarF b) {
  return scalar_lanes::Map(a, b, [](float x, float y) { return y < x ? y : x; });
}
DRAPE_LANE_INLINE ScalarF StdMax(ScalarF a, ScalarF b) {
  return scalar_lanes::Map(a, b, [](float x, float y) { return x < y ? y : x; });
}
DRAPE_LANE_INLINE ScalarF AbsLanes(ScalarF a) {
  return scalar_lanes::Map(
      a, [](float x) { return scalar_lanes::FromBits(scalar_lanes::Bits(x) & 0x7fffffffu); });
}
DRAPE_LANE_INLINE ScalarI SelectLanesI(ScalarF mask, ScalarI a, ScalarI b) {
  ScalarI r;
  for (int l = 0; l < 4; ++l) {
    const uint32_t m = scalar_lanes::Bits(mask.v[l]);
    r.v[l] = static_cast<int32_t>((m & static_cast<uint32_t>(a.v[l])) |
                                  (~m & static_cast<uint32_t>(b.v[l])));
  }
  return r;
}

namespace lanes {

DRAPE_LANE_INLINE ScalarF Add(ScalarF a, ScalarF b) {
  return scalar_lanes::Map(a, b, [](float x, float y) { return x + y; });
}
DRAPE_LANE_INLINE ScalarF Sub(ScalarF a, ScalarF b) {
  return scalar_lanes::Map(a, b, [](float x, float y) { return x - y; });
}
DRAPE_LANE_INLINE ScalarF Mul(ScalarF a, ScalarF b) {
  return scalar_lanes::Map(a, b, [](float x, float y) { return x * y; });
}
DRAPE_LANE_INLINE ScalarF Div(ScalarF a, ScalarF b) {
  return scalar_lanes::Map(a, b, [](float x, float y) { return x / y; });
}
DRAPE_LANE_INLINE ScalarF Sqrt(ScalarF a) {
  return scalar_lanes::Map(a, [](float x) { return std::sqrt(x); });
}
DRAPE_LANE_INLINE ScalarF And(ScalarF a, ScalarF b) {
  return scalar_lanes::MapBits(a, b, [](uint32_t x, uint32_t y) { return x & y; });
}
DRAPE_LANE_INLINE ScalarF Or(ScalarF a, ScalarF b) {
  return scalar_lanes::MapBits(a, b, [](uint32_t x, uint32_t y) { return x | y; });
}
DRAPE_LANE_INLINE ScalarF AndNot(ScalarF not_a, ScalarF b) {  // ~a & b
  return scalar_lanes::MapBits(not_a, b, [](uint32_t x, uint32_t y) { return ~x & y; });
}
DRAPE_LANE_INLINE ScalarF Less(ScalarF a, ScalarF b) {
  return scalar_lanes::Map(a, b, [](float x, float y) { return scalar_lanes::Mask(x < y); });
}
DRAPE_LANE_INLINE ScalarF LessEq(ScalarF a, ScalarF b) {
  return scalar_lanes::Map(a, b, [](float x, float y) { return scalar_lanes::Mask(x <= y); });
}
DRAPE_LANE_INLINE ScalarF Greater(ScalarF a, ScalarF b) {
  return scalar_lanes::Map(a, b, [](float x, float y) { return scalar_lanes::Mask(x > y); });
}
DRAPE_LANE_INLINE ScalarF GreaterEq(ScalarF a, ScalarF b) {
  return scalar_lanes::Map(a, b, [](float x, float y) { return scalar_lanes::Mask(x >= y); });
}
DRAPE_LANE_INLINE ScalarF Equal(ScalarF a, ScalarF b) {
  return scalar_lanes::Map(a, b, [](float x, float y) { return scalar_lanes::Mask(x == y); });
}
// Bit l = lane l's sign bit.
DRAPE_LANE_INLINE uint32_t LaneBits(ScalarF mask) {
  uint32_t bits = 0;
  for (int l = 0; l < 4; ++l) bits |= (scalar_lanes::Bits(mask.v[l]) >> 31) << l;
  return bits;
}

// 32-bit integer lanes: wrapping arithmetic (in uint32_t, where it is defined), signed compares.
DRAPE_LANE_INLINE ScalarI Add(ScalarI a, ScalarI b) {
  return scalar_lanes::MapI(a, b, [](int32_t x, int32_t y) {
    return static_cast<int32_t>(static_cast<uint32_t>(x) + static_cast<uint32_t>(y));
  });
}
DRAPE_LANE_INLINE ScalarI Sub(ScalarI a, ScalarI b) {
  return scalar_lanes::MapI(a, b, [](int32_t x, int32_t y) {
    return static_cast<int32_t>(static_cast<uint32_t>(x) - static_cast<uint32_t>(y));
  });
}
DRAPE_LANE_INLINE ScalarI And(ScalarI a, ScalarI b) {
  return scalar_lanes::MapI(a, b, [](int32_t x, int32_t y) { return x & y; });
}
DRAPE_LANE_INLINE ScalarI Or(ScalarI a, ScalarI b) {
  return scalar_lanes::MapI(a, b, [](int32_t x, int32_t y) { return x | y; });
}
DRAPE_LANE_INLINE ScalarI AndNot(ScalarI not_a, ScalarI b) {
  return scalar_lanes::MapI(not_a, b, [](int32_t x, int32_t y) { return ~x & y; });
}
DRAPE_LANE_INLINE ScalarI Less(ScalarI a, ScalarI b) {
  return scalar_lanes::MapI(a, b, [](int32_t x, int32_t y) { return scalar_lanes::MaskI(x < y); });
}
DRAPE_LANE_INLINE ScalarI Greater(ScalarI a, ScalarI b) {
  return scalar_lanes::MapI(a, b, [](int32_t x, int32_t y) { return scalar_lanes::MaskI(x > y); });
}
DRAPE_LANE_INLINE ScalarI Equal(ScalarI a, ScalarI b) {
  return scalar_lanes::MapI(a, b, [](int32_t x, int32_t y) { return scalar_lanes::MaskI(x == y); });
}
DRAPE_LANE_INLINE ScalarI High16(ScalarI a) {  // logical shift: 0 .. 65535
  ScalarI r;
  for (int l = 0; l < 4; ++l) r.v[l] = static_cast<int32_t>(static_cast<uint32_t>(a.v[l]) >> 16);
  return r;
}
DRAPE_LANE_INLINE ScalarI Abs(ScalarI a) {  // wraps for INT32_MIN, as the SSE2 sequence does
  ScalarI r;
  for (int l = 0; l < 4; ++l) {
    const uint32_t x = static_cast<uint32_t>(a.v[l]);
    r.v[l] = static_cast<int32_t>(a.v[l] < 0 ? 0u - x : x);
  }
  return r;
}

// Conversions: cvttps2dq (truncation; INT32_MIN for NaN and out of range), cvtdq2ps, bit casts.
DRAPE_LANE_INLINE ScalarI TruncateToInt(ScalarF a) {
  ScalarI r;
  for (int l = 0; l < 4; ++l) {
    const float x = a.v[l];
    const bool in_range = x > -2147483904.f && x < 2147483648.f;  // (INT32_MIN - 1, 2^31)
    r.v[l] = in_range ? static_cast<int32_t>(x) : INT32_MIN;
  }
  return r;
}
DRAPE_LANE_INLINE ScalarF ToFloat(ScalarI a) {
  ScalarF r;
  for (int l = 0; l < 4; ++l) r.v[l] = static_cast<float>(a.v[l]);
  return r;
}
DRAPE_LANE_INLINE ScalarI AsInt(ScalarF a) {
  ScalarI r;
  for (int l = 0; l < 4; ++l) r.v[l] = std::bit_cast<int32_t>(a.v[l]);
  return r;
}
DRAPE_LANE_INLINE ScalarF AsFloat(ScalarI a) {
  ScalarF r;
  for (int l = 0; l < 4; ++l) r.v[l] = std::bit_cast<float>(a.v[l]);
  return r;
}

}  // namespace lanes

// What only the width decides: four lanes in plain C++ (Sse2Lanes' twin).
struct ScalarLanes {
  static constexpr int kCount = 4;
  using F = ScalarF;
  using I = ScalarI;
  DRAPE_LANE_INLINE static F Splat(float x) { return {{x, x, x, x}}; }
  DRAPE_LANE_INLINE static F Zero() { return Splat(0.f); }
  DRAPE_LANE_INLINE static I SplatI(int32_t x) { return {{x, x, x, x}}; }
  DRAPE_LANE_INLINE static I ZeroI() { return SplatI(0); }
  DRAPE_LANE_INLINE static I LaneBitValues() { return {{1, 2, 4, 8}}; }  // lane l holds 1 << l
  template <class Value>
  DRAPE_LANE_INLINE static F FromLanes(const Value& value) {
    return {{value(0), value(1), value(2), value(3)}};
  }
  template <class Value>
  DRAPE_LANE_INLINE static I FromLanesI(const Value& value) {
    return {{value(0), value(1), value(2), value(3)}};
  }
  DRAPE_LANE_INLINE static F Load(const float* unaligned) {
    return {{unaligned[0], unaligned[1], unaligned[2], unaligned[3]}};
  }
  DRAPE_LANE_INLINE static void Store(int32_t* aligned, I a) {
    for (int l = 0; l < 4; ++l) aligned[l] = a.v[l];
  }
  DRAPE_LANE_INLINE static void Store(float* aligned, F a) {
    for (int l = 0; l < 4; ++l) aligned[l] = a.v[l];
  }
  // The (x, y, z, w) rows at rows[0..3] as lanes (a 4x4 transpose), and back.
  DRAPE_LANE_INLINE static void LoadRows4(float* const rows[4], F* x, F* y, F* z, F* w) {
    for (int l = 0; l < 4; ++l) {
      x->v[l] = rows[l][0];
      y->v[l] = rows[l][1];
      z->v[l] = rows[l][2];
      w->v[l] = rows[l][3];
    }
  }
  DRAPE_LANE_INLINE static void StoreRows4(float* const rows[4], F x, F y, F z, F w) {
    for (int l = 0; l < 4; ++l) {
      rows[l][0] = x.v[l];
      rows[l][1] = y.v[l];
      rows[l][2] = z.v[l];
      rows[l][3] = w.v[l];
    }
  }
  // Four consecutive (x, y, z) float triples as lanes, and back.
  DRAPE_LANE_INLINE static void LoadFloat3s(const void* triples, F* x, F* y, F* z) {
    const float* f = static_cast<const float*>(triples);
    for (int l = 0; l < 4; ++l) {
      x->v[l] = f[3 * l];
      y->v[l] = f[3 * l + 1];
      z->v[l] = f[3 * l + 2];
    }
  }
  DRAPE_LANE_INLINE static void StoreFloat3s(void* triples, F x, F y, F z) {
    float* f = static_cast<float*>(triples);
    for (int l = 0; l < 4; ++l) {
      f[3 * l] = x.v[l];
      f[3 * l + 1] = y.v[l];
      f[3 * l + 2] = z.v[l];
    }
  }
  // The float pairs (top then bottom) at address(0..3) as lanes.
  template <class Address>
  DRAPE_LANE_INLINE static void LoadSlabsAt(const Address& address, F* top, F* bottom) {
    for (int l = 0; l < 4; ++l) {
      const float* pair = static_cast<const float*>(static_cast<const void*>(address(l)));
      top->v[l] = pair[0];
      bottom->v[l] = pair[1];
    }
  }
};

}  // namespace drape::detail

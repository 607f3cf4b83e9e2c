// Private to the runtime: BodyMapCollider's lanes (short motions, walks), written once for any
// width in the lane operations of sse_lanes.h. Included by body_map_collider.cpp (four SSE2 lanes)
// and by body_map_collider_avx2.cpp (eight AVX2 lanes, inside its AVX2 target region).
//
// No #include here: everything this text uses must be declared before it is included. In the
// AVX2 file that keeps the headers (and every inline function they define) outside the AVX2
// region, so that no function the SSE2 code also uses is ever compiled for AVX2.

namespace drape {
namespace {

using detail::AbsLanes;
using detail::SelectLanes;
using detail::SelectLanesI;
using detail::StdMax;
using detail::StdMin;
using namespace detail::lanes;

// Particles' coordinates, one lane each.
template <class P>
struct Lanes3 {
  typename P::F x, y, z;
};

// P::kCount consecutive Float3 as lanes.
template <class P>
Lanes3<P> LoadFloat3Lanes(const Float3* p) {
  Lanes3<P> lanes;
  P::LoadFloat3s(p, &lanes.x, &lanes.y, &lanes.z);
  return lanes;
}

// The mask of the lanes whose bit is set in `bits`.
template <class P>
typename P::F MaskOfLanes(uint32_t bits) {
  const typename P::I bit = P::LaneBitValues();
  return AsFloat(Equal(And(P::SplatI(static_cast<int32_t>(bits)), bit), bit));
}

// BodyMapWalk::Along.
template <class P>
typename P::F AlongLanes(typename P::F a, typename P::F b, typename P::F s) {
  const typename P::F d = Sub(b, a);
  const typename P::F from_a = Add(a, Mul(d, s));
  const typename P::F from_b = Sub(b, Mul(d, Sub(P::Splat(1.f), s)));
  return SelectLanes(Less(s, P::Splat(0.5f)), from_a, from_b);
}

// DecodeOct16 of one code per lane (its two values, the first in the low 16 bits).
template <class P>
[[gnu::always_inline]] inline Lanes3<P> DecodeOct16Lanes(typename P::I code) {
  using F = typename P::F;
  const F one = P::Splat(1.f);
  const F scale = P::Splat(2.f / 65535.f);
  F x = Sub(Mul(ToFloat(And(code, P::SplatI(0xffff))), scale), one);
  F y = Sub(Mul(ToFloat(High16(code)), scale), one);
  const F z = Sub(Sub(one, AbsLanes(x)), AbsLanes(y));
  const F minus_one = P::Splat(-1.f), zero = P::Zero();
  const F sign_x = SelectLanes(GreaterEq(x, zero), one, minus_one);
  const F sign_y = SelectLanes(GreaterEq(y, zero), one, minus_one);
  const F fold = Less(z, zero);
  const F unfolded_x = Mul(Sub(one, AbsLanes(y)), sign_x);
  const F unfolded_y = Mul(Sub(one, AbsLanes(x)), sign_y);
  x = SelectLanes(fold, unfolded_x, x);
  y = SelectLanes(fold, unfolded_y, y);
  // NormalizeOr(n, +z).
  const F length = Sqrt(Add(Add(Mul(x, x), Mul(y, y)), Mul(z, z)));
  const F usable = Greater(length, P::Splat(1e-20f));
  const F inverse = Div(one, length);
  return {SelectLanes(usable, Mul(x, inverse), zero), SelectLanes(usable, Mul(y, inverse), zero),
          SelectLanes(usable, Mul(z, inverse), one)};
}

// One walk visit (BodyMapWalk::VisitTexel without gaps) of the lanes' texels over
// [s_enter, s_exit], z from z_enter to z_exit, `inside` at the entry point: where each lane
// enters the texel's slab first, if it does.
template <class P>
struct LaneVisit {
  typename P::F wall, front, back;  // masks: entered through a side wall, the front, the back
  typename P::F s, z;               // the entry parameter and the entry's z (surface or z_enter)
  typename P::F inside_after;       // no entry and inside at s_exit
};

template <class P>
LaneVisit<P> VisitLanes(typename P::F top, typename P::F bottom, typename P::F s_enter,
                        typename P::F s_exit, typename P::F z_enter, typename P::F z_exit,
                        typename P::F inside) {
  using F = typename P::F;
  LaneVisit<P> visit;
  const F in_enter = And(LessEq(z_enter, top), GreaterEq(z_enter, bottom));
  const F above = Greater(z_enter, top);  // also every background texel (top = -inf)
  visit.wall = AndNot(inside, in_enter);
  visit.front = AndNot(in_enter, And(above, LessEq(z_exit, top)));
  visit.back = AndNot(in_enter, AndNot(above, GreaterEq(z_exit, bottom)));
  // CrossingS(surface, z_enter, z_exit, s_enter, s_exit).
  const F surface = SelectLanes(above, top, bottom);
  const F r = Div(Sub(surface, z_enter), Sub(z_exit, z_enter));
  const F crossing = StdMin(StdMax(Add(s_enter, Mul(r, Sub(s_exit, s_enter))), s_enter), s_exit);
  visit.s = SelectLanes(visit.wall, s_enter, crossing);
  visit.z = SelectLanes(visit.wall, z_enter, surface);
  visit.inside_after =
      And(And(inside, in_enter), And(LessEq(z_exit, top), GreaterEq(z_exit, bottom)));
  return visit;
}

// Lanes whose nine input values are all finite: a sum holding a NaN or an infinity is not
// finite (an overflowing one only sends a finite lane to the one-by-one path).
template <class P>
typename P::F FiniteLanes(const Lanes3<P>& p0, const Lanes3<P>& p1, const Lanes3<P>& v) {
  const typename P::F sum =
      Add(Add(Add(Add(p0.x, p0.y), Add(p0.z, p1.x)), Add(Add(p1.y, p1.z), Add(v.x, v.y))), v.z);
  return Equal(Sub(sum, sum), P::Zero());
}

// BodyMapCollider::ToTexels of the motions a -> b: u0, v0, u1, v1.
template <class P>
struct TexelLanes {
  typename P::F u0, v0, u1, v1;
};
template <class P>
TexelLanes<P> ToTexelLanes(const Lanes3<P>& a, const Lanes3<P>& b, float origin_x, float origin_y,
                           float inverse_texel) {
  const typename P::F ox = P::Splat(origin_x), oy = P::Splat(origin_y);
  const typename P::F inverse = P::Splat(inverse_texel);
  return {Mul(Sub(a.x, ox), inverse), Mul(Sub(a.y, oy), inverse), Mul(Sub(b.x, ox), inverse),
          Mul(Sub(b.y, oy), inverse)};
}

// Two lane triples to memory, lane by lane: out[0..2] = a.x, a.y, a.z; out[3..5] = b's.
template <class P>
void StoreLanes(const Lanes3<P>& a, const Lanes3<P>& b, float (&out)[6][P::kCount]) {
  P::Store(out[0], a.x);
  P::Store(out[1], a.y);
  P::Store(out[2], a.z);
  P::Store(out[3], b.x);
  P::Store(out[4], b.y);
  P::Store(out[5], b.z);
}

// WalkInto's contact point in lanes: the entry at parameter s on the walked segment q0 -> q1,
// at z = entry_z, stepped back across a side wall (`wall` lanes) by `back_off_length` (metres)
// when the segment moves in x or y; or, for the `push_out` lanes, p1 moved along z to the nearer
// surface of its interval [end_bottom, end_top] (push_back: the bottom one).
template <class P>
struct LanePoint {
  Lanes3<P> point;
  typename P::F push_back;
};
template <class P>
[[gnu::always_inline]] inline LanePoint<P> PlaceContactLanes(
    const Lanes3<P>& q0, const Lanes3<P>& q1, typename P::F s, typename P::F entry_z,
    typename P::F wall, typename P::F push_out, const Lanes3<P>& p1, typename P::F end_top,
    typename P::F end_bottom, float back_off_length) {
  using F = typename P::F;
  const F zero = P::Zero();
  const F dx = Sub(q1.x, q0.x), dy = Sub(q1.y, q0.y);
  F back_off = zero, stepped_back = zero;
  if (LaneBits(wall) != 0) {
    const F length = Sqrt(Add(Mul(dx, dx), Mul(dy, dy)));
    back_off = Div(P::Splat(back_off_length), length);
    stepped_back = And(wall, Greater(length, zero));
  }
  const F x = AlongLanes<P>(q0.x, q1.x, s), y = AlongLanes<P>(q0.y, q1.y, s);
  LanePoint<P> placed;
  placed.push_back = Less(Sub(p1.z, end_bottom), Sub(end_top, p1.z));
  placed.point = {
      SelectLanes(push_out, p1.x, SelectLanes(stepped_back, Sub(x, Mul(dx, back_off)), x)),
      SelectLanes(push_out, p1.y, SelectLanes(stepped_back, Sub(y, Mul(dy, back_off)), y)),
      SelectLanes(push_out, SelectLanes(placed.push_back, end_bottom, end_top), entry_z)};
  return placed;
}

// The lanes' answers: ApplyResponse (collision_types.h) at `point` with `normal` for the lanes
// in contact, and the flags CollideOne gives. `p` and `v` hold the lanes' positions and
// velocities as read: a lane without contact gets them back, the same bits, so that no write
// waits on a branch over the contact (which lanes touch the body is data, and a mispredicted
// branch costs more than the store).
template <class P>
struct LaneAnswers {
  Lanes3<P> position, velocity;
};
template <class P>
[[gnu::always_inline]] inline LaneAnswers<P> RespondLanes(uint32_t contact_lanes,
                                                          const Lanes3<P>& point,
                                                          const Lanes3<P>& normal,
                                                          const Lanes3<P>& p, const Lanes3<P>& v,
                                                          const ResponseParams& params) {
  using F = typename P::F;
  // The position on the surface plus the separation; the velocity only where it points into
  // the body.
  const F zero = P::Zero();
  const F in_contact = MaskOfLanes<P>(contact_lanes);
  const F separation = P::Splat(params.separation);
  const auto place = [&](F on_surface, F n, F unchanged) {
    return SelectLanes(in_contact, Add(on_surface, Mul(n, separation)), unchanged);
  };
  const Lanes3<P> position = {place(point.x, normal.x, p.x), place(point.y, normal.y, p.y),
                              place(point.z, normal.z, p.z)};
  const F vn = Add(Add(Mul(v.x, normal.x), Mul(v.y, normal.y)), Mul(v.z, normal.z));
  const F keep = P::Splat(1.f - params.friction);
  const F restitution = P::Splat(params.restitution);
  const F into = And(in_contact, Less(vn, zero));
  const auto respond = [&](F velocity, F n) {
    const F normal_part = Mul(n, vn);
    const F changed = Sub(Mul(Sub(velocity, normal_part), keep), Mul(normal_part, restitution));
    return SelectLanes(into, changed, velocity);
  };
  return {position, {respond(v.x, normal.x), respond(v.y, normal.y), respond(v.z, normal.z)}};
}

// Byte l of the result is bit l of `bits` (l < 8): a copy of the eight bits in every byte
// (no carries), byte l keeps its bit l, and adding 0x7f carries any set bit into bit 7 of the
// same byte (at most 0x80 + 0x7f: no carry out of it).
constexpr uint64_t SpreadLaneBits(uint32_t bits) {
  const uint64_t kept =
      (static_cast<uint64_t>(bits & 0xffu) * 0x0101010101010101ull) & 0x8040201008040201ull;
  return ((kept + 0x7f7f7f7f7f7f7f7full) >> 7) & 0x0101010101010101ull;
}
constexpr bool SpreadsEveryLaneMask() {
  for (uint32_t bits = 0; bits < 256; ++bits) {
    for (uint32_t lane = 0; lane < 8; ++lane) {
      if (((SpreadLaneBits(bits) >> (8 * lane)) & 0xffu) != ((bits >> lane) & 1u)) return false;
    }
  }
  return true;
}
static_assert(SpreadsEveryLaneMask());

// The flags CollideOne gives, lane l in byte l.
inline uint64_t LaneFlagBytes(uint32_t contact_lanes, uint32_t wall_lanes,
                              uint32_t started_inside_lanes) {
  const uint32_t wall = wall_lanes & contact_lanes;
  const uint32_t started_inside = started_inside_lanes & ~wall_lanes & contact_lanes;
  return SpreadLaneBits(contact_lanes) * kCollisionContact |
         SpreadLaneBits(wall) * kCollisionSideWall |
         SpreadLaneBits(started_inside) * kCollisionStartedInside;
}

// The answers of every lane, to P::kCount consecutive elements of the arrays: two stores of
// triples and one of the flag bytes.
template <class P>
[[gnu::always_inline]] inline void WriteConsecutiveLaneAnswers(
    uint32_t contact_lanes, uint32_t wall_lanes, uint32_t started_inside_lanes,
    const Lanes3<P>& point, const Lanes3<P>& normal, const Lanes3<P>& p, const Lanes3<P>& v,
    const ResponseParams& params, Float3* positions, Float3* velocities, uint8_t* flags) {
  static_assert(sizeof(Float3) == 3 * sizeof(float), "StoreFloat3s writes packed triples");
  static_assert(std::endian::native == std::endian::little, "lane l's flag in byte l");
  const LaneAnswers<P> answers = RespondLanes<P>(contact_lanes, point, normal, p, v, params);
  P::StoreFloat3s(positions, answers.position.x, answers.position.y, answers.position.z);
  P::StoreFloat3s(velocities, answers.velocity.x, answers.velocity.y, answers.velocity.z);
  const uint64_t bytes = LaneFlagBytes(contact_lanes, wall_lanes, started_inside_lanes);
  std::memcpy(flags, &bytes, P::kCount);
}

// The answers of the lanes in `lanes`, to element index[l] of the arrays for lane l.
template <class P>
[[gnu::always_inline]] inline void WriteLaneAnswers(const uint32_t* index, uint32_t lanes,
                                                    uint32_t contact_lanes, uint32_t wall_lanes,
                                                    uint32_t started_inside_lanes,
                                                    const Lanes3<P>& point, const Lanes3<P>& normal,
                                                    const Lanes3<P>& p, const Lanes3<P>& v,
                                                    const ResponseParams& params, Float3* positions,
                                                    Float3* velocities, uint8_t* flags) {
  const LaneAnswers<P> answers = RespondLanes<P>(contact_lanes, point, normal, p, v, params);
  alignas(32) float out[6][P::kCount];
  StoreLanes<P>(answers.position, answers.velocity, out);
  const uint64_t bytes = LaneFlagBytes(contact_lanes, wall_lanes, started_inside_lanes);
  for (int lane = 0; lane < P::kCount; ++lane) {
    if (!((lanes >> lane) & 1u)) continue;
    const uint32_t k = index[lane];
    positions[k] = Float3{out[0][lane], out[1][lane], out[2][lane]};
    velocities[k] = Float3{out[3][lane], out[4][lane], out[5][lane]};
    flags[k] = static_cast<uint8_t>(bytes >> (8 * lane));
  }
}

// The lanes of `which` whose texel has gaps, from the flag in their slabs' tops as loaded
// (BodyMapCollider::Finish).
template <class P>
uint32_t LanesWithGaps(typename P::F top, uint32_t which) {
  const typename P::I flag = P::SplatI(1);
  return which & LaneBits(AsFloat(Equal(And(AsInt(top), flag), flag)));
}

}  // namespace

// A texel's inside set with gaps (BodyMapCollider::TexelIntervals) is its slab less the open
// gaps, split into intervals whose surfaces have slots (BodyMapCollider::Interval): the slab's
// front and back, and per gap g its lower boundary (an interval's top, slot 3 + 2g) and its upper
// one (an interval's bottom, slot 2 + 2g).
template <class P>
struct BodyMapCollider::GapLanes {
  using F = typename P::F;
  using I = typename P::I;
  uint32_t layers = 0;  // the gap layers gathered (GatherGapLanes), at most gap_layers_
  F top[kMaxBodyMapLayers - 1], bottom[kMaxBodyMapLayers - 1];

  // z strictly inside one of the gaps (BodyMapCollider::InGap).
  F InGap(F z) const {
    F in = P::Zero();
    for (uint32_t g = 0; g < layers; ++g) in = Or(in, And(Less(z, top[g]), Greater(z, bottom[g])));
    return in;
  }
  // The interval holding z (IntervalAmongGaps): bounded by the nearest gap boundary or slab
  // surface above and below z.
  struct Interval {
    F top, bottom;
    I top_slot, bottom_slot;
  };
  Interval Around(F z, F slab_top, F slab_bottom) const {
    Interval in{slab_top, slab_bottom, P::SplatI(kFrontSlot), P::SplatI(kBackSlot)};
    for (uint32_t g = 0; g < layers; ++g) {
      const F lower_above = And(GreaterEq(bottom[g], z), Less(bottom[g], in.top));
      in.top = SelectLanes(lower_above, bottom[g], in.top);
      in.top_slot = SelectLanesI(lower_above, P::SplatI(3 + 2 * static_cast<int>(g)), in.top_slot);
      const F upper_below = And(LessEq(top[g], z), Greater(top[g], in.bottom));
      in.bottom = SelectLanes(upper_below, top[g], in.bottom);
      in.bottom_slot =
          SelectLanesI(upper_below, P::SplatI(2 + 2 * static_cast<int>(g)), in.bottom_slot);
    }
    return in;
  }
  // One walk visit with gaps (BodyMapWalk::VisitTexelWithGaps) of the piece z_enter -> z_exit,
  // `inside` at its entry point. z is monotone along the piece, so the first entry is into the
  // interval holding z_enter (a side wall) or into the next interval in the direction of motion.
  // VisitLanes places the entry from kept_top / kept_bottom: the interval for a wall; the
  // surface reached as `top` (front) or `bottom` (back), the other bound out of the way.
  struct Visit {
    F wall, front, back;  // masks: how the piece enters, if it does
    F stays;              // inside at the entry and still at the exit (the next `inside`)
    F kept_top, kept_bottom;
    I top_slot, bottom_slot;  // the slots of kept_top and kept_bottom
  };
  Visit VisitTexel(F slab_top, F slab_bottom, F z_enter, F z_exit, F inside) const {
    constexpr float kInfinity = std::numeric_limits<float>::infinity();
    const F inf = P::Splat(kInfinity), minus_inf = P::Splat(-kInfinity);
    const I front_slot = P::SplatI(kFrontSlot), back_slot = P::SplatI(kBackSlot);
    const F in_enter =
        AndNot(InGap(z_enter), And(LessEq(z_enter, slab_top), GreaterEq(z_enter, slab_bottom)));
    Visit visit;
    visit.wall = AndNot(inside, in_enter);
    const Interval around = Around(z_enter, slab_top, slab_bottom);
    visit.stays = And(And(inside, in_enter),
                      And(LessEq(z_exit, around.top), GreaterEq(z_exit, around.bottom)));
    const F search = AndNot(Or(visit.wall, visit.stays), AsFloat(P::SplatI(-1)));
    // The nearest interval top below z_enter and bottom above it.
    F below = SelectLanes(Less(slab_top, z_enter), slab_top, minus_inf);
    I below_slot = front_slot;
    F over = SelectLanes(Greater(slab_bottom, z_enter), slab_bottom, inf);
    I over_slot = back_slot;
    for (uint32_t g = 0; g < layers; ++g) {
      const F lower_below = And(Less(bottom[g], z_enter), Greater(bottom[g], below));
      below = SelectLanes(lower_below, bottom[g], below);
      below_slot = SelectLanesI(lower_below, P::SplatI(3 + 2 * static_cast<int>(g)), below_slot);
      const F upper_over = And(Greater(top[g], z_enter), Less(top[g], over));
      over = SelectLanes(upper_over, top[g], over);
      over_slot = SelectLanesI(upper_over, P::SplatI(2 + 2 * static_cast<int>(g)), over_slot);
    }
    visit.front = And(search, And(Less(z_exit, z_enter), LessEq(z_exit, below)));
    visit.back = And(search, And(Greater(z_exit, z_enter), GreaterEq(z_exit, over)));
    visit.kept_top = SelectLanes(visit.wall, around.top, SelectLanes(visit.front, below, inf));
    visit.kept_bottom =
        SelectLanes(visit.wall, around.bottom, SelectLanes(visit.back, over, minus_inf));
    visit.top_slot = SelectLanesI(visit.wall, around.top_slot, below_slot);
    visit.bottom_slot = SelectLanesI(visit.wall, around.bottom_slot, over_slot);
    return visit;
  }
};

template <class P>
void BodyMapCollider::GatherGapLanes(typename P::I texel, uint32_t with_gaps,
                                     GapLanes<P>* out) const {
  constexpr int kLanes = P::kCount;
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  // out->layers counts the layers gathered: up to the last one that some lane has. An absent gap
  // (-inf, +inf) holds no z and bounds no interval, so the tests over `layers` give the same
  // answers without the layers that no lane has.
  out->layers = 0;
  if (with_gaps == 0) return;
  alignas(32) int32_t t[kLanes];
  P::Store(t, texel);
  // Each lane's gaps, or for a lane without gaps ones that hold no z (-inf, +inf): the gaps are
  // slabs, so one LoadSlabsAt per layer reads them for every lane.
  static_assert(kMaxBodyMapLayers == 4, "one absent gap per gap layer below");
  static constexpr Slab kNoGaps[kMaxBodyMapLayers - 1] = {
      {-kInfinity, kInfinity}, {-kInfinity, kInfinity}, {-kInfinity, kInfinity}};
  // (The lanes with gaps taken bit by bit: one unpredictable loop exit per call, where a test
  // of each lane's bit mispredicts up to once per lane.)
  const Slab* first[kLanes];
  for (int lane = 0; lane < kLanes; ++lane) first[lane] = kNoGaps;
  for (uint32_t bits = with_gaps; bits != 0; bits &= bits - 1u) {
    const int lane = std::countr_zero(bits);
    first[lane] = gaps_.data() + GapBaseAt(static_cast<uint32_t>(t[lane]));
  }
  // Gaps are filled from the front (Build refuses a gap after an absent one; a blend ends a
  // texel's list at the first gap it lacks), and every texel with gaps has its first. So once no
  // lane has gap g, no lane has a later one: on the bodies that need four layers most texels
  // with gaps have one, and the loads and the callers' tests of the other two are skipped.
  for (uint32_t g = 0; g < gap_layers_; ++g) {
    P::LoadSlabsAt([&first, g](int lane) { return first[lane] + g; }, &out->top[g],
                   &out->bottom[g]);
    if (g != 0 && LaneBits(Greater(out->top[g], out->bottom[g])) == 0) return;
    out->layers = g + 1;
  }
}

// The normal codes of the lanes' texels: front and back loaded as a slab's two floats are, then
// chosen by the mask. Which side each lane reads is data: a branch per lane would mispredict.
template <class P>
typename P::I BodyMapCollider::NormalCodes(const size_t* texel, typename P::F use_back) const {
  static_assert(sizeof(TexelNormals) == sizeof(Slab), "LoadSlabsAt loads both codes as 8 bytes");
  static_assert(std::endian::native == std::endian::little, "a code's first value in the low half");
  const TexelNormals* const normals = normals_.data();
  typename P::F front, back;
  P::LoadSlabsAt([normals, texel](int lane) { return normals + texel[lane]; }, &front, &back);
  return AsInt(SelectLanes(use_back, back, front));
}

// `code` with the lanes whose surface is a gap's (slot >= 2) replaced by that surface's code
// (SlotCode): few lanes, so one by one, and only when there is one.
template <class P>
typename P::I BodyMapCollider::GapSurfaceCodes(const size_t* texel, typename P::I slot,
                                               typename P::I code) const {
  constexpr int kLanes = P::kCount;
  const uint32_t gap_lanes = LaneBits(AsFloat(Greater(slot, P::SplatI(1))));
  if (gap_lanes == 0) return code;
  alignas(32) int32_t codes[kLanes], slots[kLanes];
  P::Store(codes, code);
  P::Store(slots, slot);
  for (uint32_t bits = gap_lanes; bits != 0; bits &= bits - 1u) {
    const int lane = std::countr_zero(bits);
    const uint16_t* q = SlotCode(static_cast<uint32_t>(texel[lane]), slots[lane]);
    codes[lane] = static_cast<int32_t>(q[0] | static_cast<uint32_t>(q[1]) << 16);
  }
  return P::FromLanesI([&](int l) { return codes[l]; });
}

template <class P>
uint32_t BodyMapCollider::CollideShortLanes(const Float3* previous, Float3* positions,
                                            Float3* velocities, uint8_t* flags,
                                            const ResponseParams& params,
                                            uint32_t* long_motions) const {
  using F = typename P::F;
  using I = typename P::I;
  constexpr int kLanes = P::kCount;
  const Lanes3<P> p0 = LoadFloat3Lanes<P>(previous), p1 = LoadFloat3Lanes<P>(positions),
                  v = LoadFloat3Lanes<P>(velocities);
  const F zero = P::Zero(), one = P::Splat(1.f);
  const F finite = FiniteLanes<P>(p0, p1, v);
  F answerable = finite;
  // Both ends on the grid (ToTexels' expressions) and in the clip box's z range.
  const TexelLanes<P> texels = ToTexelLanes<P>(p0, p1, origin_x_, origin_y_, inv_texel_size_);
  const F u0 = texels.u0, v0 = texels.v0, u1 = texels.u1, v1 = texels.v1;
  const F width = P::Splat(width_f_), height = P::Splat(height_f_);
  const auto within = [&](F x, F lo, F hi) { return And(GreaterEq(x, lo), LessEq(x, hi)); };
  const auto on_grid = [&](F u, F limit) { return And(GreaterEq(u, zero), Less(u, limit)); };
  answerable = And(answerable, And(on_grid(u0, width), on_grid(v0, height)));
  answerable = And(answerable, And(on_grid(u1, width), on_grid(v1, height)));
  const F z_lo = P::Splat(bounds_min_.z), z_hi = P::Splat(bounds_max_.z);
  answerable = And(answerable, And(within(p0.z, z_lo, z_hi), within(p1.z, z_lo, z_hi)));
  const F x_lo = P::Splat(clip_lo_float_[0]), x_hi = P::Splat(clip_hi_float_[0]);
  const F y_lo = P::Splat(clip_lo_float_[1]), y_hi = P::Splat(clip_hi_float_[1]);
  // The texels (truncation as in the scalar path; off-grid lanes are not used): one texel, or
  // two across one edge (the walk's one-crossing path: two visits split at s_cross).
  const I i0 = TruncateToInt(u0), j0 = TruncateToInt(v0);
  const I i1 = TruncateToInt(u1), j1 = TruncateToInt(v1);
  const I same_i = Equal(i0, i1), same_j = Equal(j0, j1);
  const I di = Sub(i1, i0), dj = Sub(j1, j0);
  const I minus_one_i = P::SplatI(-1), one_i = P::SplatI(1);
  const I step_i = Or(Equal(di, one_i), Equal(di, minus_one_i));
  const I step_j = Or(Equal(dj, one_i), Equal(dj, minus_one_i));
  const F in_one = AsFloat(And(same_i, same_j));
  const F across_i = AsFloat(And(step_i, same_j));
  const F across_j = AsFloat(And(same_i, step_j));
  const F two = Or(across_i, across_j);
  // A motion across an edge is walked only when it needs no clipping: both ends inside the clip
  // box in x and y too (in one valid texel they are; a background texel holds nothing).
  const F in_box = And(answerable, And(And(within(p0.x, x_lo, x_hi), within(p1.x, x_lo, x_hi)),
                                       And(within(p0.y, y_lo, y_hi), within(p1.y, y_lo, y_hi))));
  *long_motions = LaneBits(AndNot(Or(in_one, two), in_box));
  answerable = Or(And(answerable, in_one), And(in_box, two));
  // A motion that stays at one coordinate outside the clip box never enters it (ClipMotion's
  // test for a zero extent, exact): no contact. Points away from the body are most of these.
  const auto fixed_outside = [&](F a, F b, F lo, F hi) {
    return AndNot(within(a, lo, hi), Equal(a, b));
  };
  const uint32_t free_lanes = LaneBits(And(finite, Or(Or(fixed_outside(p0.x, p1.x, x_lo, x_hi),
                                                         fixed_outside(p0.y, p1.y, y_lo, y_hi)),
                                                      fixed_outside(p0.z, p1.z, z_lo, z_hi)))) &
                              ~LaneBits(answerable);
  // Every lane's flag starts as no contact (one store): the free lanes' answer, and the lanes in
  // air keep it. The lanes not answered here get theirs from the walk or one by one, after.
  for (int lane = 0; lane < kLanes; ++lane) flags[lane] = kCollisionNone;
  uint32_t lanes = LaneBits(answerable);
  if (lanes == 0) return free_lanes;

  // The lanes' slabs: A holds p0, B holds p1 (texel 0 for unused lanes, never used).
  alignas(32) int32_t ia[kLanes], ja[kLanes], ib[kLanes], jb[kLanes];
  P::Store(ia, i0);
  P::Store(ja, j0);
  P::Store(ib, i1);
  P::Store(jb, j1);
  // (The indices are formed lane by lane and the slabs read at them lane by lane: a vector read
  // of indices just written lane by lane would stall the store forwarding.)
  static_assert(sizeof(Slab) == 2 * sizeof(float), "LoadSlabsAt loads a slab as 8 bytes");
  size_t texel_a[kLanes], texel_b[kLanes];
  for (int lane = 0; lane < kLanes; ++lane) {
    // Masked, not branched on: which lanes are used is data. (Unsigned: an unused lane's
    // indices are whatever its coordinates truncated to.)
    const uint32_t keep = 0u - ((lanes >> lane) & 1u);
    const uint32_t row = width_;
    texel_a[lane] =
        keep & (static_cast<uint32_t>(ja[lane]) * row + static_cast<uint32_t>(ia[lane]));
    texel_b[lane] =
        keep & (static_cast<uint32_t>(jb[lane]) * row + static_cast<uint32_t>(ib[lane]));
  }
  const Slab* const slabs = slabs_.data();
  F slab_a_top, slab_a_bottom, slab_b_top, slab_b_bottom;
  P::LoadSlabsAt([slabs, &texel_a](int lane) { return slabs + texel_a[lane]; }, &slab_a_top,
                 &slab_a_bottom);
  P::LoadSlabsAt([slabs, &texel_b](int lane) { return slabs + texel_b[lane]; }, &slab_b_top,
                 &slab_b_bottom);
  // Groups without a lane across an edge (points, resting cloth) skip the second visit.
  const uint32_t two_lanes = LaneBits(two) & lanes;
  // The gaps of texels A and B (absent ones: -inf, +inf; B is A without a lane across an edge);
  // a group with none takes the slab-only visits below, which give the same answers for such
  // lanes with less work.
  GapLanes<P> gaps_a, gaps_b;
  bool with_gaps = false;
  if (gap_layers_ != 0) {
    const auto texel_lanes = [&](const size_t* texel) {
      return P::FromLanesI([&](int l) { return static_cast<int32_t>(texel[l]); });
    };
    const uint32_t gap_lanes_a = LanesWithGaps<P>(slab_a_top, lanes);
    const uint32_t gap_lanes_b = two_lanes != 0 ? LanesWithGaps<P>(slab_b_top, lanes) : 0u;
    with_gaps = (gap_lanes_a | gap_lanes_b) != 0;
    if (with_gaps) {
      GatherGapLanes<P>(texel_lanes(texel_a), gap_lanes_a, &gaps_a);
      gaps_b = gaps_a;
      if (two_lanes != 0) GatherGapLanes<P>(texel_lanes(texel_b), gap_lanes_b, &gaps_b);
    }
  }

  // The walk (BodyMapWalk::Run<1>): the crossing parameter of the edge, A over [0, s_cross],
  // then B over [s_cross, 1]. One texel: A over [0, 1], and B (the same texel) adds nothing.
  // SafeInverse, then the one-crossing path's min(max((edge - g0) * inverse, 0), 1).
  const auto crossing = [&](I a, I b, F g0, F g1) {
    const F inverse_d = StdMin(StdMax(Div(one, Sub(g1, g0)), P::Splat(-1e30f)), P::Splat(1e30f));
    const I edge = Or(And(Greater(b, a), b), AndNot(Greater(b, a), a));
    return StdMin(StdMax(Mul(Sub(ToFloat(edge), g0), inverse_d), zero), one);
  };
  F s_cross = one, z_cross = p1.z;  // Z(1) = z1 exactly
  if (two_lanes != 0) {
    s_cross = SelectLanes(across_i, crossing(i0, i1, u0, u1),
                          SelectLanes(across_j, crossing(j0, j1, v0, v1), one));
    z_cross = AlongLanes<P>(p0.z, p1.z, s_cross);
  }
  // IsInside(p0) by the slab alone, as the walk starts (a start in a gap is outside every
  // interval, which the gap visit sees at its entry point).
  const F start_inside = And(LessEq(p0.z, slab_a_top), GreaterEq(p0.z, slab_a_bottom));
  // Each visit: whether and how it enters (VisitLanes' masks), where (s, z), and what the answer
  // needs of the entered texel: the entered interval's or surface's bounds and, with gaps, their
  // slots. p1's interval bounds a push-out.
  LaneVisit<P> in_a, in_b;
  F hit_a, hit_b = zero;
  F entered_top, entered_bottom;  // of the entered interval (a side wall's: B's)
  I entered_top_slot = P::SplatI(kFrontSlot), entered_bottom_slot = P::SplatI(kBackSlot);
  F end_top = slab_b_top, end_bottom = slab_b_bottom, end_in_gap = zero;
  I end_top_slot = entered_top_slot, end_bottom_slot = entered_bottom_slot;
  if (!with_gaps) {
    in_a = VisitLanes<P>(slab_a_top, slab_a_bottom, zero, s_cross, p0.z, z_cross, start_inside);
    hit_a = Or(in_a.front, in_a.back);  // no wall at s = 0 without clipping
    in_b = in_a;                        // unused without a lane across an edge
    if (two_lanes != 0) {
      in_b =
          VisitLanes<P>(slab_b_top, slab_b_bottom, s_cross, one, z_cross, p1.z, in_a.inside_after);
      hit_b = AndNot(hit_a, And(two, Or(in_b.wall, Or(in_b.front, in_b.back))));
    }
    entered_top = slab_b_top;
    entered_bottom = slab_b_bottom;
  } else {
    // The walk's visits with gaps (CollideWalkLanes), then VisitLanes places each entry.
    const F all_lanes = AsFloat(P::SplatI(-1));
    const typename GapLanes<P>::Visit visit_a =
        gaps_a.VisitTexel(slab_a_top, slab_a_bottom, p0.z, z_cross, start_inside);
    hit_a = Or(visit_a.wall, Or(visit_a.front, visit_a.back));
    in_a = VisitLanes<P>(visit_a.kept_top, visit_a.kept_bottom, zero, s_cross, p0.z, z_cross,
                         AndNot(visit_a.wall, all_lanes));
    typename GapLanes<P>::Visit visit_b = visit_a;
    in_b = in_a;
    if (two_lanes != 0) {
      visit_b = gaps_b.VisitTexel(slab_b_top, slab_b_bottom, z_cross, p1.z, visit_a.stays);
      hit_b = AndNot(hit_a, And(two, Or(visit_b.wall, Or(visit_b.front, visit_b.back))));
      in_b = VisitLanes<P>(visit_b.kept_top, visit_b.kept_bottom, s_cross, one, z_cross, p1.z,
                           AndNot(visit_b.wall, all_lanes));
    }
    entered_top = SelectLanes(hit_a, visit_a.kept_top, visit_b.kept_top);
    entered_bottom = SelectLanes(hit_a, visit_a.kept_bottom, visit_b.kept_bottom);
    entered_top_slot = SelectLanesI(hit_a, visit_a.top_slot, visit_b.top_slot);
    entered_bottom_slot = SelectLanesI(hit_a, visit_a.bottom_slot, visit_b.bottom_slot);
    // IsInside(p1) excludes B's gaps, and a push-out goes to the nearer surface of p1's
    // interval (IntervalAt).
    end_in_gap = gaps_b.InGap(p1.z);
    const typename GapLanes<P>::Interval around = gaps_b.Around(p1.z, slab_b_top, slab_b_bottom);
    end_top = around.top;
    end_bottom = around.bottom;
    end_top_slot = around.top_slot;
    end_bottom_slot = around.bottom_slot;
  }
  const F wall = And(hit_b, in_b.wall);
  // No entry and p1 inside (IsInside(p1): texel B's slab less its gaps): pushed out along z.
  const F inside_end =
      AndNot(end_in_gap, And(LessEq(p1.z, slab_b_top), GreaterEq(p1.z, slab_b_bottom)));
  const F push_out = AndNot(Or(hit_a, hit_b), inside_end);
  const F contact = Or(Or(hit_a, hit_b), push_out);
  const uint32_t contact_lanes = LaneBits(contact) & lanes;
  if (contact_lanes == 0) return lanes | free_lanes;  // points and motions in air

  // The contact point: on the segment at the entry, stepped back across a side wall by 1e-3
  // texel (WalkInto), or p1 moved to the nearer surface of its interval.
  const F s_hit = SelectLanes(hit_a, in_a.s, in_b.s);
  const F z_hit = SelectLanes(hit_a, in_a.z, in_b.z);
  // (A lane crossing an edge moves at least a float step of u, so its length in x and y never
  // underflows; the lanes test it anyway, so that they stay the walk's operations one for one.)
  const LanePoint<P> placed = PlaceContactLanes<P>(p0, p1, s_hit, z_hit, wall, push_out, p1,
                                                   end_top, end_bottom, 1e-3f * texel_size_);
  // The normal: the entered surface's; at a side wall the nearer surface of the entered
  // interval; for the push-out the surface p1 goes to.
  const F wall_back = Less(Sub(z_hit, entered_bottom), Sub(entered_top, z_hit));
  const F use_back =
      SelectLanes(push_out, placed.push_back,
                  SelectLanes(wall, wall_back, SelectLanes(hit_a, in_a.back, in_b.back)));
  const uint32_t from_a = LaneBits(hit_a);
  // With gaps, a gap's surface (slot >= 2) has its normal among the gaps' (SlotCode).
  size_t normal_texel[kLanes];
  for (int lane = 0; lane < kLanes; ++lane) {
    normal_texel[lane] = (from_a >> lane) & 1u ? texel_a[lane] : texel_b[lane];  // push-out: B
  }
  I code = NormalCodes<P>(normal_texel, use_back);
  if (with_gaps) {
    code = GapSurfaceCodes<P>(
        normal_texel,
        SelectLanesI(push_out, SelectLanesI(use_back, end_bottom_slot, end_top_slot),
                     SelectLanesI(use_back, entered_bottom_slot, entered_top_slot)),
        code);
  }
  const Lanes3<P> normal = DecodeOct16Lanes<P>(code);
  const uint32_t wall_lanes = LaneBits(wall);
  const uint32_t started_inside_lanes = LaneBits(And(push_out, start_inside));
  // Every lane is written, with no branch on which are answered: the others get their own
  // position and velocity back and a flag the walk or the one-by-one query replaces.
  WriteConsecutiveLaneAnswers<P>(contact_lanes, wall_lanes, started_inside_lanes, placed.point,
                                 normal, p1, v, params, positions, velocities, flags);
  return lanes | free_lanes;
}

template <class P>
uint32_t BodyMapCollider::CollideWalkLanes(const uint32_t* index, uint32_t lanes,
                                           const Float3* previous, Float3* positions,
                                           Float3* velocities, uint8_t* flags,
                                           const ResponseParams& params) const {
  using F = typename P::F;
  using I = typename P::I;
  constexpr int kLanes = P::kCount;
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  const auto gather = [&](const Float3* a) {
    return Lanes3<P>{P::FromLanes([&](int l) { return a[index[l]].x; }),
                     P::FromLanes([&](int l) { return a[index[l]].y; }),
                     P::FromLanes([&](int l) { return a[index[l]].z; })};
  };
  const Lanes3<P> p0 = gather(previous), p1 = gather(positions), v = gather(velocities);
  // Finite input (non-finite lanes go one by one, which flags them).
  const F zero = P::Zero(), one = P::Splat(1.f), inf = P::Splat(kInfinity);
  lanes &= LaneBits(FiniteLanes<P>(p0, p1, v));
  if (lanes == 0) return 0;
  // Ends in the clip box (its x and y as the nearest inside floats: the double test's answer).
  // (The lambdas taking or returning lanes all capture: a capture-less one gets a conversion to
  // a function pointer, which the compiler writes outside the AVX2 region of its includer.)
  const auto within = [&](F x, F lo, F hi) { return And(GreaterEq(x, lo), LessEq(x, hi)); };
  const F x_lo = P::Splat(clip_lo_float_[0]), x_hi = P::Splat(clip_hi_float_[0]);
  const F y_lo = P::Splat(clip_lo_float_[1]), y_hi = P::Splat(clip_hi_float_[1]);
  const F z_lo = P::Splat(bounds_min_.z), z_hi = P::Splat(bounds_max_.z);
  const auto in_box = [&](const Lanes3<P>& p) {
    return And(And(within(p.x, x_lo, x_hi), within(p.y, y_lo, y_hi)), within(p.z, z_lo, z_hi));
  };
  const F p1_in_box = in_box(p1);
  // The walked segment q0 -> q1: the motion itself, or clipped to the box (ClipMotion, one lane
  // at a time: motions from outside the box are a few percent).
  Lanes3<P> q0 = p0, q1 = p1;
  const uint32_t clipped_lanes = lanes & ~LaneBits(And(in_box(p0), p1_in_box));
  uint32_t start_clipped = 0, start_on_z_face = 0, answered_misses = 0;
  if (clipped_lanes != 0) {
    alignas(32) float ends[6][kLanes];
    StoreLanes<P>(q0, q1, ends);
    for (uint32_t bits = clipped_lanes; bits != 0; bits &= bits - 1u) {  // one exit to predict
      const int lane = std::countr_zero(bits);
      ClippedMotion clip;
      if (!ClipMotion(previous[index[lane]], positions[index[lane]], &clip)) {
        flags[index[lane]] = kCollisionNone;  // misses the box: no contact, ends outside
        answered_misses |= 1u << lane;
        continue;
      }
      const float q[6] = {clip.q0.x, clip.q0.y, clip.q0.z, clip.q1.x, clip.q1.y, clip.q1.z};
      for (int k = 0; k < 6; ++k) ends[k][lane] = q[k];
      start_clipped |= static_cast<uint32_t>(clip.t_start > 0.0) << lane;
      start_on_z_face |= static_cast<uint32_t>(clip.start_on_z_face) << lane;
    }
    lanes &= ~answered_misses;
    // Read back lane by lane: a vector load of lanes just written one by one would stall the
    // store forwarding.
    const auto lanes_of = [&](int k) { return P::FromLanes([&](int l) { return ends[k][l]; }); };
    q0 = {lanes_of(0), lanes_of(1), lanes_of(2)};
    q1 = {lanes_of(3), lanes_of(4), lanes_of(5)};
  }
  // Both walked ends on the grid (the box can reach a texel beyond it).
  // (Named copies, not a structured binding: lambdas below capture them, which clang < 16
  // rejects for bindings.)
  const TexelLanes<P> texels = ToTexelLanes<P>(q0, q1, origin_x_, origin_y_, inv_texel_size_);
  const F u0 = texels.u0, v0 = texels.v0, u1 = texels.u1, v1 = texels.v1;
  const F width = P::Splat(width_f_), height = P::Splat(height_f_);
  const auto on_grid = [&](F u, F limit) { return And(GreaterEq(u, zero), Less(u, limit)); };
  lanes &= LaneBits(And(And(on_grid(u0, width), on_grid(v0, height)),
                        And(on_grid(u1, width), on_grid(v1, height))));
  if (lanes == 0) return answered_misses;
  // The end texels (truncation is the floor on the grid) and the texel edges between them.
  const I i0 = TruncateToInt(u0), j0 = TruncateToInt(v0);
  const I i1 = TruncateToInt(u1), j1 = TruncateToInt(v1);
  const I di = Sub(i1, i0), dj = Sub(j1, j0);
  I left_i = Abs(di), left_j = Abs(dj);

  // Texels with gaps (maps.layers > 1): their inside set is the slab less the open gaps.
  const I front_slot = P::SplatI(kFrontSlot), back_slot = P::SplatI(kBackSlot);
  const F all_lanes = AsFloat(P::SplatI(-1));

  // Texel indices (row-major) of the start and of the end. With p1 in the box the end is p1's
  // texel, whose slab answers IsInside(p1); beyond the box p1 is outside.
  alignas(32) int32_t ia[kLanes], ja[kLanes], ib[kLanes], jb[kLanes], start[kLanes];
  P::Store(ia, i0);
  P::Store(ja, j0);
  P::Store(ib, i1);
  P::Store(jb, j1);
  int32_t texel_b[kLanes];
  const uint32_t p1_in_box_lanes = LaneBits(p1_in_box);
  for (int lane = 0; lane < kLanes; ++lane) {
    // Masked, not branched on, as in CollideShortLanes.
    const uint32_t keep = 0u - ((lanes >> lane) & 1u);
    const uint32_t row = width_;
    start[lane] = static_cast<int32_t>(
        keep & (static_cast<uint32_t>(ja[lane]) * row + static_cast<uint32_t>(ia[lane])));
    texel_b[lane] = static_cast<int32_t>(
        keep & (static_cast<uint32_t>(jb[lane]) * row + static_cast<uint32_t>(ib[lane])));
  }
  // With gap layers every walk runs the loop with the gap tests. Where a step meets no texel with
  // gaps they cost a few mask operations (LanesWithGaps finds none, and nothing is gathered).
  // Asking first whether any 8x8 block under a lane's walk has gaps (a summed-area table, four
  // reads per lane) saved 0.7-0.9 % of the instructions where few walks have gaps near
  // (CesiumMan, 27 % of walk groups) and cost 3.1-3.6 % where nearly all do (Animated_Human,
  // RobotExpressive: the bodies that need the layers); docs/PERFORMANCE.md, sixteenth session.
  const bool gaps_near = gap_layers_ != 0;
  static_assert(sizeof(Slab) == 2 * sizeof(float), "LoadSlabsAt loads a slab as 8 bytes");
  const Slab* const slabs = slabs_.data();
  const auto load_slabs = [&](const int32_t* at, F* top, F* bottom) {
    P::LoadSlabsAt([slabs, at](int lane) { return slabs + at[lane]; }, top, bottom);
  };
  F slab_b_top, slab_b_bottom;
  load_slabs(texel_b, &slab_b_top, &slab_b_bottom);
  // With gaps at p1's texel: IsInside(p1) excludes the gaps, and a push-out goes to the nearer
  // surface of p1's interval (IntervalAt).
  F end_in_gap = zero;
  I end_top_slot = front_slot, end_bottom_slot = back_slot;
  if (gaps_near) {
    const uint32_t end_gap_lanes = LanesWithGaps<P>(slab_b_top, lanes & p1_in_box_lanes);
    if (end_gap_lanes != 0) {
      GapLanes<P> gaps;
      GatherGapLanes<P>(P::FromLanesI([&](int l) { return texel_b[l]; }), end_gap_lanes, &gaps);
      end_in_gap = gaps.InGap(p1.z);
      const typename GapLanes<P>::Interval around = gaps.Around(p1.z, slab_b_top, slab_b_bottom);
      slab_b_top = around.top;
      slab_b_bottom = around.bottom;
      end_top_slot = around.top_slot;
      end_bottom_slot = around.bottom_slot;
    }
  }

  // The walk (BodyMapWalk::Run<1>, WalkCells with cells of one texel). Each step moves to the
  // neighbour across the edge the segment crosses first, both on an exact corner; the crossing
  // parameters are (edge - g0) * SafeInverse(g1 - g0), +inf on an axis with no edge left. Run's
  // path for at most one edge per axis clamps them to [0, 1] (so a corner both reach at s = 1
  // is one step): the lanes clamp where it applies, which is only the first crossing.
  const auto safe_inverse = [&](F d) {
    return StdMin(StdMax(Div(one, d), P::Splat(-1e30f)), P::Splat(1e30f));
  };
  const F inv_du = safe_inverse(Sub(u1, u0)), inv_dv = safe_inverse(Sub(v1, v0));
  const I zero_i = P::ZeroI(), one_i = P::SplatI(1);
  const I up_i = Greater(di, zero_i), down_i = Less(di, zero_i);
  const I up_j = Greater(dj, zero_i), down_j = Less(dj, zero_i);
  const I step_i = Sub(down_i, up_i);  // +1, -1 or 0
  const I step_j = Sub(down_j, up_j);
  const I width_i = P::SplatI(static_cast<int32_t>(width_));
  const I step_row = Or(And(up_j, width_i), And(down_j, Sub(zero_i, width_i)));
  const F step_u = ToFloat(step_i), step_v = ToFloat(step_j);
  // Per axis: the next edge the segment leaves through, as a float (exact; i + 1 moving up, i
  // moving down), its crossing `next`, and the crossing of the edge after it, so that a step
  // only selects (the crossing's arithmetic stays off the loop's dependency chain).
  F edge_u = ToFloat(Sub(i0, up_i));
  F edge_v = ToFloat(Sub(j0, up_j));
  const auto crossing = [&](F edge, F g0, F inv, I left, I more) {
    return SelectLanes(AsFloat(Greater(left, more)), Mul(Sub(edge, g0), inv), inf);
  };
  const F clamped = AsFloat(And(Less(left_i, P::SplatI(2)), Less(left_j, P::SplatI(2))));
  F active = MaskOfLanes<P>(lanes);
  const auto first_crossing = [&](F edge, F g0, F inv, I left) {
    const F s = crossing(edge, g0, inv, left, zero_i);
    // Lanes that are not walked never step (their texel stays a valid index).
    return SelectLanes(active, SelectLanes(clamped, StdMin(StdMax(s, zero), one), s), inf);
  };
  F next_u = first_crossing(edge_u, u0, inv_du, left_i);
  F next_v = first_crossing(edge_v, v0, inv_dv, left_j);
  F after_u = crossing(Add(edge_u, step_u), u0, inv_du, left_i, one_i);
  F after_v = crossing(Add(edge_v, step_v), v0, inv_dv, left_j, one_i);

  // Texel by texel (BodyMapWalk::VisitTexel without gaps): the first entry of each lane. The
  // loop only finds the texel of the entry and keeps what VisitLanes needs to place it, so that
  // its division runs once, after the loop. A lane keeps stepping after its entry (along its own
  // segment, so over valid texels) until every lane is done; only `active` lanes record.
  F top, bottom;
  load_slabs(start, &top, &bottom);
  // IsInside(p0) when the walk starts at p0 (the walk starts inside when p0 is); a clipped start
  // is outside.
  const F start_inside =
      AndNot(MaskOfLanes<P>(start_clipped), And(LessEq(q0.z, top), GreaterEq(q0.z, bottom)));
  // (IsInside(p0) also excludes the gaps of p0's texel; the lanes need not. A start in a gap is
  // outside every interval of its texel, so the first step's gap test already sees no wall and
  // no staying inside there; and such a motion cannot end in a push-out, the only reader of
  // start_inside, without an entry first. The batch tests and --check hold this bit for bit.)
  F inside = start_inside;
  I texel = P::FromLanesI([&](int l) { return start[l]; });  // (written lane by lane above)
  // BodyMapWalk::Z, with the difference z1 - z0 computed once (the same bits).
  const F dz = Sub(q1.z, q0.z), half = P::Splat(0.5f);
  const auto z_at = [&](F s) {
    return SelectLanes(Less(s, half), Add(q0.z, Mul(dz, s)), Sub(q1.z, Mul(dz, Sub(one, s))));
  };
  F s_enter = zero, z_enter = z_at(zero);
  // At the entered texel: the piece [s_enter, s_exit] (its z is z_at of its ends: z_enter is
  // z_at(s_enter) at every step, so it is not kept), a side-wall entry, the texel. What the
  // answer needs of that texel (VisitLanes' top and bottom, the surfaces' slots) is its slab
  // and the slab's surfaces, read again after the walk, except for an entry in a step that ran
  // the visit with gaps (hit_in_gap_visit), which records its own: fewer vectors live per step.
  F hit = zero, hit_s_enter = zero, hit_s_exit = zero, hit_wall = zero;
  I hit_texel = zero_i;
  F hit_in_gap_visit = zero, hit_top = zero, hit_bottom = zero;
  I hit_top_slot = front_slot, hit_bottom_slot = back_slot;  // BodyMapCollider::Interval
  alignas(32) int32_t at[kLanes];
  const auto walk_texels = [&](auto with_gaps) {
    constexpr bool kGaps = decltype(with_gaps)::value;
    for (int walked = 1;; ++walked) {
      const F next = StdMin(next_u, next_v);
      const F s_exit = StdMin(StdMax(next, s_enter), one);
      const F z_exit = z_at(s_exit);
      if (walked > 1) {
        P::Store(at, texel);
        load_slabs(at, &top, &bottom);
      }
      // VisitLanes' tests: inside at entry, or reaching the slab from above or below.
      F in_enter = And(LessEq(z_enter, top), GreaterEq(z_enter, bottom));
      const F above = Greater(z_enter, top);  // also every background texel
      F wall = AndNot(inside, in_enter);
      const F reaches = SelectLanes(above, LessEq(z_exit, top), GreaterEq(z_exit, bottom));
      F entered = And(active, Or(wall, AndNot(in_enter, reaches)));
      F inside_after =
          And(And(inside, in_enter), And(LessEq(z_exit, top), GreaterEq(z_exit, bottom)));
      if constexpr (kGaps) {
        // Only a piece that meets the slab in z can meet its gaps, which lie within it: for a
        // piece wholly in front of or behind the slab (every background texel too) the visit
        // with gaps is the visit without, so such lanes skip the gather.
        const F in_front = And(above, Greater(z_exit, top));
        const F behind = And(Less(z_enter, bottom), Less(z_exit, bottom));
        const F meets_slab = AndNot(Or(in_front, behind), active);
        const uint32_t gap_lanes = LanesWithGaps<P>(top, LaneBits(meets_slab));
        if (gap_lanes != 0) [[unlikely]] {
          GapLanes<P> gaps;
          GatherGapLanes<P>(texel, gap_lanes, &gaps);
          const typename GapLanes<P>::Visit visit =
              gaps.VisitTexel(top, bottom, z_enter, z_exit, inside);
          wall = visit.wall;
          entered = And(active, Or(wall, Or(visit.front, visit.back)));
          inside_after = visit.stays;
          // What the answer needs of the texel entered here: VisitLanes' top and bottom (the
          // entered interval, or the surface reached) and the surfaces' slots.
          hit_top = SelectLanes(entered, visit.kept_top, hit_top);
          hit_bottom = SelectLanes(entered, visit.kept_bottom, hit_bottom);
          hit_top_slot = SelectLanesI(entered, visit.top_slot, hit_top_slot);
          hit_bottom_slot = SelectLanesI(entered, visit.bottom_slot, hit_bottom_slot);
          hit_in_gap_visit = Or(hit_in_gap_visit, entered);
        }
      }
      // Recorded at every step, with no test whether a lane entered: which step holds a lane's
      // entry is data, and the selects cost less than that branch's mispredictions.
      hit = Or(hit, entered);
      hit_s_enter = SelectLanes(entered, s_enter, hit_s_enter);
      hit_s_exit = SelectLanes(entered, s_exit, hit_s_exit);
      hit_wall = SelectLanes(entered, wall, hit_wall);
      hit_texel = SelectLanesI(entered, texel, hit_texel);
      inside = inside_after;
      const F going = Less(next, inf);  // an edge left to cross
      active = And(AndNot(entered, active), going);
      if (LaneBits(active) == 0) return;
      if (walked == kMaxLaneWalkTexels) {  // still walking: long through air, one by one
        lanes &= ~LaneBits(active);
        return;
      }
      // Step across the edge(s) reached at `next`.
      const F across_u = And(going, Equal(next_u, next));
      const F across_v = And(going, Equal(next_v, next));
      const I across_u_i = AsInt(across_u), across_v_i = AsInt(across_v);
      next_u = SelectLanes(across_u, after_u, next_u);
      next_v = SelectLanes(across_v, after_v, next_v);
      texel = Add(texel, Add(And(across_u_i, step_i), And(across_v_i, step_row)));
      left_i = Add(left_i, across_u_i);  // a mask is -1
      left_j = Add(left_j, across_v_i);
      edge_u = Add(edge_u, And(across_u, step_u));
      edge_v = Add(edge_v, And(across_v, step_v));
      after_u =
          SelectLanes(across_u, crossing(Add(edge_u, step_u), u0, inv_du, left_i, one_i), after_u);
      after_v =
          SelectLanes(across_v, crossing(Add(edge_v, step_v), v0, inv_dv, left_j, one_i), after_v);
      s_enter = s_exit;
      z_enter = z_exit;
    }
  };
  if (gaps_near) {
    walk_texels(std::true_type{});
  } else {
    walk_texels(std::false_type{});
  }
  if (lanes == 0) return answered_misses;
  // The entered texels, lane by lane: their slabs now, their normals at the end.
  alignas(32) int32_t entered_texel[kLanes];
  P::Store(entered_texel, hit_texel);
  {
    F slab_top, slab_bottom;
    load_slabs(entered_texel, &slab_top, &slab_bottom);
    hit_top = SelectLanes(hit_in_gap_visit, hit_top, slab_top);
    hit_bottom = SelectLanes(hit_in_gap_visit, hit_bottom, slab_bottom);
  }
  // The entry in its texel: VisitLanes again on the kept piece (a side-wall entry is one where
  // the walk was not inside at the texel's entry point).
  const LaneVisit<P> entry =
      VisitLanes<P>(hit_top, hit_bottom, hit_s_enter, hit_s_exit, z_at(hit_s_enter),
                    z_at(hit_s_exit), AndNot(hit_wall, all_lanes));
  // A side-wall entry at the clipped start on the box's top or bottom face is through that face:
  // the front surface moving down, the back moving up (BodyMapWalk::HitAtStart).
  const F z_face = And(And(hit_wall, MaskOfLanes<P>(start_on_z_face)), Equal(hit_s_enter, zero));
  const F moving_down = Less(q1.z, q0.z);
  const F hit_s = entry.s;
  const F hit_z = SelectLanes(z_face, SelectLanes(moving_down, hit_top, hit_bottom), entry.z);
  const F hit_back = SelectLanes(z_face, AndNot(moving_down, z_face), entry.back);
  hit_wall = AndNot(z_face, hit_wall);

  // The answer (WalkInto): the entry point on the segment, stepped back across a side wall by
  // 1e-3 texel, with the entered surface's normal (at a wall, the nearer surface of the entered
  // texel's slab); with no entry and p1 inside, p1 pushed out along z to the nearer surface of
  // its slab.
  const F inside_end = AndNot(
      end_in_gap, And(p1_in_box, And(LessEq(p1.z, slab_b_top), GreaterEq(p1.z, slab_b_bottom))));
  const F push_out = AndNot(hit, inside_end);
  const uint32_t contact_lanes = LaneBits(Or(hit, push_out)) & lanes;
  if (contact_lanes == 0) {  // through air (most long motions in free space)
    for (int lane = 0; lane < kLanes; ++lane) {
      if ((lanes >> lane) & 1u) flags[index[lane]] = kCollisionNone;
    }
    return lanes | answered_misses;
  }
  const F wall = And(hit, hit_wall);
  const LanePoint<P> placed = PlaceContactLanes<P>(q0, q1, hit_s, hit_z, wall, push_out, p1,
                                                   slab_b_top, slab_b_bottom, 1e-3f * texel_size_);
  const F wall_back = Less(Sub(hit_z, hit_bottom), Sub(hit_top, hit_z));
  const F use_back =
      SelectLanes(push_out, placed.push_back, SelectLanes(wall, wall_back, hit_back));
  const uint32_t push_lanes = LaneBits(push_out);
  size_t normal_texel[kLanes];
  for (int lane = 0; lane < kLanes; ++lane) {
    normal_texel[lane] =
        static_cast<size_t>((push_lanes >> lane) & 1u ? texel_b[lane] : entered_texel[lane]);
  }
  I code = NormalCodes<P>(normal_texel, use_back);
  if (gaps_near) {  // a gap's surface (slot >= 2; lanes without gaps hold the slab's slots)
    code = GapSurfaceCodes<P>(
        normal_texel,
        SelectLanesI(push_out, SelectLanesI(use_back, end_bottom_slot, end_top_slot),
                     SelectLanesI(use_back, hit_bottom_slot, hit_top_slot)),
        code);
  }
  const Lanes3<P> normal = DecodeOct16Lanes<P>(code);
  const uint32_t wall_lanes = LaneBits(wall);
  const uint32_t started_inside_lanes = push_lanes & LaneBits(start_inside);
  WriteLaneAnswers<P>(index, lanes, contact_lanes, wall_lanes, started_inside_lanes, placed.point,
                      normal, p1, v, params, positions, velocities, flags);
  return lanes | answered_misses;
}

}  // namespace drape

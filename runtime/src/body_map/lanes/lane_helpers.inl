// Private to the runtime: the lane helpers of BodyMapCollider's lanes (loading particles,
// texel coordinates, the visit of one texel's slab, the contact point, the answers written back),
// written once over a lane pack P (common/lanes/).
//
// No #include here: everything this text uses must be declared before it is included (see
// lanes.inl).

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
  const F restitution = P::Splat(params.restitution);
  const F into = And(in_contact, Less(vn, zero));
  const Lanes3<P> tangential = {Sub(v.x, Mul(normal.x, vn)), Sub(v.y, Mul(normal.y, vn)),
                                Sub(v.z, Mul(normal.z, vn))};
  // TangentialKeep lane by lane, in the same operations (the scalar path gives the same bits).
  F keep = P::Splat(1.f - params.friction);
  if (params.friction_model == FrictionModel::kCoulomb) {
    const F speed_into = Sub(zero, vn);
    const F squared = Add(Add(Mul(tangential.x, tangential.x), Mul(tangential.y, tangential.y)),
                          Mul(tangential.z, tangential.z));
    const F stick_speed = Mul(P::Splat(params.static_friction), speed_into);
    const F sticks = GreaterEq(Mul(stick_speed, stick_speed), squared);
    const F slide =
        Sub(P::Splat(1.f), Div(Mul(P::Splat(params.friction), speed_into), Sqrt(squared)));
    keep = SelectLanes(sticks, zero, SelectLanes(Greater(slide, zero), slide, zero));
  }
  const auto respond = [&](F velocity, F t, F n) {
    const F changed = Sub(Mul(t, keep), Mul(Mul(n, vn), restitution));
    return SelectLanes(into, changed, velocity);
  };
  return {position,
          {respond(v.x, tangential.x, normal.x), respond(v.y, tangential.y, normal.y),
           respond(v.z, tangential.z, normal.z)}};
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

}  // namespace drape

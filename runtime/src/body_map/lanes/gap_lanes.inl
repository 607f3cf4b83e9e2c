// Private to the runtime: the air gaps of one texel per lane (maps with layers > 1), gathered
// for the short-motion and walking lanes, and the oct16 codes of the surfaces the lanes enter.
//
// No #include here: everything this text uses must be declared before it is included (see
// lanes.inl).

namespace drape {

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

}  // namespace drape

// Private to the runtime: BodyMapCollider::CollideShortLanes, the particles whose motion stays in
// one texel or crosses one texel edge, P::kCount at a time.
//
// No #include here: everything this text uses must be declared before it is included (see
// lanes.inl).

namespace drape {

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
  // A push-out more than a texel along z may leave through a texel's side instead: Query's
  // (NearerSideExit); those lanes are not answered here.
  const F deep = And(
      push_out, Greater(StdMin(Sub(end_top, p1.z), Sub(p1.z, end_bottom)), P::Splat(texel_size_)));
  uint32_t deep_lanes = LaneBits(deep) & lanes;
  for (int lane = 0; deep_lanes != 0 && lane < kLanes; ++lane) {  // far from all air: none
    if (((deep_lanes >> lane) & 1u) && air_reach_[texel_b[lane]] > kSideExitTexels) {
      deep_lanes &= ~(1u << lane);
    }
  }
  const uint32_t contact_lanes = LaneBits(contact) & lanes & ~deep_lanes;
  // Started inside and left with no entry: Query decides whether it crossed the body (§7.4).
  const uint32_t left_lanes = LaneBits(AndNot(contact, start_inside)) & lanes;
  lanes &= ~(left_lanes | deep_lanes);
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

}  // namespace drape

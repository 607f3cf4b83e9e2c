// Private to the runtime: BodyMapCollider::CollideWalkLanes, the particles whose motion crosses
// several texels, each lane walking its own texel sequence in step with the others.
//
// No #include here: everything this text uses must be declared before it is included (see
// lanes.inl).

namespace drape {

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
  // RobotExpressive: the bodies that need the layers), counted in instructions on the
  // speed-vs-error mix.
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
  // A push-out more than a texel along z may leave through a texel's side instead: Query's
  // (NearerSideExit); those lanes are not answered here.
  const F deep = And(push_out, Greater(StdMin(Sub(slab_b_top, p1.z), Sub(p1.z, slab_b_bottom)),
                                       P::Splat(texel_size_)));
  uint32_t deep_lanes = LaneBits(deep) & lanes;
  for (int lane = 0; deep_lanes != 0 && lane < kLanes; ++lane) {  // far from all air: none
    if (((deep_lanes >> lane) & 1u) &&
        air_reach_[static_cast<size_t>(texel_b[lane])] > kSideExitTexels) {
      deep_lanes &= ~(1u << lane);
    }
  }
  const uint32_t contact_lanes = LaneBits(Or(hit, push_out)) & lanes & ~deep_lanes;
  // Started inside and left with no entry: Query decides whether it crossed the body (§7.4).
  lanes &= ~((LaneBits(AndNot(Or(hit, push_out), start_inside)) & lanes) | deep_lanes);
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

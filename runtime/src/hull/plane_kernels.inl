// Private to the runtime: the PlaneKernels of plane_kernels.h written once over a lane pack P
// (common/lanes/). Included by plane_kernels.cpp (ScalarLanes, Sse2Lanes) and, inside its AVX2
// target region, by plane_kernels_avx2.cpp (EightLanes).
//
// No #include here: everything this text uses must be declared before it is included, so that in
// the AVX2 file no function the baseline code also uses is compiled for AVX2.
//
// Same bits in every pack: plane i is in lane i % P::kCount of the i / P::kCount-th vector, in
// every pack; the max kernels keep 8 / P::kCount vectors per 8 planes and combine them in a fixed
// order, and the horizontal reductions are pairwise trees, so a width's grouping never changes
// which of two equal values (0 and -0) survives.

namespace drape::detail {
namespace {

using namespace lanes;

template <class P>
struct PlaneLanes {
  using F = typename P::F;
  static constexpr uint32_t kVectors = kPlanePad / P::kCount;  // vectors per 8 planes

  // ((nx px + ny py) + nz pz) - d for planes i .. i + P::kCount - 1.
  static F Value(const PlaneSoa& s, uint32_t i, F px, F py, F pz) {
    F v = Mul(P::Load(s.nx + i), px);
    v = Add(v, Mul(P::Load(s.ny + i), py));
    v = Add(v, Mul(P::Load(s.nz + i), pz));
    return Sub(v, P::Load(s.d + i));
  }
  // Pairwise trees over the lanes: (l0 l1)(l2 l3) for four, ((l0 l1)(l2 l3))((l4 l5)(l6 l7)) for
  // eight, with std::max / std::min's operand order (written out: std::max is an inline function
  // the baseline code shares, which must not be compiled in an AVX2 region).
  static float HorizontalMax(F v) {
    alignas(32) float l[P::kCount];
    P::Store(l, v);
    for (int width = P::kCount; width > 1; width /= 2)
      for (int k = 0; k < width / 2; ++k) l[k] = l[2 * k] < l[2 * k + 1] ? l[2 * k + 1] : l[2 * k];
    return l[0];
  }
  static float HorizontalMin(F v) {
    alignas(32) float l[P::kCount];
    P::Store(l, v);
    for (int width = P::kCount; width > 1; width /= 2)
      for (int k = 0; k < width / 2; ++k) l[k] = l[2 * k + 1] < l[2 * k] ? l[2 * k + 1] : l[2 * k];
    return l[0];
  }
  // The max of one 8-plane block's vectors: v0 alone, or max(v0, v1) as maxps(v0, v1) gives it.
  static F BlockMax(const F* v) {
    if constexpr (kVectors == 1) {
      return v[0];
    } else {
      return StdMax(v[1], v[0]);
    }
  }
  static uint32_t FirstLane(uint32_t bits) { return static_cast<uint32_t>(__builtin_ctz(bits)); }

  static float Max(const PlaneSoa& s, Float3 p) {
    const F px = P::Splat(p.x), py = P::Splat(p.y), pz = P::Splat(p.z);
    F m[kVectors];
    for (uint32_t k = 0; k < kVectors; ++k) m[k] = P::Splat(-kPadOffset);
    for (uint32_t i = 0; i < s.padded; i += kPlanePad)
      for (uint32_t k = 0; k < kVectors; ++k)
        m[k] = StdMax(m[k], Value(s, i + k * P::kCount, px, py, pz));
    return HorizontalMax(BlockMax(m));
  }

  static uint32_t FirstEqual(const PlaneSoa& s, Float3 p, float value) {
    const F px = P::Splat(p.x), py = P::Splat(p.y), pz = P::Splat(p.z);
    const F target = P::Splat(value);
    for (uint32_t i = 0; i < s.padded; i += P::kCount) {
      const uint32_t bits = LaneBits(Equal(Value(s, i, px, py, pz), target));
      if (bits != 0) return i + FirstLane(bits);
    }
    return 0;
  }

  static DualResult Dual(const PlaneSoa& s, Float3 a, Float3 b) {
    const F ax = P::Splat(a.x), ay = P::Splat(a.y), az = P::Splat(a.z);
    const F bx = P::Splat(b.x), by = P::Splat(b.y), bz = P::Splat(b.z);
    const F zero = P::Zero();
    F ma = P::Splat(-kPadOffset), mb = ma;
    for (uint32_t i = 0; i < s.padded; i += kPlanePad) {
      F fa[kVectors], fb[kVectors];
      F separated = zero;
      for (uint32_t k = 0; k < kVectors; ++k) {
        fa[k] = Value(s, i + k * P::kCount, ax, ay, az);
        fb[k] = Value(s, i + k * P::kCount, bx, by, bz);
        separated = Or(separated, And(Greater(fa[k], zero), Greater(fb[k], zero)));
      }
      if (LaneBits(separated) != 0) return {0.f, 0.f, true};
      ma = StdMax(ma, BlockMax(fa));
      mb = StdMax(mb, BlockMax(fb));
    }
    return {HorizontalMax(ma), HorizontalMax(mb), false};
  }

  static DualResult DualSame(const PlaneSoa& s, Float3 a) {
    const F ax = P::Splat(a.x), ay = P::Splat(a.y), az = P::Splat(a.z);
    const F zero = P::Zero();
    F ma = P::Splat(-kPadOffset);
    for (uint32_t i = 0; i < s.padded; i += kPlanePad) {
      F fa[kVectors];
      F outside = zero;
      for (uint32_t k = 0; k < kVectors; ++k) {
        fa[k] = Value(s, i + k * P::kCount, ax, ay, az);
        outside = Or(outside, Greater(fa[k], zero));
      }
      if (LaneBits(outside) != 0) return {0.f, 0.f, true};
      ma = StdMax(ma, BlockMax(fa));
    }
    const float m = HorizontalMax(ma);
    return {m, m, false};
  }

  static ClipResult Clip(const PlaneSoa& s, Float3 a, Float3 b) {
    const F ax = P::Splat(a.x), ay = P::Splat(a.y), az = P::Splat(a.z);
    const F bx = P::Splat(b.x), by = P::Splat(b.y), bz = P::Splat(b.z);
    const F zero = P::Zero();
    F t_in = P::Splat(-1.f), t_out = P::Splat(1.f);
    for (uint32_t i = 0; i < s.padded; i += P::kCount) {
      const F fa = Value(s, i, ax, ay, az), fb = Value(s, i, bx, by, bz);
      const F t = Div(fa, Sub(fa, fb));
      const F entering = Greater(fa, zero);
      const F leaving = AndNot(entering, Greater(fb, zero));
      t_in = StdMax(t_in, SelectLanes(entering, t, t_in));
      t_out = StdMin(t_out, SelectLanes(leaving, t, t_out));
    }
    return {HorizontalMax(t_in), HorizontalMin(t_out)};
  }

  static uint32_t Entry(const PlaneSoa& s, Float3 a, Float3 b, float t_in) {
    const F ax = P::Splat(a.x), ay = P::Splat(a.y), az = P::Splat(a.z);
    const F bx = P::Splat(b.x), by = P::Splat(b.y), bz = P::Splat(b.z);
    const F zero = P::Zero(), target = P::Splat(t_in);
    for (uint32_t i = 0; i < s.padded; i += P::kCount) {
      const F fa = Value(s, i, ax, ay, az), fb = Value(s, i, bx, by, bz);
      const F t = Div(fa, Sub(fa, fb));
      const uint32_t bits = LaneBits(And(Greater(fa, zero), Equal(t, target)));
      if (bits != 0) return i + FirstLane(bits);
    }
    return 0;
  }

  static uint32_t SphereFilter(const float* xs, const float* ys, const float* zs, const float* rs,
                               uint32_t total, Float3 mid, float half, uint32_t* out,
                               uint32_t capacity) {
    const F mx = P::Splat(mid.x), my = P::Splat(mid.y), mz = P::Splat(mid.z);
    const F hv = P::Splat(half);
    uint32_t count = 0;
    for (uint32_t k = 0; k < total; k += P::kCount) {
      const F dx = Sub(mx, P::Load(xs + k));
      const F dy = Sub(my, P::Load(ys + k));
      const F dz = Sub(mz, P::Load(zs + k));
      const F d2 = Add(Add(Mul(dx, dx), Mul(dy, dy)), Mul(dz, dz));
      const F rr = Add(P::Load(rs + k), hv);
      uint32_t bits = LaneBits(LessEq(d2, Mul(rr, rr)));
      while (bits != 0 && count < capacity) {
        const uint32_t index = k + FirstLane(bits);
        bits &= bits - 1;
        if (index < total) out[count++] = index;  // padding fails unless the segment is ~1e38 long
      }
    }
    return count;
  }

  // P::kCount consecutive Float3 as lanes; lanes at and beyond `lanes` repeat the first.
  static void LoadGroup(const Float3* v, uint32_t lanes, F* x, F* y, F* z) {
    if (lanes == static_cast<uint32_t>(P::kCount)) {
      P::LoadFloat3s(v, x, y, z);
      return;
    }
    const auto from = [lanes](int l) { return static_cast<uint32_t>(l) < lanes ? l : 0; };
    *x = P::FromLanes([&](int l) { return v[from(l)].x; });
    *y = P::FromLanes([&](int l) { return v[from(l)].y; });
    *z = P::FromLanes([&](int l) { return v[from(l)].z; });
  }

  static uint32_t SphereMasks(const Float3* p0, const Float3* p1, const Float3* velocity,
                              uint32_t lanes, const float* xs, const float* ys, const float* zs,
                              const float* rs, uint32_t total, Float3 union_center,
                              float union_radius, uint32_t* masks) {
    using I = typename P::I;
    F ax, ay, az, bx, by, bz, vx, vy, vz;
    LoadGroup(p0, lanes, &ax, &ay, &az);
    LoadGroup(p1, lanes, &bx, &by, &bz);
    LoadGroup(velocity, lanes, &vx, &vy, &vz);
    // IsFinite's answer: x - x == 0 for every coordinate.
    const F zero = P::Zero();
    F finite = Equal(zero, zero);
    const F coordinates[9] = {ax, ay, az, bx, by, bz, vx, vy, vz};
    for (const F& x : coordinates) finite = And(finite, Equal(Sub(x, x), zero));
    const F one_half = P::Splat(0.5f);
    const F mx = Mul(Add(ax, bx), one_half);
    const F my = Mul(Add(ay, by), one_half);
    const F mz = Mul(Add(az, bz), one_half);
    const F sx = Sub(bx, ax), sy = Sub(by, ay), sz = Sub(bz, az);
    const F length2 = Add(Add(Mul(sx, sx), Mul(sy, sy)), Mul(sz, sz));
    const F half = Mul(Sqrt(length2), P::Splat(0.50001f));
    const uint32_t finite_lanes = LaneBits(finite);
    // Invalid lanes fail every test; the skip needs the valid ones outside the union sphere. The
    // union test's sum is grown by 1e-5 relative (the float tests round by ~1e-7 relative), so a
    // lane that passes any collider's test passes it whatever its half length.
    const F ux = Sub(mx, P::Splat(union_center.x));
    const F uy = Sub(my, P::Splat(union_center.y));
    const F uz = Sub(mz, P::Splat(union_center.z));
    const F ud2 = Add(Add(Mul(ux, ux), Mul(uy, uy)), Mul(uz, uz));
    const F urr = Mul(Add(P::Splat(union_radius), half), P::Splat(1.00001f));
    const F near = LessEq(ud2, Mul(urr, urr));
    // One 32-bit word per 32 colliders; lane l's word w at masks[l * words + w].
    const uint32_t words = (total + 31) / 32;
    const bool any_near = LaneBits(And(near, finite)) != 0;
    for (uint32_t w = 0; w < words; ++w) {
      I acc = P::ZeroI();
      const uint32_t end = total < 32 * w + 32 ? total : 32 * w + 32;
      for (uint32_t k = 32 * w; any_near && k < end; ++k) {
        const F dx = Sub(mx, P::Splat(xs[k]));
        const F dy = Sub(my, P::Splat(ys[k]));
        const F dz = Sub(mz, P::Splat(zs[k]));
        const F d2 = Add(Add(Mul(dx, dx), Mul(dy, dy)), Mul(dz, dz));
        const F rr = Add(P::Splat(rs[k]), half);
        const F inside = LessEq(d2, Mul(rr, rr));
        acc = Or(acc, And(AsInt(inside), P::SplatI(static_cast<int32_t>(1u << (k - 32 * w)))));
      }
      alignas(32) int32_t stored[P::kCount];
      P::Store(stored, acc);
      for (int l = 0; l < P::kCount; ++l) masks[l * words + w] = static_cast<uint32_t>(stored[l]);
    }
    return finite_lanes;
  }

  // TransformPoint(m, p) per lane: ((m0 x + m1 y) + m2 z) + m3, row by row.
  static void TransformLanes(const Mat34& m, F x, F y, F z, F* ox, F* oy, F* oz) {
    const auto row = [&](int r) {
      const float* c = m.m + 4 * r;
      return Add(Add(Add(Mul(P::Splat(c[0]), x), Mul(P::Splat(c[1]), y)), Mul(P::Splat(c[2]), z)),
                 P::Splat(c[3]));
    };
    *ox = row(0);
    *oy = row(1);
    *oz = row(2);
  }

  static void ObbMasks(const Float3* p0, const Float3* p1, uint32_t lanes, const Mat34* obb_start,
                       const Mat34* obb_end, const Float3* half, uint32_t hulls, uint32_t total,
                       bool continuous, uint32_t max_candidates, uint32_t* masks) {
    F ax, ay, az, bx, by, bz;
    LoadGroup(p0, lanes, &ax, &ay, &az);
    LoadGroup(p1, lanes, &bx, &by, &bz);
    const uint32_t words = (total + 31) / 32;
    const auto hulls_in = [hulls](uint32_t w, uint32_t mask) {  // the hull bits of word w
      return hulls - 32 * w < 32 ? mask & ((1u << (hulls - 32 * w)) - 1u) : mask;
    };
    // Only lanes within max_candidates: beyond it the resolution keeps the lowest indices, which
    // dropping a rejected hull would change; within it the same contacts come out, bit for bit.
    uint32_t filtered = 0;
    for (uint32_t l = 0; l < lanes; ++l) {
      uint32_t count = 0;
      for (uint32_t w = 0; w < words; ++w)
        count += static_cast<uint32_t>(__builtin_popcount(masks[l * words + w]));
      filtered |= count <= max_candidates ? 1u << l : 0u;
    }
    // One test here serves every lane, one in ColliderContact a lane: worth it when the lanes
    // share their hulls (a cloth's neighbouring particles), not for scattered particles.
    uint32_t shared = 0, per_lane = 0;
    for (uint32_t w = 0; w * 32 < hulls; ++w) {
      uint32_t any = 0;
      for (uint32_t l = 0; l < lanes; ++l) {
        if (!((filtered >> l) & 1u)) continue;
        const uint32_t mask = hulls_in(w, masks[l * words + w]);
        any |= mask;
        per_lane += static_cast<uint32_t>(__builtin_popcount(mask));
      }
      shared += static_cast<uint32_t>(__builtin_popcount(any));
    }
    if (2 * shared > per_lane) return;
    for (uint32_t w = 0; w * 32 < hulls; ++w) {
      uint32_t any = 0;
      for (uint32_t l = 0; l < lanes; ++l) {
        if ((filtered >> l) & 1u) any |= hulls_in(w, masks[l * words + w]);
      }
      for (; any != 0; any &= any - 1u) {
        const uint32_t bit = static_cast<uint32_t>(__builtin_ctz(any));
        const uint32_t k = 32 * w + bit;
        F ox, oy, oz, ex, ey, ez;  // the start and the end in the OBB frame
        TransformLanes(obb_start[k], ax, ay, az, &ox, &oy, &oz);
        TransformLanes(obb_end[k], bx, by, bz, &ex, &ey, &ez);
        const Float3 h = half[k];
        const F hx = P::Splat(h.x), hy = P::Splat(h.y), hz = P::Splat(h.z);
        const F mx = P::Splat(-h.x), my = P::Splat(-h.y), mz = P::Splat(-h.z);
        const F end_in =
            And(And(LessEq(AbsLanes(ex), hx), LessEq(AbsLanes(ey), hy)), LessEq(AbsLanes(ez), hz));
        F reject_when_out = Equal(P::Zero(), P::Zero());  // discrete: the end outside suffices
        if (continuous) {
          const F beyond_x =
              Or(And(Greater(ox, hx), Greater(ex, hx)), And(Less(ox, mx), Less(ex, mx)));
          const F beyond_y =
              Or(And(Greater(oy, hy), Greater(ey, hy)), And(Less(oy, my), Less(ey, my)));
          const F beyond_z =
              Or(And(Greater(oz, hz), Greater(ez, hz)), And(Less(oz, mz), Less(ez, mz)));
          reject_when_out = Or(Or(beyond_x, beyond_y), beyond_z);
        }
        uint32_t rejected = LaneBits(AndNot(end_in, reject_when_out)) & filtered;
        for (; rejected != 0; rejected &= rejected - 1u) {
          const uint32_t l = static_cast<uint32_t>(__builtin_ctz(rejected));
          masks[l * words + w] &= ~(1u << bit);
        }
      }
    }
  }

  static const PlaneKernels& Table() {
    static const PlaneKernels kernels{static_cast<uint32_t>(P::kCount),
                                      Max,
                                      FirstEqual,
                                      Dual,
                                      DualSame,
                                      Clip,
                                      Entry,
                                      SphereFilter,
                                      SphereMasks,
                                      ObbMasks};
    return kernels;
  }
};

}  // namespace
}  // namespace drape::detail

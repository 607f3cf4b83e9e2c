// One particle against every collider its segment may reach: Gauss-Seidel passes, deepest
// contact first, with the contact planes of earlier responses re-imposed (docs/ALGORITHMS.md §8.6).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <new>
#include <utility>

#include "drape/runtime/hull_collider_set.h"

namespace drape {

namespace {

// The contact planes one particle has been pushed out through in one ResolveParticle call, as
// half-spaces n . x >= d (d = n . contact point + separation). Each is a supporting plane of its
// collider (a hull face plane, or a sphere's tangent plane), so a point on the outer side of all
// of them is outside every collider that produced one. Re-imposing them after each response is
// what stops a particle pinched between overlapping colliders (armpit, crotch, a skirt between
// the thighs at a large step) from being pushed out of one collider into the other and back.
class ContactPlanes {
 public:
  void Add(Float3 normal, float offset) {
    if (count_ == kMax) {  // keep the newest: shift the oldest out
      for (uint32_t i = 1; i < kMax; ++i) planes_[i - 1] = planes_[i];
      --count_;
    }
    planes_[count_++] = {normal, offset};
  }
  uint32_t count() const { return count_; }

  // Moves *x to the nearest point on the outer side of every plane, by an active-set solve in
  // double over at most three planes (the nearest point of a polyhedral region in 3D lies on at
  // most three of its faces). Leaves *x unchanged and returns false when the violated planes have
  // no common solution (they face each other: the particle is pinched with no room).
  bool Enforce(Float3* x) const {
    const double x0[3] = {x->x, x->y, x->z};
    double p[3] = {x0[0], x0[1], x0[2]};
    // The largest violation at the start: the projection may not move the particle much farther
    // than that. Planes that nearly face each other (a pinch between two colliders a few degrees
    // off parallel) meet in a line far away; following it would throw the particle across the
    // body. Refusing keeps the last response (the Gauss-Seidel passes go on from there).
    double start_violation = 0.0;
    for (uint32_t i = 0; i < count_; ++i) {
      start_violation = std::max(start_violation, Offset(i) - Dot3(i, x0));
    }
    uint32_t active[3];
    uint32_t active_count = 0;
    bool skipped[kMax] = {false, false, false, false};  // redundant with the active planes
    const auto build_and_solve = [&](double lambda[3]) {
      double g[3][3], r[3];
      for (uint32_t a = 0; a < active_count; ++a) {
        for (uint32_t b = 0; b < active_count; ++b) g[a][b] = DotNormals(active[a], active[b]);
        r[a] = Offset(active[a]) - Dot3(active[a], x0);
      }
      return Solve(g, r, active_count, lambda);
    };
    for (uint32_t round = 0; round < 2 * kMax; ++round) {
      // The most violated plane not yet active (violations below kTolerance are rounding).
      uint32_t worst = kMax;
      double worst_violation = kTolerance;
      for (uint32_t i = 0; i < count_; ++i) {
        bool is_active = skipped[i];
        for (uint32_t k = 0; k < active_count; ++k) is_active |= active[k] == i;
        const double v = Offset(i) - Dot3(i, p);
        if (!is_active && v > worst_violation) {
          worst = i;
          worst_violation = v;
        }
      }
      if (worst == kMax) break;
      if (active_count == 3) return false;
      active[active_count++] = worst;
      // p = x0 + sum_j lambda_j n_j with n_k . p = d_k for the active planes: G lambda = r.
      double lambda[3] = {0.0, 0.0, 0.0};
      if (!build_and_solve(lambda)) {
        // Dependent on the active planes (the same face met twice, coplanar neighbours): skip
        // it; the final check says whether it holds anyway.
        --active_count;
        skipped[worst] = true;
        if (!build_and_solve(lambda)) return false;
      }
      // A negative multiplier: that plane holds without being pushed on; drop it and re-solve.
      for (uint32_t a = 0; a < active_count;) {
        if (lambda[a] < 0.0) {
          for (uint32_t b = a + 1; b < active_count; ++b) active[b - 1] = active[b];
          --active_count;
          if (!build_and_solve(lambda)) return false;
          a = 0;
          continue;
        }
        ++a;
      }
      for (int k = 0; k < 3; ++k) {
        p[k] = x0[k];
        for (uint32_t a = 0; a < active_count; ++a) p[k] += lambda[a] * Component(active[a], k);
      }
    }
    for (uint32_t i = 0; i < count_; ++i) {
      if (Offset(i) - Dot3(i, p) > kTolerance) return false;  // infeasible: a pinch
    }
    const double moved =
        std::sqrt((p[0] - x0[0]) * (p[0] - x0[0]) + (p[1] - x0[1]) * (p[1] - x0[1]) +
                  (p[2] - x0[2]) * (p[2] - x0[2]));
    if (moved > kMaxStretch * start_violation + kTolerance) return false;
    *x = Float3{static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2])};
    // Rounding to float can leave a plane a few ulps short: nudge out along it.
    for (uint32_t i = 0; i < count_; ++i) {
      const Float3 n = planes_[i].normal;
      for (int tries = 0; tries < 4 && Dot(n, *x) < planes_[i].offset; ++tries) {
        const float push = std::max(planes_[i].offset - Dot(n, *x), 1e-7f);
        *x = *x + n * push;
      }
    }
    return true;
  }

 private:
  static constexpr uint32_t kMax = 4;
  static constexpr double kTolerance = 1e-6;  // metres: violations below this are rounding
  // The projection may move the particle at most this many times its largest violation: the
  // planes then meet at 11.4 degrees or more (cot(5.7 deg) = 10); narrower wedges are refused.
  static constexpr double kMaxStretch = 10.0;
  struct HalfSpace {
    Float3 normal;
    float offset;
  };
  double Offset(uint32_t i) const { return planes_[i].offset; }
  double Component(uint32_t i, int k) const {
    const Float3 n = planes_[i].normal;
    return k == 0 ? n.x : (k == 1 ? n.y : n.z);
  }
  double Dot3(uint32_t i, const double q[3]) const {
    return Component(i, 0) * q[0] + Component(i, 1) * q[1] + Component(i, 2) * q[2];
  }
  double DotNormals(uint32_t i, uint32_t j) const {
    return Component(i, 0) * Component(j, 0) + Component(i, 1) * Component(j, 1) +
           Component(i, 2) * Component(j, 2);
  }
  // Gaussian elimination with partial pivoting on an n x n system, n <= 3. False when singular
  // (parallel or dependent planes).
  static bool Solve(double g[3][3], double r[3], uint32_t n, double out[3]) {
    double a[3][4];
    for (uint32_t i = 0; i < n; ++i) {
      for (uint32_t j = 0; j < n; ++j) a[i][j] = g[i][j];
      a[i][3] = r[i];
    }
    for (uint32_t col = 0; col < n; ++col) {
      uint32_t pivot = col;
      for (uint32_t row = col + 1; row < n; ++row) {
        if (std::fabs(a[row][col]) > std::fabs(a[pivot][col])) pivot = row;
      }
      if (std::fabs(a[pivot][col]) < 1e-9) return false;
      if (pivot != col) {
        for (uint32_t j = 0; j < 4; ++j) std::swap(a[pivot][j], a[col][j]);
      }
      for (uint32_t row = 0; row < n; ++row) {
        if (row == col) continue;
        const double f = a[row][col] / a[col][col];
        for (uint32_t j = col; j < 4; ++j) a[row][j] -= f * a[col][j];
      }
    }
    for (uint32_t i = 0; i < n; ++i) out[i] = a[i][3] / a[i][i];
    return true;
  }

  HalfSpace planes_[kMax];
  uint32_t count_ = 0;
};

}  // namespace

template <bool kActive>
void HullColliderSet::ResolveParticle(Float3 p0, Float3* p1, Float3* velocity, uint8_t* flags,
                                      const ResponseParams& params, float s0, float s1,
                                      const uint32_t* first_candidates) const {
  uint8_t result = kCollisionNone;
  Float3 position = *p1, vel = *velocity;
  uint32_t last_single = UINT32_MAX;  // the one collider resolved in the previous pass, if so
  ContactPlanes planes;
  for (uint32_t pass = 0; pass < options_.gauss_seidel_passes; ++pass) {
    // Candidates for the current segment: a response may have moved the particle towards a
    // collider the original segment did not reach.
    uint32_t candidates[kMaxCandidates];
    uint32_t count = 0;
    if (pass == 0 && first_candidates != nullptr) {
      for (uint32_t mask = *first_candidates; mask != 0; mask &= mask - 1)
        candidates[count++] = static_cast<uint32_t>(__builtin_ctz(mask));
    } else {
      count = BroadPhase(p0, position, s0, s1, kActive, candidates);
    }
    if (count == 0) break;
    // Only the collider just resolved: its response left the particle on or outside it.
    if (pass > 0 && count == 1 && candidates[0] == last_single) break;
    // Transforms: the cached ones, or (other fractions) computed into raw stack storage so the
    // common path does not pay for constructing them.
    const ActiveFrames* frames[kMaxCandidates];
    alignas(
        ActiveFrames) unsigned char storage[kActive ? 1 : kMaxCandidates * sizeof(ActiveFrames)];
    for (uint32_t i = 0; i < count; ++i) {
      if constexpr (kActive) {
        frames[i] = &active_[candidates[i]];
      } else {
        ActiveFrames* f = new (storage + i * sizeof(ActiveFrames)) ActiveFrames;
        ComputeFrames(candidates[i], s0, s1, f);
        frames[i] = f;
      }
    }
    // Raw storage again: only the first `count` are constructed.
    alignas(ContactQuery) unsigned char contact_storage[kMaxCandidates * sizeof(ContactQuery)];
    ContactQuery* contacts = reinterpret_cast<ContactQuery*>(contact_storage);
    uint32_t order[kMaxCandidates];
    uint32_t hits = 0;
    for (uint32_t i = 0; i < count; ++i) {
      // The collider resolved alone in the previous pass left the particle on or outside it.
      if (candidates[i] == last_single) {
        new (&contacts[i]) ContactQuery();
        continue;
      }
      new (&contacts[i]) ContactQuery(ColliderContact(candidates[i], *frames[i], p0, position));
      if (contacts[i].contact) order[hits++] = i;
    }
    if (hits == 0) break;
    // Deepest first; ties keep collider order (insertion sort is stable).
    for (uint32_t i = 1; i < hits; ++i) {
      const uint32_t key = order[i];
      uint32_t j = i;
      while (j > 0 && contacts[order[j - 1]].depth < contacts[key].depth) {
        order[j] = order[j - 1];
        --j;
      }
      order[j] = key;
    }
    for (uint32_t rank = 0; rank < hits; ++rank) {
      const uint32_t i = order[rank];
      const ContactQuery c =
          rank == 0 ? contacts[i] : ColliderContact(candidates[i], *frames[i], p0, position);
      if (!c.contact) continue;
      ApplyResponse(c, params, &position, &vel);
      result |= static_cast<uint8_t>(kCollisionContact | c.flags);
      planes.Add(c.normal, Dot(c.normal, c.point) + params.separation);
      if (planes.count() > 1) planes.Enforce(&position);
    }
    last_single = hits == 1 ? candidates[order[0]] : UINT32_MAX;
  }
  *p1 = position;
  *velocity = vel;
  *flags = result;
}

template void HullColliderSet::ResolveParticle<true>(Float3, Float3*, Float3*, uint8_t*,
                                                     const ResponseParams&, float, float,
                                                     const uint32_t*) const;
template void HullColliderSet::ResolveParticle<false>(Float3, Float3*, Float3*, uint8_t*,
                                                      const ResponseParams&, float, float,
                                                      const uint32_t*) const;

}  // namespace drape

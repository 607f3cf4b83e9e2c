// One particle against every collider its segment may reach: Gauss-Seidel passes, deepest
// contact first, with the contact planes of earlier responses re-imposed, every response within
// the particle's motion plus depth, and the best iterate kept (docs/ALGORITHMS.md §8.6).
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

// Squared distance in double: the budget test must hold for coordinates up to float's range.
double DistanceSquared(Float3 a, Float3 b) {
  const double dx = double(a.x) - b.x, dy = double(a.y) - b.y, dz = double(a.z) - b.z;
  return dx * dx + dy * dy + dz * dz;
}

// How bad an iterate is, from the contacts of the segment previous -> iterate: first the deepest
// it lies inside one of them, then the number of colliders the segment passes through and ends
// outside (the particle tunnelled). Lower is better; ties go to the later iterate.
struct IterateScore {
  uint32_t crossings = 0;
  float depth = 0.f;  // metres
  bool operator<=(const IterateScore& o) const {
    return depth < o.depth || (depth == o.depth && crossings <= o.crossings);
  }
};

}  // namespace

template <bool kActive>
uint32_t HullColliderSet::ParticleContacts(Float3 p0, Float3 p1, float s0, float s1,
                                           const uint32_t* first_candidates, uint32_t skip,
                                           ContactFrames* out) const {
  uint32_t count = 0;
  if (first_candidates != nullptr) {
    // The lowest kMaxCandidates indices, as BroadPhase keeps.
    const uint32_t words = (collider_count_ + 31) / 32;
    for (uint32_t w = 0; w < words; ++w) {
      for (uint32_t mask = first_candidates[w]; mask != 0 && count < kMaxCandidates;
           mask &= mask - 1)
        out->candidates[count++] = 32 * w + static_cast<uint32_t>(__builtin_ctz(mask));
    }
  } else {
    count = BroadPhase(p0, p1, s0, s1, kActive, out->candidates);
  }
  out->count = count;
  out->hits = 0;
  for (uint32_t i = 0; i < count; ++i) {
    if constexpr (kActive) {
      out->frames[i] = &active_[out->candidates[i]];
    } else {
      ActiveFrames* f = new (out->storage + i * sizeof(ActiveFrames)) ActiveFrames;
      ComputeFrames(out->candidates[i], s0, s1, f);
      out->frames[i] = f;
    }
  }
  ContactQuery* contacts = out->contacts();
  for (uint32_t i = 0; i < count; ++i) {
    // The collider resolved alone in the previous pass left the particle on or outside it.
    if (out->candidates[i] == skip) {
      new (&contacts[i]) ContactQuery();
      continue;
    }
    new (&contacts[i]) ContactQuery(ColliderContact(out->candidates[i], *out->frames[i], p0, p1));
    if (contacts[i].contact) out->order[out->hits++] = i;
  }
  return count;
}

// The response bound of one ResolveParticle call. Per collider hit, in its frame: an entry
// response leaves the particle within its motion relative to the collider (the chord) of where p0
// sits on the collider at the end of the substep, which the collider carried away from p0 (a bone
// turning into a particle at rest pushes it as far as its surface travels). Responses to several
// moving colliders compose: their carries add up. Most responses stay within the floor, the
// world chord plus the depths, which needs no transform: the whole bound is computed the first
// time a response reaches beyond it (the same decisions, bit for bit: the floor's sum has fewer,
// smaller non-negative terms, and rounding is monotonic).
class HullColliderSet::ResponseBound {
 public:
  // From the first pass's contacts. `keep_frames`: the hits' frames outlive the pass (the
  // selected substep's); otherwise the bound is computed now.
  void Set(Float3 p0, Float3 p1, const ContactFrames& c, float separation, bool keep_frames) {
    p0_ = p0;
    p1_ = p1;
    separation_ = separation;
    depth_ = 0.0;
    hits_ = c.hits;
    const ContactQuery* contacts = c.contacts();
    for (uint32_t h = 0; h < c.hits; ++h) {
      frames_[h] = c.frames[c.order[h]];
      depth_ += contacts[c.order[h]].depth;
    }
    const double floor = std::sqrt(DistanceSquared(p0, p1)) + kUnionDepthFactor * depth_ +
                         static_cast<double>(separation);
    floor_squared_ = floor * floor;
    full_squared_ = -1.0;
    if (!keep_frames) Full();
  }
  // Whether x lies farther from p0 than the bound.
  bool Exceeded(Float3 x) {
    const double d2 = DistanceSquared(x, p0_);
    return d2 > floor_squared_ && d2 > Full();
  }
  double Distance() { return std::sqrt(Full()); }

 private:
  double Full() {
    if (full_squared_ >= 0.0) return full_squared_;
    double chord = std::sqrt(DistanceSquared(p0_, p1_)), carry = 0.0;
    for (uint32_t h = 0; h < hits_; ++h) {
      const Float3 a = TransformPoint(frames_[h]->to_local_start, p0_);
      const Float3 b = TransformPoint(frames_[h]->to_local_end, p1_);
      const Float3 carried = TransformPoint(frames_[h]->to_world_end, a);
      chord = std::max(chord, std::sqrt(DistanceSquared(a, b)));
      carry += std::sqrt(DistanceSquared(carried, p0_));
    }
    // Rounding of the float response: relative to the coordinates' size.
    const double scale = std::max(
        {std::fabs(double(p1_.x)), std::fabs(double(p1_.y)), std::fabs(double(p1_.z)), 1.0});
    const double bound = chord + carry + kUnionDepthFactor * depth_ +
                         static_cast<double>(separation_) + 1e-6 * scale;
    full_squared_ = bound * bound;
    return full_squared_;
  }

  Float3 p0_, p1_;
  float separation_ = 0.f;
  double depth_ = 0.0;                                // metres, the hits' depths summed
  double floor_squared_ = 0.0, full_squared_ = -1.0;  // -1: not computed yet
  uint32_t hits_ = 0;
  const ActiveFrames* frames_[kMaxCandidates];
};

template <bool kActive>
void HullColliderSet::ResolveParticle(Float3 p0, Float3* p1, Float3* velocity, uint8_t* flags,
                                      const ResponseParams& params, float s0, float s1,
                                      const uint32_t* first_candidates) const {
  uint8_t result = kCollisionNone;
  Float3 position = *p1, vel = *velocity;
  uint32_t last_single = UINT32_MAX;  // the one collider resolved in the previous pass, if so
  ContactPlanes planes;
  // No response may leave the particle farther from where it started the step than its motion
  // relative to the colliders plus the depth it ends at inside them (and the separation): set
  // from the first pass's contacts. An entry response keeps the particle within its motion of
  // p0 (projecting the end onto an entry plane shortens the segment), a push-out moves it by the
  // depth; inside overlapping colliders the nearest exit of their union can be deeper than any
  // one of them (HullColliderSet::kUnionDepthFactor). A response beyond it (contact planes of two
  // colliders meeting far from the body) is undone.
  ResponseBound bound;
  // The best iterate so far (Gauss-Seidel passes can make a pinched particle worse).
  Float3 best_position = position, best_velocity = vel;
  IterateScore best_score{UINT32_MAX, INFINITY};  // worse than any iterate
  ContactFrames pass_contacts;
  const auto score_of = [&](const ContactFrames& c) {
    IterateScore score;
    const ContactQuery* contacts = c.contacts();
    for (uint32_t h = 0; h < c.hits; ++h) {
      const ContactQuery& q = contacts[c.order[h]];
      score.crossings += q.inside_end ? 0u : 1u;
      score.depth = std::max(score.depth, q.depth);
    }
    return score;
  };
  const auto keep_if_best = [&](IterateScore score) {
    if (score <= best_score) {
      best_score = score;
      best_position = position;
      best_velocity = vel;
    }
  };
  bool converged = false;
  for (uint32_t pass = 0; pass < options_.gauss_seidel_passes; ++pass) {
    // Candidates for the current segment: a response may have moved the particle towards a
    // collider the original segment did not reach.
    const uint32_t count = ParticleContacts<kActive>(
        p0, position, s0, s1, pass == 0 ? first_candidates : nullptr, last_single, &pass_contacts);
    // Only the collider just resolved: its response left the particle on or outside it.
    const bool only_last = pass > 0 && count == 1 && pass_contacts.candidates[0] == last_single;
    const uint32_t hits = only_last ? 0 : pass_contacts.hits;
    keep_if_best(only_last ? IterateScore{} : score_of(pass_contacts));
    if (hits == 0) {
      converged = true;
      break;
    }
    const ContactQuery* contacts = pass_contacts.contacts();
    uint32_t* order = pass_contacts.order;
    if (pass == 0) bound.Set(p0, position, pass_contacts, params.separation, kActive);
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
      const ContactQuery c = rank == 0 ? contacts[i]
                                       : ColliderContact(pass_contacts.candidates[i],
                                                         *pass_contacts.frames[i], p0, position);
      if (!c.contact) continue;
      // Flags say what was found, whether or not the response below stays within the budget.
      result |= static_cast<uint8_t>(kCollisionContact | c.flags);
      const Float3 before_position = position, before_velocity = vel;
      const ContactPlanes before_planes = planes;
      ApplyResponse(c, params, &position, &vel);
      const Float3 responded = position;
      planes.Add(c.normal, Dot(c.normal, c.point) + params.separation);
      if (planes.count() > 1) planes.Enforce(&position);
      // Beyond the budget: this response alone (the contact planes meet too far away), else
      // none (the passes go on from the last iterate within it).
      if (bound.Exceeded(position)) position = responded;
      if (bound.Exceeded(position)) {
        position = before_position;
        vel = before_velocity;
        planes = before_planes;
      }
    }
    last_single = hits == 1 ? pass_contacts.candidates[order[0]] : UINT32_MAX;
  }
  if (!converged) {
    // Every pass was used: score the last iterate too, then keep the best.
    ParticleContacts<kActive>(p0, position, s0, s1, nullptr, last_single, &pass_contacts);
    keep_if_best(score_of(pass_contacts));
    position = best_position;
    vel = best_velocity;
    // Still inside (beyond kUnionExitMinDepth), having started inside: each collider's exit lay
    // inside another (out of one half of a torso into the other, and back). The nearest face
    // exit of their union, within the budget, from where the particle was (beyond it, the exit
    // of two colliders is their crease, which the contact planes found if they could).
    if (best_score.depth > kUnionExitMinDepth) {
      ParticleContacts<kActive>(p0, *p1, s0, s1, nullptr, UINT32_MAX, &pass_contacts);
      bool started_inside = false;
      const ContactQuery* contacts = pass_contacts.contacts();
      for (uint32_t h = 0; h < pass_contacts.hits; ++h)
        started_inside |= (contacts[pass_contacts.order[h]].flags & kCollisionStartedInside) != 0;
      ContactQuery exit;
      if (started_inside && NearestUnionExit(p0, *p1, pass_contacts, bound.Distance(), &exit)) {
        position = *p1;
        vel = *velocity;
        ApplyResponse(exit, params, &position, &vel);
      }
    }
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
template uint32_t HullColliderSet::ParticleContacts<true>(Float3, Float3, float, float,
                                                          const uint32_t*, uint32_t,
                                                          ContactFrames*) const;
template uint32_t HullColliderSet::ParticleContacts<false>(Float3, Float3, float, float,
                                                           const uint32_t*, uint32_t,
                                                           ContactFrames*) const;

}  // namespace drape

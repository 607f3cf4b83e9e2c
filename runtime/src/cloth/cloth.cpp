#include "drape/runtime/cloth.h"

#include "cloth/cloth_setup.h"
#include "cloth/spring_colouring.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <string>
#include <tuple>

#include "drape/runtime/math.h"

namespace drape {
namespace {

constexpr uint32_t kMaxParticles = 1u << 30;
constexpr double kMinTriangleArea = 1e-12;  // m^2: below this a triangle carries no mass
constexpr float kMinRestLength = 1e-7f;     // metres: shorter springs have no direction

Status Invalid(const std::string& message) {
  return Status(StatusCode::kInvalidArgument, "BuildCloth: " + message);
}

std::string Str(Float3 p) {
  return "(" + std::to_string(p.x) + ", " + std::to_string(p.y) + ", " + std::to_string(p.z) + ")";
}

Status ValidateMaterial(const SpringMaterial& m, const char* name) {
  const std::string field = std::string("material ") + name;
  if (!std::isfinite(m.stiffness) || m.stiffness < 0.f)
    return Invalid(field + ".stiffness = " + std::to_string(m.stiffness) +
                   " N/m: must be finite and >= 0");
  if (!std::isfinite(m.damping) || m.damping < 0.f)
    return Invalid(field + ".damping = " + std::to_string(m.damping) +
                   " N*s/m: must be finite and >= 0");
  if (!(m.correction >= 0.f && m.correction <= 1.f))
    return Invalid(field + ".correction = " + std::to_string(m.correction) + ": must be in [0, 1]");
  return Status::Ok();
}

// One edge of a kept triangle, with the vertex opposite it.
struct EdgeUse {
  uint32_t lo, hi, opposite;
  bool operator<(const EdgeUse& o) const {
    return std::tie(lo, hi, opposite) < std::tie(o.lo, o.hi, o.opposite);
  }
};

struct Pair {
  uint32_t lo, hi;
  bool operator<(const Pair& o) const { return std::tie(lo, hi) < std::tie(o.lo, o.hi); }
  bool operator==(const Pair& o) const { return lo == o.lo && hi == o.hi; }
};

// Colours the springs (detail::FirstFitColours) and appends the springs grouped by colour (spring
// order kept within a colour, which keeps their particles close in memory) and the colour ranges;
// returns the colour count.
uint32_t ColourSprings(const std::vector<ClothSpring>& springs, SpringKind kind,
                       uint32_t particle_count, std::vector<ClothSpring>* out,
                       std::vector<SpringColour>* colours) {
  std::vector<std::vector<uint64_t>> used(particle_count);
  std::vector<uint32_t> colour_of;
  const uint32_t colour_count = detail::FirstFitColours(springs, &used, &colour_of);
  std::vector<uint32_t> sizes(colour_count, 0);
  for (const uint32_t c : colour_of) ++sizes[c];
  const uint32_t base = static_cast<uint32_t>(out->size());
  std::vector<uint32_t> next(colour_count, base);
  for (uint32_t c = 0; c < colour_count; ++c) {
    SpringColour range;
    range.begin = c == 0 ? base : colours->back().end;
    range.end = range.begin + sizes[c];
    range.kind = kind;
    colours->push_back(range);
    next[c] = range.begin;
  }
  out->resize(base + springs.size());
  for (size_t k = 0; k < springs.size(); ++k) (*out)[next[colour_of[k]]++] = springs[k];
  return colour_count;
}

}  // namespace

void Cloth::Clear() { *this = Cloth(); }

float Cloth::MaxStableEulerStep(float extra_damping) const {
  const double w2 = euler_stiffness_rate_;
  const double g = static_cast<double>(euler_damping_rate_) + std::max(0.f, extra_damping);
  if (!(w2 > 0.0)) {
    return g > 0.0 ? static_cast<float>(2.0 / g) : std::numeric_limits<float>::infinity();
  }
  return static_cast<float>((std::sqrt(g * g + 4.0 * w2) - g) / w2);
}

size_t Cloth::memory_bytes() const {
  return sizeof(*this) + rest_positions_.capacity() * sizeof(Float3) +
         (masses_.capacity() + inverse_masses_.capacity() + areas_.capacity()) * sizeof(float) +
         triangles_.capacity() * sizeof(uint32_t) + springs_.capacity() * sizeof(ClothSpring) +
         colours_.capacity() * sizeof(SpringColour) + kinematic_.capacity() * sizeof(uint32_t) +
         attachments_.capacity() * sizeof(ClothAttachment) +
         tethers_.capacity() * sizeof(ClothTether) + skin_.capacity() * sizeof(ClothSkinWeights) +
         (rest_normals_.capacity() + skin_bind_.capacity()) * sizeof(Float3) +
         (max_distance_.capacity() + backstop_.capacity()) * sizeof(float) +
         constrained_.capacity() * sizeof(uint32_t);
}

namespace {

// A per-particle array: empty or n values, each not NaN and >= 0 (finite unless allow_inf).
Status ValidatePerParticle(const std::vector<float>& values, uint32_t n, const char* name,
                           const char* unit, bool allow_inf) {
  if (values.empty()) return Status::Ok();
  if (values.size() != n)
    return Invalid(std::string(name) + " has " + std::to_string(values.size()) + " entries for " +
                   std::to_string(n) + " particles");
  for (uint32_t i = 0; i < n; ++i) {
    const float v = values[i];
    if (!(v >= 0.f) || (!allow_inf && !std::isfinite(v)))
      return Invalid(std::string(name) + "[" + std::to_string(i) + "] = " + std::to_string(v) +
                     unit + ": must be " + (allow_inf ? ">= 0" : "finite and >= 0"));
  }
  return Status::Ok();
}

Status ValidateTethers(const ClothDescription& d, uint32_t n) {
  if (!std::isfinite(d.tether_stretch) || d.tether_stretch < 0.f)
    return Invalid("tether_stretch = " + std::to_string(d.tether_stretch) +
                   ": must be finite and >= 0");
  return ValidatePerParticle(d.tether_stretch_per_particle, n, "tether_stretch_per_particle", "",
                             false);
}

Status ValidateSkin(const ClothDescription& d, uint32_t n) {
  if (d.skin.empty()) {
    if (!d.max_distance.empty() || !d.backstop.empty())
      return Invalid("max_distance and backstop need skin weights (skin is empty)");
    return Status::Ok();
  }
  if (d.skin.size() != n)
    return Invalid("skin has " + std::to_string(d.skin.size()) + " entries for " +
                   std::to_string(n) + " particles");
  for (uint32_t i = 0; i < n; ++i) {
    float sum = 0.f;
    for (int k = 0; k < 4; ++k) {
      const float w = d.skin[i].weights[k];
      if (!std::isfinite(w) || w < 0.f)
        return Invalid("skin[" + std::to_string(i) + "].weights[" + std::to_string(k) +
                       "] = " + std::to_string(w) + ": must be finite and >= 0");
      if (w > 0.f && d.skin[i].joints[k] >= (1u << 16))
        return Invalid("skin[" + std::to_string(i) + "].joints[" + std::to_string(k) +
                       "] = " + std::to_string(d.skin[i].joints[k]) + ": at most 65535");
      sum += w;
    }
    if (!(sum > 0.f)) return Invalid("skin[" + std::to_string(i) + "]: the weights sum to 0");
  }
  if (!d.skin_bind_positions.empty()) {
    if (d.skin_bind_positions.size() != n)
      return Invalid("skin_bind_positions has " + std::to_string(d.skin_bind_positions.size()) +
                     " entries for " + std::to_string(n) + " particles");
    for (uint32_t i = 0; i < n; ++i)
      if (!IsFinite(d.skin_bind_positions[i]))
        return Invalid("skin_bind_positions[" + std::to_string(i) + "] is not finite");
  }
  if (Status s = ValidatePerParticle(d.max_distance, n, "max_distance", " m", true); !s.ok())
    return s;
  return ValidatePerParticle(d.backstop, n, "backstop", " m", true);
}

// Every count, index and value of the description (the messages name the field).
Status ValidateDescription(const ClothDescription& d) {
  const size_t n_size = d.positions.size();
  if (n_size == 0) return Invalid("no particles (positions is empty)");
  if (n_size > kMaxParticles)
    return Invalid(std::to_string(n_size) + " particles: at most 2^30 are supported");
  const uint32_t n = static_cast<uint32_t>(n_size);
  for (uint32_t i = 0; i < n; ++i) {
    if (!IsFinite(d.positions[i]))
      return Invalid("positions[" + std::to_string(i) + "] = " + Str(d.positions[i]) +
                     " is not finite");
  }
  if (d.triangles.size() % 3 != 0)
    return Invalid("triangles has " + std::to_string(d.triangles.size()) +
                   " indices: not a multiple of 3");
  for (size_t k = 0; k < d.triangles.size(); ++k) {
    if (d.triangles[k] >= n)
      return Invalid("triangles[" + std::to_string(k / 3) + "] corner " + std::to_string(k % 3) +
                     " = " + std::to_string(d.triangles[k]) + " is beyond the particle count " +
                     std::to_string(n));
  }
  if (!d.masses.empty()) {
    if (d.masses.size() != n)
      return Invalid("masses has " + std::to_string(d.masses.size()) + " entries for " +
                     std::to_string(n) + " particles");
    for (uint32_t i = 0; i < n; ++i) {
      if (!std::isfinite(d.masses[i]) || !(d.masses[i] > 0.f))
        return Invalid("masses[" + std::to_string(i) + "] = " + std::to_string(d.masses[i]) +
                       " kg: must be finite and > 0 (pin a particle to make it immovable)");
    }
  } else {
    if (!std::isfinite(d.density) || d.density < 0.f)
      return Invalid("density = " + std::to_string(d.density) + " kg/m^2: must be finite and >= 0");
    if (!std::isfinite(d.total_mass) || d.total_mass < 0.f)
      return Invalid("total_mass = " + std::to_string(d.total_mass) +
                     " kg: must be finite and >= 0");
    if (!(d.density > 0.f) && !(d.total_mass > 0.f))
      return Invalid("masses is empty and neither density nor total_mass is > 0");
  }
  for (size_t k = 0; k < d.pinned.size(); ++k) {
    if (d.pinned[k] >= n)
      return Invalid("pinned[" + std::to_string(k) + "] = " + std::to_string(d.pinned[k]) +
                     " is beyond the particle count " + std::to_string(n));
  }
  for (size_t k = 0; k < d.attachments.size(); ++k) {
    const ClothAttachment& a = d.attachments[k];
    const std::string name = "attachments[" + std::to_string(k) + "]";
    if (a.particle >= n)
      return Invalid(name + ".particle = " + std::to_string(a.particle) +
                     " is beyond the particle count " + std::to_string(n));
    if (a.joint < 0)
      return Invalid(name + ".joint = " + std::to_string(a.joint) + ": must be >= 0");
    if (!IsFinite(a.bind_position))
      return Invalid(name + ".bind_position = " + Str(a.bind_position) + " is not finite");
  }
  if (Status s = ValidateMaterial(d.stretch, "stretch"); !s.ok()) return s;
  if (Status s = ValidateMaterial(d.bend, "bend"); !s.ok()) return s;
  if (Status s = ValidateTethers(d, n); !s.ok()) return s;
  return ValidateSkin(d, n);
}

}  // namespace

// BuildCloth's stages, in order; each fills part of the cloth.
struct Cloth::Builder {
  // The triangles without repeated indices, and each particle's share (a third) of the area of
  // its triangles, in double (the order is fixed by the triangle index).
  static std::vector<double> Triangles(const ClothDescription& d, uint32_t n, Cloth* cloth) {
    Cloth& c = *cloth;
    ClothBuildReport& report = c.report_;
    std::vector<double> area(n, 0.0);
    c.triangles_.reserve(d.triangles.size());
    for (size_t t = 0; t < d.triangles.size() / 3; ++t) {
      const uint32_t i = d.triangles[3 * t], j = d.triangles[3 * t + 1], k = d.triangles[3 * t + 2];
      if (i == j || j == k || k == i) {
        ++report.dropped_triangles;
        continue;
      }
      c.triangles_.insert(c.triangles_.end(), {i, j, k});
      const Float3 pi = d.positions[i], pj = d.positions[j], pk = d.positions[k];
      const double ux = double(pj.x) - pi.x, uy = double(pj.y) - pi.y, uz = double(pj.z) - pi.z;
      const double vx = double(pk.x) - pi.x, vy = double(pk.y) - pi.y, vz = double(pk.z) - pi.z;
      const double cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
      const double tri_area = 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
      if (!(tri_area >= kMinTriangleArea)) {
        ++report.zero_area_triangles;
        continue;
      }
      area[i] += tri_area / 3.0;
      area[j] += tri_area / 3.0;
      area[k] += tri_area / 3.0;
    }
    return area;
  }

  // Pinned or attached particles (at most one attachment each), and the joints they need.
  static Status Kinematic(const ClothDescription& d, uint32_t n, Cloth* cloth,
                          std::vector<uint8_t>* kinematic_out) {
    Cloth& c = *cloth;
    std::vector<uint8_t>& kinematic = *kinematic_out;
    kinematic.assign(n, 0);
    for (const uint32_t p : d.pinned) kinematic[p] = 1;
    c.attachments_ = d.attachments;
    std::sort(
        c.attachments_.begin(), c.attachments_.end(),
        [](const ClothAttachment& a, const ClothAttachment& b) { return a.particle < b.particle; });
    for (size_t k = 0; k < c.attachments_.size(); ++k) {
      const ClothAttachment& a = c.attachments_[k];
      if (k > 0 && c.attachments_[k - 1].particle == a.particle) {
        const uint32_t particle = a.particle;  // `a` dies with Clear()
        c.Clear();
        return Invalid("particle " + std::to_string(particle) + " has more than one attachment");
      }
      kinematic[a.particle] = 1;
      c.required_joints_ = std::max(c.required_joints_, static_cast<uint32_t>(a.joint) + 1);
    }
    // A skinned particle with max distance 0 is placed at its skinned position.
    for (size_t i = 0; i < d.max_distance.size(); ++i)
      if (d.max_distance[i] == 0.f) kinematic[i] = 1;

    return Status::Ok();
  }

  // Masses: explicit, or by area (density; total_mass rescales the area masses to its value);
  // inverse masses, 0 for the kinematic particles.
  static Status Masses(const ClothDescription& d, uint32_t n, const std::vector<double>& area,
                       const std::vector<uint8_t>& kinematic, Cloth* cloth) {
    Cloth& c = *cloth;
    c.masses_.assign(n, 0.f);
    c.inverse_masses_.assign(n, 0.f);
    c.areas_.resize(n);
    for (uint32_t i = 0; i < n; ++i) c.areas_[i] = static_cast<float>(area[i]);
    if (!d.masses.empty()) {
      c.masses_ = d.masses;
    } else {
      const double per_area = d.density > 0.f ? static_cast<double>(d.density) : 1.0;
      double sum = 0.0;
      for (uint32_t i = 0; i < n; ++i) sum += area[i] * per_area;
      const double scale = d.total_mass > 0.f ? (sum > 0.0 ? d.total_mass / sum : 0.0) : 1.0;
      for (uint32_t i = 0; i < n; ++i)
        c.masses_[i] = static_cast<float>(area[i] * per_area * scale);
    }
    double total = 0.0;
    for (uint32_t i = 0; i < n; ++i) {
      if (kinematic[i]) {
        c.kinematic_.push_back(i);
        continue;
      }
      if (!(c.masses_[i] > 0.f) || !std::isfinite(1.f / c.masses_[i])) {
        c.Clear();
        return Invalid("particle " + std::to_string(i) +
                       " gets no mass (it is in no triangle with area and masses is empty) and is "
                       "neither pinned nor attached");
      }
      c.inverse_masses_[i] = 1.f / c.masses_[i];
      total += c.masses_[i];
    }
    c.total_mass_ = static_cast<float>(total);

    return Status::Ok();
  }

  // The stretch springs (every edge) and bend springs (between the vertices opposite an edge two
  // triangles share), each weighted by its ends' inverse masses and coloured.
  static void Springs(const ClothDescription& d, uint32_t n, Cloth* cloth) {
    Cloth& c = *cloth;
    ClothBuildReport& report = c.report_;
    // Sorted edge uses give the stretch springs; edges used twice give bend candidates.
    std::vector<EdgeUse> uses;
    uses.reserve(c.triangles_.size());
    for (size_t t = 0; t < c.triangles_.size() / 3; ++t) {
      const uint32_t v[3] = {c.triangles_[3 * t], c.triangles_[3 * t + 1], c.triangles_[3 * t + 2]};
      for (int e = 0; e < 3; ++e) {
        const uint32_t a = v[e], b = v[(e + 1) % 3], o = v[(e + 2) % 3];
        uses.push_back({std::min(a, b), std::max(a, b), o});
      }
    }
    std::sort(uses.begin(), uses.end());
    std::vector<Pair> stretch_pairs, bend_pairs;
    for (size_t k = 0; k < uses.size();) {
      size_t end = k + 1;
      while (end < uses.size() && uses[end].lo == uses[k].lo && uses[end].hi == uses[k].hi) ++end;
      stretch_pairs.push_back({uses[k].lo, uses[k].hi});
      const size_t count = end - k;
      if (count == 2) {
        const uint32_t o0 = uses[k].opposite, o1 = uses[k + 1].opposite;
        if (o0 != o1) bend_pairs.push_back({std::min(o0, o1), std::max(o0, o1)});
      } else if (count > 2) {
        ++report.non_manifold_edges;
      }
      k = end;
    }
    std::sort(bend_pairs.begin(), bend_pairs.end());
    bend_pairs.erase(std::unique(bend_pairs.begin(), bend_pairs.end()), bend_pairs.end());
    if (!d.bend_springs) bend_pairs.clear();

    const auto make_springs = [&](const std::vector<Pair>& pairs, bool skip_stretch_edges) {
      std::vector<ClothSpring> springs;
      springs.reserve(pairs.size());
      for (const Pair& p : pairs) {
        if (skip_stretch_edges && std::binary_search(stretch_pairs.begin(), stretch_pairs.end(), p))
          continue;
        const float rest = Length(d.positions[p.hi] - d.positions[p.lo]);
        const float wa = c.inverse_masses_[p.lo], wb = c.inverse_masses_[p.hi];
        if (!(rest >= kMinRestLength) || (wa == 0.f && wb == 0.f)) {
          ++report.dropped_springs;
          continue;
        }
        ClothSpring s;
        s.a = p.lo;
        s.b = p.hi;
        s.rest_length = rest;
        s.weight_a = wa / (wa + wb);
        s.weight_b = wb / (wa + wb);
        springs.push_back(s);
      }
      return springs;
    };
    const std::vector<ClothSpring> stretch = make_springs(stretch_pairs, false);
    const std::vector<ClothSpring> bend = make_springs(bend_pairs, true);
    c.stretch_count_ = static_cast<uint32_t>(stretch.size());
    c.bend_count_ = static_cast<uint32_t>(bend.size());
    c.springs_.reserve(stretch.size() + bend.size());
    report.stretch_colours =
        ColourSprings(stretch, SpringKind::kStretch, n, &c.springs_, &c.colours_);
    report.bend_colours = ColourSprings(bend, SpringKind::kBend, n, &c.springs_, &c.colours_);
  }

  // Skin weights (renormalised, zero weights' joints set to 0), rest normals, max distances and
  // backstops (+inf where not given), the particles they constrain, and the joints they need.
  static void Skin(const ClothDescription& d, uint32_t n, const std::vector<uint8_t>& kinematic,
                   Cloth* cloth) {
    Cloth& c = *cloth;
    if (d.skin.empty()) return;
    c.skin_ = d.skin;
    for (ClothSkinWeights& w : c.skin_) {
      const float sum = w.weights[0] + w.weights[1] + w.weights[2] + w.weights[3];
      for (int k = 0; k < 4; ++k) {
        w.weights[k] /= sum;
        if (w.weights[k] == 0.f) w.joints[k] = 0;
        c.required_joints_ = std::max(c.required_joints_, w.joints[k] + 1);
      }
    }
    c.skin_bind_ = d.skin_bind_positions;
    c.rest_normals_ = detail::VertexNormals(c.skin_bind_positions(), c.triangles_);
    constexpr float kUnlimited = std::numeric_limits<float>::infinity();
    c.max_distance_ = d.max_distance.empty() ? std::vector<float>(n, kUnlimited) : d.max_distance;
    c.backstop_ = d.backstop.empty() ? std::vector<float>(n, kUnlimited) : d.backstop;
    for (uint32_t i = 0; i < n; ++i) {
      if (kinematic[i]) continue;
      if (std::isfinite(c.max_distance_[i]) || std::isfinite(c.backstop_[i]))
        c.constrained_.push_back(i);
    }
  }

  static void Tethers(const ClothDescription& d, const std::vector<uint8_t>& kinematic,
                      Cloth* cloth) {
    Cloth& c = *cloth;
    if (!d.tethers) return;
    c.tethers_ =
        detail::BuildTethers(d.positions, c.triangles_, kinematic, d.tether_stretch_per_particle,
                             d.tether_stretch, &c.report_.untethered_particles);
    c.report_.tethers = static_cast<uint32_t>(c.tethers_.size());
  }

  // Explicit Euler stability rates (Gershgorin rows of M^-1 K and M^-1 C).
  static void EulerRates(uint32_t n, Cloth* cloth) {
    Cloth& c = *cloth;
    std::vector<double> k_sum(n, 0.0), c_sum(n, 0.0);
    for (const SpringColour& colour : c.colours_) {
      const SpringMaterial& m = c.material(colour.kind);
      for (uint32_t s = colour.begin; s < colour.end; ++s) {
        const ClothSpring& spring = c.springs_[s];
        k_sum[spring.a] += m.stiffness;
        k_sum[spring.b] += m.stiffness;
        c_sum[spring.a] += m.damping;
        c_sum[spring.b] += m.damping;
      }
    }
    double w2 = 0.0, g = 0.0;
    for (uint32_t i = 0; i < n; ++i) {
      const double w = c.inverse_masses_[i];
      w2 = std::max(w2, 2.0 * k_sum[i] * w);
      g = std::max(g, 2.0 * c_sum[i] * w);
    }
    c.euler_stiffness_rate_ = static_cast<float>(w2);
    c.euler_damping_rate_ = static_cast<float>(g);
  }
};

Status BuildCloth(const ClothDescription& d, Cloth* cloth) {
  if (cloth == nullptr) return Invalid("cloth is null");
  cloth->Clear();
  if (Status s = ValidateDescription(d); !s.ok()) return s;
  const uint32_t n = static_cast<uint32_t>(d.positions.size());
  cloth->rest_positions_ = d.positions;
  cloth->stretch_ = d.stretch;
  cloth->bend_ = d.bend;
  const std::vector<double> area = Cloth::Builder::Triangles(d, n, cloth);
  std::vector<uint8_t> kinematic;
  if (Status s = Cloth::Builder::Kinematic(d, n, cloth, &kinematic); !s.ok()) return s;
  if (Status s = Cloth::Builder::Masses(d, n, area, kinematic, cloth); !s.ok()) return s;
  Cloth::Builder::Springs(d, n, cloth);
  Cloth::Builder::EulerRates(n, cloth);
  Cloth::Builder::Skin(d, n, kinematic, cloth);
  Cloth::Builder::Tethers(d, kinematic, cloth);
  return Status::Ok();
}

void ClothState::Reset(const Cloth& cloth) {
  const std::span<const Float3> rest = cloth.rest_positions();
  positions.assign(rest.begin(), rest.end());
  previous_positions.assign(rest.begin(), rest.end());
  velocities.assign(rest.size(), Float3{});
}

bool ClothState::Matches(const Cloth& cloth) const {
  const size_t n = cloth.particle_count();
  return positions.size() == n && previous_positions.size() == n && velocities.size() == n;
}

namespace detail {

uint32_t FirstFitColours(std::span<const ClothSpring> springs,
                         std::vector<std::vector<uint64_t>>* used,
                         std::vector<uint32_t>* colour_of) {
  colour_of->assign(springs.size(), 0);
  uint32_t count = 0;
  for (size_t k = 0; k < springs.size(); ++k) {
    const std::vector<uint64_t>& ua = (*used)[springs[k].a];
    const std::vector<uint64_t>& ub = (*used)[springs[k].b];
    uint32_t colour = 0;
    for (size_t w = 0;; ++w) {
      const uint64_t taken = (w < ua.size() ? ua[w] : 0) | (w < ub.size() ? ub[w] : 0);
      if (taken != ~uint64_t{0}) {
        colour = static_cast<uint32_t>(64 * w + std::countr_one(taken));
        break;
      }
    }
    for (const uint32_t p : {springs[k].a, springs[k].b}) {
      std::vector<uint64_t>& bits = (*used)[p];
      if (bits.size() <= colour / 64) bits.resize(colour / 64 + 1, 0);
      bits[colour / 64] |= uint64_t{1} << (colour % 64);
    }
    (*colour_of)[k] = colour;
    count = std::max(count, colour + 1);
  }
  for (const ClothSpring& spring : springs) {
    std::fill((*used)[spring.a].begin(), (*used)[spring.a].end(), 0);
    std::fill((*used)[spring.b].begin(), (*used)[spring.b].end(), 0);
  }
  return count;
}

}  // namespace detail
}  // namespace drape

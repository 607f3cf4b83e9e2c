#include "query_sets.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace drape::bench {
namespace {

struct SurfaceSample {
  double point[3];
  double normal[3];  // unit face normal (outward for outward-wound meshes)
};

// Area-weighted sampling of the mesh surface; degenerate triangles have weight 0.
class SurfaceSampler {
 public:
  SurfaceSampler(std::span<const Float3> positions, std::span<const uint32_t> triangles)
      : positions_(positions), triangles_(triangles) {
    double total = 0.0;
    cumulative_.reserve(triangles.size() / 3);
    for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
      double n[3];
      total += 0.5 * FaceNormal(t, n);
      cumulative_.push_back(total);
    }
  }

  bool empty() const { return cumulative_.empty() || cumulative_.back() <= 0.0; }

  SurfaceSample Draw(std::mt19937_64& rng) const {
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const double pick = unit(rng) * cumulative_.back();
    const size_t t = static_cast<size_t>(
        std::upper_bound(cumulative_.begin(), cumulative_.end(), pick) - cumulative_.begin());
    const size_t first = std::min(t, cumulative_.size() - 1) * 3;
    double r1 = unit(rng), r2 = unit(rng);
    if (r1 + r2 > 1.0) {
      r1 = 1.0 - r1;
      r2 = 1.0 - r2;
    }
    const Float3& a = positions_[triangles_[first]];
    const Float3& b = positions_[triangles_[first + 1]];
    const Float3& c = positions_[triangles_[first + 2]];
    SurfaceSample s;
    s.point[0] = a.x + r1 * (double(b.x) - a.x) + r2 * (double(c.x) - a.x);
    s.point[1] = a.y + r1 * (double(b.y) - a.y) + r2 * (double(c.y) - a.y);
    s.point[2] = a.z + r1 * (double(b.z) - a.z) + r2 * (double(c.z) - a.z);
    FaceNormal(first, s.normal);
    return s;
  }

 private:
  // Unit normal of the triangle starting at index `first`; returns twice its area.
  double FaceNormal(size_t first, double n[3]) const {
    const Float3& a = positions_[triangles_[first]];
    const Float3& b = positions_[triangles_[first + 1]];
    const Float3& c = positions_[triangles_[first + 2]];
    const double e1[3] = {double(b.x) - a.x, double(b.y) - a.y, double(b.z) - a.z};
    const double e2[3] = {double(c.x) - a.x, double(c.y) - a.y, double(c.z) - a.z};
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (length > 0.0) {
      n[0] /= length;
      n[1] /= length;
      n[2] /= length;
    }
    return length;
  }

  std::span<const Float3> positions_;
  std::span<const uint32_t> triangles_;
  std::vector<double> cumulative_;  // running sum of triangle areas, m^2
};

Float3 ToFloat(const double p[3]) {
  return {static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2])};
}

void Offset(const double p[3], const double d[3], double s, double out[3]) {
  for (int k = 0; k < 3; ++k) out[k] = p[k] + d[k] * s;
}

// A unit direction within `max_angle` radians of `axis` (uniform over the cap).
void TiltedDirection(const double axis[3], double max_angle, std::mt19937_64& rng, double out[3]) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double cos_max = std::cos(max_angle);
  const double z = 1.0 - unit(rng) * (1.0 - cos_max);
  const double phi = 2.0 * 3.14159265358979323846 * unit(rng);
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  // An orthonormal basis around axis (Frisvad-style, no branch on small components).
  double t[3];
  if (std::fabs(axis[0]) < 0.9) {
    t[0] = 0.0, t[1] = -axis[2], t[2] = axis[1];  // axis x (1,0,0)
  } else {
    t[0] = axis[2], t[1] = 0.0, t[2] = -axis[0];  // axis x (0,1,0)
  }
  const double tl = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
  for (double& v : t) v /= tl;
  const double b[3] = {axis[1] * t[2] - axis[2] * t[1], axis[2] * t[0] - axis[0] * t[2],
                       axis[0] * t[1] - axis[1] * t[0]};
  for (int k = 0; k < 3; ++k) {
    out[k] = axis[k] * z + (t[k] * std::cos(phi) + b[k] * std::sin(phi)) * r;
  }
}

}  // namespace

std::vector<QuerySet> MakeQuerySets(std::span<const Float3> positions,
                                    std::span<const uint32_t> triangles,
                                    const bake::MeshReference& reference,
                                    const QuerySetOptions& options) {
  std::vector<QuerySet> sets(5);
  sets[0].name = "uniform";
  sets[1].name = "near_surface";
  sets[2].name = "thin_crossing";
  sets[3].name = "fast";
  sets[4].name = "started_inside";
  const SurfaceSampler sampler(positions, triangles);
  if (positions.empty() || sampler.empty()) return sets;
  const auto add = [](QuerySet& set, const double p0[3], const double p1[3]) {
    set.previous.push_back(ToFloat(p0));
    set.current.push_back(ToFloat(p1));
  };
  // Attempts per set are bounded so a mesh without thin parts cannot loop forever.
  const uint64_t max_attempts = uint64_t{options.count} * 50;

  {  // uniform
    std::mt19937_64 rng(options.seed + 1);
    double lo[3] = {1e30, 1e30, 1e30}, hi[3] = {-1e30, -1e30, -1e30};
    for (const Float3& p : positions) {
      const double c[3] = {p.x, p.y, p.z};
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], c[k]), hi[k] = std::max(hi[k], c[k]);
    }
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (uint32_t i = 0; i < options.count; ++i) {
      double p[3];
      for (int k = 0; k < 3; ++k) {
        p[k] = lo[k] - options.box_margin + unit(rng) * (hi[k] - lo[k] + 2.0 * options.box_margin);
      }
      add(sets[0], p, p);
    }
  }
  {  // near_surface
    std::mt19937_64 rng(options.seed + 2);
    std::uniform_real_distribution<double> band(-options.near_band, options.near_band);
    for (uint32_t i = 0; i < options.count; ++i) {
      const SurfaceSample s = sampler.Draw(rng);
      double p[3];
      Offset(s.point, s.normal, band(rng), p);
      add(sets[1], p, p);
    }
  }
  {  // thin_crossing
    std::mt19937_64 rng(options.seed + 3);
    std::uniform_real_distribution<double> lead(options.start_clearance,
                                                options.start_clearance + 0.015);
    std::vector<double> ts;
    for (uint64_t attempt = 0; attempt < max_attempts && sets[2].size() < options.count;
         ++attempt) {
      const SurfaceSample s = sampler.Draw(rng);
      double inward[3];
      TiltedDirection(s.normal, 0.35, rng, inward);
      for (double& v : inward) v = -v;
      // Cross from just outside to thin_thickness beyond the surface and find the far side.
      double a[3], b[3];
      Offset(s.point, inward, -1e-4, a);
      Offset(s.point, inward, options.thin_thickness, b);
      reference.Crossings(a, b, &ts);
      // ts[0] is the surface we start on; the far side is the next crossing.
      if (ts.size() < 2) continue;
      const double thickness = ts[1] * (options.thin_thickness + 1e-4) - 1e-4;
      if (thickness < 1e-3) continue;  // a crease or a doubled surface, not a part
      double mid[3];
      Offset(s.point, inward, 0.5 * thickness, mid);
      if (!reference.Inside(mid)) continue;  // the gap between two parts, not a part
      double p0[3], p1[3];
      Offset(s.point, inward, -lead(rng), p0);
      Offset(s.point, inward, thickness + lead(rng), p1);
      if (reference.Inside(p0) || reference.Inside(p1)) continue;
      // `lead` is measured along the motion from this part only: on blocky meshes that can put
      // the start within a few millimetres of a neighbouring part, inside every proxy's
      // inflation, where "started inside and left" is the runtime's contract, not a miss.
      if (reference.Distance(p0) < options.start_clearance) continue;
      add(sets[2], p0, p1);
    }
  }
  {  // fast
    std::mt19937_64 rng(options.seed + 4);
    std::uniform_real_distribution<double> height(options.start_clearance, 0.05),
        length(0.001, options.fast_length);
    for (uint64_t attempt = 0; attempt < max_attempts && sets[3].size() < options.count;
         ++attempt) {
      const SurfaceSample s = sampler.Draw(rng);
      double p0[3];
      Offset(s.point, s.normal, height(rng), p0);
      if (reference.Inside(p0) || reference.Distance(p0) < options.start_clearance) continue;
      double inward[3] = {-s.normal[0], -s.normal[1], -s.normal[2]}, d[3];
      TiltedDirection(inward, 1.2, rng, d);
      double p1[3];
      Offset(p0, d, length(rng), p1);
      add(sets[3], p0, p1);
    }
  }
  {  // started_inside
    std::mt19937_64 rng(options.seed + 5);
    std::uniform_real_distribution<double> depth(0.001, options.inside_depth), move(0.0, 0.005);
    for (uint64_t attempt = 0; attempt < max_attempts && sets[4].size() < options.count;
         ++attempt) {
      const SurfaceSample s = sampler.Draw(rng);
      double p0[3];
      Offset(s.point, s.normal, -depth(rng), p0);
      if (!reference.Inside(p0)) continue;
      double d[3];
      TiltedDirection(s.normal, 3.14159265358979323846, rng, d);
      double p1[3];
      Offset(p0, d, move(rng), p1);
      add(sets[4], p0, p1);
    }
  }
  return sets;
}

QuerySet ConcatenateQuerySets(std::span<const QuerySet> sets) {
  QuerySet all;
  all.name = "all";
  for (const QuerySet& s : sets) {
    all.previous.insert(all.previous.end(), s.previous.begin(), s.previous.end());
    all.current.insert(all.current.end(), s.current.begin(), s.current.end());
  }
  return all;
}

}  // namespace drape::bench

#include "evaluation.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>

namespace drape::bench {
namespace {

void ToDouble(Float3 p, double out[3]) {
  out[0] = p.x;
  out[1] = p.y;
  out[2] = p.z;
}

// The value below which `fraction` of the sorted values lie (nearest rank); 0 for none.
double Percentile(std::vector<double> values, double fraction) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const size_t rank = static_cast<size_t>(std::ceil(fraction * static_cast<double>(values.size())));
  return values[std::min(values.size() - 1, rank == 0 ? 0 : rank - 1)];
}

std::vector<Float3> StepVelocities(const QuerySet& set) {
  std::vector<Float3> v(set.size());
  for (size_t i = 0; i < set.size(); ++i)
    v[i] = (set.current[i] - set.previous[i]) * (1.f / kStepSeconds);
  return v;
}

double TimeCollide(const Method& method, const QuerySet& set, int threads, uint32_t repetitions) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(threads);
  const std::vector<Float3> start_velocities = StepVelocities(set);
  std::vector<Float3> positions(set.size()), velocities(set.size());
  std::vector<uint8_t> flags(set.size());
  double best = std::numeric_limits<double>::infinity();
  for (uint32_t r = 0; r < repetitions + 1; ++r) {  // the first run warms caches, not counted
    positions = set.current;
    velocities = start_velocities;
    const auto begin = std::chrono::steady_clock::now();
    method.Collide(set.previous, positions, velocities, flags);
    const auto end = std::chrono::steady_clock::now();
    if (r > 0) best = std::min(best, std::chrono::duration<double, std::nano>(end - begin).count());
  }
  omp_set_num_threads(saved);
  return set.size() == 0 ? 0.0 : best / static_cast<double>(set.size());
}

double AngleDegrees(Float3 a, const double b[3]) {
  const double la = std::sqrt(double(a.x) * a.x + double(a.y) * a.y + double(a.z) * a.z);
  const double lb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
  if (la == 0.0 || lb == 0.0) return 180.0;
  const double c = (a.x * b[0] + a.y * b[1] + a.z * b[2]) / (la * lb);
  return std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / 3.14159265358979323846;
}

}  // namespace

std::vector<ReferenceAnswer> AnswerQueries(const bake::MeshReference& reference,
                                           const QuerySet& set) {
  std::vector<ReferenceAnswer> answers(set.size());
  const long count = static_cast<long>(set.size());
#pragma omp parallel for schedule(dynamic, 64)
  for (long i = 0; i < count; ++i) {
    const size_t k = static_cast<size_t>(i);
    double a[3], b[3];
    ToDouble(set.previous[k], a);
    ToDouble(set.current[k], b);
    ReferenceAnswer& r = answers[k];
    r.start_inside = reference.Inside(a);
    r.end_inside = reference.Inside(b);
    r.contact_expected = r.end_inside;
    if (!r.start_inside && !r.end_inside) {
      std::vector<double> ts;
      reference.Crossings(a, b, &ts);
      // Inside somewhere between two consecutive crossings (a flap, a seam or a grazed fold can
      // come first: every interval is tested, not only the first).
      for (size_t c = 0; c + 1 < ts.size() && !r.contact_expected; ++c) {
        if (!(ts[c + 1] > ts[c])) continue;
        const double t = 0.5 * (ts[c] + ts[c + 1]);
        const double mid[3] = {a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t,
                               a[2] + (b[2] - a[2]) * t};
        r.contact_expected = reference.Inside(mid);
      }
    }
  }
  return answers;
}

Metrics Evaluate(const Method& method, const QuerySet& set,
                 std::span<const ReferenceAnswer> answers, const bake::MeshReference& reference,
                 const EvaluationOptions& options) {
  Metrics m;
  m.queries = set.size();
  if (set.size() == 0) return m;
  m.ns_one_thread = TimeCollide(method, set, 1, options.repetitions);
  if (options.two_threads) m.ns_two_threads = TimeCollide(method, set, 2, options.repetitions);
  if (!options.accuracy || method.speed_only) return m;
  if (answers.size() != set.size()) {
    std::fprintf(stderr, "speed_vs_error: %zu reference answers for %zu motions\n", answers.size(),
                 set.size());
    std::exit(1);
  }
  m.has_accuracy = true;

  // One untimed batch for the positions after the response.
  std::vector<Float3> positions = set.current, velocities = StepVelocities(set);
  std::vector<uint8_t> flags(set.size());
  method.Collide(set.previous, positions, velocities, flags);
  m.own_surface_misses = method.OwnSurfaceMisses(set.previous, set.current, flags);
  {  // the batch against one particle at a time, on these real motions
    std::vector<Float3> one_positions = set.current, one_velocities = StepVelocities(set);
    std::vector<uint8_t> one_flags(set.size());
    if (method.QueryEachAndRespond(set.previous, one_positions, one_velocities, one_flags)) {
      m.batch_mismatches = 0;
      for (size_t k = 0; k < set.size(); ++k) {
        m.batch_mismatches += flags[k] != one_flags[k] ||
                              std::memcmp(&positions[k], &one_positions[k], sizeof(Float3)) != 0 ||
                              std::memcmp(&velocities[k], &one_velocities[k], sizeof(Float3)) != 0;
      }
    }
  }

  const long count = static_cast<long>(set.size());
  std::vector<double> penetration(set.size(), -1.0), point_error(set.size(), -1.0),
      normal_error(set.size(), -1.0);
#pragma omp parallel for schedule(dynamic, 64)
  for (long i = 0; i < count; ++i) {
    const size_t k = static_cast<size_t>(i);
    const bool contact = (flags[k] & kCollisionContact) != 0;
    if (!answers[k].contact_expected && !contact) continue;
    double p[3];
    ToDouble(positions[k], p);
    penetration[k] = reference.Inside(p) ? reference.Distance(p) : 0.0;
    const ContactQuery c = method.Query(set.previous[k], set.current[k]);
    if (!c.contact) continue;
    double q[3], closest[3], normal[3];
    uint32_t triangle = 0;
    ToDouble(c.point, q);
    point_error[k] = reference.ClosestPoint(q, closest, &triangle, normal);
    normal_error[k] = AngleDegrees(c.normal, normal);
  }
  std::vector<double> pen, cp, ne;
  for (size_t k = 0; k < set.size(); ++k) {
    const bool contact = (flags[k] & kCollisionContact) != 0;
    if (answers[k].contact_expected) {
      ++m.expected;
      m.missed += !contact;
    } else {
      m.false_contacts += contact;
    }
    if (penetration[k] >= 0.0) pen.push_back(penetration[k] * 1e3);
    if (point_error[k] >= 0.0) cp.push_back(point_error[k] * 1e3);
    if (normal_error[k] >= 0.0) ne.push_back(normal_error[k]);
  }
  m.missed_rate = m.expected ? double(m.missed) / double(m.expected) : 0.0;
  const size_t not_expected = m.queries - m.expected;
  m.false_contact_rate = not_expected ? double(m.false_contacts) / double(not_expected) : 0.0;
  m.penetration_p99_mm = Percentile(pen, 0.99);
  m.penetration_max_mm = pen.empty() ? 0.0 : *std::max_element(pen.begin(), pen.end());
  m.contact_point_p50_mm = Percentile(cp, 0.5);
  m.contact_point_p99_mm = Percentile(cp, 0.99);
  m.normal_p50_deg = Percentile(ne, 0.5);
  m.normal_p99_deg = Percentile(ne, 0.99);
  return m;
}

}  // namespace drape::bench

#pragma once
// What the exact mesh says about each query, and the metrics of one method on one query set
// against it. Definitions, for a motion p0 -> p1:
//  - contact expected: p1 is inside the mesh (winding number > 1/2), or p0 and p1 are outside and
//    the segment is inside somewhere between two consecutive crossings (tested at the middle of
//    each interval): a thin part crossed in one step counts (tunnelling).
//  - missed: contact expected, and the method reports no contact.
//  - false contact: no contact expected, and the method reports one (includes contacts with the
//    method's deliberate inflation: epsilon for the maps, delta and growth for the hulls).
//  - penetration after response: the depth of the method's output position inside the exact mesh
//    (distance to the surface when the winding number says inside, else 0), over the queries
//    where contact was expected or reported.
//  - contact-point error: distance from the method's contact point to the exact surface.
//  - normal error: angle between the method's normal and the face normal of the exact surface
//    nearest to its contact point.

#include <cstdint>
#include <span>
#include <vector>

#include "drape/bake/mesh_reference.h"
#include "methods.h"
#include "query_sets.h"

namespace drape::bench {

struct ReferenceAnswer {
  bool start_inside = false;
  bool end_inside = false;
  bool contact_expected = false;
};

std::vector<ReferenceAnswer> AnswerQueries(const bake::MeshReference& reference,
                                           const QuerySet& set);

struct Metrics {
  size_t queries = 0;
  size_t expected = 0;  // queries with contact expected
  size_t missed = 0;
  size_t false_contacts = 0;
  double ns_one_thread = 0.0;   // per particle, Collide on the whole set, best of the repetitions
  double ns_two_threads = 0.0;  // 0 when not timed
  double missed_rate = 0.0;     // missed / expected
  double false_contact_rate = 0.0;  // false contacts / (queries - expected)
  double penetration_p99_mm = 0.0, penetration_max_mm = 0.0;
  double contact_point_p50_mm = 0.0, contact_point_p99_mm = 0.0;
  double normal_p50_deg = 0.0, normal_p99_deg = 0.0;
  long own_surface_misses = -1;  // motions into the proxy's own surface left uncaught (-1: n/a)
  // particles whose Collide answer (flags, position, velocity) differs in a bit from
  // Method::QueryEachAndRespond (-1: the method documents no such equality)
  long batch_mismatches = -1;
  bool has_accuracy = false;
};

struct EvaluationOptions {
  uint32_t repetitions = 5;  // timing runs; the fastest counts
  bool two_threads = true;   // also time with two OpenMP threads
  bool accuracy = true;      // compute the accuracy metrics (speed-only peers: false)
};

Metrics Evaluate(const Method& method, const QuerySet& set,
                 std::span<const ReferenceAnswer> answers, const bake::MeshReference& reference,
                 const EvaluationOptions& options);

}  // namespace drape::bench

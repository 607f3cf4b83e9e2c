#pragma once
// The particle motions every method is measured on, per character and pose, drawn with fixed
// seeds so every method sees the same particles in the same order.
// A query is a motion previous -> current in the asset frame (metres); a point query has
// previous == current.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "drape/bake/mesh_reference.h"
#include "drape/formats/types.h"

namespace drape::bench {

struct QuerySet {
  std::string name;
  std::vector<Float3> previous;
  std::vector<Float3> current;
  size_t size() const { return current.size(); }
};

struct QuerySetOptions {
  uint32_t count = 4000;         // queries per set, > 0
  uint64_t seed = 20261122;      // every set derives its own stream from this
  float box_margin = 0.10f;      // metres the uniform box extends beyond the mesh bounds
  float near_band = 0.005f;      // metres: near-surface points within +-near_band
  float thin_thickness = 0.04f;  // metres: a part is thin when crossing it inward is shorter
  float fast_length = 0.10f;     // metres: the longest fast segment (one step)
  float inside_depth = 0.02f;    // metres: deepest starting point of the started-inside set
  // metres: the moving sets (thin_crossing, fast) start outside the surface and at least this
  // far from every part of it (the mesh distance), beyond every method's inflation in the sweep
  // (epsilon, delta <= 10 mm) and a texel: a motion that starts inside a proxy and leaves it is,
  // by the runtime's contract, no contact.
  float start_clearance = 0.015f;
};

// The five sets, in this order:
//  uniform         points uniform in the mesh bounds enlarged by box_margin;
//  near_surface    surface samples (area-weighted) moved along the face normal by U(-band, band);
//  thin_crossing   segments that enter a part thinner than thin_thickness along the inward
//                  normal (fingers, wrists, ankles, ears) and leave it on the far side: only a
//                  continuous test catches them (tunnelling);
//  fast            segments from start_clearance .. 5 cm outside the surface, up to fast_length
//  long,
//                  heading into the body on average;
//  started_inside  points 1 mm .. inside_depth below the surface (exact inside) that move up to
//                  5 mm: the body moved onto the particle.
// Sets that cannot be filled (a mesh with no thin part) hold what was found, possibly nothing.
std::vector<QuerySet> MakeQuerySets(std::span<const Float3> positions,
                                    std::span<const uint32_t> triangles,
                                    const bake::MeshReference& reference,
                                    const QuerySetOptions& options);

// All sets concatenated in order, named "all".
QuerySet ConcatenateQuerySets(std::span<const QuerySet> sets);

}  // namespace drape::bench

#pragma once
// Greedy edge collapse with constrained placement: the default
// simplification of the inflated hull, always convex and containing it.

#include <cstdint>

#include "drape/bake/hull_builder.h"
#include "hull/growth_reference.h"
#include "hull/hull_mesh.h"

namespace drape::bake::detail {

// Collapses edges of h0, least growth first, until at most max_triangles remain or no collapse
// keeps every vertex within max_growth (metres) of h0. Each collapse places the new vertex by a
// small LP and is accepted only by exact predicates on its float-rounded position: locally (the
// link of the collapsed edge) or, with global_checks, against every vertex and triangle. Fills
// stats->collapses, rejected and evaluations when stats is not null.
Mesh CollapseEdges(const Mesh& h0, const GrowthReference& reference, double max_growth,
                   uint32_t max_triangles, bool global_checks, HullStats* stats);

}  // namespace drape::bake::detail

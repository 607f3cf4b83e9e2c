#pragma once
// The CGAL kernel of the hull stage: EPICK. Its predicates are exact; nothing here relies on its
// constructions. Every hull source that uses CGAL includes this header before any other CGAL
// header, so that all of them see one configuration (CGAL's OBB optimiser needs Eigen).

#ifndef CGAL_EIGEN3_ENABLED
#define CGAL_EIGEN3_ENABLED 1
#endif
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include "hull/hull_mesh.h"

namespace drape::bake::detail {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;

inline Point ToPoint(Vec3 v) { return Point(v.x, v.y, v.z); }

}  // namespace drape::bake::detail

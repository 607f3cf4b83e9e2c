// Extremes of a convex polytope by incremental linear programming (Seidel's method in a fixed
// order, worst case cubic in the plane count, a few hundred planes at most): the optimum over the
// first k constraints, when the next one cuts it off, moves onto that constraint's plane, where
// the same method runs in two dimensions and, below it, on a line. A box of half-size `limit`
// keeps every subproblem bounded.
#include "shapes/convex_bounds.h"

#include <algorithm>
#include <cmath>

#include "common/rigid_transform.h"

namespace drape::detail {
namespace {

struct HalfSpace {  // n . x <= d
  Vec3D n;
  double d = 0.0;
};

// Constraint j: the box's six faces (+x, -x, +y, -y, +z, -z) first, then the planes.
HalfSpace ConstraintAt(const Plane* planes, double limit, uint32_t j) {
  if (j < 6) {
    const double sign = j % 2 == 0 ? 1.0 : -1.0;
    return {{j / 2 == 0 ? sign : 0.0, j / 2 == 1 ? sign : 0.0, j / 2 == 2 ? sign : 0.0}, limit};
  }
  const Plane& p = planes[j - 6];
  return {{p.normal.x, p.normal.y, p.normal.z}, p.offset};
}

// A unit vector normal to the unit vector n.
Vec3D Perpendicular(const Vec3D& n) {
  const double ax = std::fabs(n.x), ay = std::fabs(n.y), az = std::fabs(n.z);
  const Vec3D axis =
      ax <= ay && ax <= az ? Vec3D{1, 0, 0} : (ay <= az ? Vec3D{0, 1, 0} : Vec3D{0, 0, 1});
  const Vec3D p = CrossD(n, axis);
  return p * (1.0 / LengthD(p));
}

// Maximises c . x over constraint `on`'s plane, within the constraints before it. False when
// they leave no point on the plane.
bool MaximizeOnPlane(const Plane* planes, double limit, uint32_t on, const Vec3D& c, double tol,
                     Vec3D* x) {
  const HalfSpace plane = ConstraintAt(planes, limit, on);
  const Vec3D origin = plane.n * plane.d;
  const Vec3D e1 = Perpendicular(plane.n), e2 = CrossD(plane.n, e1);
  const double cu = DotD(c, e1), cv = DotD(c, e2);
  // The square |u|, |v| <= m holds the box's section of the plane.
  const double m = 4.0 * limit + LengthD(origin);
  double u = cu >= 0.0 ? m : -m, v = cv >= 0.0 ? m : -m;
  // Constraint i in the plane's coordinates: au u + av v <= b.
  const auto in_plane = [&](uint32_t i, double* au, double* av, double* b) {
    const HalfSpace h = ConstraintAt(planes, limit, i);
    *au = DotD(h.n, e1);
    *av = DotD(h.n, e2);
    *b = h.d - DotD(h.n, origin);
  };
  for (uint32_t i = 0; i < on; ++i) {
    double au, av, b;
    in_plane(i, &au, &av, &b);
    if (au * u + av * v <= b + tol) continue;
    const double length_squared = au * au + av * av;
    if (length_squared < 1e-24) return false;  // parallel to the plane, and violated
    // The optimum moves onto the line au u + av v = b: (w0u, w0v) + s (du, dv).
    const double length = std::sqrt(length_squared);
    const double w0u = au * b / length_squared, w0v = av * b / length_squared;
    const double du = -av / length, dv = au / length;
    double lo = -INFINITY, hi = INFINITY;
    bool feasible = true;
    const auto clip = [&](double a1, double a2, double rhs) {
      const double slope = a1 * du + a2 * dv;
      const double room = rhs - (a1 * w0u + a2 * w0v);
      if (slope > 1e-12) {
        hi = std::min(hi, room / slope);
      } else if (slope < -1e-12) {
        lo = std::max(lo, room / slope);
      } else if (room < -tol) {
        feasible = false;
      }
    };
    clip(1.0, 0.0, m);
    clip(-1.0, 0.0, m);
    clip(0.0, 1.0, m);
    clip(0.0, -1.0, m);
    for (uint32_t k = 0; k < i && feasible; ++k) {
      double a1, a2, rhs;
      in_plane(k, &a1, &a2, &rhs);
      clip(a1, a2, rhs);
    }
    if (!feasible || lo > hi + tol) return false;
    const double along = cu * du + cv * dv;
    const double s = lo > hi       ? 0.5 * (lo + hi)
                     : along > 0.0 ? hi
                     : along < 0.0 ? lo
                                   : std::clamp(0.0, lo, hi);
    u = w0u + s * du;
    v = w0v + s * dv;
  }
  *x = origin + e1 * u + e2 * v;
  return true;
}

}  // namespace

ConvexBounds MeasureConvex(const Plane* planes, uint32_t plane_count, double limit) {
  // Violations below this are rounding (metres): double's relative precision at the box's size.
  const double tol = 1e-10 * limit;
  double extreme[6];  // the largest +x, -x, +y, -y, +z, -z over the polytope
  for (uint32_t dir = 0; dir < 6; ++dir) {
    const Vec3D c = ConstraintAt(planes, limit, dir).n;
    // The box corner maximising c: optimal over the box's own six constraints.
    Vec3D x{c.x >= 0.0 ? limit : -limit, c.y >= 0.0 ? limit : -limit, c.z >= 0.0 ? limit : -limit};
    for (uint32_t j = 6; j < 6 + plane_count; ++j) {
      const HalfSpace h = ConstraintAt(planes, limit, j);
      if (DotD(h.n, x) <= h.d + tol) continue;
      if (!MaximizeOnPlane(planes, limit, j, c, tol, &x)) return {ConvexExtent::kEmpty, 0.0};
    }
    extreme[dir] = DotD(c, x);
    if (extreme[dir] >= limit * (1.0 - 1e-9)) return {ConvexExtent::kUnbounded, 0.0};
  }
  if (extreme[0] < -extreme[1] - tol || extreme[2] < -extreme[3] - tol ||
      extreme[4] < -extreme[5] - tol)
    return {ConvexExtent::kEmpty, 0.0};
  double squared = 0.0;
  for (uint32_t axis = 0; axis < 3; ++axis) {
    const double far = std::max(std::fabs(extreme[2 * axis]), std::fabs(extreme[2 * axis + 1]));
    squared += far * far;
  }
  return {ConvexExtent::kBounded, std::sqrt(squared) * (1.0 + 1e-9) + tol};
}

}  // namespace drape::detail

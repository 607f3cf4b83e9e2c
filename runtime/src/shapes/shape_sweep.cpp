// The entry of a segment into one shape: analytic for spheres and planes, slab and Cyrus-Beck
// clipping (exact) for boxes and convexes, and for the round cone a golden-section search for
// a point inside (its distance along the segment is convex) then bisection to the entry.
#include "shapes/shape_sweep.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace drape::detail {
namespace {

constexpr double kGoldenRatio = 0.6180339887498949;  // (sqrt(5) - 1) / 2
// Searches stop once the bracket is this short along the segment (metres): far below the
// separation a response leaves, far above double's rounding at body scale.
constexpr double kResolution = 1e-9;
constexpr int kMaxSearchSteps = 80;  // golden section: 0.618^80 = 2e-17 of the segment
constexpr int kMaxBisections = 64;

Vec3D At(const Vec3D& q0, const Vec3D& delta, double t) { return q0 + delta * t; }

// The first root of |a + t delta| = radius in [0, 1), a = q0 minus the centre, q0 outside.
bool SphereEntry(const LocalShape& s, const Vec3D& q0, const Vec3D& delta, double* t) {
  const Vec3D a{q0.x - s.center_x, q0.y, q0.z};
  const double qa = DotD(delta, delta), qb = DotD(a, delta);
  const double qc = DotD(a, a) - s.radius * s.radius;
  if (!(qa > 0.0) || !(qb < 0.0)) return false;  // not moving towards the centre
  const double disc = qb * qb - qa * qc;
  if (!(disc > 0.0)) return false;  // misses, or grazes
  // The smaller root without cancellation: (-qb - sqrt(disc)) / qa = qc / (-qb + sqrt(disc)).
  const double root = std::max(qc, 0.0) / (-qb + std::sqrt(disc));
  if (!(root < 1.0)) return false;
  *t = root;
  return true;
}

// Slab clipping: the entry t and the entered face's normal, when the segment passes inside.
bool BoxEntry(const LocalShape& s, const Vec3D& q0, const Vec3D& delta, double* t, Vec3D* normal,
              Vec3D* point) {
  const double p[3] = {q0.x, q0.y, q0.z}, d[3] = {delta.x, delta.y, delta.z};
  const double e[3] = {s.half_extents.x, s.half_extents.y, s.half_extents.z};
  double enter = -INFINITY, exit = INFINITY, face = 0.0;
  int axis = -1;
  for (int i = 0; i < 3; ++i) {
    if (d[i] == 0.0) {
      if (std::fabs(p[i]) > e[i]) return false;  // parallel, outside this slab
      continue;
    }
    double near = (-e[i] - p[i]) / d[i], far = (e[i] - p[i]) / d[i];
    double sign = -1.0;  // moving +: in through the -e face
    if (near > far) {
      std::swap(near, far);
      sign = 1.0;
    }
    if (near > enter) {
      enter = near;
      axis = i;
      face = sign;
    }
    exit = std::min(exit, far);
  }
  const double lo = std::max(enter, 0.0), hi = std::min(exit, 1.0);
  if (axis < 0 || !(lo < hi)) return false;
  *t = lo;
  const Vec3D c = At(q0, delta, lo);
  double cp[3] = {c.x, c.y, c.z}, n[3] = {0.0, 0.0, 0.0};
  for (int i = 0; i < 3; ++i) cp[i] = std::clamp(cp[i], -e[i], e[i]);
  cp[axis] = face * e[axis];
  n[axis] = face;
  *normal = {n[0], n[1], n[2]};
  *point = {cp[0], cp[1], cp[2]};
  return true;
}

// Cyrus-Beck clipping by the half-spaces: the entry t is the largest entering plane's.
bool ConvexEntry(const LocalShape& s, const Vec3D& q0, const Vec3D& delta, double* t,
                 uint32_t* plane) {
  double enter = -INFINITY, exit = INFINITY;
  uint32_t arg = UINT32_MAX;
  for (uint32_t k = 0; k < s.plane_count; ++k) {
    const Plane& p = s.planes[k];
    const Vec3D n{p.normal.x, p.normal.y, p.normal.z};
    const double distance = DotD(n, q0) - double(p.offset), rate = DotD(n, delta);
    if (rate == 0.0) {
      if (distance > 0.0) return false;  // parallel, outside this plane
      continue;
    }
    const double tk = -distance / rate;
    if (rate < 0.0) {
      if (tk > enter) {
        enter = tk;
        arg = k;
      }
    } else {
      exit = std::min(exit, tk);
    }
    if (std::max(enter, 0.0) >= std::min(exit, 1.0)) return false;  // the interval only shrinks
  }
  const double lo = std::max(enter, 0.0), hi = std::min(exit, 1.0);
  if (arg == UINT32_MAX || !(lo < hi)) return false;
  *t = lo;
  *plane = arg;
  return true;
}

// The outside end of a bracket [lo, hi] with the distance >= 0 at lo and < 0 at hi, shrunk to
// kResolution along the segment.
double Bisect(const LocalShape& s, const Vec3D& q0, const Vec3D& delta, double length, double lo,
              double hi) {
  for (int step = 0; step < kMaxBisections && (hi - lo) * length > kResolution; ++step) {
    const double mid = 0.5 * (lo + hi);
    if (Distance(s, At(q0, delta, mid)).value < 0.0) {
      hi = mid;
    } else {
      lo = mid;
    }
  }
  return lo;
}

// A t whose point lies inside the shape, for a segment with both ends outside: golden-section
// search for the distance's minimum over the part of the segment in the bounding sphere,
// stopped at the first sample inside, or once no point of the bracket can be (the distance
// changes by at most `length` per unit of t).
bool FindInside(const LocalShape& s, const Vec3D& q0, const Vec3D& delta, double length,
                double* t_inside) {
  const double qa = DotD(delta, delta), qb = DotD(q0, delta);
  const double qc = DotD(q0, q0) - s.bound_radius * s.bound_radius;
  const double disc = qb * qb - qa * qc;
  if (!(qa > 0.0) || !(disc > 0.0)) return false;
  const double root = std::sqrt(disc);
  double a = std::max((-qb - root) / qa, 0.0), b = std::min((-qb + root) / qa, 1.0);
  if (!(a < b)) return false;
  const auto f = [&](double t) { return Distance(s, At(q0, delta, t)).value; };
  double x1 = b - kGoldenRatio * (b - a), x2 = a + kGoldenRatio * (b - a);
  double f1 = f(x1), f2 = f(x2);
  for (int step = 0; step < kMaxSearchSteps; ++step) {
    if (f1 < 0.0 || f2 < 0.0) {
      *t_inside = f1 < 0.0 ? x1 : x2;
      return true;
    }
    const double width = (b - a) * length;
    if (std::min(f1, f2) > width || width < kResolution) return false;
    if (f1 < f2) {
      b = x2;
      x2 = x1;
      f2 = f1;
      x1 = b - kGoldenRatio * (b - a);
      f1 = f(x1);
    } else {
      a = x1;
      x1 = x2;
      f1 = f2;
      x2 = a + kGoldenRatio * (b - a);
      f2 = f(x2);
    }
  }
  return false;
}

// The entry of a segment starting outside, by kind; false when it stays outside.
bool Entry(const LocalShape& s, const Vec3D& q0, const Vec3D& q1, double d0, double d1,
           LocalContact* c) {
  const Vec3D delta = q1 - q0;
  const double length = LengthD(delta);
  switch (s.kind) {
    case ShapeKind::kSphere: {
      if (!SphereEntry(s, q0, delta, &c->t)) return false;
      const Vec3D center{s.center_x, 0.0, 0.0};
      const Vec3D v = At(q0, delta, c->t) - center;
      const double len = LengthD(v);
      c->normal = len > 1e-300 ? v * (1.0 / len) : delta * (-1.0 / length);
      c->point = center + c->normal * s.radius;
      return true;
    }
    case ShapeKind::kPlane: {
      if (!(d1 < 0.0)) return false;
      c->t = d0 / (d0 - d1);
      const Vec3D at = At(q0, delta, c->t);
      c->normal = {0.0, 1.0, 0.0};
      c->point = {at.x, 0.0, at.z};
      return true;
    }
    case ShapeKind::kBox:
      return BoxEntry(s, q0, delta, &c->t, &c->normal, &c->point);
    case ShapeKind::kConvex: {
      uint32_t k = 0;
      if (!ConvexEntry(s, q0, delta, &c->t, &k)) return false;
      const Plane& p = s.planes[k];
      c->normal = {p.normal.x, p.normal.y, p.normal.z};
      const Vec3D at = At(q0, delta, c->t);
      c->point = at - c->normal * (DotD(c->normal, at) - double(p.offset));
      return true;
    }
    case ShapeKind::kCapsule: {
      double hi = 1.0;
      if (!(d1 < 0.0) && !FindInside(s, q0, delta, length, &hi)) return false;
      c->t = Bisect(s, q0, delta, length, 0.0, hi);
      // The bracket's outside end: its gradient's plane supports the cone at the nearest point.
      const Vec3D at = At(q0, delta, c->t);
      const SignedDistance sd = Distance(s, at);
      c->normal = sd.gradient;
      c->point = at - sd.gradient * sd.value;
      return true;
    }
  }
  return false;
}

}  // namespace

LocalContact Sweep(const LocalShape& shape, const Vec3D& q0, const Vec3D& q1) {
  LocalContact c;
  const SignedDistance end = Distance(shape, q1);
  c.end_depth = end.value < 0.0 ? -end.value : 0.0;
  const double d0 = Distance(shape, q0).value;
  if (d0 < 0.0) {
    if (end.value < 0.0) {  // the nearest surface point to q1
      c.hit = true;
      c.started_inside = true;
      c.t = 0.0;
      c.normal = end.gradient;
      c.point = q1 - end.gradient * end.value;
    }
    return c;
  }
  // The distance is 1-Lipschitz: along the segment it stays >= (d0 + d1 - length) / 2.
  if (!(d0 + end.value < LengthD(q1 - q0))) return c;
  c.hit = Entry(shape, q0, q1, d0, end.value, &c);
  return c;
}

}  // namespace drape::detail

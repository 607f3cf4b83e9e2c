// A joint sphere against one particle segment, in the sphere's frame (its centre at the origin):
// the radial push-out, or the first entry along the segment solved in double.
#include <algorithm>
#include <cmath>

#include "common/rigid_transform.h"
#include "drape/runtime/hull_collider_set.h"
#include "hull/nudge_out.h"

namespace drape {

using detail::DotD;
using detail::NudgeOut;
using detail::ToD;
using detail::ToF;
using detail::Vec3D;

ContactQuery HullColliderSet::SphereNarrow(float radius, Float3 a, Float3 b) const {
  ContactQuery c;
  const float r2 = radius * radius;
  const float lb2 = Dot(b, b);
  const bool inside_b = lb2 <= r2;
  c.inside_end = inside_b;
  c.depth = inside_b ? std::max(0.f, radius - std::sqrt(lb2)) : 0.f;
  auto outside_sphere = [&](Float3 x) { return Dot(x, x) - r2; };
  auto radial = [&](float t, uint8_t flags) {
    const Float3 n = NormalizeOr(b, NormalizeOr(a - b, NormalizeOr(a, Float3{0.f, 1.f, 0.f})));
    c.contact = true;
    c.t = t;
    c.flags = flags;
    c.normal = n;
    c.point = NudgeOut(n * radius, n, radius, outside_sphere);
  };
  if (!options_.continuous) {
    if (inside_b) radial(1.f, kCollisionNone);
    return c;
  }
  if (Dot(a, a) <= r2) {
    if (inside_b) radial(0.f, kCollisionStartedInside);
    return c;
  }
  // |a + t (b - a)|^2 = r^2, first root, in double.
  const Vec3D ad = ToD(a), dd = ToD(b - a);
  const double qa = DotD(dd, dd), qb = DotD(ad, dd), qc = DotD(ad, ad) - double(radius) * radius;
  const double disc = qb * qb - qa * qc;
  if (qa > 0.0 && qb < 0.0 && disc >= 0.0) {
    const double t = (-qb - std::sqrt(disc)) / qa;
    if (t <= 1.0) {
      const Float3 entry_point = ToF(ad + dd * t);
      const Float3 n = NormalizeOr(entry_point, NormalizeOr(a, Float3{0.f, 1.f, 0.f}));
      c.contact = true;
      c.t = static_cast<float>(std::max(0.0, t));
      c.normal = n;
      auto outside_plane = [&](Float3 x) { return Dot(n, x) - radius; };
      if (options_.entry_response == EntryResponse::kProjectEnd) {
        // Onto the tangent plane at the entry point: on or outside the sphere.
        const Float3 target = b - n * (Dot(n, b) - radius);
        c.point = NudgeOut(target, n, radius, outside_plane);
      } else {
        c.point = NudgeOut(n * radius, n, radius, outside_sphere);
      }
      return c;
    }
  }
  if (inside_b) radial(1.f, kCollisionNone);
  return c;
}

}  // namespace drape

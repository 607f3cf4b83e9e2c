#include "shapes/shape_response.h"

#include <algorithm>
#include <cmath>

namespace drape::detail {

Vec3D ResolvePosition(const LocalContact& c, const Vec3D& q0, const Vec3D& q1,
                      const ResponseParams& params) {
  const Vec3D& n = c.normal;
  const double separation = params.separation;
  // How far along n: out of the shape at q1 for a started-inside segment (the nearest surface),
  // else onto the supporting plane at the entry point, which keeps the motion along it and is at
  // most the rest of the motion away (clamped: rounding of far-away inputs).
  double push = c.end_depth + separation;
  if (!c.started_inside) {
    push = std::min(std::max(DotD(n, c.point - q1), 0.0), LengthD(q1 - q0)) + separation;
  }
  const Vec3D pushed = q1 + n * push;
  if (params.friction_model != FrictionModel::kCoulomb) return pushed;
  // Coulomb on positions: the displacement over the substep relative to the shape, tangential to
  // n, is cancelled while within static_friction times the push (sticks), else shortened by
  // friction times the push. Both stay on the supporting plane through `pushed`, within
  // |q1 - q0| + push of q1.
  const Vec3D moved = pushed - q0;
  const Vec3D tangential = moved - n * DotD(n, moved);
  const double slide = LengthD(tangential);
  if (!(slide > 0.0)) return pushed;
  if (slide <= double(params.static_friction) * push) return pushed - tangential;
  const double cut = std::min(1.0, double(params.friction) * push / slide);
  return pushed - tangential * cut;
}

Vec3D ResolveVelocity(const Vec3D& velocity, const Vec3D& surface_velocity, const Vec3D& normal,
                      const ResponseParams& params) {
  const Vec3D relative = velocity - surface_velocity;
  const double vn = DotD(relative, normal);
  if (!(vn < 0.0)) return velocity;
  const Vec3D tangential = relative - normal * vn;
  // TangentialKeep works in float: speeds capped at 1e18 m/s keep its squares finite.
  constexpr double kMaxSpeed = 1e18;
  const float into = static_cast<float>(std::min(-vn, kMaxSpeed));
  const float tangential_squared =
      static_cast<float>(std::min(DotD(tangential, tangential), kMaxSpeed * kMaxSpeed));
  const double keep = TangentialKeep(params, into, tangential_squared);
  return surface_velocity + tangential * keep - normal * (vn * double(params.restitution));
}

}  // namespace drape::detail

#include "capsule/capsule_fit.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "drape/runtime/math.h"

namespace drape::bake {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The nearest-rank quantile q of the values (sorted in place); 0 for none.
double Quantile(std::vector<double>& values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const size_t rank = static_cast<size_t>(std::ceil(q * static_cast<double>(values.size())));
  return values[std::clamp<size_t>(rank, 1, values.size()) - 1];
}

Eigen::Vector3d ToEigen(Float3 p) { return {p.x, p.y, p.z}; }

// The principal axis of the points (unit, double), and their centroid.
void PrincipalAxis(const std::vector<Eigen::Vector3d>& points, Eigen::Vector3d* centre,
                   Eigen::Vector3d* axis) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : points) covariance += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  *centre = mean;
  *axis = solver.eigenvectors().col(2).normalized();  // eigenvalues ascend
}

// Whether a limb runs from its joint to its only child: the bone lies along the skin's principal
// axis and the skin spans the middle of the bone.
bool AlongTheBone(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& joint,
                  const Eigen::Vector3d& child, const Eigen::Vector3d& principal) {
  const double length = (child - joint).norm();
  if (!(length > 1e-6)) return false;
  const Eigen::Vector3d u = (child - joint) / length;
  if (std::abs(u.dot(principal)) < 0.9) return false;
  double t_min = INFINITY, t_max = -INFINITY;
  for (const Eigen::Vector3d& p : points) {
    const double t = (p - joint).dot(u);
    t_min = std::min(t_min, t), t_max = std::max(t_max, t);
  }
  return t_min < 0.5 * length && t_max > 0.5 * length;
}

// One bone's capsule in the rest pose: false when its surface has no length. With `child` (the
// bone's only child joint) and the bone along its skin, the capsule runs from joint to child
// (NvCloth's sphere chains: the next limb's capsule starts where this one ends, so a bent joint
// stays covered); otherwise along the skin's principal axis, its caps reaching the skin's ends.
bool FitOne(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& joint,
            const Eigen::Vector3d* child, const CapsuleFitOptions& o, Eigen::Vector3d* a,
            double* ra, Eigen::Vector3d* b, double* rb) {
  Eigen::Vector3d centre, u;
  PrincipalAxis(points, &centre, &u);
  if (u.dot(centre - joint) < 0.0) u = -u;  // `from` is the end nearer the joint
  const bool chain = child != nullptr && AlongTheBone(points, joint, *child, u);
  if (chain) centre = joint, u = (*child - joint).normalized();
  std::vector<double> t(points.size()), rho(points.size());
  double t_min = INFINITY, t_max = -INFINITY, rho_max = 0.0;
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d d = points[i] - centre;
    t[i] = d.dot(u);
    rho[i] = (d - t[i] * u).norm();
    t_min = std::min(t_min, t[i]), t_max = std::max(t_max, t[i]);
    rho_max = std::max(rho_max, rho[i]);
  }
  if (!(t_max - t_min > 1e-6)) return false;
  // Each slab's median radius, then r(t) = alpha + beta t by least squares weighted by the slab's
  // points.
  const uint32_t slabs = std::max(o.slabs, 1u);
  std::vector<std::vector<double>> slab_rho(slabs);
  std::vector<double> slab_t(slabs, 0.0);
  for (size_t i = 0; i < points.size(); ++i) {
    const double f = (t[i] - t_min) / (t_max - t_min);
    const uint32_t k = std::min(static_cast<uint32_t>(f * slabs), slabs - 1);
    slab_rho[k].push_back(rho[i]);
    slab_t[k] += t[i];
  }
  double sw = 0, st = 0, sr = 0, stt = 0, str = 0;
  for (uint32_t k = 0; k < slabs; ++k) {
    const double w = static_cast<double>(slab_rho[k].size());
    if (w < 3) continue;
    const double tk = slab_t[k] / w, rk = Quantile(slab_rho[k], 0.5);
    sw += w, st += w * tk, sr += w * rk, stt += w * tk * tk, str += w * tk * rk;
  }
  if (!(sw > 0)) return false;
  const double denominator = sw * stt - st * st;
  const double beta = denominator > 1e-12 * sw * sw ? (sw * str - st * sr) / denominator : 0.0;
  // The taper from the slabs' median radii, raised until radius_quantile of the points lie
  // inside it.
  double alpha = (sr - beta * st) / sw;
  std::vector<double> residuals(points.size());
  for (size_t i = 0; i < points.size(); ++i) residuals[i] = rho[i] - (alpha + beta * t[i]);
  alpha += Quantile(residuals, o.radius_quantile);
  const auto radius = [&](double at) {
    return std::clamp(alpha + beta * at, static_cast<double>(o.min_radius),
                      std::max(rho_max, static_cast<double>(o.min_radius)));
  };
  if (chain) {
    *a = joint, *b = *child, *ra = radius(0.0), *rb = radius((*child - joint).norm());
    return true;
  }
  // The caps reach the ends of the surface: centres one radius inside them.
  double r0 = radius(t_min), r1 = radius(t_max);
  r0 = radius(t_min + r0), r1 = radius(t_max - r1);
  const double t0 = t_min + r0, t1 = t_max - r1;
  if (t0 <= t1) {
    *a = centre + t0 * u, *b = centre + t1 * u, *ra = r0, *rb = r1;
    return true;
  }
  // Shorter than its two caps: a sphere at the middle, its radius the quantile of the distances.
  const Eigen::Vector3d middle = centre + 0.5 * (t_min + t_max) * u;
  std::vector<double> distances;
  for (const Eigen::Vector3d& p : points) distances.push_back((p - middle).norm());
  *a = *b = middle;
  *ra = *rb = std::max(Quantile(distances, o.radius_quantile), static_cast<double>(o.min_radius));
  return true;
}

}  // namespace

std::vector<CapsuleColliderData> FitCapsules(const Regions& regions, const MeshData& mesh,
                                             std::span<const int32_t> parents,
                                             const CapsuleFitOptions& options) {
  const uint32_t joints = static_cast<uint32_t>(regions.rest_skinning.size());
  const auto position = [&](size_t j) {
    const Mat34& frame = regions.collider_frames[j];
    return Eigen::Vector3d(frame.m[3], frame.m[7], frame.m[11]);
  };
  std::vector<int32_t> only_child(joints, -1);  // -2: several children
  for (size_t c = 0; c < parents.size() && c < joints; ++c) {
    const int32_t p = parents[c];
    if (p < 0 || static_cast<uint32_t>(p) >= joints) continue;
    only_child[static_cast<size_t>(p)] =
        only_child[static_cast<size_t>(p)] == -1 ? static_cast<int32_t>(c) : -2;
  }
  const std::vector<int32_t> bones = TriangleBones(mesh, joints);
  std::vector<std::vector<uint32_t>> carried(joints);
  for (size_t t = 0; t < bones.size(); ++t) {
    if (bones[t] < 0) continue;
    for (int k = 0; k < 3; ++k)
      carried[static_cast<size_t>(bones[t])].push_back(mesh.triangles[3 * t + k]);
  }
  std::vector<CapsuleColliderData> capsules;
  for (uint32_t j = 0; j < joints; ++j) {
    std::vector<uint32_t>& v = carried[j];
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    if (v.size() < options.min_vertices) continue;
    std::vector<Eigen::Vector3d> points;
    for (const uint32_t i : v)
      if (i < regions.rest_positions.size()) points.push_back(ToEigen(regions.rest_positions[i]));
    const Eigen::Vector3d joint = position(j);
    const Eigen::Vector3d child =
        only_child[j] >= 0 ? position(static_cast<size_t>(only_child[j])) : joint;
    Eigen::Vector3d a, b;
    double ra = 0, rb = 0;
    if (!FitOne(points, joint, only_child[j] >= 0 ? &child : nullptr, options, &a, &ra, &b, &rb))
      continue;
    Mat34 rest_to_bind;
    if (!InverseAffine(regions.rest_skinning[j], &rest_to_bind)) continue;
    CapsuleColliderData c;
    c.joint = static_cast<int32_t>(j);
    c.from = TransformPoint(
        rest_to_bind,
        Float3{static_cast<float>(a.x()), static_cast<float>(a.y()), static_cast<float>(a.z())});
    c.to = TransformPoint(rest_to_bind, Float3{static_cast<float>(b.x()), static_cast<float>(b.y()),
                                               static_cast<float>(b.z())});
    c.radius_from = static_cast<float>(ra);
    c.radius_to = static_cast<float>(rb);
    capsules.push_back(c);
  }
  return capsules;
}

void RoundConeMesh(const double a[3], double radius_a, const double b[3], double radius_b,
                   uint32_t segments, uint32_t rings, std::vector<double>* positions,
                   std::vector<uint32_t>* triangles) {
  Eigen::Vector3d pa(a[0], a[1], a[2]), pb(b[0], b[1], b[2]);
  const double length = (pb - pa).norm();
  const bool sphere = !(length > std::abs(radius_a - radius_b)) || length < 1e-12;
  if (sphere && radius_b > radius_a) pa = pb, radius_a = radius_b;
  Eigen::Vector3d u = sphere ? Eigen::Vector3d::UnitY() : Eigen::Vector3d((pb - pa) / length);
  // Two unit vectors normal to the axis.
  const Eigen::Vector3d helper =
      std::abs(u.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d v = u.cross(helper).normalized(), w = u.cross(v);
  // The profile from +u to -u by the angle of the normal to the axis: cap b over [0, theta_t],
  // cap a over [theta_t, pi]; the straight flank joins them at theta_t.
  const double sin_alpha = sphere ? 0.0 : (radius_a - radius_b) / length;
  const double theta_t = sphere ? kPi : std::acos(std::clamp(sin_alpha, -1.0, 1.0));
  std::vector<std::pair<Eigen::Vector3d, double>> profile;  // (centre, radius) per ring, angle
  std::vector<double> angles;
  for (uint32_t r = 0; r <= rings && !sphere; ++r) {
    angles.push_back(theta_t * r / rings);
    profile.push_back({pb, radius_b});
  }
  const uint32_t a_rings = sphere ? 2 * rings : rings;
  const double a_start = sphere ? 0.0 : theta_t;
  for (uint32_t r = 0; r <= a_rings; ++r) {
    angles.push_back(a_start + (kPi - a_start) * r / a_rings);
    profile.push_back({pa, radius_a});
  }
  const uint32_t base = static_cast<uint32_t>(positions->size() / 3);
  for (size_t r = 0; r < angles.size(); ++r) {
    for (uint32_t s = 0; s < segments; ++s) {
      const double phi = 2.0 * kPi * s / segments;
      const Eigen::Vector3d n =
          std::cos(angles[r]) * u + std::sin(angles[r]) * (std::cos(phi) * v + std::sin(phi) * w);
      const Eigen::Vector3d p = profile[r].first + profile[r].second * n;
      positions->insert(positions->end(), {p.x(), p.y(), p.z()});
    }
  }
  for (uint32_t r = 0; r + 1 < angles.size(); ++r) {
    for (uint32_t s = 0; s < segments; ++s) {
      const uint32_t i = base + r * segments + s, j = base + r * segments + (s + 1) % segments;
      triangles->insert(triangles->end(), {i, i + segments, j, j, i + segments, j + segments});
    }
  }
}

double RoundConeDistance(const double p[3], const double a[3], double radius_a, const double b[3],
                         double radius_b) {
  const Eigen::Vector3d q(p[0], p[1], p[2]), pa(a[0], a[1], a[2]), pb(b[0], b[1], b[2]);
  const double length = (pb - pa).norm();
  if (!(length > std::abs(radius_a - radius_b)) || length < 1e-12)  // a sphere
    return radius_a >= radius_b ? (q - pa).norm() - radius_a : (q - pb).norm() - radius_b;
  // In the plane of the axis: x along it from a, y >= 0 from it; the flank's unit normal
  // n = (sin alpha, cos alpha) and its direction t = (cos alpha, -sin alpha).
  const Eigen::Vector3d u = (pb - pa) / length, d = q - pa;
  const double x = d.dot(u), y = (d - x * u).norm();
  const double sin_alpha = (radius_a - radius_b) / length;
  const double cos_alpha = std::sqrt(std::max(0.0, 1.0 - sin_alpha * sin_alpha));
  const double along = x * cos_alpha - y * sin_alpha;
  if (along < 0.0) return std::hypot(x, y) - radius_a;
  if (along > length * cos_alpha) return std::hypot(x - length, y) - radius_b;
  return x * sin_alpha + y * cos_alpha - radius_a;
}

}  // namespace drape::bake

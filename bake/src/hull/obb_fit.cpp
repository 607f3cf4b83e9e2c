#include "hull/obb_fit.h"

#include "hull/hull_kernel.h"  // first of the CGAL headers

#include <CGAL/optimal_bounding_box.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>

namespace drape::bake::detail {

Obb FitObb(const std::array<Vec3, 3>& axes_in, const Mesh& mesh, const std::vector<Vec3>& inputs,
           double delta) {
  // Orthonormalise (Gram-Schmidt), then project.
  std::array<Vec3, 3> axes = axes_in;
  axes[0] = axes[0] * (1.0 / Norm(axes[0]));
  axes[1] = axes[1] - axes[0] * Dot(axes[0], axes[1]);
  axes[1] = axes[1] * (1.0 / Norm(axes[1]));
  axes[2] = Cross(axes[0], axes[1]);
  double lo[3], hi[3];
  for (int k = 0; k < 3; ++k) {
    lo[k] = std::numeric_limits<double>::infinity();
    hi[k] = -lo[k];
    for (const Vec3& v : mesh.points) {
      lo[k] = std::min(lo[k], Dot(axes[static_cast<size_t>(k)], v));
      hi[k] = std::max(hi[k], Dot(axes[static_cast<size_t>(k)], v));
    }
    for (const Vec3& x : inputs) {
      lo[k] = std::min(lo[k], Dot(axes[static_cast<size_t>(k)], x) - delta);
      hi[k] = std::max(hi[k], Dot(axes[static_cast<size_t>(k)], x) + delta);
    }
  }
  // Longest first, then right-handed.
  std::array<int, 3> order{0, 1, 2};
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return hi[a] - lo[a] > hi[b] - lo[b]; });
  std::array<Vec3, 3> sorted{axes[static_cast<size_t>(order[0])],
                             axes[static_cast<size_t>(order[1])],
                             axes[static_cast<size_t>(order[2])]};
  // Canonical signs: the largest component of axes 0 and 1 positive.
  for (int k = 0; k < 2; ++k) {
    const Vec3 a = sorted[static_cast<size_t>(k)];
    const double big = std::fabs(a.x) >= std::fabs(a.y) && std::fabs(a.x) >= std::fabs(a.z)
                           ? a.x
                           : (std::fabs(a.y) >= std::fabs(a.z) ? a.y : a.z);
    if (big < 0.0) sorted[static_cast<size_t>(k)] = a * -1.0;
  }
  sorted[2] = Cross(sorted[0], sorted[1]);
  // The centre does not depend on the order or signs of the axes.
  Vec3 center{};
  for (int k = 0; k < 3; ++k)
    center = center + axes[static_cast<size_t>(k)] * (0.5 * (lo[k] + hi[k]));
  Obb obb;
  obb.center = ToFloat3(center);
  const Vec3 c = ToVec3(obb.center);
  float* half[3] = {&obb.half_extents.x, &obb.half_extents.y, &obb.half_extents.z};
  for (int k = 0; k < 3; ++k) {
    obb.axes[k] = ToFloat3(sorted[static_cast<size_t>(k)]);
    const Vec3 a = ToVec3(obb.axes[k]);
    // Runtime: fl(dot(a, fl(p - c))); bound its error by 4 float epsilons of sum
    // |a_i|(|p_i|+|c_i|).
    auto error = [&](const Vec3& p) {
      return 4.0 * FLT_EPSILON *
             (std::fabs(a.x) * (std::fabs(p.x) + std::fabs(c.x)) +
              std::fabs(a.y) * (std::fabs(p.y) + std::fabs(c.y)) +
              std::fabs(a.z) * (std::fabs(p.z) + std::fabs(c.z)));
    };
    double h = 0.0;
    for (const Vec3& v : mesh.points) h = std::max(h, std::fabs(Dot(a, v - c)) + error(v));
    const double a_len = Norm(a);
    for (const Vec3& x : inputs) {
      h = std::max(h,
                   std::fabs(Dot(a, x - c)) + delta * a_len + error(x) + 4.0 * FLT_EPSILON * delta);
    }
    *half[k] = std::nextafter(RoundUpToFloat(h), std::numeric_limits<float>::infinity());
  }
  return obb;
}

std::array<Vec3, 3> CovarianceAxes(const Mesh& mesh) {
  Vec3 origin{};
  for (const Vec3& p : mesh.points) origin = origin + p;
  origin = origin * (1.0 / static_cast<double>(mesh.points.size()));
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  Eigen::Vector3d first = Eigen::Vector3d::Zero();
  double total = 0.0;
  for (const auto& tri : mesh.triangles) {
    const Vec3 p = mesh.points[tri[0]] - origin, q = mesh.points[tri[1]] - origin,
               r = mesh.points[tri[2]] - origin;
    const double area = 0.5 * Norm(Cross(q - p, r - p));
    const Eigen::Vector3d ep(p.x, p.y, p.z), eq(q.x, q.y, q.z), er(r.x, r.y, r.z);
    const Eigen::Vector3d m = (ep + eq + er) / 3.0;
    // Gottschalk: second moment of a uniform triangle.
    second +=
        area / 12.0 *
        (9.0 * m * m.transpose() + ep * ep.transpose() + eq * eq.transpose() + er * er.transpose());
    first += area * m;
    total += area;
  }
  std::array<Vec3, 3> axes{Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};
  if (!(total > 0.0)) return axes;
  const Eigen::Vector3d mean = first / total;
  const Eigen::Matrix3d covariance = second / total - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  if (solver.info() != Eigen::Success) return axes;
  const Eigen::Matrix3d vectors = solver.eigenvectors();  // ascending eigenvalues
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d col = vectors.col(2 - k);
    if (!col.allFinite()) return {Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};
    axes[static_cast<size_t>(k)] = {col.x(), col.y(), col.z()};
  }
  return axes;
}

std::array<Vec3, 3> CgalOptimalAxes(const Mesh& mesh, uint32_t seed) {
  std::vector<Point> points;
  points.reserve(mesh.points.size());
  for (const Vec3& p : mesh.points) points.push_back(ToPoint(p));
  Kernel::Aff_transformation_3 rotation;
  CGAL::oriented_bounding_box(points, rotation,
                              CGAL::parameters::random_seed(seed).use_convex_hull(true));
  // rotation maps the box to an axis-aligned one: its rows are the box axes.
  std::array<Vec3, 3> axes;
  for (int r = 0; r < 3; ++r) {
    axes[static_cast<size_t>(r)] = {CGAL::to_double(rotation.m(r, 0)),
                                    CGAL::to_double(rotation.m(r, 1)),
                                    CGAL::to_double(rotation.m(r, 2))};
  }
  return axes;
}

}  // namespace drape::bake::detail

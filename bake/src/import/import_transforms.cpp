#include "import/import_transforms.h"

#include <algorithm>
#include <cmath>

namespace drape::bake::detail {

double Decompose(const Mat4& m, Transform* t) {
  const Eigen::Matrix3d linear = m.topLeftCorner<3, 3>();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(linear, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  const Eigen::Matrix3d v = svd.matrixV();
  Eigen::Vector3d sigma = svd.singularValues();
  if ((u * v.transpose()).determinant() < 0.0) {
    u.col(2) = -u.col(2);
    sigma(2) = -sigma(2);
  }
  const Eigen::Matrix3d rotation = u * v.transpose();
  const Eigen::Matrix3d stretch = v * sigma.asDiagonal() * v.transpose();
  const Eigen::Quaterniond q(rotation);
  t->translation = {static_cast<float>(m(0, 3)), static_cast<float>(m(1, 3)),
                    static_cast<float>(m(2, 3))};
  t->rotation = {static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()),
                 static_cast<float>(q.w())};
  t->scale = {static_cast<float>(stretch(0, 0)), static_cast<float>(stretch(1, 1)),
              static_cast<float>(stretch(2, 2))};
  const double off = std::fabs(stretch(0, 1)) + std::fabs(stretch(0, 2)) + std::fabs(stretch(1, 2));
  return off / std::max(1e-12, stretch.diagonal().cwiseAbs().maxCoeff());
}

}  // namespace drape::bake::detail

#include "torsion/fem/factored_tet_hessian.h"

#include <cmath>

namespace torsion {

std::array<Eigen::Vector3d, 4> shapeGradients(const Eigen::Matrix3d& B) {
  return {Eigen::Vector3d(-(B.row(0) + B.row(1) + B.row(2)).transpose()), B.row(0).transpose(),
          B.row(1).transpose(), B.row(2).transpose()};
}

FactoredTetHessian factoredTetHessian(const Eigen::Matrix3d& F,
                                      const std::array<Eigen::Vector3d, 4>& g, double volume,
                                      double curvature, double pressure) {
  FactoredTetHessian h;
  const Eigen::Matrix3d cof = std::sqrt(volume * curvature) * cofactor(F);
  for (size_t a = 0; a < 4; ++a)
    h.c[a].noalias() = cof * g[a];
  const Eigen::Matrix3d scaled = (volume * pressure) * F;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b)
      h.w[static_cast<size_t>(nodePairIndex(a, b))].noalias() =
          scaled * g[static_cast<size_t>(b)].cross(g[static_cast<size_t>(a)]);
  return h;
}

Eigen::Matrix3d factoredHessianBlock(const FactoredTetHessian& h,
                                     const std::array<Eigen::Vector3d, 4>& g, double shear_volume,
                                     int a, int b) {
  const size_t ua = static_cast<size_t>(a), ub = static_cast<size_t>(b);
  Eigen::Matrix3d K = h.c[ua] * h.c[ub].transpose();
  K.diagonal().array() += shear_volume * g[ua].dot(g[ub]);
  if (a == b) return K;
  const Eigen::Vector3d w = a < b ? h.w[static_cast<size_t>(nodePairIndex(a, b))]
                                  : Eigen::Vector3d(-h.w[static_cast<size_t>(nodePairIndex(b, a))]);
  K(0, 1) -= w.z();
  K(0, 2) += w.y();
  K(1, 0) += w.z();
  K(1, 2) -= w.x();
  K(2, 0) -= w.y();
  K(2, 1) += w.x();
  return K;
}

TetStiffness expandFactoredHessian(const FactoredTetHessian& h,
                                   const std::array<Eigen::Vector3d, 4>& g, double shear_volume) {
  TetStiffness K;
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b)
      K.block<3, 3>(3 * a, 3 * b) = factoredHessianBlock(h, g, shear_volume, a, b);
  return K;
}

}  // namespace torsion

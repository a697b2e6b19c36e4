#include "torsion/analysis/deformation_metrics.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace torsion {

double elementStrain(const Eigen::Matrix3d& deformation_gradient) {
  // Singular values are the square roots of the eigenvalues of F^T F (closed form for 3x3).
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(deformation_gradient.transpose() * deformation_gradient,
                      Eigen::EigenvaluesOnly);
  Eigen::Vector3d s = eigen.eigenvalues().cwiseMax(0).cwiseSqrt();  // ascending
  if (deformation_gradient.determinant() < 0) s(0) = -s(0);         // the least-stretched axis
  return (s.array() - 1).abs().maxCoeff();
}

namespace {

Eigen::Matrix3d tetDeformationGradient(const FemModel& model, const Eigen::VectorXd& positions,
                                       size_t t) {
  const auto& tet = model.mesh().tets()[t];
  const Eigen::Vector3d x0 = positions.segment<3>(3 * tet[0]);
  Eigen::Matrix3d ds;
  for (int k = 0; k < 3; ++k)
    ds.col(k) = positions.segment<3>(3 * tet[static_cast<size_t>(k + 1)]) - x0;
  return ds * model.tetRestData()[t].rest_shape_inverse;
}

}  // namespace

int countInvertedTets(const FemModel& model, const Eigen::VectorXd& positions) {
  int inverted = 0;
  for (size_t t = 0; t < model.mesh().tets().size(); ++t) {
    if (!(tetDeformationGradient(model, positions, t).determinant() > 0)) ++inverted;
  }
  return inverted;
}

DeformationMetrics measureDeformation(const FemModel& model, const Eigen::VectorXd& positions) {
  DeformationMetrics metrics;
  for (size_t t = 0; t < model.mesh().tets().size(); ++t) {
    const Eigen::Matrix3d f = tetDeformationGradient(model, positions, t);
    if (!(f.determinant() > 0)) ++metrics.inverted_tets;
    const double strain = elementStrain(f);
    if (!(strain <= metrics.max_strain)) {  // also takes NaN, so it is never hidden
      metrics.max_strain = strain;
      metrics.max_strain_tet = static_cast<int>(t);
    }
  }
  return metrics;
}

}  // namespace torsion

#include "torsion/fem/volume_barrier.h"

#include <Eigen/Eigenvalues>
#include <algorithm>

#include "torsion/fem/factored_tet_hessian.h"

namespace torsion {

namespace {

using Matrix9d = Eigen::Matrix<double, 9, 9>;
using Vector9d = Eigen::Matrix<double, 9, 1>;

Eigen::Matrix3d cross(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// d2E/dF2 over vec(F) = [f_0; f_1; f_2] (the columns), exact.
Matrix9d energyHessianInF(const Eigen::Matrix3d& F, double volume, const VolumeBarrier& barrier) {
  const double J = F.determinant();
  const Eigen::Matrix3d C = cofactor(F);
  const Vector9d c = Eigen::Map<const Vector9d>(C.data());
  Matrix9d H = barrier.densitySecondDerivative(J) * (c * c.transpose());
  const double w1 = barrier.densityDerivative(J);
  const Eigen::Matrix3d H01 = -cross(F.col(2));
  const Eigen::Matrix3d H02 = cross(F.col(1));
  const Eigen::Matrix3d H12 = -cross(F.col(0));
  H.block<3, 3>(0, 3) += w1 * H01;
  H.block<3, 3>(3, 0) += w1 * H01.transpose();
  H.block<3, 3>(0, 6) += w1 * H02;
  H.block<3, 3>(6, 0) += w1 * H02.transpose();
  H.block<3, 3>(3, 6) += w1 * H12;
  H.block<3, 3>(6, 3) += w1 * H12.transpose();
  return volume * H;
}

// K_ab = sum_ij g_a[i] g_b[j] H(i, j) (dF = sum_a dx_a g_a^T: column i of dF is sum_a g_a[i] dx_a).
TetStiffness toNodes(const Matrix9d& H, const TetRestData& rest) {
  const std::array<Eigen::Vector3d, 4> g = shapeGradients(rest.rest_shape_inverse);
  TetStiffness K = TetStiffness::Zero();
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) {
      Eigen::Matrix3d block = Eigen::Matrix3d::Zero();
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          block += (g[static_cast<size_t>(a)][i] * g[static_cast<size_t>(b)][j]) *
                   H.block<3, 3>(3 * i, 3 * j);
      K.block<3, 3>(3 * a, 3 * b) = block;
    }
  }
  return K;
}

}  // namespace

double VolumeBarrier::density(double J) const {
  if (!active(J)) return 0.0;
  const double d = threshold - J;
  return pressure / 3.0 * d * d * d / (threshold * threshold);
}

double VolumeBarrier::densityDerivative(double J) const {
  if (!active(J)) return 0.0;
  const double d = threshold - J;
  return -pressure * d * d / (threshold * threshold);
}

double VolumeBarrier::densitySecondDerivative(double J) const {
  if (!active(J)) return 0.0;
  return 2.0 * pressure * (threshold - J) / (threshold * threshold);
}

VolumeBarrier volumeBarrierOf(const Material& material) {
  VolumeBarrier barrier;
  barrier.threshold = material.barrier_threshold;
  barrier.pressure = material.barrier_stiffness * material.bulkModulus();
  return barrier;
}

Eigen::Matrix3d cofactor(const Eigen::Matrix3d& F) {
  Eigen::Matrix3d C;
  C.col(0) = F.col(1).cross(F.col(2));
  C.col(1) = F.col(2).cross(F.col(0));
  C.col(2) = F.col(0).cross(F.col(1));
  return C;
}

double volumeBarrierEnergy(const Eigen::Matrix3d& F, const TetRestData& rest,
                           const VolumeBarrier& barrier) {
  return rest.volume * barrier.density(F.determinant());
}

std::array<Eigen::Vector3d, 4> volumeBarrierForces(const Eigen::Matrix3d& F,
                                                   const TetRestData& rest,
                                                   const VolumeBarrier& barrier) {
  // Columns of H = -V P Bm^T are the forces on nodes 1..3; node 0 takes minus their sum.
  const Eigen::Matrix3d P = barrier.densityDerivative(F.determinant()) * cofactor(F);
  const Eigen::Matrix3d H = -rest.volume * P * rest.rest_shape_inverse.transpose();
  return {-(H.col(0) + H.col(1) + H.col(2)), H.col(0), H.col(1), H.col(2)};
}

TetStiffness volumeBarrierHessian(const Eigen::Matrix3d& F, const TetRestData& rest,
                                  const VolumeBarrier& barrier) {
  if (!barrier.active(F.determinant())) return TetStiffness::Zero();
  return toNodes(energyHessianInF(F, rest.volume, barrier), rest);
}

TetStiffness volumeBarrierStiffness(const Eigen::Matrix3d& F, const TetRestData& rest,
                                    const VolumeBarrier& barrier) {
  if (!barrier.active(F.determinant())) return TetStiffness::Zero();
  Eigen::SelfAdjointEigenSolver<Matrix9d> eigen(energyHessianInF(F, rest.volume, barrier));
  const Vector9d clamped = eigen.eigenvalues().cwiseMax(0.0);
  const Matrix9d projected =
      eigen.eigenvectors() * clamped.asDiagonal() * eigen.eigenvectors().transpose();
  return toNodes(projected, rest);
}

}  // namespace torsion

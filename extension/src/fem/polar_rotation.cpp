#include "torsion/fem/polar_rotation.h"

#include <Eigen/SVD>
#include <cmath>

namespace torsion {

SignedSvd signedSvd(const Eigen::Matrix3d& F) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  SignedSvd result{svd.matrixU(), svd.singularValues(), svd.matrixV()};
  // Singular values come sorted descending, so column 2 carries the smallest: flipping it moves
  // the reflection onto the least-stretched direction (Irving et al. 2004, section 5).
  if (result.U.determinant() < 0) {
    result.U.col(2) *= -1;
    result.sigma(2) *= -1;
  }
  if (result.V.determinant() < 0) {
    result.V.col(2) *= -1;
    result.sigma(2) *= -1;
  }
  return result;
}

Eigen::Matrix3d rotationBySvd(const Eigen::Matrix3d& F) {
  const SignedSvd svd = signedSvd(F);
  return svd.U * svd.V.transpose();
}

Eigen::Matrix3d extractRotation(const Eigen::Matrix3d& F, Eigen::Quaterniond& q, int max_iterations,
                                double tolerance) {
  if (!(F.determinant() > 0)) {
    Eigen::Matrix3d R = rotationBySvd(F);  // not const: returned by move
    q = Eigen::Quaterniond(R);
    return R;
  }
  Eigen::Matrix3d R = q.toRotationMatrix();
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    // Torque-like vector that rotates R's columns toward F's columns (Mueller et al. 2016, eq. 6).
    const Eigen::Vector3d omega_num =
        R.col(0).cross(F.col(0)) + R.col(1).cross(F.col(1)) + R.col(2).cross(F.col(2));
    const double omega_den =
        std::abs(R.col(0).dot(F.col(0)) + R.col(1).dot(F.col(1)) + R.col(2).dot(F.col(2))) + 1e-9;
    Eigen::Vector3d omega = omega_num / omega_den;
    const double angle_sq = omega.squaredNorm();
    if (angle_sq < tolerance * tolerance) break;
    // Near the fixed point omega is (tr(S) I - S) / tr(S) times the remaining rotation (S the
    // stretch), i.e. 2/3 of it for a nearly rigid tet. Scaling by 3/2 makes that a full step;
    // for any positive stretch the gain 1.5 (1 - s_i / tr S) stays in (0, 1.5), inside the
    // (0, 2) that converges, so large stretch only slows it. Far from the fixed point (cold
    // starts) the plain step is kept.
    if (angle_sq < 0.25) omega *= 1.5;
    // Rotate q by omega. The paper uses the exact exponential; a normalised first-order
    // quaternion (1, omega / 2) has the same fixed point and needs no sin/cos. Large first
    // steps (cold starts) still move toward the fixed point, just less than the full angle.
    const Eigen::Quaterniond delta(1.0, 0.5 * omega.x(), 0.5 * omega.y(), 0.5 * omega.z());
    q = (delta * q).normalized();
    R = q.toRotationMatrix();
  }
  return R;
}

}  // namespace torsion

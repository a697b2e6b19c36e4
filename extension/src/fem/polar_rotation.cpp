#include "torsion/fem/polar_rotation.h"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace torsion {

SignedSvd signedSvd(const Eigen::Matrix3d& F) {
  // V and sigma^2 from the symmetric eigenproblem of C = F^T F (Eigen's iterative solver: 1.6x
  // faster than its two-sided Jacobi SVD on 3x3 and as accurate where it matters here; the
  // closed-form one loses 1e-8 of F on clustered singular values), then U from F V: its first
  // two columns by Gram-Schmidt, the third their cross product, so U and V are rotations and the
  // last singular value u_2 . F v_2 carries det F's sign (Irving et al. 2004, section 5).
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(F.transpose() * F);
  SignedSvd result;
  for (int k = 0; k < 3; ++k)
    result.V.col(k) = eigen.eigenvectors().col(2 - k);  // descending
  if (result.V.determinant() < 0) result.V.col(2) *= -1;
  const Eigen::Matrix3d B = F * result.V;  // column k: u_k sigma_k
  const double first = B.col(0).norm();
  const Eigen::Vector3d u0 =
      first > 0 ? Eigen::Vector3d(B.col(0) / first) : Eigen::Vector3d::UnitX();
  Eigen::Vector3d u1 = B.col(1) - u0.dot(B.col(1)) * u0;
  const double second = u1.norm();
  u1 = second > 0 ? Eigen::Vector3d(u1 / second) : u0.unitOrthogonal();  // F of rank <= 1
  result.U.col(0) = u0;
  result.U.col(1) = u1;
  result.U.col(2) = u0.cross(u1);
  for (int k = 0; k < 3; ++k)
    result.sigma(k) = result.U.col(k).dot(B.col(k));
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

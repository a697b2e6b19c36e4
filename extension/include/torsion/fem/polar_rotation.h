#pragma once
// The rotation of a deformation gradient F = R S (polar decomposition), robust to inversion.
//
// Fast path: Mueller, Bender, Chentanez, Macklin, "A Robust Method to Extract the Rotational Part
// of Deformations", MIG 2016. It maximises tr(R^T F) over rotations by a few quaternion updates,
// warm-started from the previous step's rotation, so it usually converges in 1-3 iterations and
// always returns a proper rotation.
// Inverted or flat tets (det F <= 0) take the SVD path of Irving, Teran, Fedkiw, "Invertible
// Finite Elements for Robust Simulation of Large Deformation", SCA 2004: F = U Sigma V^T with the
// signs fixed so U and V are rotations (the smallest singular value takes the negative sign).
// R = U V^T then makes the corotated strain compressive along the inverted direction, and the
// elastic force pushes the tet back to positive volume.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace torsion {

/// Rotation of F, warm-started and updated in place through `q` (unit quaternion).
/// Returns the rotation matrix. The fast path stops when its update is below `tolerance` (rad)
/// or after max_iterations. The default 1e-6 rad leaves a relative force error of about 1e-6,
/// below what the CG tolerance (1e-4) resolves; tests of exact identities pass a tighter one.
Eigen::Matrix3d extractRotation(const Eigen::Matrix3d& F, Eigen::Quaterniond& q,
                                int max_iterations = 20, double tolerance = 1e-6);

/// F = U diag(sigma) V^T with U and V rotations (det +1): sigma descending in magnitude, its last
/// entry negative when det F < 0 (Irving et al. 2004). Accurate to rounding in F's norm, also at
/// repeated and zero singular values.
struct SignedSvd {
  Eigen::Matrix3d U;
  Eigen::Vector3d sigma;
  Eigen::Matrix3d V;
};
SignedSvd signedSvd(const Eigen::Matrix3d& F);

/// The SVD path alone (Irving et al. 2004), for tests and inverted tets.
Eigen::Matrix3d rotationBySvd(const Eigen::Matrix3d& F);

}  // namespace torsion

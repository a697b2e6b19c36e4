#pragma once
// The passive part of a local stiffness K_h (6x6, rows force N / torque N m, columns translation
// m / rotation rad; SimulationWrench::stiffness), so that the loop's prediction between two
// simulation steps, W = W_sim + K_h (pose - pose_sim), can store energy but never make it.
//
// Why. Over a closed path of the device the work of the predicted wrench is the integral of
// dpose^T K_h dpose: its antisymmetric part (a circulatory, follower-load term, e.g. the lever
// arm of a rotating loaded patch) pumps energy around any loop, and a positive eigenvalue of its
// symmetric part is a spring that pushes outward (energy grows with displacement). Keeping
//     K_p = V min(Lambda, 0) V^T,    V Lambda V^T = (K_h + K_h^T) / 2
// makes dpose^T K_p dpose <= 0 for every dpose: the prediction is a conservative, restoring
// spring about pose_sim (the nearest such matrix to K_h in the Frobenius norm). Rows and columns
// mix units; the pairing force . translation + torque . rotation is energy, so the test
// "K_p negative semidefinite" does not depend on the choice of units.

namespace torsion::device {

/// `out` = the passive part of `k` (both 36, row-major). `out` may be `k`. Non-finite input
/// gives zero (no prediction).
void passiveStiffness(const double k[36], double out[36]);

/// Largest eigenvalue of the symmetric part of `k` (36, row-major): <= 0 when `k` is passive.
double largestSymmetricEigenvalue(const double k[36]);

}  // namespace torsion::device

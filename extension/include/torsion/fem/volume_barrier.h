#pragma once
// A volume barrier against inverted tets, as pure functions: an energy that is exactly zero while
// a tet keeps more than a fraction J0 of its rest volume and grows as J = det F falls below it.
//
// Why: corotated linear elasticity (corotated_element.h) resists collapse only finitely. With the
// rotation of an inverted tet taken from the sign-fixed SVD (polar_rotation.h, Irving, Teran &
// Fedkiw 2004) the force does point back toward positive volume, but a tet squeezed flat
// (one singular value 0) stores only V (mu + lambda / 2) and pushes back with a pressure of about
// lambda + 2 mu, so a kink's crease under a large twist flattens its tets through zero volume
// (docs/validation-twist.md, "Twisting past the kink"). Hyperelastic laws (neo-Hookean: -mu log J +
// lambda / 2 log^2 J) stiffen without bound as J -> 0; this term adds that stiffening where the
// linear law is far outside its range, and nothing elsewhere.
//
// Energy density (Pa), k the barrier's pressure at J = 0, J0 in (0, 1):
//   W(J) = (k / 3) (J0 - J)^3 / J0^2   for J < J0,   0 otherwise,
//   W'(J) = -k (J0 - J)^2 / J0^2,   W''(J) = 2 k (J0 - J) / J0^2,
// so W, W' and W'' all vanish at J0 (C2: the implicit step's linearisation does not jump when a
// tet crosses the threshold). It stays finite for J <= 0, so a tet that is already inverted (or
// that one step pushes past zero) is pushed back by a force that keeps growing as it inverts
// further: pressure k at J = 0, 4 k at J = -J0.
// Per tet of volume V, F = Ds Bm (shape gradients g_a: the rows of Bm, g_0 minus their sum):
//   E = V W(J),   dE/dF = V W'(J) cof(F)   (cof(F) = dJ/dF = J F^-T, written without the
//   inverse so that it holds at J <= 0), f_a = -V W'(J) cof(F) g_a,
//   d2E/dF2 = V (W''(J) vec(cof F) vec(cof F)^T + W'(J) d2J/dF2),
// with d2J/dF2 in the columns f_i of F: d2J/df_0 df_1 = -[f_2]x, d2J/df_0 df_2 = [f_1]x,
// d2J/df_1 df_2 = -[f_0]x (J = f_0 . (f_1 x f_2)). The second term is indefinite, so the implicit
// solve gets the 9x9 F-space Hessian projected onto its non-negative eigenvalues (Teran, Sifakis,
// Irving & Fedkiw 2005, "Robust quasistatic finite elements and flesh simulation", section 4),
// K_ab = sum_ij g_a[i] g_b[j] H_F(i, j) (3x3 blocks of column i, j of F): symmetric positive
// semi-definite, so CG and CHOLMOD keep working.
// Rotation invariance: J and the energy do not change under x -> Q x + c, and the forces turn
// with Q. Tet10 bodies apply it to the 8 linear sub-tets of each element (FemModel::mesh()), the
// same tets the step anomaly monitor checks for inversion.

#include <Eigen/Core>
#include <array>

#include "torsion/fem/fem_model.h"

namespace torsion {

/// The barrier's two constants, from Material (threshold J0 and k = stiffness * bulk modulus).
struct VolumeBarrier {
  double threshold = 0;  ///< J0: the barrier acts below J = J0 (0: off)
  double pressure = 0;   ///< k: its pressure at J = 0, Pa

  bool active(double J) const { return J < threshold; }
  /// W(J), W'(J), W''(J) (the header's formulas), Pa.
  double density(double J) const;
  double densityDerivative(double J) const;
  double densitySecondDerivative(double J) const;
};

/// The barrier of a body's material (off when material.barrier_threshold is 0).
VolumeBarrier volumeBarrierOf(const Material& material);

/// cof(F) = dJ/dF (J F^-T where F is invertible).
Eigen::Matrix3d cofactor(const Eigen::Matrix3d& F);

/// Energy V W(J) of one linear tet, J.
double volumeBarrierEnergy(const Eigen::Matrix3d& F, const TetRestData& rest,
                           const VolumeBarrier& barrier);
/// f_a = -dE/dx_a on the tet's four nodes, N (zero above the threshold).
std::array<Eigen::Vector3d, 4> volumeBarrierForces(const Eigen::Matrix3d& F,
                                                   const TetRestData& rest,
                                                   const VolumeBarrier& barrier);

/// 12x12 stiffness of one tet: blocks K(3a.., 3b..) for nodes a, b, N/m.
using TetStiffness = Eigen::Matrix<double, 12, 12>;
/// The exact Hessian d2E/dx2 (indefinite in general; for tests).
TetStiffness volumeBarrierHessian(const Eigen::Matrix3d& F, const TetRestData& rest,
                                  const VolumeBarrier& barrier);
/// The Hessian with its F-space part projected to be positive semi-definite: what the implicit
/// solve adds to K.
TetStiffness volumeBarrierStiffness(const Eigen::Matrix3d& F, const TetRestData& rest,
                                    const VolumeBarrier& barrier);

}  // namespace torsion

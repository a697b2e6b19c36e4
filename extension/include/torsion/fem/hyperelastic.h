#pragma once
// Hyperelastic material laws and the linear tet built on them, as pure functions
// (docs/materials.md). Not yet used by the time step (it runs the corotated law of
// corotated_element.h).
//
// F is the deformation gradient, J = det F, I_C = |F|^2 = tr C, C = F^T F, cof F = dJ/dF
// (cofactor(), volume_barrier.h). 3x3 matrices are vectorised by columns, vec(F) = [f_0; f_1;
// f_2], and the tangent dP/dF is the 9x9 matrix A(i, j) = d vec(P)_i / d vec(F)_j (symmetric: it
// is the Hessian of Psi).
//
// Stable neo-Hookean (Smith, de Goes & Kim 2018), shifted Lame parameters mu', l':
//   Psi = mu'/2 (I_C - 3) + l'/2 (J - alpha)^2 [- mu'/2 log(I_C + 1)] - Psi_rest
//   without the log term: mu' = mu,       l' = lambda + mu,       alpha = 1 + mu'/l'
//   with the log term:    mu' = 4 mu / 3, l' = lambda + 5 mu / 6, alpha = 1 + 3 mu' / (4 l')
// (mu, lambda the small-strain Lame parameters of (E, nu), Material::mu(), lambda()). Both are
// zero-stress at F = I and have the small-strain stiffness of (E, nu); polynomial in F (and
// log(I_C + 1), I_C >= 0), so smooth and finite through inversion (J <= 0). Without the log term
// it is exactly neo-Hookean at J = 1 (simple shear: sigma_12 = mu gamma); the log term stiffens
// it at large strain (sigma_12 = mu' gamma (3 + gamma^2) / (4 + gamma^2), mu' = 4 mu / 3).
//
// Mooney-Rivlin, compressible, with the invariants of C (not their isochoric parts) and the same
// kind of shifted volumetric term, so that it is also rest-stable and finite through inversion:
//   Psi = C1 (I_C - 3) + C2 (II_C - 3) + l'/2 (J - alpha)^2 - Psi_rest
//   II_C = (I_C^2 - tr C^2) / 2,  l' = lambda + 2 C1,  alpha = 1 + (2 C1 + 4 C2) / l'
// Small strain: mu = 2 (C1 + C2), lambda as given (lambda = kappa - 2 mu / 3). At J = 1 it is
// the incompressible Mooney-Rivlin law (simple shear: sigma_12 = 2 (C1 + C2) gamma exactly).
//
// Psi_rest (the energy at F = I) is subtracted so that Psi(I) = 0. The stiffness the implicit
// solve gets is the tangent projected onto its non-negative eigenvalues
// (projectPositiveSemiDefinite), then mapped to the tet's nodes.

#include <Eigen/Core>
#include <array>

#include "torsion/fem/fem_model.h"
#include "torsion/fem/volume_barrier.h"

namespace torsion {

using PiolaTangent = Eigen::Matrix<double, 9, 9>;

/// Stable neo-Hookean constants (the shifted ones: the header's mu', l', alpha), Pa.
struct StableNeoHookean {
  double mu = 0;
  double lambda = 0;
  double alpha = 1;
  bool log_term = false;  ///< with -mu'/2 log(I_C + 1) (Smith et al. 2018)
  double rest_energy = 0;

  /// From Young's modulus (Pa) and Poisson's ratio in [0, 0.5).
  static StableNeoHookean fromYoungPoisson(double youngs_modulus, double poisson_ratio,
                                           bool log_term = false);
};

/// Compressible Mooney-Rivlin constants (the header's C1, C2, l', alpha), Pa.
struct MooneyRivlin {
  double c1 = 0;
  double c2 = 0;
  double lambda = 0;
  double alpha = 1;
  double rest_energy = 0;

  /// From (E, nu) with C2 / (C1 + C2) = c2_fraction in [0, 1]; needs lambda + 2 C1 > 0
  /// (only nu = 0 with c2_fraction = 1 fails).
  static MooneyRivlin fromYoungPoisson(double youngs_modulus, double poisson_ratio,
                                       double c2_fraction);
  /// From C1, C2 and the small-strain bulk modulus kappa = lambda + 2 mu / 3 (mu = 2 (C1 + C2)).
  static MooneyRivlin fromConstants(double c1, double c2, double bulk_modulus);
};

/// Energy density Psi(F), Pa (J/m^3).
double energyDensity(const StableNeoHookean& law, const Eigen::Matrix3d& F);
double energyDensity(const MooneyRivlin& law, const Eigen::Matrix3d& F);
/// First Piola-Kirchhoff stress P = dPsi/dF, Pa.
Eigen::Matrix3d firstPiola(const StableNeoHookean& law, const Eigen::Matrix3d& F);
Eigen::Matrix3d firstPiola(const MooneyRivlin& law, const Eigen::Matrix3d& F);
/// The exact tangent dP/dF (indefinite in general), Pa.
PiolaTangent firstPiolaDerivative(const StableNeoHookean& law, const Eigen::Matrix3d& F);
PiolaTangent firstPiolaDerivative(const MooneyRivlin& law, const Eigen::Matrix3d& F);

/// The symmetric matrix with A's eigenvectors and its eigenvalues clamped at zero: the nearest
/// positive semi-definite matrix to A (Frobenius norm). A is symmetrised first.
PiolaTangent projectPositiveSemiDefinite(const PiolaTangent& A);

/// One linear tet: energy V Psi (J), forces f_a = -dE/dx_a (N), stiffness d2E/dx2 (N/m).
struct HyperelasticTetResponse {
  double energy = 0;
  std::array<Eigen::Vector3d, 4> forces;
  TetStiffness stiffness = TetStiffness::Zero();
};
/// What the implicit step assembles, at node positions x (rest data from FemModel). With
/// `project` the stiffness is built from the projected tangent (positive semi-definite);
/// without, it is the exact Hessian of the energy.
HyperelasticTetResponse hyperelasticTet(const StableNeoHookean& law,
                                        const std::array<Eigen::Vector3d, 4>& x,
                                        const TetRestData& rest, bool project = true);
HyperelasticTetResponse hyperelasticTet(const MooneyRivlin& law,
                                        const std::array<Eigen::Vector3d, 4>& x,
                                        const TetRestData& rest, bool project = true);

}  // namespace torsion

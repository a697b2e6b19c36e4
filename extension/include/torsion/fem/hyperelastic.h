#pragma once
// Hyperelastic material laws and the linear and quadratic tets built on them, as pure functions
// (docs/materials.md). The implicit step of a hyperelastic body runs them per tet
// (src/solve/hyperelastic_pass.h).
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
// Psi_rest (the energy at F = I) is subtracted so that Psi(I) = 0.
//
// The tangent's eigensystem in closed form (Smith, de Goes & Kim 2019, "Analytic Eigensystems
// for Isotropic Distortion Energies"; Teran et al. 2005). With F = U diag(s) V^T, U and V
// rotations and s signed (s_2 < 0 when det F < 0), an isotropic Psi(s_0, s_1, s_2) has, for each
// pair (i, j) with k the third axis, the eigenvectors U (e_i e_j^T -+ e_j e_i^T) V^T / sqrt 2:
//   rotation (antisymmetric):  (psi_i + psi_j) / (s_i + s_j)
//   shear    (symmetric):      (psi_i - psi_j) / (s_i - s_j)        (psi_i = dPsi/ds_i)
// and on U diag(.) V^T the 3x3 block d2Psi/ds_i ds_j. For both laws the two quotients are
// polynomials in s (no division: they hold through repeated and zero singular values), e.g.
// stable neo-Hookean: mu' + l'(J - alpha) s_k and mu' - l'(J - alpha) s_k. The projected
// stiffness (the implicit step's fallback where the exact Hessian fails a Newton direction) is the
// tangent with its eigenvalues filtered (each quotient clamped or mirrored, the 3x3 block
// likewise), mapped to the tet's nodes; the exact tangent is the same sum unfiltered (the step
// takes stable neo-Hookean's tet4 one in closed form, factored_tet_hessian.h).

#include <Eigen/Core>
#include <array>

#include "torsion/fem/fem_model.h"
#include "torsion/fem/quadratic_element.h"
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

/// The tangent dP/dF in the frame of F's singular values (the header's closed forms).
struct PrincipalTangent {
  Eigen::Matrix3d U, V;     ///< rotations (det +1), F = U diag(sigma) V^T
  Eigen::Vector3d sigma;    ///< signed singular values: sigma(2) < 0 when det F < 0
  Eigen::Matrix3d stretch;  ///< d2Psi / dsigma_i dsigma_j, Pa
  /// Index k: the eigenvalue of the mode of the pair (i, j) without k, Pa: `rotation` of
  /// U (e_i e_j^T - e_j e_i^T) V^T / sqrt 2, `shear` of U (e_i e_j^T + e_j e_i^T) V^T / sqrt 2.
  Eigen::Vector3d rotation, shear;
};
PrincipalTangent principalTangent(const StableNeoHookean& law, const Eigen::Matrix3d& F);
PrincipalTangent principalTangent(const MooneyRivlin& law, const Eigen::Matrix3d& F);
/// What becomes of a tangent's negative eigenvalues: kept (the exact tangent), clamped at zero (the
/// nearest positive semi-definite matrix), or mirrored (replaced by their magnitudes: positive
/// semi-definite as well, but keeping the curvature the clamp drops, so that a Newton step along a
/// direction where the energy bends down stays short; Chen, Liu, Jacobson, Levin and Zheng 2024,
/// "Trust-Region Eigenvalue Filtering for Projected Newton").
enum class EigenvalueFilter { kExact, kClamp, kMirror };

/// dP/dF rebuilt from its eigensystem, its eigenvalues filtered.
PiolaTangent tangentOf(const PrincipalTangent& tangent, EigenvalueFilter filter);

/// Which stiffnesses hyperelasticTet computes (the forces and the energy always): the projected
/// one built from the clamped (kProjected, kProjectedAndExact) or the mirrored (kMirrored)
/// tangent, and the exact one (kExact, kProjectedAndExact).
enum class TetStiffnessKind { kNone, kProjected, kMirrored, kExact, kProjectedAndExact };
/// Whether `kind` asks for the projected (positive semi-definite), or the exact, stiffness.
inline bool projectedAsked(TetStiffnessKind kind) {
  return kind == TetStiffnessKind::kProjected || kind == TetStiffnessKind::kMirrored ||
         kind == TetStiffnessKind::kProjectedAndExact;
}
inline bool exactAsked(TetStiffnessKind kind) {
  return kind == TetStiffnessKind::kExact || kind == TetStiffnessKind::kProjectedAndExact;
}
/// The filter that makes `kind`'s projected stiffness.
inline EigenvalueFilter projectionOf(TetStiffnessKind kind) {
  return kind == TetStiffnessKind::kMirrored ? EigenvalueFilter::kMirror : EigenvalueFilter::kClamp;
}

/// One linear tet: energy V Psi (J), forces f_a = -dE/dx_a (N), stiffness d2E/dx2 (N/m): the
/// exact Hessian, and built from the projected tangent (positive semi-definite).
struct HyperelasticTetResponse {
  double energy = 0;
  std::array<Eigen::Vector3d, 4> forces;
  TetStiffness projected_stiffness = TetStiffness::Zero();
  TetStiffness exact_stiffness = TetStiffness::Zero();
};
/// What the implicit step assembles, at node positions x (rest data from FemModel). The
/// projected stiffness has the same bits whether or not the exact one is computed with it.
HyperelasticTetResponse hyperelasticTet(const StableNeoHookean& law,
                                        const std::array<Eigen::Vector3d, 4>& x,
                                        const TetRestData& rest,
                                        TetStiffnessKind kind = TetStiffnessKind::kProjected);
HyperelasticTetResponse hyperelasticTet(const MooneyRivlin& law,
                                        const std::array<Eigen::Vector3d, 4>& x,
                                        const TetRestData& rest,
                                        TetStiffnessKind kind = TetStiffnessKind::kProjected);

/// The energy and forces alone (the bits hyperelasticTet gives them).
struct HyperelasticTetForces {
  double energy = 0;
  std::array<Eigen::Vector3d, 4> forces;
};
HyperelasticTetForces hyperelasticTetForces(const StableNeoHookean& law,
                                            const std::array<Eigen::Vector3d, 4>& x,
                                            const TetRestData& rest);
HyperelasticTetForces hyperelasticTetForces(const MooneyRivlin& law,
                                            const std::array<Eigen::Vector3d, 4>& x,
                                            const TetRestData& rest);

/// One quadratic (10-node) tet (quadratic_element.h): at each of the 4 quadrature points q of the
/// corotated P2 element (weight V / 4, shape gradients g_qa = rest.gradients[q][a]),
/// F_q = sum_a x_a g_qa^T, and
///   E = (V / 4) sum_q Psi(F_q),   f_a = -(V / 4) sum_q P(F_q) g_qa,
///   K = (V / 4) sum_q Z_q^T D_q Z_q   (Z_q(m, a) = Q_m g_qa, D_q from principalTangent(F_q)),
/// the tet's mode stiffness at each point, with D_q clamped for the projected stiffness. The
/// projected stiffness has the same bits whether or not the exact one is computed with it; both
/// are symmetric to the bit. F is linear over the element, so the rule is exact for a quadratic
/// energy (small strain: the corotated P2 element's stiffness); at finite strain Psi(F) is a
/// polynomial of higher degree and the rule is the corotated element's, not exact.
struct HyperelasticTet10Response {
  double energy = 0;
  Tet10Vectors forces;
  Tet10Stiffness projected_stiffness = Tet10Stiffness::Zero();
  Tet10Stiffness exact_stiffness = Tet10Stiffness::Zero();
};
HyperelasticTet10Response hyperelasticTet10(const StableNeoHookean& law, const Tet10Vectors& x,
                                            const QuadraticRestData& rest,
                                            TetStiffnessKind kind = TetStiffnessKind::kProjected);
HyperelasticTet10Response hyperelasticTet10(const MooneyRivlin& law, const Tet10Vectors& x,
                                            const QuadraticRestData& rest,
                                            TetStiffnessKind kind = TetStiffnessKind::kProjected);

}  // namespace torsion

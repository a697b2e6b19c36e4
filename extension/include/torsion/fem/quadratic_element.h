#pragma once
// Corotated linear elasticity of one quadratic (10-node) tet, as pure functions: the P2
// counterpart of corotated_element.h (Zienkiewicz & Taylor, "The Finite Element Method", vol. 1,
// section 8.8 for the P2 shape functions; Mueller & Gross 2004 for the corotation).
//
// Shape functions in barycentric coordinates L: corner a: N_a = L_a (2 L_a - 1); mid-edge node of
// edge (i, j): N = 4 L_i L_j. With straight edges the map is affine, so grad L comes from the
// corner Bm and the gradients are linear in L: corner (4 L_a - 1) grad L_a, edge
// 4 (L_i grad L_j + L_j grad L_i). The strain is linear over the element, so the stiffness and
// the energy integrands are quadratic: the 4-point degree-2 rule (weights V/4, points
// (a, b, b, b) and permutations, a = (5 + 3 sqrt 5) / 20, b = (5 - sqrt 5) / 20) integrates them
// exactly.
//
// One rotation per element: the polar rotation of F at the centroid. F is linear in L, so F at
// the centroid is the element's mean deformation gradient; its rotation sees the mid-edge nodes
// (the corner tet's F would not: a bending mode that moves only mid-edge nodes leaves it at I).
// At the centroid the corner gradients vanish and edge (i, j) has grad L_i + grad L_j. A rigid
// motion x = Q X + c gives F = Q at every point, so R = Q and every strain is zero.
// Per quadrature point q: eps_q = sym(R^T F_q) - I, sigma_q = 2 mu eps_q + lambda tr(eps_q) I,
// energy E = (V / 4) sum_q (mu eps_q : eps_q + lambda / 2 tr(eps_q)^2), and the forces are its
// exact gradient with R = R(x):
//   f_a = -(V / 4) sum_q R sigma_q g_qa  +  R (gc_a x M^-1 tau),
// tau = dE/d omega = (V / 2) sum_q axial(skew(S_q sigma_q)) (S_q = R^T F_q, R -> R (I + [omega])),
// M = tr(S_c) I - S_c (S_c = R^T F_c), gc_a the centroid gradients. The second term is the
// rotation's response: for the linear tet tau is zero (one S, symmetric, commuting with sigma),
// here one R serves four points and tau is second order in the strain. Without it the forces
// would carry a second-order net torque and a free body could spin up after a large deformation;
// with it E is rotation invariant and the forces conserve angular momentum.
//   K_ab = (V / 4) sum_q [mu (g_qa . g_qb) I + mu (R g_qb)(R g_qa)^T + lambda (R g_qa)(R g_qb)^T]
// (stiffness warping: R held fixed in the differential, as for the linear tet; the rotation
// term's own differential is dropped with it, both vanish at rigid configurations).

#include <Eigen/Core>
#include <array>

namespace torsion {

inline constexpr int kTet10QuadraturePoints = 4;

/// Rest data of one P2 element (straight edges).
struct QuadraticRestData {
  /// Shape-function gradients at the quadrature points, gradients[q][a], 1/m.
  std::array<std::array<Eigen::Vector3d, 10>, kTet10QuadraturePoints> gradients;
  /// Gradients at the centroid of the mid-edge nodes (local 4..9); the corners' are zero, 1/m.
  std::array<Eigen::Vector3d, 6> centroid_edge_gradients;
  /// The corner tet's barycentric gradients grad L_0..3 (the rows of Bm, and minus their sum), 1/m.
  std::array<Eigen::Vector3d, 4> corner_gradients;
  double volume = 0;  ///< rest volume V, m^3 (each quadrature weight is V / 4)
};

/// Rest data from the corner tet's Bm = Dm^-1 and rest volume.
QuadraticRestData quadraticRestData(const Eigen::Matrix3d& corner_rest_shape_inverse,
                                    double volume);

/// The P2 gradients as combinations of the barycentric ones, the same for every element:
/// gradients[q][a] = sum over c of coefficients[q][a][c] grad L_c. (The stiffness blocks are built
/// from them: K_ab is a combination of the products (R grad L_c)(R grad L_d)^T.)
using Tet10GradientCoefficients =
    std::array<std::array<std::array<double, 4>, 10>, kTet10QuadraturePoints>;
const Tet10GradientCoefficients& quadraticGradientCoefficients();

using Tet10Vectors = std::array<Eigen::Vector3d, 10>;
/// 30x30 stiffness of one P2 element: blocks K(3a.., 3b..) for local nodes a, b, N/m.
using Tet10Stiffness = Eigen::Matrix<double, 30, 30>;

/// F at quadrature point q: sum_a x_a g_qa^T.
Eigen::Matrix3d quadraticDeformationGradient(const Tet10Vectors& x, const QuadraticRestData& rest,
                                             int q);
/// F at the centroid (= the element's mean F), whose polar rotation is the element's rotation.
Eigen::Matrix3d quadraticCentroidGradient(const Tet10Vectors& x, const QuadraticRestData& rest);

struct QuadraticResponse {
  Tet10Vectors forces;  ///< N
  double energy = 0;    ///< J
};
/// Elastic forces and energy at positions x with the element rotation R (the polar rotation of
/// quadraticCentroidGradient(x); the forces are the exact gradient of the energy for that R).
QuadraticResponse quadraticResponse(const Tet10Vectors& x, const Eigen::Matrix3d& R,
                                    const QuadraticRestData& rest, double mu, double lambda);

/// df = -K dx for nodal displacements dx (R held fixed).
Tet10Vectors quadraticForceDifferential(const Tet10Vectors& dx, const Eigen::Matrix3d& R,
                                        const QuadraticRestData& rest, double mu, double lambda);

/// The 3x3 block K_ab of the warped stiffness (the formula above).
Eigen::Matrix3d quadraticStiffnessBlock(const Eigen::Matrix3d& R, const QuadraticRestData& rest,
                                        double mu, double lambda, int a, int b);

/// Lumped masses of a P2 element by HRZ (Hinton, Rock & Zienkiewicz 1976): the consistent mass
/// diagonal (rho V / 70 at a corner, 8 rho V / 105 at a mid-edge node) scaled to the element's
/// mass: rho V / 36 per corner, 4 rho V / 27 per mid-edge node. Row-sum lumping would give the
/// corners -rho V / 20 (a negative mass); HRZ keeps every mass positive.
inline constexpr double kTet10CornerMassFraction = 1.0 / 36.0;
inline constexpr double kTet10EdgeMassFraction = 4.0 / 27.0;

}  // namespace torsion

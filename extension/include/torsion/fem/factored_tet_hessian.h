#pragma once
// The exact Hessian of a linear tet whose energy density is a shear term mu/2 I_C plus any
// function U(J) of the volume ratio J = det F, kept in factored form: the stable neo-Hookean law
// without its log term (hyperelastic.h: U = l'/2 (J - alpha)^2), with the volume barrier
// (volume_barrier.h) added to U where it acts.
//
// Why: the implicit step's Newton directions use the exact Hessian, once per iteration on every
// tet. Built from the tangent's eigensystem it needs an SVD of F and a 12x12 product per tet,
// and the assembly then reads 1.1 kB per tet; in this form it needs cof F and six products of F,
// 240 bytes per tet, and the assembly builds each 3x3 block from them directly.
//
// With g_a the tet's shape gradients (rest), V its rest volume, c = cof F = dJ/dF:
//   dE/dx_a = V (mu F + U'(J) cof F) g_a,
//   K_ab = d2E/dx_a dx_b = V mu (g_a . g_b) I + V U''(J) (c g_a)(c g_b)^T + V U'(J) [F (g_b x
//   g_a)]x,
// the last term from d2J/dF2 (d2J[u g_a^T, w g_b^T] = (u x w) . F (g_a x g_b)). It is
// symmetric (K_ba = K_ab^T: [.]x is antisymmetric and g_b x g_a = -(g_a x g_b)) and indefinite
// in general, as the exact Hessian of any non-convex energy.

#include <Eigen/Core>
#include <array>

#include "torsion/fem/volume_barrier.h"

namespace torsion {

/// The shape gradients g_0..g_3 of a linear tet from its inverse rest shape Bm (the rows of Bm,
/// and minus their sum).
std::array<Eigen::Vector3d, 4> shapeGradients(const Eigen::Matrix3d& rest_shape_inverse);

/// The index of the node pair (a, b), a < b, in FactoredTetHessian::w: (0,1) (0,2) (0,3) (1,2)
/// (1,3) (2,3).
constexpr int nodePairIndex(int a, int b) {
  return a == 0 ? b - 1 : a + b;
}

/// K_ab = shear V (g_a . g_b) I + c_a c_b^T + [w_ab]x (w_ba = -w_ab, w_aa = 0): the shear term
/// comes from the rest data and the material, so only the J terms are stored,
///   c_a = sqrt(V U''(J)) cof(F) g_a,   w_ab = V U'(J) F (g_b x g_a).
struct FactoredTetHessian {
  std::array<Eigen::Vector3d, 4> c;
  std::array<Eigen::Vector3d, 6> w;  ///< pair (a, b), a < b, at nodePairIndex(a, b)
};

/// The J terms at F, for U''(J) = `curvature` >= 0 and U'(J) = `pressure`.
FactoredTetHessian factoredTetHessian(const Eigen::Matrix3d& F,
                                      const std::array<Eigen::Vector3d, 4>& gradients,
                                      double volume, double curvature, double pressure);

/// Block K_ab (N/m) of the Hessian with shear modulus `shear` (Pa).
Eigen::Matrix3d factoredHessianBlock(const FactoredTetHessian& hessian,
                                     const std::array<Eigen::Vector3d, 4>& gradients,
                                     double shear_volume, int a, int b);

/// The whole 12x12 Hessian (tests; the implicit step assembles the blocks directly).
TetStiffness expandFactoredHessian(const FactoredTetHessian& hessian,
                                   const std::array<Eigen::Vector3d, 4>& gradients,
                                   double shear_volume);

}  // namespace torsion

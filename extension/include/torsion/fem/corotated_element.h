#pragma once
// Corotated linear elasticity of one linear tet, as pure functions (Mueller & Gross 2004;
// Sifakis & Barbic, "FEM Simulation of 3D Deformable Solids", SIGGRAPH 2012 course, section 4).
//
// With F = Ds Bm and its rotation R, the strain in the rotated frame is
//   eps = sym(R^T F) - I,   sigma = 2 mu eps + lambda tr(eps) I,   P = R sigma,
// and the elastic force on node a is f_a = -V P grad N_a, with grad N_a (a = 1..3) the a-th row of
// Bm and grad N_0 = -(grad N_1 + grad N_2 + grad N_3). This equals -Re Ke (Re^T x - X) of the
// report's eq. 4.2 without forming the 12x12 Ke.
// The force differential holds R fixed (stiffness warping, K = Re Ke Re^T):
//   dP = R (2 mu sym(R^T dF) + lambda tr(R^T dF) I),  df_a = -V dP grad N_a.

#include <Eigen/Core>
#include <array>

#include "torsion/fem/fem_model.h"

namespace torsion {

/// Deformation gradient F = Ds Bm of a tet at positions x0..x3.
Eigen::Matrix3d deformationGradient(const std::array<Eigen::Vector3d, 4>& x,
                                    const Eigen::Matrix3d& rest_shape_inverse);

/// Elastic forces on the tet's four nodes (N), given its rotation R.
std::array<Eigen::Vector3d, 4> corotatedForces(const Eigen::Matrix3d& F, const Eigen::Matrix3d& R,
                                               const TetRestData& rest, double mu, double lambda);

/// Forces and energy together (one strain evaluation): what a time step needs.
struct CorotatedResponse {
  std::array<Eigen::Vector3d, 4> forces;
  double energy = 0;
};
CorotatedResponse corotatedResponse(const Eigen::Matrix3d& F, const Eigen::Matrix3d& R,
                                    const TetRestData& rest, double mu, double lambda);

/// df = -K dx for nodal displacements dx (R held fixed): the stiffness product, negated.
std::array<Eigen::Vector3d, 4> corotatedForceDifferential(const std::array<Eigen::Vector3d, 4>& dx,
                                                          const Eigen::Matrix3d& R,
                                                          const TetRestData& rest, double mu,
                                                          double lambda);

/// Elastic energy V (mu eps:eps + lambda/2 tr(eps)^2), J.
double corotatedEnergy(const Eigen::Matrix3d& F, const Eigen::Matrix3d& R, const TetRestData& rest,
                       double mu, double lambda);

}  // namespace torsion

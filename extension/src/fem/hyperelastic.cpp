#include "torsion/fem/hyperelastic.h"

#include <Eigen/Eigenvalues>
#include <cmath>

#include "torsion/fem/corotated_element.h"

namespace torsion {

namespace {

using PiolaVector = Eigen::Matrix<double, 9, 1>;

double lameLambda(double E, double nu) {
  return E * nu / ((1 + nu) * (1 - 2 * nu));
}
double lameMu(double E, double nu) {
  return E / (2 * (1 + nu));
}

double doubleDot(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B) {
  return A.cwiseProduct(B).sum();
}

// The differential of cof F in the direction dF (cof is bilinear in the columns of F).
Eigen::Matrix3d cofactorDifferential(const Eigen::Matrix3d& F, const Eigen::Matrix3d& dF) {
  Eigen::Matrix3d D;
  D.col(0) = dF.col(1).cross(F.col(2)) + F.col(1).cross(dF.col(2));
  D.col(1) = dF.col(2).cross(F.col(0)) + F.col(2).cross(dF.col(0));
  D.col(2) = dF.col(0).cross(F.col(1)) + F.col(0).cross(dF.col(1));
  return D;
}

// The 9x9 tangent from its directional derivative dP(dF): column j is dP(E_j).
template <typename Differential>
PiolaTangent tangentFromDifferential(const Differential& dP) {
  PiolaTangent A;
  for (int j = 0; j < 9; ++j) {
    Eigen::Matrix3d E = Eigen::Matrix3d::Zero();
    E(j % 3, j / 3) = 1.0;
    const Eigen::Matrix3d column = dP(E);
    A.col(j) = Eigen::Map<const PiolaVector>(column.data());
  }
  return 0.5 * (A + A.transpose());
}

// II_C = (I_C^2 - tr C^2) / 2 (its gradient: 2 (I_C F - F C)).
double secondInvariant(const Eigen::Matrix3d& F) {
  const Eigen::Matrix3d C = F.transpose() * F;
  const double ic = C.trace();
  return 0.5 * (ic * ic - (C * C).trace());
}

std::array<Eigen::Vector3d, 4> hyperelasticNodeForces(const Eigen::Matrix3d& P,
                                                      const TetRestData& rest) {
  const Eigen::Matrix3d H = -rest.volume * P * rest.rest_shape_inverse.transpose();
  return {-(H.col(0) + H.col(1) + H.col(2)), H.col(0), H.col(1), H.col(2)};
}

// K_ab = V sum_ij g_a[i] g_b[j] A(i, j) (3x3 blocks of A; column i of dF is sum_a g_a[i] dx_a).
TetStiffness hyperelasticNodeStiffness(const PiolaTangent& A, const TetRestData& rest) {
  const Eigen::Matrix3d& B = rest.rest_shape_inverse;
  Eigen::Matrix<double, 4, 3> g;
  g.row(0) = -(B.row(0) + B.row(1) + B.row(2));
  g.bottomRows<3>() = B;
  TetStiffness K;
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) {
      Eigen::Matrix3d block = Eigen::Matrix3d::Zero();
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          block += (g(a, i) * g(b, j)) * A.block<3, 3>(3 * i, 3 * j);
      K.block<3, 3>(3 * a, 3 * b) = rest.volume * block;
    }
  }
  return K;
}

template <typename Law>
HyperelasticTetResponse hyperelasticResponse(const Law& law,
                                             const std::array<Eigen::Vector3d, 4>& x,
                                             const TetRestData& rest, bool project) {
  const Eigen::Matrix3d F = deformationGradient(x, rest.rest_shape_inverse);
  HyperelasticTetResponse response;
  response.energy = rest.volume * energyDensity(law, F);
  response.forces = hyperelasticNodeForces(firstPiola(law, F), rest);
  const PiolaTangent A = firstPiolaDerivative(law, F);
  response.stiffness =
      hyperelasticNodeStiffness(project ? projectPositiveSemiDefinite(A) : A, rest);
  return response;
}

}  // namespace

StableNeoHookean StableNeoHookean::fromYoungPoisson(double youngs_modulus, double poisson_ratio,
                                                    bool log_term) {
  const double shear = lameMu(youngs_modulus, poisson_ratio);
  const double first_lame = lameLambda(youngs_modulus, poisson_ratio);
  StableNeoHookean law;
  law.log_term = log_term;
  if (log_term) {
    law.mu = 4.0 * shear / 3.0;
    law.lambda = first_lame + 5.0 * shear / 6.0;
    law.alpha = 1.0 + 3.0 * law.mu / (4.0 * law.lambda);
  } else {
    law.mu = shear;
    law.lambda = first_lame + shear;
    law.alpha = 1.0 + law.mu / law.lambda;
  }
  law.rest_energy = 0.0;
  law.rest_energy = energyDensity(law, Eigen::Matrix3d::Identity());
  return law;
}

MooneyRivlin MooneyRivlin::fromYoungPoisson(double youngs_modulus, double poisson_ratio,
                                            double c2_fraction) {
  const double mu = lameMu(youngs_modulus, poisson_ratio);
  const double kappa = lameLambda(youngs_modulus, poisson_ratio) + 2.0 * mu / 3.0;
  return fromConstants((1.0 - c2_fraction) * mu / 2.0, c2_fraction * mu / 2.0, kappa);
}

MooneyRivlin MooneyRivlin::fromConstants(double c1, double c2, double bulk_modulus) {
  const double mu = 2.0 * (c1 + c2);
  MooneyRivlin law;
  law.c1 = c1;
  law.c2 = c2;
  law.lambda = bulk_modulus - 2.0 * mu / 3.0 + 2.0 * c1;
  law.alpha = 1.0 + (2.0 * c1 + 4.0 * c2) / law.lambda;
  law.rest_energy = 0.0;
  law.rest_energy = energyDensity(law, Eigen::Matrix3d::Identity());
  return law;
}

double energyDensity(const StableNeoHookean& law, const Eigen::Matrix3d& F) {
  const double ic = F.squaredNorm();
  const double dj = F.determinant() - law.alpha;
  double psi = 0.5 * law.mu * (ic - 3.0) + 0.5 * law.lambda * dj * dj;
  if (law.log_term) psi -= 0.5 * law.mu * std::log(ic + 1.0);
  return psi - law.rest_energy;
}

Eigen::Matrix3d firstPiola(const StableNeoHookean& law, const Eigen::Matrix3d& F) {
  const double shear = law.log_term ? law.mu * (1.0 - 1.0 / (F.squaredNorm() + 1.0)) : law.mu;
  return shear * F + law.lambda * (F.determinant() - law.alpha) * cofactor(F);
}

PiolaTangent firstPiolaDerivative(const StableNeoHookean& law, const Eigen::Matrix3d& F) {
  const double ic1 = F.squaredNorm() + 1.0;
  const double shear = law.log_term ? law.mu * (1.0 - 1.0 / ic1) : law.mu;
  const double log_curvature = law.log_term ? 2.0 * law.mu / (ic1 * ic1) : 0.0;
  const Eigen::Matrix3d cof = cofactor(F);
  const double pressure = law.lambda * (F.determinant() - law.alpha);
  return tangentFromDifferential([&](const Eigen::Matrix3d& dF) -> Eigen::Matrix3d {
    return shear * dF + (log_curvature * doubleDot(F, dF)) * F +
           (law.lambda * doubleDot(cof, dF)) * cof + pressure * cofactorDifferential(F, dF);
  });
}

double energyDensity(const MooneyRivlin& law, const Eigen::Matrix3d& F) {
  const double dj = F.determinant() - law.alpha;
  return law.c1 * (F.squaredNorm() - 3.0) + law.c2 * (secondInvariant(F) - 3.0) +
         0.5 * law.lambda * dj * dj - law.rest_energy;
}

Eigen::Matrix3d firstPiola(const MooneyRivlin& law, const Eigen::Matrix3d& F) {
  const Eigen::Matrix3d C = F.transpose() * F;
  return 2.0 * law.c1 * F + 2.0 * law.c2 * (C.trace() * F - F * C) +
         law.lambda * (F.determinant() - law.alpha) * cofactor(F);
}

PiolaTangent firstPiolaDerivative(const MooneyRivlin& law, const Eigen::Matrix3d& F) {
  const Eigen::Matrix3d C = F.transpose() * F;
  const double ic = C.trace();
  const Eigen::Matrix3d cof = cofactor(F);
  const double pressure = law.lambda * (F.determinant() - law.alpha);
  return tangentFromDifferential([&](const Eigen::Matrix3d& dF) -> Eigen::Matrix3d {
    const Eigen::Matrix3d dC = dF.transpose() * F + F.transpose() * dF;
    const Eigen::Matrix3d d_second = 2.0 * doubleDot(F, dF) * F + ic * dF - dF * C - F * dC;
    return 2.0 * law.c1 * dF + 2.0 * law.c2 * d_second + (law.lambda * doubleDot(cof, dF)) * cof +
           pressure * cofactorDifferential(F, dF);
  });
}

PiolaTangent projectPositiveSemiDefinite(const PiolaTangent& A) {
  const Eigen::SelfAdjointEigenSolver<PiolaTangent> eigen(0.5 * (A + A.transpose()));
  const PiolaVector clamped = eigen.eigenvalues().cwiseMax(0.0);
  return eigen.eigenvectors() * clamped.asDiagonal() * eigen.eigenvectors().transpose();
}

HyperelasticTetResponse hyperelasticTet(const StableNeoHookean& law,
                                        const std::array<Eigen::Vector3d, 4>& x,
                                        const TetRestData& rest, bool project) {
  return hyperelasticResponse(law, x, rest, project);
}

HyperelasticTetResponse hyperelasticTet(const MooneyRivlin& law,
                                        const std::array<Eigen::Vector3d, 4>& x,
                                        const TetRestData& rest, bool project) {
  return hyperelasticResponse(law, x, rest, project);
}

}  // namespace torsion

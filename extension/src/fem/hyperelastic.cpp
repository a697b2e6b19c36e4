#include "torsion/fem/hyperelastic.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "torsion/fem/corotated_element.h"
#include "torsion/fem/polar_rotation.h"

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

// The pair (i, j) of singular axes without k.
constexpr int kPairFirst[3] = {1, 2, 0};
constexpr int kPairSecond[3] = {2, 0, 1};

void signedSvd(const Eigen::Matrix3d& F, PrincipalTangent& t) {
  const SignedSvd svd = torsion::signedSvd(F);
  t.U = svd.U;
  t.V = svd.V;
  t.sigma = svd.sigma;
}

// The terms every law here shares: l'/2 (J - alpha)^2, whose gradient in sigma is
// pressure * (J / sigma_i) and whose pair quotients are +- pressure * sigma_k.
void addVolumetric(double lambda, double alpha, PrincipalTangent& t) {
  const Eigen::Vector3d& s = t.sigma;
  const double pressure = lambda * (s.prod() - alpha);
  const Eigen::Vector3d others(s(1) * s(2), s(0) * s(2), s(0) * s(1));  // J / sigma_i
  t.stretch += lambda * others * others.transpose();
  for (int k = 0; k < 3; ++k) {
    t.stretch(kPairFirst[k], kPairSecond[k]) += pressure * s(k);
    t.stretch(kPairSecond[k], kPairFirst[k]) += pressure * s(k);
  }
  t.rotation += pressure * s;
  t.shear -= pressure * s;
}

// Eigenvalues as `filter` leaves them (kExact: as they are).
Eigen::Vector3d filtered(const Eigen::Vector3d& eigenvalues, EigenvalueFilter filter) {
  switch (filter) {
    case EigenvalueFilter::kClamp:
      return eigenvalues.cwiseMax(0.0);
    case EigenvalueFilter::kMirror:
      return eigenvalues.cwiseAbs();
    case EigenvalueFilter::kExact:
      break;
  }
  return eigenvalues;
}

// The 3x3 stretch block with its eigenvalues filtered; unchanged when positive definite (the
// usual case: checked by its leading minors, no decomposition) or when `filter` keeps them.
Eigen::Matrix3d filterStretch(const Eigen::Matrix3d& H, EigenvalueFilter filter) {
  if (filter == EigenvalueFilter::kExact) return H;
  const double minor2 = H(0, 0) * H(1, 1) - H(0, 1) * H(1, 0);
  if (H(0, 0) > 0 && minor2 > 0 && H.determinant() > 0) return H;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(H);
  return eigen.eigenvectors() * filtered(eigen.eigenvalues(), filter).asDiagonal() *
         eigen.eigenvectors().transpose();
}

// The 9 eigenmodes' images on the tet's nodes 1-3 (node 0's is minus their sum: g_0 = -sum g_a):
// row m, columns 3 (a - 1) .. 3 a - 1 hold Q_m g_a; m = i the stretch mode U e_i e_i^T V^T,
// 3 + k the rotation and 6 + k the shear mode of the pair without k.
using ModeGradients = Eigen::Matrix<double, 9, 9>;
ModeGradients modeGradients(const PrincipalTangent& t, const Eigen::Matrix3d& rest_shape_inverse) {
  ModeGradients Z;
  const double half_root = std::sqrt(0.5);
  const Eigen::Matrix3d W = t.V.transpose() * rest_shape_inverse.transpose();  // column a: V^T g_a
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d w = W.col(a);
    for (int i = 0; i < 3; ++i)
      Z.block<1, 3>(i, 3 * a) = w(i) * t.U.col(i).transpose();
    for (int k = 0; k < 3; ++k) {
      const int i = kPairFirst[k], j = kPairSecond[k];
      const Eigen::Vector3d first = t.U.col(i) * w(j), second = t.U.col(j) * w(i);
      Z.block<1, 3>(3 + k, 3 * a) = half_root * (first - second).transpose();
      Z.block<1, 3>(6 + k, 3 * a) = half_root * (first + second).transpose();
    }
  }
  return Z;
}

// V Z^T D Z, D = diag(stretch block, rotation values, shear values): nodes 1-3 from the modes
// (the upper triangle, mirrored), node 0's rows and columns from translation invariance (the
// rows of a block column sum to zero), so that K is symmetric to the bit.
TetStiffness modeStiffness(const ModeGradients& Z, const Eigen::Matrix3d& stretch,
                           const Eigen::Vector3d& rotation, const Eigen::Vector3d& shear,
                           double volume) {
  ModeGradients DZ;
  DZ.topRows<3>() = volume * stretch * Z.topRows<3>();
  DZ.middleRows<3>(3) = (volume * rotation).asDiagonal() * Z.middleRows<3>(3);
  DZ.bottomRows<3>() = (volume * shear).asDiagonal() * Z.bottomRows<3>();
  TetStiffness K;
  for (int c = 0; c < 9; ++c) {
    for (int r = 0; r <= c; ++r) {
      K(3 + r, 3 + c) = Z.col(r).dot(DZ.col(c));
      K(3 + c, 3 + r) = K(3 + r, 3 + c);
    }
  }
  for (int c = 3; c < 12; ++c) {
    for (int r = 0; r < 3; ++r) {
      K(r, c) = -(K(3 + r, c) + K(6 + r, c) + K(9 + r, c));
      K(c, r) = K(r, c);
    }
  }
  const Eigen::Matrix3d corner = -(K.block<3, 3>(0, 3) + K.block<3, 3>(0, 6) + K.block<3, 3>(0, 9));
  K.topLeftCorner<3, 3>() = 0.5 * (corner + corner.transpose());
  return K;
}

template <typename Law>
HyperelasticTetForces energyAndForces(const Law& law, const Eigen::Matrix3d& F,
                                      const TetRestData& rest) {
  return {rest.volume * energyDensity(law, F), hyperelasticNodeForces(firstPiola(law, F), rest)};
}

template <typename Law>
HyperelasticTetResponse hyperelasticResponse(const Law& law,
                                             const std::array<Eigen::Vector3d, 4>& x,
                                             const TetRestData& rest, TetStiffnessKind kind) {
  const Eigen::Matrix3d F = deformationGradient(x, rest.rest_shape_inverse);
  HyperelasticTetResponse response;
  const HyperelasticTetForces forces = energyAndForces(law, F, rest);
  response.energy = forces.energy;
  response.forces = forces.forces;
  if (kind == TetStiffnessKind::kNone) return response;
  const PrincipalTangent t = principalTangent(law, F);
  const ModeGradients Z = modeGradients(t, rest.rest_shape_inverse);
  if (projectedAsked(kind)) {
    const EigenvalueFilter filter = projectionOf(kind);
    response.projected_stiffness =
        modeStiffness(Z, filterStretch(t.stretch, filter), filtered(t.rotation, filter),
                      filtered(t.shear, filter), rest.volume);
  }
  if (exactAsked(kind))
    response.exact_stiffness = modeStiffness(Z, t.stretch, t.rotation, t.shear, rest.volume);
  return response;
}

// The P2 element's modes, all four quadrature points stacked: rows 9 q .. 9 q + 8 are point q's
// nine modes (ordered as in modeGradients), columns 3 a .. 3 a + 2 their images Q_m g_qa on local
// node a (no node is eliminated: the ten gradients of a point sum to zero only to rounding).
using Tet10Modes = Eigen::Matrix<double, 9 * kTet10QuadraturePoints, 30>;

void tet10PointModes(const PrincipalTangent& t, const std::array<Eigen::Vector3d, 10>& g, int q,
                     Tet10Modes& Z) {
  const double half_root = std::sqrt(0.5);
  const int row = 9 * q;
  for (int a = 0; a < 10; ++a) {
    const Eigen::Vector3d w = t.V.transpose() * g[static_cast<size_t>(a)];  // V^T g_qa
    for (int i = 0; i < 3; ++i)
      Z.block<1, 3>(row + i, 3 * a) = w(i) * t.U.col(i).transpose();
    for (int k = 0; k < 3; ++k) {
      const int i = kPairFirst[k], j = kPairSecond[k];
      const Eigen::Vector3d first = t.U.col(i) * w(j), second = t.U.col(j) * w(i);
      Z.block<1, 3>(row + 3 + k, 3 * a) = half_root * (first - second).transpose();
      Z.block<1, 3>(row + 6 + k, 3 * a) = half_root * (first + second).transpose();
    }
  }
}

// Point q's rows of D Z (weight w = V / 4): the stretch block and the pair eigenvalues.
void tet10PointWeightedModes(const Tet10Modes& Z, int q, double weight,
                             const Eigen::Matrix3d& stretch, const Eigen::Vector3d& rotation,
                             const Eigen::Vector3d& shear, Tet10Modes& DZ) {
  const int row = 9 * q;
  DZ.middleRows<3>(row) = (weight * stretch) * Z.middleRows<3>(row);
  DZ.middleRows<3>(row + 3) = (weight * rotation).asDiagonal() * Z.middleRows<3>(row + 3);
  DZ.middleRows<3>(row + 6) = (weight * shear).asDiagonal() * Z.middleRows<3>(row + 6);
}

// sum_q w Z_q^T D_q Z_q = Z^T (D Z): the upper triangle, mirrored (symmetric to the bit).
Tet10Stiffness tet10ModeStiffness(const Tet10Modes& Z, const Tet10Modes& DZ) {
  Tet10Stiffness K;
  for (int c = 0; c < 30; ++c) {
    for (int r = 0; r <= c; ++r) {
      K(r, c) = Z.col(r).dot(DZ.col(c));
      K(c, r) = K(r, c);
    }
  }
  return K;
}

template <typename Law>
HyperelasticTet10Response hyperelasticTet10Response(const Law& law, const Tet10Vectors& x,
                                                    const QuadraticRestData& rest,
                                                    TetStiffnessKind kind) {
  HyperelasticTet10Response response;
  for (Eigen::Vector3d& f : response.forces)
    f.setZero();
  const bool projected = projectedAsked(kind), exact = exactAsked(kind);
  const double weight = rest.volume / kTet10QuadraturePoints;
  Tet10Modes Z, projected_modes, exact_modes;
  for (int q = 0; q < kTet10QuadraturePoints; ++q) {
    const std::array<Eigen::Vector3d, 10>& g = rest.gradients[static_cast<size_t>(q)];
    const Eigen::Matrix3d F = quadraticDeformationGradient(x, rest, q);
    response.energy += weight * energyDensity(law, F);
    const Eigen::Matrix3d P = weight * firstPiola(law, F);
    for (size_t a = 0; a < 10; ++a)
      response.forces[a].noalias() -= P * g[a];
    if (kind == TetStiffnessKind::kNone) continue;
    const PrincipalTangent t = principalTangent(law, F);
    tet10PointModes(t, g, q, Z);
    if (projected) {
      const EigenvalueFilter filter = projectionOf(kind);
      tet10PointWeightedModes(Z, q, weight, filterStretch(t.stretch, filter),
                              filtered(t.rotation, filter), filtered(t.shear, filter),
                              projected_modes);
    }
    if (exact) tet10PointWeightedModes(Z, q, weight, t.stretch, t.rotation, t.shear, exact_modes);
  }
  if (projected) response.projected_stiffness = tet10ModeStiffness(Z, projected_modes);
  if (exact) response.exact_stiffness = tet10ModeStiffness(Z, exact_modes);
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

PrincipalTangent principalTangent(const StableNeoHookean& law, const Eigen::Matrix3d& F) {
  PrincipalTangent t;
  signedSvd(F, t);
  const Eigen::Vector3d& s = t.sigma;
  // mu'/2 (I_C - 3) [- mu'/2 log(I_C + 1)]: psi_i = shear sigma_i, shear = mu' [(1 - 1/(I_C + 1))].
  const double ic1 = s.squaredNorm() + 1.0;
  const double shear = law.log_term ? law.mu * (1.0 - 1.0 / ic1) : law.mu;
  const double curvature = law.log_term ? 2.0 * law.mu / (ic1 * ic1) : 0.0;
  t.stretch = shear * Eigen::Matrix3d::Identity() + curvature * s * s.transpose();
  t.rotation = Eigen::Vector3d::Constant(shear);
  t.shear = Eigen::Vector3d::Constant(shear);
  addVolumetric(law.lambda, law.alpha, t);
  return t;
}

PrincipalTangent principalTangent(const MooneyRivlin& law, const Eigen::Matrix3d& F) {
  PrincipalTangent t;
  signedSvd(F, t);
  const Eigen::Vector3d& s = t.sigma;
  const Eigen::Vector3d sq = s.cwiseAbs2();
  // C1 I_C + C2 II_C: psi_i = 2 C1 s_i + 2 C2 s_i (s_j^2 + s_k^2).
  for (int i = 0; i < 3; ++i) {
    t.stretch(i, i) = 2.0 * law.c1 + 2.0 * law.c2 * (sq.sum() - sq(i));
    for (int j = 0; j < 3; ++j)
      if (j != i) t.stretch(i, j) = 4.0 * law.c2 * s(i) * s(j);
  }
  for (int k = 0; k < 3; ++k) {
    const double product = s(kPairFirst[k]) * s(kPairSecond[k]);
    t.rotation(k) = 2.0 * law.c1 + 2.0 * law.c2 * (product + sq(k));
    t.shear(k) = 2.0 * law.c1 + 2.0 * law.c2 * (sq(k) - product);
  }
  addVolumetric(law.lambda, law.alpha, t);
  return t;
}

PiolaTangent tangentOf(const PrincipalTangent& t, EigenvalueFilter filter) {
  const Eigen::Matrix3d stretch = filterStretch(t.stretch, filter);
  const Eigen::Vector3d rotations = filtered(t.rotation, filter),
                        shears = filtered(t.shear, filter);
  std::array<PiolaVector, 9> modes;
  std::array<Eigen::Matrix3d, 9> Q;
  for (int i = 0; i < 3; ++i)
    Q[static_cast<size_t>(i)] = t.U.col(i) * t.V.col(i).transpose();
  for (int k = 0; k < 3; ++k) {
    const int i = kPairFirst[k], j = kPairSecond[k];
    const Eigen::Matrix3d a = t.U.col(i) * t.V.col(j).transpose();
    const Eigen::Matrix3d b = t.U.col(j) * t.V.col(i).transpose();
    Q[static_cast<size_t>(3 + k)] = std::sqrt(0.5) * (a - b);
    Q[static_cast<size_t>(6 + k)] = std::sqrt(0.5) * (a + b);
  }
  for (size_t m = 0; m < 9; ++m)
    modes[m] = Eigen::Map<const PiolaVector>(Q[m].data());
  PiolaTangent A = PiolaTangent::Zero();
  for (size_t i = 0; i < 3; ++i)
    for (size_t j = 0; j < 3; ++j)
      A += stretch(static_cast<int>(i), static_cast<int>(j)) * modes[i] * modes[j].transpose();
  for (int k = 0; k < 3; ++k) {
    const double rotation = rotations(k), shear = shears(k);
    A += rotation * modes[static_cast<size_t>(3 + k)] *
         modes[static_cast<size_t>(3 + k)].transpose();
    A += shear * modes[static_cast<size_t>(6 + k)] * modes[static_cast<size_t>(6 + k)].transpose();
  }
  return A;
}

HyperelasticTetResponse hyperelasticTet(const StableNeoHookean& law,
                                        const std::array<Eigen::Vector3d, 4>& x,
                                        const TetRestData& rest, TetStiffnessKind kind) {
  return hyperelasticResponse(law, x, rest, kind);
}

HyperelasticTetResponse hyperelasticTet(const MooneyRivlin& law,
                                        const std::array<Eigen::Vector3d, 4>& x,
                                        const TetRestData& rest, TetStiffnessKind kind) {
  return hyperelasticResponse(law, x, rest, kind);
}

HyperelasticTetForces hyperelasticTetForces(const StableNeoHookean& law,
                                            const std::array<Eigen::Vector3d, 4>& x,
                                            const TetRestData& rest) {
  return energyAndForces(law, deformationGradient(x, rest.rest_shape_inverse), rest);
}

HyperelasticTetForces hyperelasticTetForces(const MooneyRivlin& law,
                                            const std::array<Eigen::Vector3d, 4>& x,
                                            const TetRestData& rest) {
  return energyAndForces(law, deformationGradient(x, rest.rest_shape_inverse), rest);
}

HyperelasticTet10Response hyperelasticTet10(const StableNeoHookean& law, const Tet10Vectors& x,
                                            const QuadraticRestData& rest, TetStiffnessKind kind) {
  return hyperelasticTet10Response(law, x, rest, kind);
}

HyperelasticTet10Response hyperelasticTet10(const MooneyRivlin& law, const Tet10Vectors& x,
                                            const QuadraticRestData& rest, TetStiffnessKind kind) {
  return hyperelasticTet10Response(law, x, rest, kind);
}

}  // namespace torsion

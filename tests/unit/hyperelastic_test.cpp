// Hyperelastic laws (fem/hyperelastic.h): stress and tangent are the derivatives of the energy
// (central differences), zero stress at rest and frame invariance, the small-strain limit is
// linear elasticity of (E, nu), uniaxial tension and simple shear against the closed forms of
// rubber elasticity, the closed-form eigensystem rebuilds the tangent and its projection (a
// numerical 9x9 decomposition as reference, also at repeated and zero singular values), the
// projected tangent is positive semi-definite (also inverted), and the linear and quadratic tets'
// forces and stiffness are the derivatives of their energy (the quadratic tet's stiffness at rest
// is the corotated P2 element's). Figures: docs/materials.md.
#include "torsion/fem/hyperelastic.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "torsion/mesh/quadratic_tet_mesh.h"

// A named namespace: its helpers cannot clash with another source's in a unity batch.
namespace torsion::hyperelastic_test {

using Energy = std::function<double(const Eigen::Matrix3d&)>;
using Stress = std::function<Eigen::Matrix3d(const Eigen::Matrix3d&)>;
using Tangent = std::function<PiolaTangent(const Eigen::Matrix3d&)>;
using Principal = std::function<PrincipalTangent(const Eigen::Matrix3d&)>;

constexpr double kE = 1e5;

// One law behind std::function, so that every test runs over all of them.
struct Law {
  const char* name;
  Energy psi;
  Stress piola;
  Tangent tangent;
  Principal principal;
};

template <typename L>
Law wrap(const char* name, const L& law) {
  return {name, [law](const Eigen::Matrix3d& F) { return energyDensity(law, F); },
          [law](const Eigen::Matrix3d& F) { return firstPiola(law, F); },
          [law](const Eigen::Matrix3d& F) { return firstPiolaDerivative(law, F); },
          [law](const Eigen::Matrix3d& F) { return principalTangent(law, F); }};
}

std::vector<Law> laws(double nu) {
  return {wrap("stable neo-Hookean", StableNeoHookean::fromYoungPoisson(kE, nu)),
          wrap("stable neo-Hookean with log", StableNeoHookean::fromYoungPoisson(kE, nu, true)),
          wrap("Mooney-Rivlin", MooneyRivlin::fromYoungPoisson(kE, nu, 0.3))};
}

double shearModulus(double nu) {
  return kE / (2 * (1 + nu));
}
double lameLambda(double nu) {
  return kE * nu / ((1 + nu) * (1 - 2 * nu));
}

// Deformation gradients: near rest, stretched, sheared, and inverted (det < 0).
std::vector<Eigen::Matrix3d> sampleGradients() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  std::vector<Eigen::Matrix3d> Fs;
  for (int k = 0; k < 6; ++k) {
    Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
    for (int i = 0; i < 9; ++i)
      F(i % 3, i / 3) += u(rng);
    Fs.push_back(F);
  }
  Fs.push_back(Eigen::Vector3d(2.0, 0.7, 0.8).asDiagonal());
  Eigen::Matrix3d inverted = Fs[0];
  inverted.col(2) *= -0.6;
  Fs.push_back(inverted);
  Fs.push_back(Eigen::Vector3d(1.1, 0.9, -0.3).asDiagonal());
  return Fs;
}

Eigen::Matrix3d unit(int j) {
  Eigen::Matrix3d E = Eigen::Matrix3d::Zero();
  E(j % 3, j / 3) = 1.0;
  return E;
}

// Central differences, step h = 1e-5 (F is O(1)): truncation h^2/6 Psi''' ~ 1e-11 and rounding
// eps |Psi| / h ~ 1e-11 relative to the stress scale mu, five orders under the 1e-6 tolerance
// (a wrong term is an O(1) error).
constexpr double kStep = 1e-5;
constexpr double kDifferenceTolerance = 1e-6;

TEST(HyperelasticDerivatives, StressAndTangentAreCentralDifferences) {
  for (double nu : {0.0, 0.3, 0.45}) {
    const double scale = shearModulus(nu) + lameLambda(nu);
    for (const Law& law : laws(nu)) {
      for (const Eigen::Matrix3d& F : sampleGradients()) {
        const Eigen::Matrix3d P = law.piola(F);
        const PiolaTangent A = law.tangent(F);
        for (int j = 0; j < 9; ++j) {
          const Eigen::Matrix3d dF = kStep * unit(j);
          const double dpsi = (law.psi(F + dF) - law.psi(F - dF)) / (2 * kStep);
          EXPECT_NEAR(dpsi, P(j % 3, j / 3), kDifferenceTolerance * scale) << law.name << " " << j;
          const Eigen::Matrix3d dP = (law.piola(F + dF) - law.piola(F - dF)) / (2 * kStep);
          const Eigen::Map<const Eigen::Matrix<double, 9, 1>> column(dP.data());
          EXPECT_LE((column - A.col(j)).norm(), kDifferenceTolerance * scale)
              << law.name << " column " << j << "\n"
              << F;
        }
      }
    }
  }
}

Eigen::Matrix3d rotation(double angle, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

TEST(HyperelasticInvariance, ZeroAtRestAndUnderRotations) {
  for (double nu : {0.0, 0.3, 0.499}) {
    for (const Law& law : laws(nu)) {
      const double mu = shearModulus(nu);
      const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
      EXPECT_NEAR(law.psi(I), 0.0, 1e-12 * mu) << law.name;
      EXPECT_LE(law.piola(I).norm(), 1e-12 * mu) << law.name;
      const Eigen::Matrix3d R = rotation(1.1, Eigen::Vector3d(1, -2, 0.5));
      EXPECT_NEAR(law.psi(R), 0.0, 1e-10 * mu) << law.name;
      EXPECT_LE(law.piola(R).norm(), 1e-10 * mu) << law.name;
      for (const Eigen::Matrix3d& F : sampleGradients()) {
        const double scale = mu * (1 + F.squaredNorm() * F.squaredNorm());
        EXPECT_NEAR(law.psi(R * F), law.psi(F), 1e-12 * scale) << law.name;
        EXPECT_LE((law.piola(R * F) - R * law.piola(F)).norm(), 1e-12 * scale) << law.name;
      }
    }
  }
}

// |P(I + eps H) - sigma(eps sym H)| for linear elasticity's sigma = 2 mu e + lambda tr(e) I.
double smallStrainError(const Law& law, double nu, const Eigen::Matrix3d& H, double eps) {
  const Eigen::Matrix3d e = eps * 0.5 * (H + H.transpose());
  const Eigen::Matrix3d sigma =
      2 * shearModulus(nu) * e + lameLambda(nu) * e.trace() * Eigen::Matrix3d::Identity();
  return (law.piola(Eigen::Matrix3d::Identity() + eps * H) - sigma).norm();
}

TEST(HyperelasticSmallStrain, StressIsLinearElasticityToSecondOrder) {
  Eigen::Matrix3d H;
  H << 0.3, -0.7, 0.2, 0.4, -0.1, 0.9, -0.5, 0.6, 0.8;  // strain and rotation
  for (double nu : {0.0, 0.25, 0.45, 0.499}) {
    for (const Law& law : laws(nu)) {
      const double coarse = smallStrainError(law, nu, H, 1e-3);
      const double fine = smallStrainError(law, nu, H, 1e-4);
      // O(eps^2): a tenth of the strain leaves a hundredth of the error (the O(eps^3) term moves
      // the ratio by about eps = 1e-3 relative), and the error is small beside sigma itself.
      EXPECT_NEAR(coarse / fine, 100.0, 5.0) << law.name << " nu " << nu;
      const double sigma_scale = 1e-4 * (shearModulus(nu) + lameLambda(nu));
      EXPECT_LT(fine, 1e-2 * sigma_scale) << law.name << " nu " << nu;
    }
  }
}

// The lateral stretch s of F = diag(l, s, s) with P_22 = 0 (Newton on the law's tangent).
double lateralStretch(const Law& law, double stretch) {
  double s = 1.0 / std::sqrt(stretch);
  for (int it = 0; it < 50; ++it) {
    const Eigen::Matrix3d F = Eigen::Vector3d(stretch, s, s).asDiagonal();
    const PiolaTangent A = law.tangent(F);
    s -= law.piola(F)(1, 1) / (A(4, 4) + A(4, 8));
  }
  return s;
}

TEST(HyperelasticUniaxial, NeoHookeanNominalStressAtStretchTwo) {
  const double nu = 0.499;
  const double mu = shearModulus(nu);
  const StableNeoHookean snh = StableNeoHookean::fromYoungPoisson(kE, nu);
  const Law law = wrap("stable neo-Hookean", snh);
  const double l = 2.0;
  const double s = lateralStretch(law, l);
  const Eigen::Matrix3d F = Eigen::Vector3d(l, s, s).asDiagonal();
  const Eigen::Matrix3d P = law.piola(F);
  ASSERT_LE(std::abs(P(1, 1)), 1e-9 * mu);
  // Closed form of this law: P_22 = 0 gives l' (J - alpha) = -mu / l, so
  // J = 1 + (mu / l')(1 - 1 / l) and P_11 = mu (l - J / l^2).
  const double J = 1 + mu / snh.lambda * (1 - 1 / l);
  EXPECT_NEAR(F.determinant(), J, 1e-12);
  EXPECT_NEAR(P(0, 0), mu * (l - J / (l * l)), 1e-10 * mu);
  // Against the incompressible mu (l - l^-2): off by mu (J - 1) / l^2, relative
  // (mu / l')(1 - 1/l) / (l^3 - 1) = 1 / 7000 at l' = 500 mu (nu = 0.499), l = 2.
  const double incompressible = mu * (l - 1 / (l * l));
  const double bound = (mu / snh.lambda) * (1 - 1 / l) / (l * l * l - 1);
  EXPECT_NEAR(bound, 1.0 / 7000, 1e-6);
  EXPECT_LE(std::abs(P(0, 0) / incompressible - 1), 1.01 * bound);
}

TEST(HyperelasticUniaxial, MooneyRivlinNominalStressAtStretchTwo) {
  const double nu = 0.499;
  const MooneyRivlin mr = MooneyRivlin::fromYoungPoisson(kE, nu, 0.3);
  const Law law = wrap("Mooney-Rivlin", mr);
  const double l = 2.0;
  const double s = lateralStretch(law, l);
  const Eigen::Matrix3d F = Eigen::Vector3d(l, s, s).asDiagonal();
  const Eigen::Matrix3d P = law.piola(F);
  ASSERT_LE(std::abs(P(1, 1)), 1e-9 * shearModulus(nu));
  // Incompressible Mooney-Rivlin: 2 (C1 + C2 / l)(l - l^-2). With q = s^2 = J / l, P_22 = 0 gives
  // P_11(q) = 2 C1 l + q (4 C2 l - (2 C1 + 2 C2 l^2) / l) - 2 C2 q^2 / l, so the volume change
  // J - 1 = O(mu / l') moves it from q = 1 / l by (J - 1) / l (2 C2 l - 2 C1 / l - 4 C2 / l^2) to
  // first order (here J - 1 = 5.5e-4, relative 1.8e-5), the rest O((J - 1)^2).
  const double incompressible = 2 * (mr.c1 + mr.c2 / l) * (l - 1 / (l * l));
  const double dJ = F.determinant() - 1;
  EXPECT_GT(dJ, 0.0);
  EXPECT_LT(dJ, 3 * shearModulus(nu) / mr.lambda);
  const double first_order =
      dJ / l * (2 * mr.c2 * l - 2 * mr.c1 / l - 4 * mr.c2 / (l * l)) / incompressible;
  EXPECT_NEAR(P(0, 0) / incompressible - 1, first_order, 10 * dJ * dJ);
  EXPECT_LE(std::abs(P(0, 0) / incompressible - 1), 1e-4);
}

// Cauchy stress sigma = P F^T / J in simple shear F = I + gamma e_1 e_2^T (J = 1).
Eigen::Matrix3d shearStress(const Law& law, double gamma) {
  Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
  F(0, 1) = gamma;
  return law.piola(F) * F.transpose();
}

TEST(HyperelasticShear, ShearStressAndNormalStressDifferences) {
  const double nu = 0.45;
  const double mu = shearModulus(nu);
  const Law snh = wrap("snh", StableNeoHookean::fromYoungPoisson(kE, nu));
  const StableNeoHookean with_log = StableNeoHookean::fromYoungPoisson(kE, nu, true);
  const Law snh_log = wrap("snh log", with_log);
  const MooneyRivlin mr = MooneyRivlin::fromYoungPoisson(kE, nu, 0.3);
  const Law mooney = wrap("mr", mr);
  for (double g : {0.1, 0.5, 1.0, 2.0}) {
    const Eigen::Matrix3d a = shearStress(snh, g);
    EXPECT_NEAR(a(0, 1), mu * g, 1e-12 * mu);
    EXPECT_NEAR(a(0, 0) - a(1, 1), mu * g * g, 1e-12 * mu);
    EXPECT_NEAR(a(1, 1) - a(2, 2), 0.0, 1e-12 * mu);
    const Eigen::Matrix3d b = shearStress(snh_log, g);
    EXPECT_NEAR(b(0, 1), with_log.mu * g * (3 + g * g) / (4 + g * g), 1e-12 * mu);
    const Eigen::Matrix3d c = shearStress(mooney, g);
    EXPECT_NEAR(c(0, 1), 2 * (mr.c1 + mr.c2) * g, 1e-12 * mu);
    EXPECT_NEAR(c(0, 0) - c(1, 1), 2 * (mr.c1 + mr.c2) * g * g, 1e-12 * mu);
    EXPECT_NEAR(c(1, 1) - c(2, 2), -2 * mr.c2 * g * g, 1e-12 * mu);
  }
}

double smallestEigenvalue(const PiolaTangent& A) {
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A).eigenvalues()(0);
}

// The reference filters: a numerical 9x9 eigen-decomposition, its eigenvalues clamped at zero or
// replaced by their magnitudes.
PiolaTangent numericalFilter(const PiolaTangent& A, EigenvalueFilter filter) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(0.5 * (A + A.transpose()));
  const Eigen::Matrix<double, 9, 1> values = filter == EigenvalueFilter::kMirror
                                                 ? eigen.eigenvalues().cwiseAbs().eval()
                                                 : eigen.eigenvalues().cwiseMax(0.0).eval();
  return eigen.eigenvectors() * values.asDiagonal() * eigen.eigenvectors().transpose();
}

// Gradients where the singular values repeat or vanish, the closed forms' delicate cases (the
// quotients (psi_i -+ psi_j) / (s_i -+ s_j) taken as polynomials), and a plain rotation.
std::vector<Eigen::Matrix3d> degenerateGradients() {
  const Eigen::Matrix3d R = rotation(0.9, Eigen::Vector3d(1, -2, 0.5));
  const Eigen::Matrix3d Q = rotation(-0.4, Eigen::Vector3d(0.3, 0.2, 1));
  std::vector<Eigen::Matrix3d> Fs;
  for (const Eigen::Vector3d& s :
       {Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(1.5, 1.5, 0.6), Eigen::Vector3d(0.8, 0.8, 0.8),
        Eigen::Vector3d(1.3, 0.7, 0.0), Eigen::Vector3d(1.2, 1.2, -1.2),
        Eigen::Vector3d(1.0, 1.0 + 1e-9, 1.0 - 1e-9)})
    Fs.push_back(R * s.asDiagonal() * Q);
  return Fs;
}

TEST(HyperelasticEigensystem, ClosedFormsRebuildTheTangentAndItsFilteredForms) {
  int clamped = 0;
  for (double nu : {0.0, 0.3, 0.45, 0.499}) {
    for (const Law& law : laws(nu)) {
      std::vector<Eigen::Matrix3d> Fs = sampleGradients();
      for (const Eigen::Matrix3d& F : degenerateGradients())
        Fs.push_back(F);
      for (const Eigen::Matrix3d& F : Fs) {
        const PrincipalTangent t = law.principal(F);
        const PiolaTangent A = law.tangent(F);
        // The frame: rotations, F = U diag(s) V^T, s signed with det F.
        EXPECT_NEAR(t.U.determinant(), 1.0, 1e-12);
        EXPECT_NEAR(t.V.determinant(), 1.0, 1e-12);
        EXPECT_LE((t.U * t.sigma.asDiagonal() * t.V.transpose() - F).norm(), 1e-12 * F.norm());
        // Exact: the closed forms give the tangent of the derivative test above (an error in a
        // quotient or a mode is O(mu)); clamped and mirrored: the numerical decomposition's.
        EXPECT_LE((tangentOf(t, EigenvalueFilter::kExact) - A).norm(), 1e-10 * A.norm())
            << law.name << "\n"
            << F;
        for (EigenvalueFilter filter : {EigenvalueFilter::kClamp, EigenvalueFilter::kMirror}) {
          const PiolaTangent filtered = tangentOf(t, filter);
          EXPECT_LE((filtered - numericalFilter(A, filter)).norm(), 1e-9 * A.norm())
              << law.name << "\n"
              << F;
          EXPECT_GE(smallestEigenvalue(filtered), -1e-12 * A.norm()) << law.name << "\n" << F;
        }
        if (smallestEigenvalue(A) < -1e-9 * A.norm()) ++clamped;
      }
      // At rest the tangent is linear elasticity's (PSD, zero on the 3 rotations): unchanged.
      const PrincipalTangent rest = law.principal(Eigen::Matrix3d::Identity());
      for (EigenvalueFilter filter : {EigenvalueFilter::kClamp, EigenvalueFilter::kMirror}) {
        EXPECT_LE((tangentOf(rest, filter) - tangentOf(rest, EigenvalueFilter::kExact)).norm(),
                  1e-12 * tangentOf(rest, EigenvalueFilter::kExact).norm());
      }
    }
  }
  EXPECT_GT(clamped, 0);  // the samples do exercise the clamp
}

TEST(HyperelasticProjection, InvertedGradientGivesFiniteEnergyStressAndPsdTangent) {
  const Eigen::Matrix3d R = rotation(0.7, Eigen::Vector3d(0.2, 1, -0.4));
  for (double J : {-0.5, -1e-3, 0.0}) {
    const Eigen::Matrix3d F = R * Eigen::Vector3d(1.2, 0.9, J / 1.08).asDiagonal();
    for (const Law& law : laws(0.45)) {
      EXPECT_TRUE(std::isfinite(law.psi(F)));
      EXPECT_GT(law.psi(F), 0.0) << law.name;
      EXPECT_TRUE(law.piola(F).allFinite());
      const PiolaTangent projected = tangentOf(law.principal(F), EigenvalueFilter::kClamp);
      ASSERT_TRUE(projected.allFinite());
      EXPECT_GE(smallestEigenvalue(projected), -1e-12 * projected.norm()) << law.name;
    }
  }
}

using Nodes = std::array<Eigen::Vector3d, 4>;

template <typename L>
void checkTet(const L& law, const Nodes& x, const TetRestData& rest) {
  const HyperelasticTetResponse r =
      hyperelasticTet(law, x, rest, TetStiffnessKind::kProjectedAndExact);
  const HyperelasticTetResponse exact = hyperelasticTet(law, x, rest, TetStiffnessKind::kExact);
  // Either stiffness alone has the bits it has beside the other (the pass relies on it).
  EXPECT_EQ(hyperelasticTet(law, x, rest, TetStiffnessKind::kProjected).projected_stiffness,
            r.projected_stiffness);
  EXPECT_EQ(exact.exact_stiffness, r.exact_stiffness);
  double force_scale = 0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), torque = Eigen::Vector3d::Zero();
  for (size_t a = 0; a < 4; ++a) {
    force_scale += r.forces[a].norm();
    sum += r.forces[a];
    torque += x[a].cross(r.forces[a]);
  }
  ASSERT_GT(force_scale, 0.0);
  EXPECT_LE(sum.norm(), 1e-12 * force_scale);
  EXPECT_LE(torque.norm(), 1e-12 * force_scale * 2.0);  // |x| < 2
  const double h = 1e-6;                                // node positions are O(1) m
  for (int k = 0; k < 12; ++k) {
    Nodes plus = x, minus = x;
    plus[static_cast<size_t>(k / 3)][k % 3] += h;
    minus[static_cast<size_t>(k / 3)][k % 3] -= h;
    const HyperelasticTetResponse p = hyperelasticTet(law, plus, rest, TetStiffnessKind::kNone);
    const HyperelasticTetResponse m = hyperelasticTet(law, minus, rest, TetStiffnessKind::kNone);
    const double dE = (p.energy - m.energy) / (2 * h);
    EXPECT_NEAR(r.forces[static_cast<size_t>(k / 3)][k % 3], -dE, 1e-6 * force_scale);
    for (int i = 0; i < 12; ++i) {
      const double df =
          p.forces[static_cast<size_t>(i / 3)][i % 3] - m.forces[static_cast<size_t>(i / 3)][i % 3];
      EXPECT_NEAR(exact.exact_stiffness(i, k), -df / (2 * h), 1e-6 * exact.exact_stiffness.norm());
    }
  }
  const TetStiffness& K = r.projected_stiffness;
  EXPECT_EQ(K, K.transpose());
  EXPECT_EQ(r.exact_stiffness, r.exact_stiffness.transpose());
  const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(K).eigenvalues()(0);
  EXPECT_GE(smallest, -1e-12 * K.norm());
  // The projection only removes: K_exact - K_projected is negative semi-definite.
  const double largest_removed =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(r.exact_stiffness - K).eigenvalues()(11);
  EXPECT_LE(largest_removed, 1e-12 * K.norm());
}

TEST(HyperelasticTet, ForcesAndStiffnessAreDerivativesOfTheEnergy) {
  const Nodes X = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0.1, 0),
                   Eigen::Vector3d(0.2, 0.9, 0.1), Eigen::Vector3d(0.1, 0.2, 1.1)};
  const TetRestData rest = tetRestData(X);
  Nodes stretched = X, inverted = X;
  stretched[1] += Eigen::Vector3d(0.4, -0.1, 0.2);
  stretched[3] += Eigen::Vector3d(-0.2, 0.3, 0.3);
  inverted[3] = Eigen::Vector3d(0.2, 0.3, -0.4);  // through face (0, 1, 2)
  for (const Nodes& x : {stretched, inverted}) {
    checkTet(StableNeoHookean::fromYoungPoisson(kE, 0.3), x, rest);
    checkTet(StableNeoHookean::fromYoungPoisson(kE, 0.3, true), x, rest);
    checkTet(MooneyRivlin::fromConstants(2e4, 1e4, 3e5), x, rest);
  }
  // At rest: zero forces, zero energy.
  const HyperelasticTetResponse at_rest =
      hyperelasticTet(StableNeoHookean::fromYoungPoisson(kE, 0.45), X, rest);
  EXPECT_NEAR(at_rest.energy, 0.0, 1e-12 * kE * rest.volume);
  for (const Eigen::Vector3d& f : at_rest.forces)
    EXPECT_LE(f.norm(), 1e-10 * kE);
}

// ---- The quadratic (10-node) tet ----

using Nodes10 = Tet10Vectors;

// Corners X, mid-edge nodes at the edge midpoints (the straight-sided rest element).
Nodes10 tet10Nodes(const Nodes& X) {
  Nodes10 x;
  for (size_t a = 0; a < 4; ++a)
    x[a] = X[a];
  for (size_t e = 0; e < 6; ++e) {
    x[4 + e] = 0.5 * (X[static_cast<size_t>(kTet10Edges[e][0])] +
                      X[static_cast<size_t>(kTet10Edges[e][1])]);
  }
  return x;
}

QuadraticRestData tet10Rest(const Nodes& X) {
  const TetRestData corner = tetRestData(X);
  return quadraticRestData(corner.rest_shape_inverse, corner.volume);
}

template <typename L>
void checkTet10(const L& law, const Nodes10& x, const QuadraticRestData& rest) {
  const HyperelasticTet10Response r =
      hyperelasticTet10(law, x, rest, TetStiffnessKind::kProjectedAndExact);
  // Either stiffness alone has the bits it has beside the other (the pass relies on it).
  EXPECT_EQ(hyperelasticTet10(law, x, rest, TetStiffnessKind::kProjected).projected_stiffness,
            r.projected_stiffness);
  EXPECT_EQ(hyperelasticTet10(law, x, rest, TetStiffnessKind::kExact).exact_stiffness,
            r.exact_stiffness);
  double force_scale = 0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), torque = Eigen::Vector3d::Zero();
  for (size_t a = 0; a < 10; ++a) {
    force_scale += r.forces[a].norm();
    sum += r.forces[a];
    torque += x[a].cross(r.forces[a]);
  }
  ASSERT_GT(force_scale, 0.0);
  EXPECT_LE(sum.norm(), 1e-12 * force_scale);
  EXPECT_LE(torque.norm(), 1e-12 * force_scale * 2.0);  // |x| < 2
  // Central differences, step 1e-6 m on O(1) m positions: truncation (h^2 / 6) E^(3) ~ 1e-13 and
  // rounding eps |E| / h ~ 1e-10 relative to the force scale, four orders under the tolerance.
  const double h = 1e-6;
  const double stiffness_scale = r.exact_stiffness.norm();
  for (int k = 0; k < 30; ++k) {
    Nodes10 plus = x, minus = x;
    plus[static_cast<size_t>(k / 3)][k % 3] += h;
    minus[static_cast<size_t>(k / 3)][k % 3] -= h;
    const HyperelasticTet10Response p = hyperelasticTet10(law, plus, rest, TetStiffnessKind::kNone);
    const HyperelasticTet10Response m =
        hyperelasticTet10(law, minus, rest, TetStiffnessKind::kNone);
    const double dE = (p.energy - m.energy) / (2 * h);
    EXPECT_NEAR(r.forces[static_cast<size_t>(k / 3)][k % 3], -dE, 1e-6 * force_scale);
    for (int i = 0; i < 30; ++i) {
      const double df =
          p.forces[static_cast<size_t>(i / 3)][i % 3] - m.forces[static_cast<size_t>(i / 3)][i % 3];
      EXPECT_NEAR(r.exact_stiffness(i, k), -df / (2 * h), 1e-6 * stiffness_scale)
          << "entry " << i << ", " << k;
    }
  }
  const Tet10Stiffness& K = r.projected_stiffness;
  EXPECT_EQ(K, K.transpose());
  EXPECT_EQ(r.exact_stiffness, r.exact_stiffness.transpose());
  const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(K).eigenvalues()(0);
  EXPECT_GE(smallest, -1e-12 * K.norm());
  // The projection only removes: K_exact - K_projected is negative semi-definite.
  const double largest_removed =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(r.exact_stiffness - K).eigenvalues()(29);
  EXPECT_LE(largest_removed, 1e-12 * K.norm());
}

Nodes tet10Corners() {
  return {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0.1, 0), Eigen::Vector3d(0.2, 0.9, 0.1),
          Eigen::Vector3d(0.1, 0.2, 1.1)};
}

TEST(HyperelasticTet10, ForcesAndStiffnessAreDerivativesOfTheEnergy) {
  const Nodes X = tet10Corners();
  const QuadraticRestData rest = tet10Rest(X);
  const Nodes10 at_rest = tet10Nodes(X);
  // Distorted: every node moved differently (curved edges: F differs at each quadrature point).
  Nodes10 distorted = at_rest;
  std::mt19937 random(7);
  std::uniform_real_distribution<double> offset(-0.12, 0.12);
  for (Eigen::Vector3d& p : distorted)
    p += Eigen::Vector3d(offset(random), offset(random), offset(random));
  // Stretched: 40 % along x, 15 % lateral contraction, a shear, and one mid-edge node bent.
  Eigen::Matrix3d G;
  G << 1.4, 0.2, 0, 0, 0.85, 0.1, 0, 0, 0.85;
  Nodes10 stretched;
  for (size_t a = 0; a < 10; ++a)
    stretched[a] = G * at_rest[a];
  stretched[6] += Eigen::Vector3d(0.05, -0.08, 0.02);
  for (const Nodes10& x : {distorted, stretched}) {
    checkTet10(StableNeoHookean::fromYoungPoisson(kE, 0.3), x, rest);
    checkTet10(StableNeoHookean::fromYoungPoisson(kE, 0.45, true), x, rest);
    checkTet10(MooneyRivlin::fromConstants(2e4, 1e4, 3e5), x, rest);
  }
  // At rest, and moved rigidly: zero energy, zero forces.
  const Eigen::Matrix3d R = rotation(0.9, Eigen::Vector3d(1, -0.3, 0.5));
  Nodes10 moved;
  for (size_t a = 0; a < 10; ++a)
    moved[a] = R * at_rest[a] + Eigen::Vector3d(0.3, -1, 2);
  for (const Nodes10& x : {at_rest, moved}) {
    const HyperelasticTet10Response r =
        hyperelasticTet10(MooneyRivlin::fromYoungPoisson(kE, 0.45, 0.3), x, rest);
    EXPECT_NEAR(r.energy, 0.0, 1e-12 * kE * rest.volume);
    for (const Eigen::Vector3d& f : r.forces)
      EXPECT_LE(f.norm(), 1e-10 * kE);
  }
}

// At rest every law's tangent is linear elasticity of (E, nu), and both P2 elements use the same
// 4-point rule: the hyperelastic tet10 stiffness is the corotated one (quadratic_element.h) to
// rounding, also for a rotated element (then the corotated one with that R).
TEST(HyperelasticTet10, StiffnessAtRestIsTheCorotatedElementStiffness) {
  const Nodes X = tet10Corners();
  const QuadraticRestData rest = tet10Rest(X);
  const Eigen::Matrix3d R = rotation(0.6, Eigen::Vector3d(0.2, 1, -0.4));
  Nodes10 x = tet10Nodes(X);
  for (Eigen::Vector3d& p : x)
    p = R * p;
  for (double nu : {0.3, 0.45, 0.499}) {
    Tet10Stiffness corotated;
    for (int a = 0; a < 10; ++a)
      for (int b = 0; b < 10; ++b)
        corotated.block<3, 3>(3 * a, 3 * b) =
            quadraticStiffnessBlock(R, rest, shearModulus(nu), lameLambda(nu), a, b);
    const std::vector<HyperelasticTet10Response> responses = {
        hyperelasticTet10(StableNeoHookean::fromYoungPoisson(kE, nu), x, rest,
                          TetStiffnessKind::kProjectedAndExact),
        hyperelasticTet10(StableNeoHookean::fromYoungPoisson(kE, nu, true), x, rest,
                          TetStiffnessKind::kProjectedAndExact),
        hyperelasticTet10(MooneyRivlin::fromYoungPoisson(kE, nu, 0.3), x, rest,
                          TetStiffnessKind::kProjectedAndExact)};
    for (const HyperelasticTet10Response& r : responses) {
      EXPECT_LE((r.exact_stiffness - corotated).norm(), 1e-10 * corotated.norm()) << "nu " << nu;
      EXPECT_LE((r.projected_stiffness - corotated).norm(), 1e-10 * corotated.norm())
          << "nu " << nu;
    }
  }
}

TEST(HyperelasticParameters, ShiftedLameParametersOfThePapers) {
  const double nu = 0.3, mu = shearModulus(nu), lambda = lameLambda(nu);
  const StableNeoHookean a = StableNeoHookean::fromYoungPoisson(kE, nu);
  EXPECT_DOUBLE_EQ(a.mu, mu);
  EXPECT_DOUBLE_EQ(a.lambda, lambda + mu);
  EXPECT_DOUBLE_EQ(a.alpha, 1 + mu / (lambda + mu));
  const StableNeoHookean b = StableNeoHookean::fromYoungPoisson(kE, nu, true);
  EXPECT_DOUBLE_EQ(b.mu, 4 * mu / 3);
  EXPECT_DOUBLE_EQ(b.lambda, lambda + 5 * mu / 6);
  EXPECT_DOUBLE_EQ(b.alpha, 1 + 3 * b.mu / (4 * b.lambda));
  const MooneyRivlin c = MooneyRivlin::fromYoungPoisson(kE, nu, 0.3);
  EXPECT_DOUBLE_EQ(2 * (c.c1 + c.c2), mu);
  EXPECT_DOUBLE_EQ(c.c2 / (c.c1 + c.c2), 0.3);
  EXPECT_NEAR(c.lambda, lambda + 2 * c.c1, 1e-9 * mu);
}

}  // namespace torsion::hyperelastic_test

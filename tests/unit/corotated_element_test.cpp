// Element facts of the corotated linear tet (docs/design.md section 5): zero force at rest and
// under rigid motion, a symmetric positive semi-definite stiffness with exactly six zero modes,
// force differentials that match finite differences, and the assembled blocks used by CHOLMOD.
#include "torsion/fem/corotated_element.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <random>

#include "torsion/fem/polar_rotation.h"

namespace torsion {
namespace {

constexpr double kMu = 3.846e4;  // E = 1e5, nu = 0.3
constexpr double kLambda = 5.769e4;

struct TetFixture {
  std::array<Eigen::Vector3d, 4> rest = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0.1, 0),
                                         Eigen::Vector3d(0.2, 0.9, 0.1),
                                         Eigen::Vector3d(0.1, 0.2, 1.1)};
  TetRestData data = tetRestData(rest);
  std::array<Eigen::Vector3d, 4> forces(const std::array<Eigen::Vector3d, 4>& x) const {
    const Eigen::Matrix3d F = deformationGradient(x, data.rest_shape_inverse);
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    return corotatedForces(F, extractRotation(F, q, 100, 1e-13), data, kMu, kLambda);
  }
  Eigen::Matrix3d rotation(const std::array<Eigen::Vector3d, 4>& x) const {
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    return extractRotation(deformationGradient(x, data.rest_shape_inverse), q, 100, 1e-13);
  }
  // 12x12 stiffness K (df = -K dx) built column by column from the force differential.
  Eigen::Matrix<double, 12, 12> stiffness(const Eigen::Matrix3d& R) const {
    Eigen::Matrix<double, 12, 12> K;
    for (int c = 0; c < 12; ++c) {
      std::array<Eigen::Vector3d, 4> dx;
      for (auto& v : dx)
        v.setZero();
      dx[static_cast<size_t>(c / 3)][c % 3] = 1;
      const auto df = corotatedForceDifferential(dx, R, data, kMu, kLambda);
      for (int a = 0; a < 4; ++a)
        K.block<3, 1>(3 * a, c) = -df[static_cast<size_t>(a)];
    }
    return K;
  }
};

std::array<Eigen::Vector3d, 4> rigidlyMoved(const std::array<Eigen::Vector3d, 4>& x,
                                            const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  std::array<Eigen::Vector3d, 4> y;
  for (size_t a = 0; a < 4; ++a)
    y[a] = R * x[a] + t;
  return y;
}

Eigen::Matrix3d randomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
}

TEST(CorotatedElement, ZeroForceAtRest) {
  TetFixture tet;
  for (const auto& f : tet.forces(tet.rest))
    EXPECT_LT(f.norm(), 1e-9);
}

TEST(CorotatedElement, ZeroForceUnderRigidMotions) {
  TetFixture tet;
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    const auto moved = rigidlyMoved(tet.rest, randomRotation(rng), Eigen::Vector3d(3, -2, 5));
    // Forces scale with E * area ~ 1e5; rigid motion must leave round-off only.
    for (const auto& f : tet.forces(moved))
      EXPECT_LT(f.norm(), 1e-6) << "trial " << trial;
  }
}

TEST(CorotatedElement, ForcesSumToZeroAndCarryNoTorque) {
  TetFixture tet;
  auto x = tet.rest;
  x[2] += Eigen::Vector3d(0.1, -0.05, 0.2);  // a real deformation
  const auto f = tet.forces(x);
  Eigen::Vector3d total = Eigen::Vector3d::Zero(), torque = Eigen::Vector3d::Zero();
  for (size_t a = 0; a < 4; ++a) {
    total += f[a];
    torque += x[a].cross(f[a]);
  }
  const double scale = f[2].norm();
  EXPECT_LT(total.norm(), 1e-10 * scale);
  // Corotated linear forces are torque-free because R^T F's stress is symmetric and R is the
  // polar rotation of F.
  EXPECT_LT(torque.norm(), 1e-8 * scale);
}

TEST(CorotatedElement, StiffnessSymmetricPsdWithSixZeroModes) {
  TetFixture tet;
  std::mt19937 rng(3);
  for (const Eigen::Matrix3d& R :
       {Eigen::Matrix3d(Eigen::Matrix3d::Identity()), randomRotation(rng)}) {
    const Eigen::Matrix<double, 12, 12> K = tet.stiffness(R);
    EXPECT_LT((K - K.transpose()).norm(), 1e-9 * K.norm());
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (K + K.transpose()));
    const auto values = eig.eigenvalues();  // ascending
    const double largest = values(11);
    for (int i = 0; i < 6; ++i)
      EXPECT_LT(std::abs(values(i)), 1e-10 * largest) << "mode " << i;
    for (int i = 6; i < 12; ++i)
      EXPECT_GT(values(i), 1e-4 * largest) << "mode " << i;
  }
}

TEST(CorotatedElement, DifferentialMatchesFiniteDifferenceAtRigidConfigurations) {
  // At a rigidly rotated configuration the rotation's own derivative does not contribute, so the
  // warped stiffness is the exact tangent: central differences agree to O(h^2).
  TetFixture tet;
  std::mt19937 rng(11);
  const Eigen::Matrix3d R = randomRotation(rng);
  const auto x = rigidlyMoved(tet.rest, R, Eigen::Vector3d(1, 2, 3));
  std::normal_distribution<double> n(0, 1);
  std::array<Eigen::Vector3d, 4> dx;
  for (auto& v : dx)
    v = Eigen::Vector3d(n(rng), n(rng), n(rng));
  const double h = 1e-6;
  std::array<Eigen::Vector3d, 4> plus = x, minus = x;
  for (size_t a = 0; a < 4; ++a) {
    plus[a] += h * dx[a];
    minus[a] -= h * dx[a];
  }
  const auto fp = tet.forces(plus), fm = tet.forces(minus);
  const auto df = corotatedForceDifferential(dx, tet.rotation(x), tet.data, kMu, kLambda);
  for (size_t a = 0; a < 4; ++a) {
    const Eigen::Vector3d fd = (fp[a] - fm[a]) / (2 * h);
    EXPECT_LT((fd - df[a]).norm(), 1e-5 * df[a].norm() + 1e-6) << "node " << a;
  }
}

TEST(CorotatedElement, DifferentialCloseToFiniteDifferenceUnderSmallStrain) {
  // Away from rigid configurations the warped stiffness drops the dR terms, an error of the order
  // of the strain: at 0.1 % strain the directional derivative agrees within 1 %.
  TetFixture tet;
  auto x = tet.rest;
  x[3] += 1e-3 * Eigen::Vector3d(0.3, -0.2, 1.0);
  std::array<Eigen::Vector3d, 4> dx = {Eigen::Vector3d(0.1, 0, 0), Eigen::Vector3d(0, 0.2, 0),
                                       Eigen::Vector3d(0, 0, -0.1), Eigen::Vector3d(0.3, 0.1, 0.2)};
  const double h = 1e-7;
  std::array<Eigen::Vector3d, 4> plus = x, minus = x;
  for (size_t a = 0; a < 4; ++a) {
    plus[a] += h * dx[a];
    minus[a] -= h * dx[a];
  }
  const auto fp = tet.forces(plus), fm = tet.forces(minus);
  const auto df = corotatedForceDifferential(dx, tet.rotation(x), tet.data, kMu, kLambda);
  double err = 0, ref = 0;
  for (size_t a = 0; a < 4; ++a) {
    err += ((fp[a] - fm[a]) / (2 * h) - df[a]).squaredNorm();
    ref += df[a].squaredNorm();
  }
  EXPECT_LT(std::sqrt(err / ref), 1e-2);
}

TEST(CorotatedElement, EnergyIsZeroAtRestAndGrowsQuadratically) {
  TetFixture tet;
  auto energy = [&](double s) {
    auto x = tet.rest;
    x[1] += s * Eigen::Vector3d(1, 0, 0);
    const Eigen::Matrix3d F = deformationGradient(x, tet.data.rest_shape_inverse);
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    return corotatedEnergy(F, extractRotation(F, q), tet.data, kMu, kLambda);
  };
  EXPECT_NEAR(energy(0), 0, 1e-12);
  EXPECT_NEAR(energy(2e-3) / energy(1e-3), 4.0, 1e-2);
}

}  // namespace
}  // namespace torsion

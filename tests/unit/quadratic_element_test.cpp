// Element facts of the corotated quadratic (10-node) tet (docs/design.md section 5, the same facts
// as corotated_element_test.cpp for the linear tet): zero force at rest and under rigid motion, a
// symmetric positive semi-definite 30x30 stiffness with exactly six zero modes (the 4-point rule
// is exact, so no spurious zero-energy modes), blocks that agree with the force differential,
// force differentials that match finite differences, the exact strain of a linear field, and
// HRZ masses that match the consistent mass diagonal.
#include "torsion/fem/quadratic_element.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <random>

#include "torsion/fem/polar_rotation.h"
#include "torsion/mesh/quadratic_tet_mesh.h"

namespace torsion {
// Named, not anonymous: its helpers share a unity batch with other files' (TORSION_UNITY_BUILD).
namespace quadratic_element_test {

constexpr double kMu = 3.846e4;  // E = 1e5, nu = 0.3
constexpr double kLambda = 5.769e4;
using Matrix30 = Eigen::Matrix<double, 30, 30>;

struct Tet10Fixture {
  Tet10Vectors rest;
  QuadraticRestData data;
  Tet10Fixture() {
    rest[0] = Eigen::Vector3d(0, 0, 0);
    rest[1] = Eigen::Vector3d(1, 0.1, 0);
    rest[2] = Eigen::Vector3d(0.2, 0.9, 0.1);
    rest[3] = Eigen::Vector3d(0.1, 0.2, 1.1);
    for (size_t e = 0; e < 6; ++e) {
      rest[4 + e] = 0.5 * (rest[static_cast<size_t>(kTet10Edges[e][0])] +
                           rest[static_cast<size_t>(kTet10Edges[e][1])]);
    }
    Eigen::Matrix3d Dm;
    for (int k = 0; k < 3; ++k)
      Dm.col(k) = rest[static_cast<size_t>(k + 1)] - rest[0];
    data = quadraticRestData(Dm.inverse(), Dm.determinant() / 6);
  }
  Eigen::Matrix3d rotation(const Tet10Vectors& x) const {
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    return extractRotation(quadraticCentroidGradient(x, data), q, 100, 1e-13);
  }
  Tet10Vectors forces(const Tet10Vectors& x) const {
    return quadraticResponse(x, rotation(x), data, kMu, kLambda).forces;
  }
  // 30x30 stiffness K (df = -K dx) built column by column from the force differential.
  Matrix30 stiffness(const Eigen::Matrix3d& R) const {
    Matrix30 K;
    for (int c = 0; c < 30; ++c) {
      Tet10Vectors dx;
      for (auto& v : dx)
        v.setZero();
      dx[static_cast<size_t>(c / 3)][c % 3] = 1;
      const Tet10Vectors df = quadraticForceDifferential(dx, R, data, kMu, kLambda);
      for (int a = 0; a < 10; ++a)
        K.block<3, 1>(3 * a, c) = -df[static_cast<size_t>(a)];
    }
    return K;
  }
};

Tet10Vectors rigidlyMoved(const Tet10Vectors& x, const Eigen::Matrix3d& R,
                          const Eigen::Vector3d& t) {
  Tet10Vectors y;
  for (size_t a = 0; a < 10; ++a)
    y[a] = R * x[a] + t;
  return y;
}

Eigen::Matrix3d randomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
}

Tet10Vectors randomVectors(std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  Tet10Vectors v;
  for (auto& x : v)
    x = Eigen::Vector3d(n(rng), n(rng), n(rng));
  return v;
}

TEST(QuadraticElement, ZeroForceAtRest) {
  Tet10Fixture tet;
  for (const auto& f : tet.forces(tet.rest))
    EXPECT_LT(f.norm(), 1e-9);
  EXPECT_NEAR(
      quadraticResponse(tet.rest, Eigen::Matrix3d::Identity(), tet.data, kMu, kLambda).energy, 0,
      1e-12);
}

TEST(QuadraticElement, ZeroForceUnderRigidMotions) {
  Tet10Fixture tet;
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Matrix3d Q = randomRotation(rng);
    const auto moved = rigidlyMoved(tet.rest, Q, Eigen::Vector3d(3, -2, 5));
    // The centroid F is Q exactly, so R = Q (to the polar tolerance, 1e-13).
    EXPECT_LT((tet.rotation(moved) - Q).norm(), 1e-10);
    // Forces scale with E * area ~ 1e5; rigid motion must leave round-off only.
    for (const auto& f : tet.forces(moved))
      EXPECT_LT(f.norm(), 1e-6) << "trial " << trial;
  }
}

TEST(QuadraticElement, ForcesSumToZeroAndCarryNoTorque) {
  // The energy is invariant under translations and rotations of x (R = polar of the centroid F
  // rotates with the body) and the forces are its exact gradient, so they sum to zero and carry
  // no net torque, even at a 10 % deformation. (Without the rotation term of the header the
  // torque here would be ~5 % of force x size.)
  Tet10Fixture tet;
  std::mt19937 rng(5);
  Tet10Vectors x = tet.rest;
  const Tet10Vectors d = randomVectors(rng);
  for (size_t a = 0; a < 10; ++a)
    x[a] += 0.1 * d[a];
  const auto f = tet.forces(x);
  Eigen::Vector3d total = Eigen::Vector3d::Zero(), torque = Eigen::Vector3d::Zero();
  double scale = 0;
  for (size_t a = 0; a < 10; ++a) {
    total += f[a];
    torque += x[a].cross(f[a]);
    scale = std::max(scale, f[a].norm());
  }
  EXPECT_LT(total.norm(), 1e-10 * scale);
  EXPECT_LT(torque.norm(), 1e-9 * scale);
}

TEST(QuadraticElement, ForcesAreTheGradientOfTheEnergy) {
  // Central differences of E(x) (R recomputed at every x) against the forces, at a 5 %
  // deformation: O(h^2) agreement, 1e-6 relative with h = 1e-6 m on a unit element.
  Tet10Fixture tet;
  std::mt19937 rng(19);
  Tet10Vectors x = tet.rest;
  const Tet10Vectors d = randomVectors(rng);
  for (size_t a = 0; a < 10; ++a)
    x[a] += 0.05 * d[a];
  auto energy = [&](const Tet10Vectors& y) {
    return quadraticResponse(y, tet.rotation(y), tet.data, kMu, kLambda).energy;
  };
  const Tet10Vectors f = tet.forces(x);
  double scale = 0;
  for (const auto& v : f)
    scale = std::max(scale, v.norm());
  const double h = 1e-6;
  for (size_t a = 0; a < 10; ++a) {
    for (int k = 0; k < 3; ++k) {
      Tet10Vectors plus = x, minus = x;
      plus[a][k] += h;
      minus[a][k] -= h;
      const double derivative = (energy(plus) - energy(minus)) / (2 * h);
      EXPECT_NEAR(-derivative, f[a][k], 1e-6 * scale) << "node " << a << " axis " << k;
    }
  }
}

TEST(QuadraticElement, StiffnessSymmetricPsdWithSixZeroModes) {
  Tet10Fixture tet;
  std::mt19937 rng(3);
  for (const Eigen::Matrix3d& R :
       {Eigen::Matrix3d(Eigen::Matrix3d::Identity()), randomRotation(rng)}) {
    const Matrix30 K = tet.stiffness(R);
    EXPECT_LT((K - K.transpose()).norm(), 1e-9 * K.norm());
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (K + K.transpose()));
    const auto values = eig.eigenvalues();  // ascending
    const double largest = values(29);
    for (int i = 0; i < 6; ++i)
      EXPECT_LT(std::abs(values(i)), 1e-10 * largest) << "mode " << i;
    // The 24 deformation modes are all stiff: no hourglass mode (the rule is exact). The
    // softest is about 1e-2 of the largest for this shape; 1e-4 leaves room for other shapes.
    for (int i = 6; i < 30; ++i)
      EXPECT_GT(values(i), 1e-4 * largest) << "mode " << i;
  }
}

TEST(QuadraticElement, StiffnessBlocksMatchTheForceDifferential) {
  Tet10Fixture tet;
  std::mt19937 rng(13);
  const Eigen::Matrix3d R = randomRotation(rng);
  const Matrix30 K = tet.stiffness(R);
  for (int a = 0; a < 10; ++a) {
    for (int b = 0; b < 10; ++b) {
      EXPECT_LT(
          (quadraticStiffnessBlock(R, tet.data, kMu, kLambda, a, b) - K.block<3, 3>(3 * a, 3 * b))
              .norm(),
          1e-12 * K.norm())
          << a << "," << b;
    }
  }
}

TEST(QuadraticElement, DifferentialMatchesFiniteDifferenceAtRigidConfigurations) {
  // At a rigidly rotated configuration the rotation's own derivative does not contribute, so the
  // warped stiffness is the exact tangent: central differences agree to O(h^2).
  Tet10Fixture tet;
  std::mt19937 rng(11);
  const Eigen::Matrix3d Q = randomRotation(rng);
  const auto x = rigidlyMoved(tet.rest, Q, Eigen::Vector3d(1, 2, 3));
  const Tet10Vectors dx = randomVectors(rng);
  const double h = 1e-6;
  Tet10Vectors plus = x, minus = x;
  for (size_t a = 0; a < 10; ++a) {
    plus[a] += h * dx[a];
    minus[a] -= h * dx[a];
  }
  const auto fp = tet.forces(plus), fm = tet.forces(minus);
  const auto df = quadraticForceDifferential(dx, tet.rotation(x), tet.data, kMu, kLambda);
  for (size_t a = 0; a < 10; ++a) {
    const Eigen::Vector3d fd = (fp[a] - fm[a]) / (2 * h);
    EXPECT_LT((fd - df[a]).norm(), 1e-5 * df[a].norm() + 1e-6) << "node " << a;
  }
}

TEST(QuadraticElement, DifferentialCloseToFiniteDifferenceUnderSmallStrain) {
  // Away from rigid configurations the warped stiffness drops the dR terms, an error of the order
  // of the strain: at 0.1 % strain the directional derivative agrees within 1 %.
  Tet10Fixture tet;
  std::mt19937 rng(17);
  Tet10Vectors x = tet.rest;
  const Tet10Vectors d = randomVectors(rng);
  for (size_t a = 0; a < 10; ++a)
    x[a] += 1e-3 * d[a];
  const Tet10Vectors dx = randomVectors(rng);
  const double h = 1e-7;
  Tet10Vectors plus = x, minus = x;
  for (size_t a = 0; a < 10; ++a) {
    plus[a] += h * dx[a];
    minus[a] -= h * dx[a];
  }
  const auto fp = tet.forces(plus), fm = tet.forces(minus);
  const auto df = quadraticForceDifferential(dx, tet.rotation(x), tet.data, kMu, kLambda);
  double err = 0, ref = 0;
  for (size_t a = 0; a < 10; ++a) {
    err += ((fp[a] - fm[a]) / (2 * h) - df[a]).squaredNorm();
    ref += df[a].squaredNorm();
  }
  EXPECT_LT(std::sqrt(err / ref), 1e-2);
}

TEST(QuadraticElement, LinearFieldGivesItsExactConstantGradient) {
  // Single-element part of the patch test (the assembled part is in quadratic_mesh_test.cpp):
  // nodes displaced by u = G X give F = I + G at every quadrature point and at the centroid, so
  // the stress is the same constant at each point.
  Tet10Fixture tet;
  Eigen::Matrix3d G;
  G << 1e-3, 2e-3, -1e-3, 0.5e-3, -2e-3, 1e-3, 3e-3, 0, 1e-3;
  Tet10Vectors x;
  for (size_t a = 0; a < 10; ++a)
    x[a] = tet.rest[a] + G * tet.rest[a];
  const Eigen::Matrix3d F = Eigen::Matrix3d::Identity() + G;
  EXPECT_LT((quadraticCentroidGradient(x, tet.data) - F).norm(), 1e-14);
  for (int q = 0; q < kTet10QuadraturePoints; ++q)
    EXPECT_LT((quadraticDeformationGradient(x, tet.data, q) - F).norm(), 1e-14) << "point " << q;
  // The energy is V times the energy density of the constant strain.
  const Eigen::Matrix3d R = tet.rotation(x);
  const Eigen::Matrix3d RtF = R.transpose() * F;
  const Eigen::Matrix3d eps = 0.5 * (RtF + RtF.transpose()) - Eigen::Matrix3d::Identity();
  const double density = kMu * eps.squaredNorm() + 0.5 * kLambda * eps.trace() * eps.trace();
  EXPECT_NEAR(quadraticResponse(x, R, tet.data, kMu, kLambda).energy, tet.data.volume * density,
              1e-12 * tet.data.volume * density);
}

TEST(QuadraticElement, GradientsReproduceConstantsAndTheRestShape) {
  // sum_a N_a = 1 means sum_a grad N_a = 0 at every point, and X = sum_a X_a N_a means
  // sum_a X_a grad N_a^T = I at every point: the rest data is consistent with the geometry.
  Tet10Fixture tet;
  for (int q = 0; q < kTet10QuadraturePoints; ++q) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& g : tet.data.gradients[static_cast<size_t>(q)])
      sum += g;
    EXPECT_LT(sum.norm(), 1e-12);
    EXPECT_LT(
        (quadraticDeformationGradient(tet.rest, tet.data, q) - Eigen::Matrix3d::Identity()).norm(),
        1e-13);
  }
}

TEST(QuadraticElement, HrzMassesAreTheScaledConsistentDiagonal) {
  // Consistent mass diagonal from the exact monomial integrals over a tet,
  // int L^k dV = 6 V k! / (k + 3)!, int L_i^2 L_j^2 dV = 6 V 2! 2! / 7!:
  //   corner: int (2 L^2 - L)^2 = 4 I4 - 4 I3 + I2;  edge: 16 int L_i^2 L_j^2.
  auto integral = [](int k) {  // int L^k dV / V
    double num = 6, den = 1;
    for (int i = 2; i <= k; ++i)
      num *= i;
    for (int i = 2; i <= k + 3; ++i)
      den *= i;
    return num / den;
  };
  const double corner = 4 * integral(4) - 4 * integral(3) + integral(2);
  const double edge = 16 * 6.0 * 2 * 2 / 5040.0;
  EXPECT_NEAR(corner, 1.0 / 70, 1e-15);
  EXPECT_NEAR(edge, 8.0 / 105, 1e-15);
  const double diagonal_sum = 4 * corner + 6 * edge;
  EXPECT_NEAR(kTet10CornerMassFraction, corner / diagonal_sum, 1e-15);
  EXPECT_NEAR(kTet10EdgeMassFraction, edge / diagonal_sum, 1e-15);
  EXPECT_NEAR(4 * kTet10CornerMassFraction + 6 * kTet10EdgeMassFraction, 1.0, 1e-15);
  EXPECT_GT(kTet10CornerMassFraction, 0);  // row-sum lumping would give -1/20 here
}

}  // namespace quadratic_element_test
}  // namespace torsion

// The volume barrier against inverted tets (fem/volume_barrier.h): its forces are minus the
// gradient of its energy and its Hessian the derivative of the forces (central differences), the
// stiffness the implicit solve gets is that Hessian made positive semi-definite, everything is
// exactly zero above the threshold (so a body at ordinary strains steps bit for bit as without
// it), the stepper adds its forces and stiffness, and a tet driven through its own face is pushed
// back before it inverts, where the plain corotated tet inverts.
#include "torsion/fem/volume_barrier.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <memory>
#include <random>

#include "torsion/fem/corotated_element.h"
#include "torsion/mesh/box_mesh.h"
#include "torsion/solve/implicit_stepper.h"

namespace torsion {
namespace {

using Nodes = std::array<Eigen::Vector3d, 4>;

const Nodes kRest = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0.1, 0),
                     Eigen::Vector3d(0.2, 0.9, 0.1), Eigen::Vector3d(0.1, 0.2, 1.1)};

TetRestData restData() {
  return tetRestData(kRest);
}

VolumeBarrier defaultBarrier() {
  return volumeBarrierOf(Material{});
}

// The rest tet with two nodes nudged (so that no configuration is special) and node 3 moved
// along the normal of face (0, 1, 2) until the volume ratio is J (negative: through the face).
Nodes squeezed(double J) {
  Nodes x = kRest;
  x[1] += Eigen::Vector3d(0.03, -0.02, 0.01);
  x[2] += Eigen::Vector3d(-0.01, 0.02, 0.015);
  const Eigen::Vector3d n = (x[1] - x[0]).cross(x[2] - x[0]).normalized();
  // J is affine in node 3's position: J(s) for x_3 - s n, from two values.
  const TetRestData rest = restData();
  auto ratio = [&](double s) {
    Nodes y = x;
    y[3] -= s * n;
    return deformationGradient(y, rest.rest_shape_inverse).determinant();
  };
  const double j0 = ratio(0), j1 = ratio(1);
  x[3] -= (j0 - J) / (j0 - j1) * n;
  return x;
}

double energyAt(const Nodes& x) {
  const TetRestData rest = restData();
  return volumeBarrierEnergy(deformationGradient(x, rest.rest_shape_inverse), rest,
                             defaultBarrier());
}

Nodes forcesAt(const Nodes& x) {
  const TetRestData rest = restData();
  return volumeBarrierForces(deformationGradient(x, rest.rest_shape_inverse), rest,
                             defaultBarrier());
}

TEST(VolumeBarrier, TheDensityAndItsTwoDerivativesVanishAtTheThreshold) {
  const VolumeBarrier b = defaultBarrier();
  EXPECT_EQ(b.density(b.threshold), 0.0);
  EXPECT_EQ(b.densityDerivative(b.threshold), 0.0);
  EXPECT_EQ(b.densitySecondDerivative(b.threshold), 0.0);
  // Just below, each is of the order its power of the distance predicts (C2, not C3).
  const double d = 1e-4;
  EXPECT_NEAR(b.density(b.threshold - d), b.pressure / 3 * d * d * d / (b.threshold * b.threshold),
              1e-12 * b.pressure);
  EXPECT_NEAR(b.densitySecondDerivative(b.threshold - d),
              0.5 * b.densitySecondDerivative(b.threshold - 2 * d), 1e-9 * b.pressure);
  // The pressure at J = 0 is k = barrier_stiffness times the bulk modulus.
  EXPECT_DOUBLE_EQ(-b.densityDerivative(0),
                   Material{}.barrier_stiffness * Material{}.bulkModulus());
}

TEST(VolumeBarrier, NothingAboveTheThreshold) {
  const TetRestData rest = restData();
  const VolumeBarrier barrier = defaultBarrier();
  // Rest, a rotation with stretch, and a squeeze just above the threshold.
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  for (const Eigen::Matrix3d& F :
       {Eigen::Matrix3d(Eigen::Matrix3d::Identity()),
        Eigen::Matrix3d(rotation * Eigen::Vector3d(1.5, 0.8, 0.6).asDiagonal()),
        deformationGradient(squeezed(barrier.threshold + 1e-9), rest.rest_shape_inverse)}) {
    ASSERT_GE(F.determinant(), barrier.threshold);
    EXPECT_EQ(volumeBarrierEnergy(F, rest, barrier), 0.0);
    for (const Eigen::Vector3d& f : volumeBarrierForces(F, rest, barrier))
      EXPECT_EQ(f, Eigen::Vector3d::Zero());
    EXPECT_EQ(volumeBarrierStiffness(F, rest, barrier), TetStiffness::Zero());
  }
}

TEST(VolumeBarrier, ForcesAreMinusTheEnergyGradient) {
  for (double J : {0.28, 0.15, 0.02, -0.1, -0.4}) {
    const Nodes x = squeezed(J);
    const Nodes f = forcesAt(x);
    double scale = 0;
    for (const Eigen::Vector3d& v : f)
      scale = std::max(scale, v.norm());
    ASSERT_GT(scale, 0) << "J = " << J;
    const double h = 1e-6;
    for (size_t a = 0; a < 4; ++a) {
      for (int i = 0; i < 3; ++i) {
        Nodes plus = x, minus = x;
        plus[a][i] += h;
        minus[a][i] -= h;
        const double gradient = (energyAt(plus) - energyAt(minus)) / (2 * h);
        EXPECT_NEAR(f[a][i], -gradient, 1e-6 * scale) << "J = " << J << ", node " << a;
      }
    }
  }
}

TEST(VolumeBarrier, TheHessianIsTheForceDerivative) {
  const TetRestData rest = restData();
  for (double J : {0.28, 0.15, 0.02, -0.1, -0.4}) {
    const Nodes x = squeezed(J);
    const TetStiffness K = volumeBarrierHessian(deformationGradient(x, rest.rest_shape_inverse),
                                                rest, defaultBarrier());
    const double scale = K.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0);
    EXPECT_LT((K - K.transpose()).cwiseAbs().maxCoeff(), 1e-12 * scale);
    const double h = 1e-6;
    for (int c = 0; c < 12; ++c) {
      Nodes plus = x, minus = x;
      plus[static_cast<size_t>(c / 3)][c % 3] += h;
      minus[static_cast<size_t>(c / 3)][c % 3] -= h;
      const Nodes fp = forcesAt(plus), fm = forcesAt(minus);
      for (int r = 0; r < 12; ++r) {
        const size_t a = static_cast<size_t>(r / 3);
        const double derivative = -(fp[a][r % 3] - fm[a][r % 3]) / (2 * h);
        EXPECT_NEAR(K(r, c), derivative, 1e-6 * scale) << "J = " << J << ", entry " << r << c;
      }
    }
  }
}

TEST(VolumeBarrier, TheSolvesStiffnessIsPositiveSemiDefiniteAndKeepsTheCurvatureAlongJ) {
  const TetRestData rest = restData();
  for (double J : {0.28, 0.15, 0.02, -0.1, -0.4}) {
    const Eigen::Matrix3d F = deformationGradient(squeezed(J), rest.rest_shape_inverse);
    const TetStiffness K = volumeBarrierStiffness(F, rest, defaultBarrier());
    const TetStiffness H = volumeBarrierHessian(F, rest, defaultBarrier());
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(K);
    const double largest = eigen.eigenvalues().maxCoeff();
    EXPECT_GE(eigen.eigenvalues().minCoeff(), -1e-10 * largest) << "J = " << J;
    // The exact Hessian is indefinite here (the d2J/dF2 part); the projection keeps the
    // barrier's curvature along dJ/dx, the direction that matters.
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> exact(H);
    EXPECT_LT(exact.eigenvalues().minCoeff(), 0) << "J = " << J;
    Eigen::Matrix<double, 12, 1> gradient;  // dJ/dx
    const Eigen::Matrix3d C = cofactor(F);
    const Eigen::Matrix3d G = C * rest.rest_shape_inverse.transpose();
    gradient.segment<3>(0) = -(G.col(0) + G.col(1) + G.col(2));
    for (int a = 1; a < 4; ++a)
      gradient.segment<3>(3 * a) = G.col(a - 1);
    EXPECT_GE(gradient.dot(K * gradient), 0.999 * gradient.dot(H * gradient) - 1e-9 * largest);
    // Translations are free: K t = 0.
    Eigen::Matrix<double, 12, 1> t;
    for (int a = 0; a < 4; ++a)
      t.segment<3>(3 * a) = Eigen::Vector3d(0.3, -0.2, 0.9);
    EXPECT_LT((K * t).norm(), 1e-9 * largest * t.norm());
  }
}

TEST(VolumeBarrier, ARigidMotionOnlyTurnsTheForces) {
  const Eigen::Matrix3d Q =
      Eigen::AngleAxisd(2.1, Eigen::Vector3d(-1, 0.5, 2).normalized()).toRotationMatrix();
  const Nodes x = squeezed(-0.05);
  Nodes moved;
  for (size_t a = 0; a < 4; ++a)
    moved[a] = Q * x[a] + Eigen::Vector3d(3, -1, 2);
  EXPECT_NEAR(energyAt(moved), energyAt(x), 1e-12 * energyAt(x));
  const Nodes f = forcesAt(x), g = forcesAt(moved);
  for (size_t a = 0; a < 4; ++a)
    EXPECT_LT((g[a] - Q * f[a]).norm(), 1e-9 * f[a].norm() + 1e-12);
}

// ---- In the implicit step ----

TEST(VolumeBarrier, ABodyAtOrdinaryStrainStepsBitForBitAsWithoutIt) {
  Material without;
  without.barrier_threshold = 0;
  for (ElementKind kind : {ElementKind::kTet4, ElementKind::kTet10}) {
    auto mesh = std::make_shared<TetMesh>(
        makeBoxTetMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(4, 1, 1), 8, 2, 2).value());
    auto with_model = FemModel::create(mesh, Material{}, kind).value();
    auto without_model = FemModel::create(mesh, without, kind).value();
    Parallel parallel(2);
    ImplicitStepper with_stepper(with_model, SolverSettings{}, parallel);
    ImplicitStepper without_stepper(without_model, SolverSettings{}, parallel);
    FemState state = FemState::atRest(*with_model);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> noise(-0.02, 0.02);  // strains up to ~8 %
    for (int i = 0; i < state.positions.size(); ++i)
      state.positions[i] += noise(rng);
    double smallest = 1;  // the volume ratio of the most compressed tet: far above the threshold
    for (size_t t = 0; t < with_model->mesh().tets().size(); ++t) {
      Nodes x;
      for (size_t a = 0; a < 4; ++a)
        x[a] = state.positions.segment<3>(3 * with_model->mesh().tets()[t][a]);
      smallest = std::min(
          smallest,
          deformationGradient(x, with_model->tetRestData()[t].rest_shape_inverse).determinant());
    }
    ASSERT_GT(smallest, 0.5);
    FemState other = state;
    EXPECT_EQ(with_stepper.computeElasticForces(state),
              without_stepper.computeElasticForces(other));
    EXPECT_EQ(with_stepper.elasticForces(), without_stepper.elasticForces());
    Eigen::VectorXd y(state.positions.size()), a, b;
    for (int i = 0; i < y.size(); ++i)
      y[i] = noise(rng);
    with_stepper.system().multiplyStiffness(y, a);
    without_stepper.system().multiplyStiffness(y, b);
    EXPECT_EQ(a, b) << toString(kind);
  }
}

TEST(VolumeBarrier, TheStepperAddsItsForcesAndStiffness) {
  // One tet squeezed below the threshold: the stepper's forces and K differ from those without
  // the barrier by exactly the barrier's forces and (projected) stiffness.
  auto mesh = std::make_shared<TetMesh>(std::vector<Eigen::Vector3d>(kRest.begin(), kRest.end()),
                                        std::vector<Tet>{{0, 1, 2, 3}});
  Material without;
  without.barrier_threshold = 0;
  auto with_model = FemModel::create(mesh, Material{}).value();
  auto without_model = FemModel::create(mesh, without).value();
  Parallel parallel(1);
  ImplicitStepper with_stepper(with_model, SolverSettings{}, parallel);
  ImplicitStepper without_stepper(without_model, SolverSettings{}, parallel);
  FemState state = FemState::atRest(*with_model);
  const Nodes x = squeezed(0.1);
  for (int a = 0; a < 4; ++a)
    state.positions.segment<3>(3 * a) = x[static_cast<size_t>(a)];
  FemState other = state;
  const double energy_with = with_stepper.computeElasticForces(state);
  const double energy_without = without_stepper.computeElasticForces(other);
  EXPECT_NEAR(energy_with - energy_without, energyAt(x), 1e-9 * energyAt(x));
  const Nodes f = forcesAt(x);
  for (int a = 0; a < 4; ++a) {
    const Eigen::Vector3d added = with_stepper.elasticForces().segment<3>(3 * a) -
                                  without_stepper.elasticForces().segment<3>(3 * a);
    EXPECT_LT((added - f[static_cast<size_t>(a)]).norm(), 1e-9 * f[static_cast<size_t>(a)].norm());
  }
  const TetRestData rest = restData();
  const TetStiffness K = volumeBarrierStiffness(deformationGradient(x, rest.rest_shape_inverse),
                                                rest, defaultBarrier());
  Eigen::VectorXd y(12), Ky_with, Ky_without;
  y << 0.3, -0.1, 0.2, 0.5, 0.4, -0.3, -0.2, 0.1, 0.6, 0.05, -0.7, 0.2;
  with_stepper.system().multiplyStiffness(y, Ky_with);
  without_stepper.system().multiplyStiffness(y, Ky_without);
  const Eigen::VectorXd expected = K * y;
  EXPECT_LT((Ky_with - Ky_without - expected).norm(), 1e-9 * expected.norm());
}

TEST(VolumeBarrier, Tet10BodiesApplyItToTheirEightSubTets) {
  // One quadratic element with a mid-edge node pushed through the element's centroid: some of
  // its 8 linear sub-tets (FemModel::mesh()) fall below the threshold, and the stepper's
  // forces and K gain exactly the barrier's terms of those sub-tets.
  auto mesh = std::make_shared<TetMesh>(std::vector<Eigen::Vector3d>(kRest.begin(), kRest.end()),
                                        std::vector<Tet>{{0, 1, 2, 3}});
  Material without;
  without.barrier_threshold = 0;
  auto with_model = FemModel::create(mesh, Material{}, ElementKind::kTet10).value();
  auto without_model = FemModel::create(mesh, without, ElementKind::kTet10).value();
  Parallel parallel(1);
  ImplicitStepper with_stepper(with_model, SolverSettings{}, parallel);
  ImplicitStepper without_stepper(without_model, SolverSettings{}, parallel);
  FemState state = FemState::atRest(*with_model);
  const int n = with_model->nodeCount();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> noise(-0.02, 0.02);
  for (int i = 0; i < 3 * n; ++i)
    state.positions[i] += noise(rng);
  const int mid_edge = with_model->elementNodes()[9];  // a mid-edge node (local 9)
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& corner : kRest)
    centroid += corner / 4;
  // Through the centroid: the sub-tets on that node's side flatten, the others stretch.
  state.positions.segment<3>(3 * mid_edge) +=
      1.5 * (centroid - state.positions.segment<3>(3 * mid_edge));
  FemState other = state;
  with_stepper.computeElasticForces(state);
  without_stepper.computeElasticForces(other);
  const VolumeBarrier barrier = defaultBarrier();
  Eigen::VectorXd expected_forces = Eigen::VectorXd::Zero(3 * n);
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  int below = 0;
  for (size_t t = 0; t < with_model->mesh().tets().size(); ++t) {
    const Tet& tet = with_model->mesh().tets()[t];
    const TetRestData& rest = with_model->tetRestData()[t];
    Nodes x;
    for (size_t a = 0; a < 4; ++a)
      x[a] = state.positions.segment<3>(3 * tet[a]);
    const Eigen::Matrix3d F = deformationGradient(x, rest.rest_shape_inverse);
    if (barrier.active(F.determinant())) ++below;
    const Nodes f = volumeBarrierForces(F, rest, barrier);
    const TetStiffness k = volumeBarrierStiffness(F, rest, barrier);
    for (size_t a = 0; a < 4; ++a) {
      expected_forces.segment<3>(3 * tet[a]) += f[a];
      for (size_t b = 0; b < 4; ++b)
        K.block<3, 3>(3 * tet[a], 3 * tet[b]) +=
            k.block<3, 3>(3 * static_cast<int>(a), 3 * static_cast<int>(b));
    }
  }
  ASSERT_GT(below, 0);  // 4 of the 8
  ASSERT_LT(below, 8);
  const Eigen::VectorXd added = with_stepper.elasticForces() - without_stepper.elasticForces();
  EXPECT_LT((added - expected_forces).norm(), 1e-9 * expected_forces.norm());
  Eigen::VectorXd y(3 * n), Ky_with, Ky_without;
  for (int i = 0; i < y.size(); ++i)
    y[i] = noise(rng);
  with_stepper.system().multiplyStiffness(y, Ky_with);
  without_stepper.system().multiplyStiffness(y, Ky_without);
  const Eigen::VectorXd expected = K * y;
  EXPECT_LT((Ky_with - Ky_without - expected).norm(), 1e-9 * expected.norm());
}

// Minimum volume ratio of a tet whose apex is thrown at `speed` toward its base.
double smallestVolumeRatio(const Material& material, double speed) {
  auto mesh = std::make_shared<TetMesh>(std::vector<Eigen::Vector3d>(kRest.begin(), kRest.end()),
                                        std::vector<Tet>{{0, 1, 2, 3}});
  auto model = FemModel::create(mesh, material).value();
  Parallel parallel(1);
  ImplicitStepper stepper(model, SolverSettings{}, parallel);
  FemState state = FemState::atRest(*model);
  const Eigen::Vector3d n = (kRest[1] - kRest[0]).cross(kRest[2] - kRest[0]).normalized();
  state.velocities.segment<3>(9) = -speed * n;
  NodeConstraints constraints(model->nodeCount());
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(12);
  const TetRestData rest = restData();
  double smallest = 1;
  for (int k = 0; k < 100; ++k) {
    const StepReport r = stepper.step(state, constraints, zero);
    EXPECT_FALSE(isFatal(r.health)) << r.message;
    Nodes x;
    for (int a = 0; a < 4; ++a)
      x[static_cast<size_t>(a)] = state.positions.segment<3>(3 * a);
    smallest = std::min(smallest, deformationGradient(x, rest.rest_shape_inverse).determinant());
  }
  return smallest;
}

TEST(VolumeBarrier, PushesATetThrownThroughItsOwnFaceBackBeforeItInverts) {
  // 50 m/s carries the apex (a quarter of the mass) through the base of the plain corotated tet
  // (down to J = -0.72); with the barrier the tet keeps a positive volume (J = 0.11 at the
  // deepest) and comes back. The barrier is finite (pressure k at J = 0): at 80 m/s the tet
  // inverts with it too.
  Material without;
  without.barrier_threshold = 0;
  const double speed = 50;
  EXPECT_LT(smallestVolumeRatio(without, speed), 0);
  const double with_barrier = smallestVolumeRatio(Material{}, speed);
  EXPECT_GT(with_barrier, 0);
  EXPECT_LT(with_barrier, Material{}.barrier_threshold);  // it did reach the barrier
}

}  // namespace
}  // namespace torsion

// The lagged model's impulse (sap_problem.h): the compliant normal law, friction on the exact disk
// of radius mu gamma_n^lag, its derivative G against finite differences, the cost's gradient
// -gamma, and the regularisation's constants.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>

#include "sap_test_support.h"
#include "torsion/contact/solve/sap_problem.h"

namespace torsion::sap {
namespace {

RowModel someModel(double mu, double lagged = 0.4) {
  RowModel m;
  m.mu = mu;
  m.radius = mu * lagged;
  m.rt = 2e-4;
  m.rn = 3e-2;
  m.v_hat = 0.01;
  return m;
}

TEST(SapProjection, RegionsFollowTheCompliantLawAndTheDisk) {
  const RowModel m = someModel(0.5);
  // At rest against the bias: gamma = (0, 0, v_hat / R_n), stuck.
  RowResponse r = projectImpulse(m, Eigen::Vector3d::Zero());
  EXPECT_EQ(r.state, ContactState::kStick);
  EXPECT_EQ(r.gamma, Eigen::Vector3d(0, 0, m.v_hat / m.rn));
  // Separating fast: no normal impulse; without slip no friction either.
  r = projectImpulse(m, Eigen::Vector3d(0.0, 0.0, 1.0));
  EXPECT_EQ(r.gamma, Eigen::Vector3d::Zero());
  r = projectImpulse(someModel(0.5, 0.0), Eigen::Vector3d(0.0, 0.0, 1.0));
  EXPECT_EQ(r.state, ContactState::kSeparated);
  EXPECT_EQ(r.gamma, Eigen::Vector3d::Zero());
  EXPECT_EQ(r.g, Eigen::Matrix3d::Zero());
  // Sliding fast along t1: friction on the disk's circle against the slip, and the normal
  // impulse that of the contact at rest: no dilation, whatever the slip.
  for (double slip : {0.01, 1.0, 100.0}) {
    r = projectImpulse(m, Eigen::Vector3d(slip, -0.5 * slip, 0.0));
    EXPECT_EQ(r.state, ContactState::kSlide);
    EXPECT_NEAR(r.gamma.head<2>().norm(), m.radius, 1e-15 * m.radius);
    EXPECT_NEAR(r.gamma.head<2>().normalized().dot(Eigen::Vector2d(-1, 0.5).normalized()), 1.0,
                1e-15);
    EXPECT_EQ(r.gamma(2), m.v_hat / m.rn);
  }
}

// The slip curvature (the Newton model after a short step, sap_solver.h): on a sliding row, G's
// tangential block becomes r / |v_t| I, the curvature of the quadratic that touches the friction
// cost r |v_t| - R_t r^2 / 2 at v_t and lies above it; G stays symmetric positive semidefinite and
// its normal part is untouched. A sticking row, a frictionless one and a joint row keep G.
TEST(SapProjection, SlipCurvatureIsThatOfTheQuadraticAboveTheFrictionCost) {
  const RowModel m = someModel(0.5);
  const Eigen::Vector3d vc(0.03, -0.04, -0.002);  // |v_t| = 0.05 m/s: sliding
  const RowResponse r = projectImpulse(m, vc);
  ASSERT_EQ(r.state, ContactState::kSlide);
  Eigen::Matrix3d g = r.g;
  addSlipCurvature(m, vc, g);
  const double curvature = m.radius / 0.05;
  const Eigen::Matrix2d tangential = g.topLeftCorner<2, 2>();
  EXPECT_TRUE(tangential.isApprox(curvature * Eigen::Matrix2d::Identity(), 1e-12)) << tangential;
  EXPECT_EQ(g.col(2), r.g.col(2));
  EXPECT_EQ(g.row(2), r.g.row(2));
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(g).eigenvalues().minCoeff(), 0.0);
  // Along the slip, from v_t: the quadratic with that curvature, touching the cost (same value,
  // same slope -gamma_t) at v_t, is above the cost everywhere and meets it only there.
  const Eigen::Vector2d t = vc.head<2>().normalized();
  const double normal_cost = projectImpulse(m, Eigen::Vector3d(0, 0, vc(2))).cost;
  const auto friction_cost = [&](double s) {
    Eigen::Vector3d v = vc;
    v.head<2>() = s * t;
    return projectImpulse(m, v).cost - normal_cost;
  };
  const double s0 = 0.05, slope = m.radius;  // d/ds of r |v_t| along t
  for (double s : {-0.2, -0.05, 0.0, 1e-6, 0.01, 0.049, 0.051, 0.2, 1.0}) {
    const double quadratic =
        friction_cost(s0) + slope * (s - s0) + 0.5 * curvature * (s - s0) * (s - s0);
    EXPECT_GE(quadratic, friction_cost(s) - 1e-12) << "s = " << s;
  }
  // Rows whose G is whole keep it.
  for (const Eigen::Vector3d& stuck :
       {Eigen::Vector3d(1e-6, 0, -0.002), Eigen::Vector3d(0, 0, 0)}) {
    const RowResponse s = projectImpulse(m, stuck);
    ASSERT_EQ(s.state, ContactState::kStick);
    Eigen::Matrix3d same = s.g;
    addSlipCurvature(m, stuck, same);
    EXPECT_EQ(same, s.g);
  }
  const RowModel frictionless = someModel(0.0);
  Eigen::Matrix3d same = projectImpulse(frictionless, vc).g;
  addSlipCurvature(frictionless, vc, same);
  EXPECT_EQ(same, projectImpulse(frictionless, vc).g);
}

// Without friction a contact with no tangential velocity at all (a cold start at v = 0) still
// separates when the normal velocity opens the gap: no negative normal impulse.
TEST(SapProjection, FrictionlessContactWithoutSlipSeparates) {
  const RowModel m = someModel(0.0);
  RowResponse r = projectImpulse(m, Eigen::Vector3d(0.0, 0.0, 0.1));
  EXPECT_EQ(r.state, ContactState::kSeparated);
  EXPECT_EQ(r.gamma, Eigen::Vector3d::Zero());
  r = projectImpulse(m, Eigen::Vector3d(0.0, 0.0, -0.1));
  EXPECT_EQ(r.state, ContactState::kStick);
  EXPECT_DOUBLE_EQ(r.gamma(2), (m.v_hat + 0.1) / m.rn);
}

// G = -d gamma / d v_c, symmetric and positive semi-definite, and d ell_i / d v_c = -gamma, in
// each region, by central differences.
TEST(SapProjection, DerivativesMatchFiniteDifferences) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  int seen[3] = {0, 0, 0};
  for (int trial = 0; trial < 300; ++trial) {
    // A fifth of the trials without friction (mu = 0 or a new contact: no lagged impulse).
    const double lagged = trial % 10 == 0 ? 0.0 : 0.4;
    const RowModel m = someModel(trial % 10 == 5 ? 0.0 : 0.8 * (uniform(rng) + 1), lagged);
    // Slow slips (a third of the trials) land inside the disk, fast ones on its circle.
    const double slip = trial % 3 == 0 ? 1e-5 : 0.02;
    const Eigen::Vector3d vc(slip * uniform(rng), slip * uniform(rng), 0.03 * uniform(rng));
    const RowResponse r = projectImpulse(m, vc);
    ++seen[static_cast<int>(r.state)];
    const double h = 1e-9;
    for (int j = 0; j < 3; ++j) {
      const Eigen::Vector3d e = Eigen::Vector3d::Unit(j);
      const RowResponse plus = projectImpulse(m, vc + h * e);
      const RowResponse minus = projectImpulse(m, vc - h * e);
      if (plus.state != r.state || minus.state != r.state) continue;  // on a region's boundary
      const Eigen::Vector3d dgamma = (plus.gamma - minus.gamma) / (2 * h);
      const double scale = r.g.norm() + 1 / m.rt;
      EXPECT_LE((r.g.col(j) + dgamma).norm(), 1e-5 * scale) << "trial " << trial;
      EXPECT_NEAR((plus.cost - minus.cost) / (2 * h), -r.gamma(j), 1e-5 * (r.gamma.norm() + 1e-9))
          << "trial " << trial;
    }
    EXPECT_LE((r.g - r.g.transpose()).norm(), 1e-12 * r.g.norm());
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(r.g).eigenvalues().minCoeff(),
              -1e-12 * r.g.norm());
  }
  EXPECT_GT(seen[0], 10);
  EXPECT_GT(seen[1], 10);
  EXPECT_GT(seen[2], 5);
}

// R_n from the stiffness until the near-rigid cap, R_t = sigma w, v_hat = -phi0 / (dt + tau_d).
// A joint row (sap_problem.h): the impulse (v_hat - v_n) / R_n clamped to [lo, hi], nothing
// along the tangents; G and the cost's slope -gamma against finite differences, the cost C1
// across the bounds.
TEST(SapProjection, AJointRowClampsItsImpulseToItsBoundsWithAC1Cost) {
  RowModel m;
  m.kind = RowKind::kJoint;
  m.rn = 2e-3;
  m.v_hat = 0.01;
  m.lower = -0.5;
  m.upper = 2.0;
  auto at = [&m](double vn) { return projectImpulse(m, Eigen::Vector3d(0.3, -0.2, vn)); };
  EXPECT_EQ(at(0.0).gamma, Eigen::Vector3d(0, 0, m.upper));  // y = 5, beyond hi
  EXPECT_EQ(at(0.0).state, ContactState::kSlide);
  EXPECT_EQ(at(0.009).gamma, Eigen::Vector3d(0, 0, (m.v_hat - 0.009) / m.rn));
  EXPECT_EQ(at(0.009).state, ContactState::kStick);
  EXPECT_EQ(at(0.05).gamma.z(), m.lower);
  const double h = 1e-7;
  for (double vn : {-0.1, 0.0, 0.0075, 0.009, 0.0105, 0.02, 0.1}) {
    const RowResponse r = at(vn);
    EXPECT_EQ(r.gamma.head<2>(), Eigen::Vector2d::Zero());
    const double slope = (at(vn + h).cost - at(vn - h).cost) / (2 * h);
    EXPECT_NEAR(slope, -r.gamma.z(), 1e-6 * (1 + std::abs(r.gamma.z()))) << "v_n " << vn;
    const double dgamma = (at(vn + h).gamma.z() - at(vn - h).gamma.z()) / (2 * h);
    EXPECT_NEAR(r.g(2, 2), -dgamma, 1e-6 / m.rn) << "v_n " << vn;
  }
  // Across each bound the cost meets itself: y = hi at v_n = v_hat - R_n hi.
  for (double bound : {m.upper, m.lower}) {
    const double vn = m.v_hat - m.rn * bound;
    EXPECT_NEAR(at(vn - 1e-12).cost, at(vn + 1e-12).cost, 1e-9);
  }
}

TEST(SapProjection, RegularisationFollowsTheCompliance) {
  const double mass = 2.0, dt = 1e-3;
  MatrixBody particle(test::massMatrix({mass}), Eigen::VectorXd::Zero(3));
  ContactRow row;
  row.frame = contactFrame(Eigen::Vector3d::UnitZ());
  row.terms.push_back(nodeTerm(0, 0, 1.0, row.frame));
  row.mu = 0.3;
  row.dissipation_time = 4e-3;
  row.gap = -1e-4;
  const double w = std::sqrt(3.0) / mass / 3;  // |I / m|_F / 3
  for (double k : {1e4, 1e9}) {
    row.stiffness = k;
    const SapProblem problem = SapProblem::create({&particle}, {row}, dt).value();
    const RowModel& m = problem.model(0);
    EXPECT_NEAR(m.w, w, 1e-15);
    EXPECT_NEAR(m.rt, 1e-3 * w, 1e-18);
    const double physical = 1 / (dt * (dt + 4e-3) * k);
    const double pi = std::acos(-1.0);
    const double cap = w / (4 * pi * pi);
    EXPECT_DOUBLE_EQ(m.rn, std::max(physical, cap));
    EXPECT_DOUBLE_EQ(m.v_hat, 1e-4 / (dt + 4e-3));
  }
}

TEST(SapProjection, MalformedRowsAreRefused) {
  MatrixBody particle(test::massMatrix({1.0}), Eigen::VectorXd::Zero(3));
  ContactRow row;
  row.terms.push_back(nodeTerm(0, 1, 1.0, row.frame));  // node 1 of a one-node body
  row.stiffness = 1e5;
  EXPECT_FALSE(SapProblem::create({&particle}, {row}, 1e-3).ok());
  row.terms[0] = nodeTerm(0, 0, 1.0, row.frame);
  EXPECT_TRUE(SapProblem::create({&particle}, {row}, 1e-3).ok());
  row.mu = -0.1;
  EXPECT_FALSE(SapProblem::create({&particle}, {row}, 1e-3).ok());
}

}  // namespace
}  // namespace torsion::sap

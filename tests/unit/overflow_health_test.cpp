// Overflow must not pass as success: the shared CG loop and the rigid-body health check.
#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "torsion/bullet/rigid_health.h"
#include "torsion/solve/pcg_iterations.h"

namespace torsion {
namespace {

// CG on A = diag(1, 2, 3) from x = 0: r = b on entry.
LinearSolveReport solveDiagonal(const Eigen::Vector3d& b, Eigen::VectorXd& x) {
  const Eigen::Vector3d diagonal(1, 2, 3);
  SolverSettings settings;
  settings.tolerance = 1e-10;
  settings.max_iterations = 10;
  x = Eigen::VectorXd::Zero(3);
  Eigen::VectorXd r = b;
  PcgScratch scratch;
  return pcgIterations(
      [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) { out = diagonal.cwiseProduct(in); },
      [](const Eigen::VectorXd& in, Eigen::VectorXd& out) { out = in; }, b.norm(), settings, x, r,
      scratch);
}

TEST(OverflowHealth, ConjugateGradientSolvesAFiniteSystem) {
  Eigen::VectorXd x;
  const LinearSolveReport report = solveDiagonal(Eigen::Vector3d(1, 4, 9), x);
  EXPECT_TRUE(report.converged);
  EXPECT_FALSE(report.breakdown);
  EXPECT_NEAR(x[2], 3.0, 1e-9);
}

TEST(OverflowHealth, ConjugateGradientCallsAnInfiniteRightHandSideABreakdown) {
  // inf <= tolerance * inf used to pass as converged in 0 iterations.
  Eigen::VectorXd x;
  const LinearSolveReport report =
      solveDiagonal(Eigen::Vector3d(std::numeric_limits<double>::infinity(), 0, 0), x);
  EXPECT_FALSE(report.converged);
  EXPECT_TRUE(report.breakdown);
  ASSERT_NE(report.breakdown_reason, nullptr);
  EXPECT_NE(std::string(report.breakdown_reason).find("not finite"), std::string::npos);
}

TEST(OverflowHealth, ConjugateGradientCallsAnOverflowingNormABreakdown) {
  // Every entry finite, but |b|^2 = 3e400 is not: the arithmetic cannot carry this system.
  Eigen::VectorXd x;
  const LinearSolveReport report = solveDiagonal(Eigen::Vector3d(1e200, 1e200, 1e200), x);
  EXPECT_TRUE(report.breakdown);
  EXPECT_FALSE(report.converged);
}

struct OneSphere {
  btSphereShape shape{0.5};
  btDefaultMotionState motion;
  btRigidBody body{
      btRigidBody::btRigidBodyConstructionInfo(1.0, &motion, &shape, btVector3(0.1, 0.1, 0.1))};
};

TEST(OverflowHealth, HealthyRigidBodiesPass) {
  OneSphere s;
  s.body.setLinearVelocity(btVector3(1, 2, 3));
  EXPECT_FALSE(findUnhealthyRigidBody({{"ball", &s.body}}).has_value());
}

TEST(OverflowHealth, ANanRigidBodyIsFoundByName) {
  OneSphere good, bad;
  btTransform t = bad.body.getCenterOfMassTransform();
  t.setOrigin(btVector3(std::nan(""), 0, 0));
  bad.body.setCenterOfMassTransform(t);
  const auto fault = findUnhealthyRigidBody({{"crate", &good.body}, {"ball", &bad.body}});
  ASSERT_TRUE(fault.has_value());
  EXPECT_EQ(fault->name, "ball");
  EXPECT_EQ(fault->body, &bad.body);
  EXPECT_NE(fault->message.find("rigid body 'ball': position"), std::string::npos)
      << fault->message;
}

TEST(OverflowHealth, AnOverflowingVelocityIsFoundInAWorld) {
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher(&configuration);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &configuration);
  OneSphere s;
  world.addRigidBody(&s.body);
  EXPECT_FALSE(findUnhealthyRigidBody(world).has_value());
  s.body.setAngularVelocity(btVector3(0, 1e200, 0));
  const auto fault = findUnhealthyRigidBody(world);
  ASSERT_TRUE(fault.has_value());
  EXPECT_EQ(fault->name, "#0");
  EXPECT_NE(fault->message.find("angular velocity"), std::string::npos) << fault->message;
  world.removeRigidBody(&s.body);
}

}  // namespace
}  // namespace torsion

// Bullet's rigid contacts taken into an island (contact/solve/rigid_contact_rows.h): which bodies a
// group takes, undoing Bullet's contact impulses exactly, the rows' geometry, and the write-back.
// Plain Bullet worlds, no FEM body: the group is what Bullet's step left.

#include "torsion/contact/solve/rigid_contact_rows.h"

#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "sap_test_support.h"
#include "torsion/bt_conversions.h"
#include "torsion/contact/solve/node_contact_rows.h"
#include "torsion/contact/solve/sap_problem.h"
#include "torsion/contact/solve/sap_solver.h"

namespace torsion::sap {
namespace {

constexpr double kDt = 0.01;
constexpr double kG = 9.81;
// What Bullet's velocities and impulses hold to: double, or float Bullet's 7 digits through its
// solver's sums (velocities of 0.1 m/s, impulses of 0.1 N s).
constexpr double kBulletRounding = sizeof(btScalar) == sizeof(double) ? 1e-9 : 1e-5;

// Ground plane z = 0 and a column of 0.2 m boxes of 1 kg resting on it, stepped until at rest.
struct Column {
  explicit Column(int count) {
    world.setGravity(btVector3(0, 0, btScalar(-kG)));
    add(std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), 0), 0, {0, 0, 0});
    for (int k = 0; k < count; ++k)
      boxes.push_back(
          add(std::make_unique<btBoxShape>(btVector3(btScalar(0.1), btScalar(0.1), btScalar(0.1))),
              1.0, btVector3(0, 0, btScalar(0.1 + 0.2 * k))));
  }
  ~Column() {
    for (btTypedConstraint* c : joints)
      world.removeConstraint(c);
    for (auto& b : bodies)
      world.removeRigidBody(b.get());
  }
  btRigidBody* add(std::unique_ptr<btCollisionShape> shape, double mass, const btVector3& at) {
    btVector3 inertia(0, 0, 0);
    if (mass > 0) shape->calculateLocalInertia(btScalar(mass), inertia);
    btRigidBody::btRigidBodyConstructionInfo info(btScalar(mass), nullptr, shape.get(), inertia);
    info.m_startWorldTransform.setIdentity();
    info.m_startWorldTransform.setOrigin(at);
    info.m_friction = btScalar(0.5);
    bodies.push_back(std::make_unique<btRigidBody>(info));
    bodies.back()->setActivationState(DISABLE_DEACTIVATION);
    world.addRigidBody(bodies.back().get());
    shapes.push_back(std::move(shape));
    return bodies.back().get();
  }
  void step(int steps) {
    for (int k = 0; k < steps; ++k)
      world.stepSimulation(btScalar(kDt), 1, btScalar(kDt));
  }
  RigidContactGroup gather(const std::vector<btRigidBody*>& seeds) {
    std::vector<const btRigidBody*> jointed;
    for (int c = 0; c < world.getNumConstraints(); ++c) {
      jointed.push_back(&world.getConstraint(c)->getRigidBodyA());
      jointed.push_back(&world.getConstraint(c)->getRigidBodyB());
    }
    std::sort(jointed.begin(), jointed.end());
    // Bullet has moved the bodies by their velocity: back to the step's start.
    return gatherRigidContactGroup(
        *world.getDispatcher(), seeds,
        [](const btCollisionObject& object) {
          const btRigidBody* b = btRigidBody::upcast(&object);
          btTransform start = object.getWorldTransform();
          if (b == nullptr || b->isStaticObject()) return start;
          btTransformUtil::integrateTransform(object.getWorldTransform(), -b->getLinearVelocity(),
                                              -b->getAngularVelocity(), btScalar(kDt), start);
          return start;
        },
        jointed);
  }

  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  std::vector<btRigidBody*> boxes;
  std::vector<btTypedConstraint*> joints;
  std::vector<std::unique_ptr<btTypedConstraint>> owned_joints;
};

Vector6d twist(const btRigidBody& body) {
  return (Vector6d() << toEigen(body.getLinearVelocity()), toEigen(body.getAngularVelocity()))
      .finished();
}

TEST(RigidContactRows, AGroupTakesTheWholeColumnAndUndoesBulletsImpulsesExactly) {
  Column column(3);
  column.step(99);
  std::vector<Vector6d> before;
  for (const btRigidBody* box : column.boxes)
    before.push_back(twist(*box));
  column.step(1);
  const RigidContactGroup group = column.gather({column.boxes[0]});
  ASSERT_EQ(group.bodies.size(), 3u);  // the bottom box reaches the two above it
  EXPECT_TRUE(group.kept_by_bullet.empty());
  EXPECT_EQ(group.points.size(), 12u);  // four corners on the ground and on each box below
  // Undone, Bullet's contact impulses leave each box with its velocity before the step plus
  // gravity's g dt: Bullet applies exactly those impulses at those points. (Gyroscopic terms of
  // the boxes' micro-radian-per-second spin are far below the tolerance.)
  for (std::size_t b = 0; b < group.bodies.size(); ++b) {
    const btRigidBody& body = *group.bodies[b];
    const Vector6d& w = group.bullet_impulses[b];
    Vector6d free = twist(body);
    free.head<3>() -= w.head<3>() * toDouble(body.getInvMass());
    free.tail<3>() -= toEigen(body.getInvInertiaTensorWorld()) * w.tail<3>();
    Vector6d expected = before[b];
    expected(2) -= kG * kDt;
    EXPECT_LT((free - expected).norm(), kBulletRounding) << "box " << b;
    // At rest Bullet's contacts on each box net its weight: m g dt up (m = 1 kg), within what its
    // drift of a fraction of a millimetre per second changes.
    EXPECT_NEAR(w(2), kG * kDt, 0.05 * kG * kDt) << "box " << b;
  }
}

TEST(RigidContactRows, ABodyWithAJointStaysWithBulletWithItsWholeGroup) {
  Column column(2);
  column.owned_joints.push_back(
      std::make_unique<btPoint2PointConstraint>(*column.boxes[1], btVector3(0, 0, btScalar(0.1))));
  column.joints.push_back(column.owned_joints.back().get());
  column.world.addConstraint(column.joints.back());
  column.step(20);
  const RigidContactGroup group = column.gather({column.boxes[0]});
  EXPECT_TRUE(group.bodies.empty());
  EXPECT_TRUE(group.points.empty());
  ASSERT_EQ(group.kept_by_bullet.size(), 1u);
  EXPECT_NE(group.kept_by_bullet[0].find("joint"), std::string::npos) << group.kept_by_bullet[0];
}

// The rows solved alone (no FEM body): every contact obeys the model, no box sinks faster than its
// contacts' compliance allows, and the island's impulses written back give the island's own
// wrench when undone.
TEST(RigidContactRows, SolvedRowsCarryTheColumnAndWriteBackWhatTheVelocitiesCarry) {
  Column column(3);
  column.step(100);
  const RigidContactGroup group = column.gather({column.boxes[0]});
  ASSERT_EQ(group.bodies.size(), 3u);
  NodeContactIsland island;
  std::vector<int> group_body;
  for (std::size_t b = 0; b < group.bodies.size(); ++b) {
    const btRigidBody& body = *group.bodies[b];
    const Eigen::Matrix3d inverse_inertia = toEigen(body.getInvInertiaTensorWorld());
    const Eigen::Matrix3d inertia = inverse_inertia.inverse();
    Vector6d free = twist(body);
    free.head<3>() -= group.bullet_impulses[b].head<3>();  // m = 1 kg
    free.tail<3>() -= inverse_inertia * group.bullet_impulses[b].tail<3>();
    Eigen::VectorXd momentum(6);
    momentum << free.head<3>(), inertia * free.tail<3>();
    island.rigid_bodies.push_back(std::make_unique<RigidBody>(1.0, inertia, momentum));
    group_body.push_back(static_cast<int>(b));
  }
  addRigidContactRows(island, group, group_body, RowDefaults{}, kDt);
  ASSERT_EQ(island.rows.size(), group.points.size());
  std::vector<const IslandBody*> bodies;
  for (const auto& b : island.rigid_bodies)
    bodies.push_back(b.get());
  Result<SapProblem> problem = SapProblem::create(bodies, island.rows, kDt);
  ASSERT_TRUE(problem.ok());
  Eigen::VectorXd v;
  SapSolver solver;
  const SapReport report = solver.solve(problem.value(), v);
  test::expectCoulombAndComplementarity(problem.value(), report);
  // No box sinks faster than its contacts' near-rigid compliance lets it: each contact closes at
  // most at R_n gamma_n beyond its push-out v_hat (sap_problem.h), so box k (level k, bottom 0) at
  // most k + 1 times the largest of them. (One solve from Bullet's state, not the rows' rest: at
  // rest each contact sits R_n gamma_n (dt + tau_d) deep, RigidStack.* in the physics tests.)
  double sink = 0;
  for (int i = 0; i < problem.value().rowCount(); ++i) {
    const RowModel& m = problem.value().model(i);
    sink = std::max(sink, m.rn * report.impulses[static_cast<std::size_t>(i)].z() - m.v_hat);
  }
  for (int b = 0; b < 3; ++b)
    EXPECT_GT(v(6 * b + 2), -(b + 1) * sink * (1 + 1e-9)) << "box " << b;
  // Written back, the points hold the island's impulses: gathered again, the undo is the
  // island's own wrench on each body.
  const std::vector<Eigen::Vector3d> impulses = rigidPointImpulses(island, group, report);
  writeBackRigidImpulses(group, impulses);
  const RigidContactGroup again = column.gather({column.boxes[0]});
  ASSERT_EQ(again.bodies.size(), 3u);
  for (std::size_t b = 0; b < 3; ++b) {
    Vector6d island_wrench = Vector6d::Zero();
    for (std::size_t i = 0; i < group.points.size(); ++i) {
      const RigidContactPoint& p = group.points[i];
      if (p.body_a == static_cast<int>(b)) island_wrench += pointWrench(impulses[i], p.lever_a);
      if (p.body_b == static_cast<int>(b)) island_wrench += pointWrench(-impulses[i], p.lever_b);
    }
    // Stored in btScalar: exact to double rounding, or to float's 7 digits.
    EXPECT_LT((again.bullet_impulses[b] - island_wrench).norm(),
              sizeof(btScalar) == sizeof(double) ? 1e-12 : 1e-6)
        << "box " << b;
  }
}

}  // namespace
}  // namespace torsion::sap

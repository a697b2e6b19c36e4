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
#include "torsion/contact/solve/rigid_joint_rows.h"
#include "torsion/contact/solve/sap_problem.h"
#include "torsion/contact/solve/sap_solver.h"

namespace torsion::sap {
// Named, not anonymous: its constants share a unity batch with other files' (TORSION_UNITY_BUILD).
namespace rigid_contact_rows_test {

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
  // Each step as FemSoftBodySolver drives the ledger: begun before Bullet's solve (no damping
  // here, so before the step is the same).
  void step(int steps) {
    for (int k = 0; k < steps; ++k) {
      ledger.begin(world, kDt);
      world.stepSimulation(btScalar(kDt), 1, btScalar(kDt));
    }
  }
  static btTransform startPose(const btCollisionObject& object) {
    const btRigidBody* b = btRigidBody::upcast(&object);
    btTransform start = object.getWorldTransform();
    if (b == nullptr || b->isStaticObject()) return start;
    btTransformUtil::integrateTransform(object.getWorldTransform(), -b->getLinearVelocity(),
                                        -b->getAngularVelocity(), btScalar(kDt), start);
    return start;
  }
  RigidContactGroup gather(const std::vector<btRigidBody*>& seeds) {
    std::vector<btTypedConstraint*> world_joints;
    for (int c = 0; c < world.getNumConstraints(); ++c)
      world_joints.push_back(world.getConstraint(c));
    // Bullet has moved the bodies by their velocity: back to the step's start.
    return gatherRigidContactGroup(*world.getDispatcher(), seeds, startPose, world_joints);
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
  JointLedger ledger;
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

Matrix6d massMatrix(const btRigidBody& body) {
  Matrix6d m = Matrix6d::Zero();
  m.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() / toDouble(body.getInvMass());
  m.bottomRightCorner<3, 3>() = toEigen(body.getInvInertiaTensorWorld()).inverse();
  return m;
}

// The top box of a column of two hangs from a point-to-point joint at its top face's centre: the
// joint joins the group (it no longer leaves it to Bullet), Bullet's joint impulse is undone
// exactly (joint_ledger.h), the joint's rows are Bullet's at the step's start, and solved with
// the contacts they hold the pivot.
TEST(RigidContactRows, AJointedBodyJoinsTheGroupWithItsJointSolvedWithItsContacts) {
  Column column(2);
  btRigidBody& top = *column.boxes[1];
  column.owned_joints.push_back(
      std::make_unique<btPoint2PointConstraint>(top, btVector3(0, 0, btScalar(0.1))));
  column.joints.push_back(column.owned_joints.back().get());
  column.world.addConstraint(column.joints.back());
  column.step(19);
  std::vector<Vector6d> before;
  for (const btRigidBody* box : column.boxes)
    before.push_back(twist(*box));
  column.step(1);
  // Inside Bullet's step, where the FEM solve runs, the bodies still carry their forces; the
  // world has cleared them since.
  for (btRigidBody* box : column.boxes)
    box->applyGravity();
  RigidContactGroup group = column.gather({column.boxes[0]});
  ASSERT_EQ(group.bodies.size(), 2u) << "the bottom box reaches the top one by contact";
  EXPECT_TRUE(group.kept_by_bullet.empty());
  addJointRows(group, column.ledger, Column::startPose, kDt);
  ASSERT_EQ(group.joints.size(), 1u);
  ASSERT_EQ(group.joint_rows.size(), 3u);  // a point-to-point joint: three linear rows
  // Undone, Bullet's contact and joint impulses leave each box with its velocity before the step
  // plus g dt.
  std::vector<Vector6d> start(2);
  for (std::size_t b = 0; b < 2; ++b) {
    const btRigidBody& body = *group.bodies[b];
    const Matrix6d m = massMatrix(body);
    const Vector6d undone = group.bullet_impulses[b] +
                            column.ledger.jointImpulse(body, group.bullet_impulses[b], m, kDt);
    start[b] = twist(body) - m.inverse() * undone;
    Vector6d expected = before[b];
    expected(2) -= kG * kDt;
    EXPECT_LT((start[b] - expected).norm(), kBulletRounding) << "box " << b;
  }
  // The rows at the step's start: each reads the velocity of the box's pivot along its axis
  // (v + omega x r, r the pivot's lever at the start pose), and aims at Bullet's error correction.
  const btTransform pose = Column::startPose(top);
  const Eigen::Vector3d lever = toEigen(pose.getBasis() * btVector3(0, 0, btScalar(0.1)));
  const auto top_index = static_cast<int>(
      std::find(group.bodies.begin(), group.bodies.end(), &top) - group.bodies.begin());
  Vector6d probe;
  probe << 0.3, -0.2, 0.1, 0.5, 0.7, -0.4;
  for (const RigidJointRow& row : group.joint_rows) {
    EXPECT_EQ(row.body_a, top_index);
    EXPECT_EQ(row.body_b, -1) << "the world's fixed body";
    const Eigen::Vector3d point = probe.head<3>() + probe.tail<3>().cross(lever);
    const Eigen::Vector3d axis = row.jacobian_a.head<3>();
    EXPECT_NEAR(axis.norm(), 1, 1e-12);
    EXPECT_NEAR(row.jacobian_a.dot(probe), axis.dot(point), kBulletRounding);
    EXPECT_LT(std::abs(row.target_velocity), 0.01) << "a joint at rest has little error";
  }
  // Solved with the contacts: the pivot holds to the joint rows' compliance, R_n |lambda| per row.
  NodeContactIsland island;
  std::vector<int> group_body;
  for (std::size_t b = 0; b < 2; ++b) {
    const Matrix6d m = massMatrix(*group.bodies[b]);
    Eigen::VectorXd momentum = m * start[b];
    momentum(2) -= kG * kDt * toDouble(1 / group.bodies[b]->getInvMass());
    island.rigid_bodies.push_back(
        std::make_unique<RigidBody>(toDouble(1 / group.bodies[b]->getInvMass()),
                                    Eigen::Matrix3d(m.bottomRightCorner<3, 3>()), momentum));
    group_body.push_back(static_cast<int>(b));
  }
  addRigidContactRows(island, group, group_body, RowDefaults{}, kDt);
  addRigidJointRows(island, group, group_body);
  ASSERT_EQ(island.rows.size(), group.points.size() + 3);
  std::vector<const IslandBody*> bodies;
  for (const auto& b : island.rigid_bodies)
    bodies.push_back(b.get());
  Result<SapProblem> problem = SapProblem::create(bodies, island.rows, kDt);
  ASSERT_TRUE(problem.ok()) << problem.error().message;
  Eigen::VectorXd v;
  SapSolver solver;
  const SapReport report = solver.solve(problem.value(), v);
  ASSERT_TRUE(report.converged) << report.message;
  const std::vector<double> lambda = jointRowImpulses(island, group, report);
  ASSERT_EQ(lambda.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    const RigidJointRow& row = group.joint_rows[i];
    const RowModel& m = problem.value().model(static_cast<int>(group.points.size() + i));
    const double velocity = row.jacobian_a.dot(v.segment<6>(6 * top_index));
    EXPECT_NEAR(velocity, row.target_velocity - m.rn * lambda[i], 1e-9 + 1e-6 * kG * kDt);
  }
  // Written back: the ledger holds the island's joint impulse for the top box, the bottom box has
  // none.
  writeBackJointImpulses(group, lambda, column.ledger, kDt);
  const Vector6d on_top = column.ledger.jointImpulse(top, Vector6d::Zero(), massMatrix(top), kDt);
  Vector6d expected = Vector6d::Zero();
  for (std::size_t i = 0; i < 3; ++i)
    expected += lambda[i] * group.joint_rows[i].jacobian_a;
  EXPECT_LT((on_top - expected).norm(), 1e-15 + 1e-12 * expected.norm());
  EXPECT_EQ(column.ledger
                .jointImpulse(*column.boxes[0], Vector6d::Zero(), massMatrix(*column.boxes[0]), kDt)
                .norm(),
            0.0);
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

}  // namespace rigid_contact_rows_test
}  // namespace torsion::sap

// Two-way anchors (docs/contact.md, "Anchors"): FEM nodes glued to rigid bodies and multibody
// links, inside the implicit solve.
#include <gtest/gtest.h>

#include <cmath>

#include "multibody_world.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion {
// Named, not anonymous: its helpers share a unity batch with other files' (TORSION_UNITY_BUILD).
namespace anchor_test {

using testing::MultibodyWorld;

constexpr double kDt = 1 / 240.;

std::vector<int> nodesWhere(const FemBody& body,
                            const std::function<bool(const Eigen::Vector3d&)>& pick) {
  std::vector<int> nodes;
  for (int i = 0; i < body.model().nodeCount(); ++i) {
    if (pick(body.state().position(i))) nodes.push_back(i);
  }
  return nodes;
}

Eigen::Vector3d femMomentum(const FemBody& body) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i < body.model().nodeCount(); ++i)
    p += body.model().nodeMasses()[static_cast<size_t>(i)] * body.state().velocity(i);
  return p;
}

double femKineticEnergy(const FemBody& body) {
  double e = 0;
  for (int i = 0; i < body.model().nodeCount(); ++i)
    e += 0.5 * body.model().nodeMasses()[static_cast<size_t>(i)] *
         body.state().velocity(i).squaredNorm();
  return e;
}

double maxNodeSpeed(const FemBody& body) {
  double s = 0;
  for (int i = 0; i < body.model().nodeCount(); ++i)
    s = std::max(s, body.state().velocity(i).norm());
  return s;
}

// Largest distance of anchored nodes from where the object's pose carries their offsets.
double anchorError(const FemBody& body, const btCollisionObject& object,
                   const std::vector<int>& nodes, const std::vector<Eigen::Vector3d>& local) {
  double worst = 0;
  for (size_t a = 0; a < nodes.size(); ++a) {
    const Eigen::Vector3d target = toEigen(object.getWorldTransform() * toBt(local[a]));
    worst = std::max(worst, (body.state().position(nodes[a]) - target).norm());
  }
  return worst;
}

std::vector<Eigen::Vector3d> localPoints(const FemBody& body, const btCollisionObject& object,
                                         const std::vector<int>& nodes) {
  std::vector<Eigen::Vector3d> local;
  for (int i : nodes)
    local.push_back(toEigen(object.getWorldTransform().inverse() * toBt(body.state().position(i))));
  return local;
}

// Momentum is exchanged exactly up to the CG's residual (docs/contact.md): the momentum tests
// solve to 1e-9 instead of the default 1e-4, whose residual, summed over thousands of steps, is of
// the order of the 1 % tested.
void solveTightly(FemSoftBodySolver& fem) {
  SolverSettings settings = fem.solverSettings();
  settings.tolerance = 1e-9;
  ASSERT_TRUE(fem.setSolverSettings(settings).ok());
}

FemBody* addBar(FemSoftBodySolver& fem) {
  Material material;
  material.youngs_modulus = 1e5;
  return fem
      .addBody("bar", makeBoxTetMesh({0, -0.025, -0.025}, {0.4, 0.025, 0.025}, 8, 1, 1).value(),
               material)
      .value();
}

// The pendulums' block: a 0.1 m cube 0.5 to 0.6 m below the origin (their pivot).
FemBody* addHangingBlock(FemSoftBodySolver& fem) {
  Material material;
  material.youngs_modulus = 1e5;
  return fem
      .addBody("block", makeBoxTetMesh({-0.05, -0.05, -0.6}, {0.05, 0.05, -0.5}, 3, 3, 3).value(),
               material)
      .value();
}

void pullALightFreeBodyWithASoftBar() {
  MultibodyWorld user(btVector3(0, 0, 0));  // no external force
  solveTightly(user.fem);
  FemBody* bar = addBar(user.fem);  // 1 kg
  const double mass = 0.01;         // a hundred times lighter than the bar
  btRigidBody* box = user.addRigid(std::make_unique<btBoxShape>(btVector3(0.025, 0.025, 0.025)),
                                   mass, btVector3(0.425, 0, 0));
  const std::vector<int> end =
      nodesWhere(*bar, [](const Eigen::Vector3d& p) { return p.x() > 0.4 - 1e-9; });
  ASSERT_TRUE(bar->anchorNodes(end, box).ok());
  const std::vector<Eigen::Vector3d> local = localPoints(*bar, *box, end);
  // The box flies off along the bar and across it: it stretches and bends the bar, which pulls.
  box->setLinearVelocity(btVector3(2, 1, 0));
  const Eigen::Vector3d before = mass * toEigen(box->getLinearVelocity());
  double slowest = 1e9, fastest_node = 0, worst_anchor = 0;
  for (int k = 0; k < 2400; ++k) {
    user.world.stepSimulation(kDt, 0);
    ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;
    slowest = std::min(slowest, static_cast<double>(box->getLinearVelocity().x()));
    fastest_node = std::max(fastest_node, maxNodeSpeed(*bar));
    worst_anchor = std::max(worst_anchor, anchorError(*bar, *box, end, local));
  }
  const Eigen::Vector3d after = femMomentum(*bar) + mass * toEigen(box->getLinearVelocity());
  EXPECT_LT((after - before).norm(), 0.01 * before.norm())
      << "before " << before.transpose() << ", after " << after.transpose();
  EXPECT_LT(slowest, 0.5) << "the bar pulled the box back";
  EXPECT_LT(fastest_node, 2.5) << "nothing faster than the box's own start";
  EXPECT_LT(worst_anchor, 1e-3) << "the anchored nodes stay on the box";
}

TEST(Anchors, ALightFreeBodyPulledByASoftBarConservesMomentumAndStaysStable) {
  pullALightFreeBodyWithASoftBar();
}

// Bullet's pivot is solved before the FEM step, with the bob alone: the block's pull reaches it a
// step late, so the bob must not be much lighter than what hangs from it (a multibody's joints
// are inside the solve: the next test's bob is twenty times lighter).
void swingOnARigidPendulum() {
  MultibodyWorld user(btVector3(0, 0, 0));
  FemBody* block = addHangingBlock(user.fem);  // 1 kg
  const double mass = 1.0;
  btRigidBody* bob = user.addRigid(std::make_unique<btBoxShape>(btVector3(0.05, 0.05, 0.025)), mass,
                                   btVector3(0, 0, -0.475));
  // A rod to a fixed pivot at the origin (Bullet's point-to-point constraint).
  btPoint2PointConstraint pivot(*bob, btVector3(0, 0, 0.475));
  user.world.addConstraint(&pivot);
  const std::vector<int> top =
      nodesWhere(*block, [](const Eigen::Vector3d& p) { return p.z() > -0.5 - 1e-9; });
  ASSERT_TRUE(block->anchorNodes(top, bob).ok());
  const std::vector<Eigen::Vector3d> local = localPoints(*block, *bob, top);
  EXPECT_TRUE((block->setVelocity({1, 0, 0}).ok()));
  bob->setLinearVelocity(btVector3(1, 0, 0));
  bob->setAngularVelocity(btVector3(0, 1 / 0.475, 0));  // the rod turns with the bob
  const double energy = femKineticEnergy(*block) + 0.5 * mass * 1.0;
  double peak = 0, worst_anchor = 0, worst_rod = 0, highest = -1;
  for (int k = 0; k < 3000; ++k) {
    user.world.stepSimulation(kDt, 0);
    ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;
    const double e =
        femKineticEnergy(*block) +
        0.5 * mass *
            static_cast<double>(bob->getLinearVelocity().length2());  // + the bob's spin, small
    peak = std::max(peak, e);
    highest = std::max(highest, static_cast<double>(bob->getCenterOfMassPosition().z()));
    worst_anchor = std::max(worst_anchor, anchorError(*block, *bob, top, local));
    worst_rod = std::max(worst_rod,
                         std::abs(static_cast<double>(
                             (bob->getCenterOfMassTransform() * btVector3(0, 0, 0.475)).length())));
  }
  // It swings round the pivot (a quarter turn at least) without blowing up.
  EXPECT_GT(highest, 0);
  EXPECT_LT(peak, 1.05 * energy) << "kinetic energy must not grow (the deformation stores some)";
  EXPECT_LT(worst_anchor, 2e-3);
  EXPECT_LT(worst_rod, 0.01) << "Bullet's pivot holds the light bob against the heavy block";
}

TEST(Anchors, ASoftBlockOnARigidPendulumSwingsWithoutGainingEnergy) {
  swingOnARigidPendulum();
}

void swingOnALightMultibodyPendulum() {
  MultibodyWorld user(btVector3(0, 0, 0));
  FemBody* block = addHangingBlock(user.fem);  // 1 kg
  // A revolute joint about y at the origin; the bob, twenty times lighter than the block, 0.475 m
  // below it.
  const double mass = 0.05;
  const btVector3 half(0.05, 0.05, 0.025);
  btVector3 inertia;
  btBoxShape(half).calculateLocalInertia(mass, inertia);
  btMultiBody* pendulum = user.addMultibody(1, 0, btVector3(0, 0, 0), true, btVector3(0, 0, 0));
  pendulum->setupRevolute(0, mass, inertia, -1, btQuaternion::getIdentity(), btVector3(0, 1, 0),
                          btVector3(0, 0, 0), btVector3(0, 0, -0.475), true);
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  shapes.push_back(nullptr);
  shapes.push_back(std::make_unique<btBoxShape>(half));
  user.addColliders(pendulum, std::move(shapes), 0.5);
  const btMultiBodyLinkCollider& bob = *pendulum->getLinkCollider(0);
  const std::vector<int> top =
      nodesWhere(*block, [](const Eigen::Vector3d& p) { return p.z() > -0.5 - 1e-9; });
  ASSERT_TRUE(block->anchorNodes(top, pendulum->getLinkCollider(0)).ok());
  const std::vector<Eigen::Vector3d> local = localPoints(*block, bob, top);
  // Bullet's revolute joint turns about -y for +x at the bottom: qdot = -v / r.
  EXPECT_TRUE((block->setVelocity({1, 0, 0}).ok()));
  pendulum->setJointVel(0, -1 / 0.475);
  const double link_inertia = mass * 0.475 * 0.475 + static_cast<double>(inertia.y());
  auto energy = [&] {
    const double qdot = pendulum->getJointVel(0);
    return femKineticEnergy(*block) + 0.5 * link_inertia * qdot * qdot;
  };
  const double start = energy();
  double peak = 0, worst_anchor = 0, highest = -1;
  for (int k = 0; k < 3000; ++k) {
    user.world.stepSimulation(kDt, 0);
    ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;
    peak = std::max(peak, energy());
    highest = std::max(highest, static_cast<double>(bob.getWorldTransform().getOrigin().z()));
    worst_anchor = std::max(worst_anchor, anchorError(*block, bob, top, local));
  }
  EXPECT_GT(highest, 0) << "it swings round the pivot (a quarter turn at least)";
  EXPECT_LT(peak, 1.05 * start) << "kinetic energy must not grow (the deformation stores some)";
  EXPECT_LT(worst_anchor, 2e-3);
}

TEST(Anchors, ASoftBlockOnALightMultibodyPendulumSwingsWithoutGainingEnergy) {
  swingOnALightMultibodyPendulum();
}

void followAKinematicBody() {
  MultibodyWorld user(btVector3(0, 0, -9.81));
  Material material;
  material.youngs_modulus = 1e5;
  FemBody* block =
      user.fem
          .addBody("block", makeBoxTetMesh({-0.05, -0.05, -0.1}, {0.05, 0.05, 0}, 3, 3, 3).value(),
                   material)
          .value();
  btRigidBody* plate = user.addRigid(std::make_unique<btBoxShape>(btVector3(0.08, 0.08, 0.01)), 0,
                                     btVector3(0, 0, 0.01));
  plate->setCollisionFlags(plate->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
  const std::vector<int> top =
      nodesWhere(*block, [](const Eigen::Vector3d& p) { return p.z() > -1e-9; });
  ASSERT_TRUE(block->anchorNodes(top, plate).ok());
  const std::vector<Eigen::Vector3d> local = localPoints(*block, *plate, top);
  double worst = 0;
  for (int k = 1; k <= 480; ++k) {
    // Scripted: up and sideways at up to 0.5 m/s, turning at 1 rad/s about a tilted axis.
    const double t = k * kDt;
    btTransform pose;
    pose.setIdentity();
    pose.setOrigin(btVector3(0.2 * std::sin(2 * t), 0.1 * t, 0.01 + 0.2 * t));
    pose.setRotation(btQuaternion(btVector3(0.3, 0.2, 1).normalized(), t));
    plate->setWorldTransform(pose);
    user.world.stepSimulation(kDt, 0);
    ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;
    worst = std::max(worst, anchorError(*block, *plate, top, local));
  }
  // Each step the nodes move with the plate's velocity at their point plus the drift: what is left
  // is the step's curvature of the rotating motion, about (omega dt)^2 r ~ 2e-6 m, corrected at
  // the next step.
  EXPECT_LT(worst, 1e-5);
  // The block hangs from the plate: it sags under its weight, it does not fall.
  EXPECT_GT(block->state().position(0).z(),
            static_cast<double>(plate->getWorldTransform().getOrigin().z()) - 0.2);
}

TEST(Anchors, NodesAnchoredToAKinematicBodyFollowItExactly) {
  followAKinematicBody();
}

TEST(Anchors, ASoftBarAnchoredToAFreeMultibodyConservesMomentum) {
  MultibodyWorld user(btVector3(0, 0, 0));
  solveTightly(user.fem);
  FemBody* bar = addBar(user.fem);
  const double mass = 0.05;
  auto shape = std::make_unique<btBoxShape>(btVector3(0.025, 0.025, 0.025));
  btVector3 inertia;
  shape->calculateLocalInertia(mass, inertia);
  btMultiBody* body = user.addMultibody(0, mass, inertia, false, btVector3(0.425, 0, 0));
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  shapes.push_back(std::move(shape));
  user.addColliders(body, std::move(shapes), 0.5);
  const std::vector<int> end =
      nodesWhere(*bar, [](const Eigen::Vector3d& p) { return p.x() > 0.4 - 1e-9; });
  ASSERT_TRUE(bar->anchorNodes(end, body->getBaseCollider()).ok());
  const std::vector<Eigen::Vector3d> local = localPoints(*bar, *body->getBaseCollider(), end);
  body->setBaseVel(btVector3(2, 1, 0));
  const Eigen::Vector3d before = mass * toEigen(body->getBaseVel());
  double slowest = 1e9, worst_anchor = 0;
  for (int k = 0; k < 1200; ++k) {
    user.world.stepSimulation(kDt, 0);
    ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;
    slowest = std::min(slowest, static_cast<double>(body->getBaseVel().x()));
    worst_anchor = std::max(worst_anchor, anchorError(*bar, *body->getBaseCollider(), end, local));
  }
  const Eigen::Vector3d after = femMomentum(*bar) + mass * toEigen(body->getBaseVel());
  EXPECT_LT((after - before).norm(), 0.01 * before.norm())
      << "before " << before.transpose() << ", after " << after.transpose();
  EXPECT_LT(slowest, 1.0) << "the bar pulled the multibody back";
  EXPECT_LT(worst_anchor, 1e-3);
}

TEST(Anchors, BadAnchorRequestsAreErrorsNamingTheProblem) {
  MultibodyWorld user(btVector3(0, 0, 0));
  FemBody* bar = addBar(user.fem);
  btRigidBody* box = user.addRigid(std::make_unique<btBoxShape>(btVector3(0.025, 0.025, 0.025)), 1,
                                   btVector3(0.425, 0, 0));
  auto message = [](const Result<int>& r) { return r.ok() ? std::string() : r.error().message; };
  EXPECT_NE(message(bar->anchorNodes({0}, nullptr)).find("no object"), std::string::npos);
  EXPECT_NE(message(bar->anchorNodes({}, box)).find("no nodes"), std::string::npos);
  EXPECT_NE(message(bar->anchorNodes({-1}, box)).find("out of range"), std::string::npos);
  EXPECT_NE(message(bar->anchorNodes({1, 1}, box)).find("twice"), std::string::npos);
  Result<int> first = bar->anchorNodes({1, 2}, box);
  ASSERT_TRUE(first.ok());
  EXPECT_NE(message(bar->anchorNodes({2}, box)).find("anchored already"), std::string::npos);
  EXPECT_TRUE(bar->removeAnchor(first.value()).ok());
  EXPECT_FALSE(bar->removeAnchor(first.value()).ok()) << "removed already";
  EXPECT_FALSE(bar->removeAnchor(7).ok());
  EXPECT_TRUE(bar->anchorNodes({2}, box).ok()) << "a removed anchor frees its nodes";
}

}  // namespace anchor_test
}  // namespace torsion

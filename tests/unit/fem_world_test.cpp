// FEM bodies inside a btSoftRigidDynamicsWorld, beside rigid bodies.
#include "torsion/bullet/fem_world.h"

#include <gtest/gtest.h>

#include <cmath>

#include "torsion/bt_conversions.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion {
// Named, not anonymous: its helpers share a unity batch with other files' (TORSION_UNITY_BUILD).
namespace fem_world_test {

TetMesh beam() {
  return makeBoxTetMesh({0, 0, 0}, {4, 1, 1}, 8, 2, 2).value();
}

std::vector<int> nodesWhere(const FemBody& body,
                            const std::function<bool(const Eigen::Vector3d&)>& pick) {
  std::vector<int> nodes;
  for (int i = 0; i < body.model().nodeCount(); ++i) {
    if (pick(body.model().mesh().restPositions()[static_cast<size_t>(i)])) nodes.push_back(i);
  }
  return nodes;
}

TEST(FemWorld, CantileverSagsAndRigidBoxFallsBesideIt) {
  WorldSettings settings;
  FemWorld world(settings);
  FemBody* body = world.addBody("beam", beam(), Material{}).value();
  body->carryNodes(
      "clamp", nodesWhere(*body, [](const Eigen::Vector3d& p) { return p.x() < 1e-9; }),
      [](double) { return Frame{}; }, world.time());
  btTransform start;
  start.setIdentity();
  start.setOrigin(btVector3(20, 0, 10));  // far from the beam: no contact
  btRigidBody* box =
      world.addRigidBody(std::make_unique<btBoxShape>(btVector3(0.5, 0.5, 0.5)), 1.0, start);

  const int steps = 50;
  for (int k = 0; k < steps; ++k) {
    const WorldStepReport r = world.step();
    ASSERT_TRUE(r.ok) << r.message;
  }
  // Bullet passes dt as btScalar: a float Bullet's clock is the sum of float(dt).
  EXPECT_NEAR(world.time(),
              steps * static_cast<double>(static_cast<btScalar>(settings.solver.time_step)), 1e-12);

  // The free end sags; the clamped end stays.
  const FemState& s = body->state();
  double tip_z = 0;
  for (int i : nodesWhere(*body, [](const Eigen::Vector3d& p) { return p.x() > 4 - 1e-9; }))
    tip_z += s.position(i).z();
  EXPECT_LT(tip_z, 0);
  for (int i : nodesWhere(*body, [](const Eigen::Vector3d& p) { return p.x() < 1e-9; })) {
    EXPECT_EQ(s.position(i), body->model().mesh().restPositions()[static_cast<size_t>(i)]);
  }
  // Bullet sees our node positions, rounded to btScalar (exactly ours on double Bullet). Compared
  // in btScalar: GCC 12.2's SLP vectorizer drops the rounding of toEigen(toBt(x)) at -O2.
  for (int i = 0; i < body->model().nodeCount(); ++i) {
    const btVector3 x = toBt(s.position(i));
    for (int a = 0; a < 3; ++a)
      EXPECT_EQ(body->softBody()->m_nodes[i].m_x[a], x[a]) << "node " << i << " axis " << a;
  }
  // The rigid box fell freely: z = 10 - g t^2 / 2 within Bullet's semi-implicit Euler error.
  const double t = world.time();
  EXPECT_NEAR(box->getWorldTransform().getOrigin().z(), 10 - 0.5 * 9.81 * t * t,
              0.5 * 9.81 * t * settings.solver.time_step + 1e-9);
}

// A body alone in the world skips its node tree (nothing can touch it); when a rigid body
// arrives, the first step brings it up to date, and the fall onto it is bit for bit the fall of
// a world that refreshed it every step (one with a far box from the start).
TEST(FemWorld, ALoneBodyCatchesUpItsContactDataWhenSomethingArrives) {
  auto fall = [](bool far_box_from_start) {
    WorldSettings settings;
    auto world = std::make_unique<FemWorld>(settings);
    Frame pose;
    pose.origin = Eigen::Vector3d(0, 0, 0.3);
    FemBody* body = world->addBody("beam", beam(), Material{}, pose).value();
    // Turning, so that its node tree's boxes change while it is alone.
    EXPECT_TRUE(body->setRigidVelocity(Eigen::Vector3d::Zero(), Eigen::Vector3d(0.6, 0.4, 0)).ok());
    btTransform at;
    at.setIdentity();
    if (far_box_from_start) {
      at.setOrigin(btVector3(500, 0, 0));
      world->addRigidBody(std::make_unique<btBoxShape>(btVector3(1, 1, 1)), 0.0, at);
    }
    for (int k = 0; k < 10; ++k)
      EXPECT_TRUE(world->step().ok);
    at.setOrigin(btVector3(2, 0.5, -0.5));  // a static slab whose top is z = 0
    world->addRigidBody(std::make_unique<btBoxShape>(btVector3(5, 5, 0.5)), 0.0, at);
    int touching_steps = 0;
    for (int k = 0; k < 40; ++k) {
      EXPECT_TRUE(world->step().ok);
      if (body->contacts().stats().active > 0) ++touching_steps;
    }
    EXPECT_GT(touching_steps, 0);  // it landed
    return world;
  };
  const std::unique_ptr<FemWorld> lone = fall(false);
  const std::unique_ptr<FemWorld> never_lone = fall(true);
  const FemBody& a = *lone->bodies().front();
  const FemBody& b = *never_lone->bodies().front();
  for (int i = 0; i < a.model().nodeCount(); ++i) {
    for (int c = 0; c < 3; ++c)
      ASSERT_EQ(a.state().position(i)(c), b.state().position(i)(c)) << "node " << i;
  }
}

// A lone body skips only its node tree: Bullet's node normals, which a user's program may draw the
// body from, follow the nodes every step, as in a world where something else is present.
TEST(FemWorld, ALoneBodysNormalsFollowItsNodesEveryStep) {
  auto turning = [](bool far_box) {
    auto world = std::make_unique<FemWorld>(WorldSettings{});
    FemBody* body = world->addBody("beam", beam(), Material{}).value();
    EXPECT_TRUE(body->setRigidVelocity(Eigen::Vector3d::Zero(), Eigen::Vector3d(0.6, 0.4, 0)).ok());
    if (far_box) {
      btTransform at;
      at.setIdentity();
      at.setOrigin(btVector3(500, 0, 0));
      world->addRigidBody(std::make_unique<btBoxShape>(btVector3(1, 1, 1)), 0.0, at);
    }
    for (int k = 0; k < 10; ++k)
      EXPECT_TRUE(world->step().ok);
    return world;
  };
  const std::unique_ptr<FemWorld> lone = turning(false);
  const std::unique_ptr<FemWorld> never_lone = turning(true);
  btSoftBody& a = *lone->bodies().front()->softBody();
  const btSoftBody& b = *never_lone->bodies().front()->softBody();
  std::vector<btVector3> kept;
  for (int i = 0; i < a.m_nodes.size(); ++i) {
    ASSERT_TRUE(a.m_nodes[i].m_n == b.m_nodes[i].m_n) << "node " << i;
    kept.push_back(a.m_nodes[i].m_n);
  }
  a.updateNormals();  // from the nodes as they are now: nothing may change
  for (int i = 0; i < a.m_nodes.size(); ++i)
    ASSERT_TRUE(a.m_nodes[i].m_n == kept[static_cast<size_t>(i)]) << "node " << i;
}

TEST(FemWorld, SetGravityPullsFemAndRigidBodiesAsleepOrAddedLaterTheNewWay) {
  WorldSettings settings;
  settings.gravity = Eigen::Vector3d::Zero();
  FemWorld world(settings);
  FemBody* body = world.addBody("beam", beam(), Material{}).value();
  btTransform start;
  start.setIdentity();
  start.setOrigin(btVector3(20, 0, 10));  // far from the beam: no contact
  btRigidBody* box =
      world.addRigidBody(std::make_unique<btBoxShape>(btVector3(0.5, 0.5, 0.5)), 1.0, start);
  box->setActivationState(ISLAND_SLEEPING);

  EXPECT_FALSE(world.setGravity(Eigen::Vector3d(0, 0, std::nan(""))).ok());
  EXPECT_EQ(world.settings().gravity, Eigen::Vector3d::Zero());
  const Eigen::Vector3d g(0, 0, -5);
  ASSERT_TRUE(world.setGravity(g).ok());
  EXPECT_EQ(world.settings().gravity, g);
  start.setOrigin(btVector3(-20, 0, 10));
  btRigidBody* later =
      world.addRigidBody(std::make_unique<btBoxShape>(btVector3(0.5, 0.5, 0.5)), 1.0, start);
  EXPECT_EQ(toEigen(later->getGravity()), g);

  const WorldStepReport r = world.step();
  ASSERT_TRUE(r.ok) << r.message;
  // One step from rest: v = g dt, for the sleeping box (woken) and the free FEM body alike (a
  // rigid motion: no elastic or damping force; the FEM's within the CG's relative tolerance).
  const double dt = settings.solver.time_step;
  EXPECT_NEAR(box->getLinearVelocity().z(), g.z() * dt, 1e-6);
  EXPECT_NEAR(later->getLinearVelocity().z(), g.z() * dt, 1e-6);
  const double cg = settings.solver.tolerance * std::abs(g.z() * dt);
  for (int i = 0; i < body->model().nodeCount(); ++i)
    EXPECT_NEAR(body->state().velocity(i).z(), g.z() * dt, cg) << "node " << i;
}

TEST(FemWorld, PoseMovesTheRestShape) {
  FemWorld world(WorldSettings{});
  Frame pose;
  pose.origin = Eigen::Vector3d(1, 2, 3);
  pose.rotation = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
  FemBody* body = world.addBody("b", beam(), Material{}, pose).value();
  const Eigen::Vector3d lo = body->model().mesh().boundsMin(),
                        hi = body->model().mesh().boundsMax();
  EXPECT_NEAR(lo.x(), 0, 1e-12);  // x in [1 - 1, 1]
  EXPECT_NEAR(hi.y(), 6, 1e-12);  // y in [2, 2 + 4]
  EXPECT_NEAR(lo.z(), 3, 1e-12);
}

TEST(FemWorld, DuplicateNameAndBadMaterialAreErrors) {
  FemWorld world(WorldSettings{});
  ASSERT_TRUE(world.addBody("b", beam(), Material{}).ok());
  EXPECT_FALSE(world.addBody("b", beam(), Material{}).ok());
  Material bad;
  bad.poisson_ratio = 0.5;
  Result<FemBody*> r = world.addBody("c", beam(), bad);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("poisson_ratio"), std::string::npos);
}

TEST(FemWorld, InstabilityStopsWithBodyAndStep) {
  WorldSettings settings;
  settings.solver.max_speed = 5;  // gravity alone exceeds it after ~0.5 s of free fall
  FemWorld world(settings);
  world.addBody("faller", beam(), Material{}).value();
  WorldStepReport r;
  for (int k = 0; k < 200 && r.ok; ++k)
    r = world.step();
  ASSERT_FALSE(r.ok);
  EXPECT_NE(r.message.find("body 'faller', step "), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("blow-up"), std::string::npos) << r.message;
}

TEST(FemWorld, AWorldWithoutBodiesStillCountsItsSteps) {
  WorldSettings settings;
  FemWorld world(settings);
  for (int k = 1; k <= 3; ++k) {
    const WorldStepReport r = world.step();
    ASSERT_TRUE(r.ok) << r.message;
    EXPECT_EQ(r.step, k);
  }
  EXPECT_EQ(world.stepCount(), 3);
  const double dt = static_cast<double>(static_cast<btScalar>(settings.solver.time_step));
  EXPECT_NEAR(world.time(), 3 * dt, 1e-12);
  // A body added now starts at the world's clock and the count goes on from there.
  world.addBody("late", beam(), Material{}).value();
  ASSERT_TRUE(world.step().ok);
  EXPECT_EQ(world.stepCount(), 4);
  EXPECT_NEAR(world.time(), 4 * dt, 1e-12);
}

TEST(FemWorld, AFailedStepIsCountedFreezesTheWorldAndIsUndoneByRestoringACheckpoint) {
  WorldSettings settings;
  settings.solver.max_speed = 5;  // gravity alone exceeds it after ~0.5 s of free fall
  FemWorld world(settings);
  FemBody* body = world.addBody("faller", beam(), Material{}).value();
  WorldCheckpoint before_failure = world.checkpoint();
  Eigen::VectorXd positions_before_failure = body->state().positions;
  WorldStepReport r;
  for (int k = 0; k < 200; ++k) {
    before_failure = world.checkpoint();
    positions_before_failure = body->state().positions;
    r = world.step();
    if (!r.ok) break;
  }
  ASSERT_FALSE(r.ok);
  // The failed step counts on the clock, and the body keeps what that step computed.
  EXPECT_EQ(world.stepCount(), r.step);
  EXPECT_NE(body->state().positions, positions_before_failure);

  // Later steps move nothing and report the same failure.
  const Eigen::VectorXd positions_after_failure = body->state().positions;
  const double time_after_failure = world.time();
  const WorldStepReport again = world.step();
  EXPECT_FALSE(again.ok);
  EXPECT_EQ(again.step, r.step);
  EXPECT_EQ(again.message, r.message);
  EXPECT_EQ(world.stepCount(), r.step);
  EXPECT_EQ(world.time(), time_after_failure);
  EXPECT_EQ(body->state().positions, positions_after_failure);

  // The checkpoint from before the failed step brings back the bodies, the clock and the health.
  ASSERT_TRUE(world.restore(before_failure).ok());
  EXPECT_EQ(world.stepCount(), r.step - 1);
  EXPECT_EQ(body->state().positions, positions_before_failure);
  const WorldStepReport retried = world.step();
  EXPECT_FALSE(retried.ok);  // the same step, taken again, fails the same way
  EXPECT_EQ(retried.step, r.step);
  EXPECT_EQ(world.stepCount(), r.step);
}

TEST(FemWorld, ScriptedRotationCarriesNodesExactly) {
  WorldSettings settings;
  settings.gravity.setZero();
  FemWorld world(settings);
  FemBody* body = world.addBody("beam", beam(), Material{}).value();
  const Eigen::Vector3d axis_point(4, 0.5, 0.5);
  const double omega = 1.0;
  const int end = body->carryNodes(
      "end", nodesWhere(*body, [](const Eigen::Vector3d& p) { return p.x() > 4 - 1e-9; }),
      [&](double t) {
        Frame f;
        f.origin = axis_point;
        f.rotation = Eigen::AngleAxisd(omega * t, Eigen::Vector3d::UnitX());
        return f;
      },
      world.time());
  body->carryNodes(
      "clamp", nodesWhere(*body, [](const Eigen::Vector3d& p) { return p.x() < 1e-9; }),
      [](double) { return Frame{}; }, world.time());
  for (int k = 0; k < 20; ++k)
    ASSERT_TRUE(world.step().ok);
  const CarriedNodes& group = *body->groups()[static_cast<size_t>(end)];
  const Frame frame = group.frameAt(world.time());
  for (size_t k = 0; k < group.nodes().size(); ++k) {
    EXPECT_LT(
        (body->state().position(group.nodes()[k]) - frame.toWorld(group.localCoordinates()[k]))
            .norm(),
        1e-12);
  }
  // Twisting the end by +omega t about +x: the body resists with a negative torque about x.
  const Wrench w = body->groupWrench(end, axis_point);
  EXPECT_LT(w.torque.x(), 0);
}

}  // namespace fem_world_test
}  // namespace torsion

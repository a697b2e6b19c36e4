// Torsion inside a world the user built and steps: Bullet's clock and substeps, Bullet's rigid and
// soft bodies beside FEM bodies, multibody worlds.
#include "user_world.h"

#include <BulletDynamics/Featherstone/btMultiBodyConstraintSolver.h>
#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftMultiBodyDynamicsWorld.h>
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>

#include "torsion/bt_conversions.h"
#include "torsion/mesh/ball_mesh.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion {
namespace {

using testing::UserWorld;

std::vector<int> nodesWhere(const FemBody& body,
                            const std::function<bool(const Eigen::Vector3d&)>& pick) {
  std::vector<int> nodes;
  for (int i = 0; i < body.model().nodeCount(); ++i) {
    if (pick(body.model().mesh().restPositions()[static_cast<size_t>(i)])) nodes.push_back(i);
  }
  return nodes;
}

// A soft beam clamped at x = 0: it sags and swings under gravity, so its trajectory is a sharp
// witness of every step's dt and time.
FemBody* addClampedBeam(FemSoftBodySolver& fem, const Eigen::Vector3d& offset) {
  Material material;
  material.youngs_modulus = 2e4;
  FemBody* body = fem.addBody("beam", makeBoxTetMesh({0, 0, 0}, {2, 0.4, 0.4}, 10, 2, 2).value(),
                              material, Frame{offset, Eigen::Quaterniond::Identity()})
                      .value();
  body->carryNodes(
      "clamp",
      nodesWhere(*body, [&](const Eigen::Vector3d& p) { return p.x() < offset.x() + 1e-9; }),
      [](double) { return Frame{}; }, fem.time());
  return body;
}

double maxDifference(const FemState& a, const FemState& b) {
  return (a.positions - b.positions).cwiseAbs().maxCoeff();
}

TEST(UserWorld, SubstepsGiveTheSameTrajectoryAsSteppingAtTheSubstepRate) {
  UserWorld sixty, direct;
  FemBody* a = addClampedBeam(sixty.fem, Eigen::Vector3d::Zero());
  FemBody* b = addClampedBeam(direct.fem, Eigen::Vector3d::Zero());
  for (int call = 0; call < 60; ++call)
    sixty.world.stepSimulation(btScalar(1 / 60.), 10, btScalar(1 / 240.));
  ASSERT_TRUE(sixty.fem.status().ok) << sixty.fem.status().message;
  // Bullet's accumulator decides how many substeps the 60 calls make (240, give or take one
  // rounding); the other world takes exactly as many steps of 1/240 s.
  const std::int64_t substeps = sixty.fem.stepCount();
  EXPECT_NEAR(static_cast<double>(substeps), 240, 1);
  for (std::int64_t k = 0; k < substeps; ++k)
    direct.world.stepSimulation(btScalar(1 / 240.), 0);
  ASSERT_TRUE(direct.fem.status().ok) << direct.fem.status().message;

  // The substeps as Bullet passes them: 1/240 s as a btScalar (a float in a float Bullet).
  EXPECT_NEAR(sixty.fem.time(),
              static_cast<double>(substeps) * static_cast<double>(btScalar(1 / 240.)), 1e-12);
  EXPECT_EQ(sixty.fem.time(), direct.fem.time());
  const double sag = a->state().position(a->model().nodeCount() - 1).z() - 0.4;
  ASSERT_LT(sag, -0.01) << "the beam must move for the comparison to mean anything";
  EXPECT_EQ(maxDifference(a->state(), b->state()), 0.0);  // the same steps, bit for bit
}

TEST(UserWorld, FemBodyFallsLikeARigidBody) {
  UserWorld user;
  Material material;
  material.youngs_modulus = 1e6;
  FemBody* ball =
      user.fem.addBody("ball", makeBallTetMesh({0, 0, 10}, 0.5, 3).value(), material).value();
  btRigidBody* rigid =
      user.addRigid(std::make_unique<btSphereShape>(btScalar(0.5)), 1.0, btVector3(5, 0, 10));
  for (int call = 0; call < 60; ++call)
    user.world.stepSimulation(btScalar(1 / 60.), 10, btScalar(1 / 240.));
  ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;

  // Centre of mass of the FEM ball (lumped masses).
  const std::vector<double>& m = ball->model().nodeMasses();
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  double mass = 0;
  for (int i = 0; i < ball->model().nodeCount(); ++i) {
    com += m[static_cast<size_t>(i)] * ball->state().position(i);
    mass += m[static_cast<size_t>(i)];
  }
  com /= mass;
  const double fem_fall = 10 - com.z();
  const double rigid_fall = 10 - static_cast<double>(rigid->getWorldTransform().getOrigin().z());
  // Both integrators give g dt^2 n (n + 1) / 2 after n steps: the same fall, 0.4 % above the
  // continuous g t^2 / 2 at 240 Hz.
  const double t = user.fem.time();
  EXPECT_NEAR(t, 1.0, 1.0 / 240 + 1e-9);
  EXPECT_NEAR(fem_fall, rigid_fall, 1e-3 * rigid_fall);
  EXPECT_NEAR(fem_fall, 0.5 * 9.81 * t * t, 0.01 * fem_fall);
}

TEST(UserWorld, ScriptedNodesFollowTheSubstepClock) {
  UserWorld user;
  FemBody* beam = addClampedBeam(user.fem, Eigen::Vector3d::Zero());
  // A second group, the free end, pulled along x at 0.1 m/s by a scripted motion.
  const std::vector<int> tip =
      nodesWhere(*beam, [](const Eigen::Vector3d& p) { return p.x() > 2 - 1e-9; });
  beam->carryNodes(
      "pull", tip,
      [](double t) {
        return Frame{Eigen::Vector3d(0.1 * t, 0, 0), Eigen::Quaterniond::Identity()};
      },
      user.fem.time());
  for (int call = 0; call < 30; ++call)
    user.world.stepSimulation(btScalar(1 / 60.), 10, btScalar(1 / 240.));
  ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;
  const double t = user.fem.time();
  EXPECT_GT(t, 0.49);
  for (int i : tip) {
    const double x0 = beam->model().mesh().restPositions()[static_cast<size_t>(i)].x();
    EXPECT_NEAR(beam->state().position(i).x(), x0 + 0.1 * t, 1e-12);
  }
}

TEST(UserWorld, ChangingTheSubstepBetweenCallsIsExact) {
  // The implicit step takes any dt: a world whose fixed substep changes between calls gives the
  // same trajectory as one stepped directly with the same sequence of steps.
  UserWorld varying, direct;
  FemBody* a = addClampedBeam(varying.fem, Eigen::Vector3d::Zero());
  FemBody* b = addClampedBeam(direct.fem, Eigen::Vector3d::Zero());
  const double substeps[] = {1 / 240., 1 / 120., 1 / 480.};
  std::vector<double> taken;
  for (int call = 0; call < 30; ++call) {
    const double h = substeps[call % 3];
    const std::int64_t before = varying.fem.stepCount();
    varying.world.stepSimulation(btScalar(1 / 60.), 10, btScalar(h));
    for (std::int64_t k = before; k < varying.fem.stepCount(); ++k)
      taken.push_back(varying.fem.lastTimeStep());
    ASSERT_TRUE(varying.fem.status().ok) << varying.fem.status().message;
  }
  double sum = 0;
  for (double h : taken) {
    direct.world.stepSimulation(btScalar(h), 0);
    sum += h;
  }
  EXPECT_NEAR(varying.fem.time(), sum, 1e-12);
  EXPECT_EQ(maxDifference(a->state(), b->state()), 0.0);
}

TEST(UserWorld, BulletClothBesideFemBodiesFallsAndLands) {
  UserWorld user;
  addClampedBeam(user.fem, Eigen::Vector3d(10, 0, 1));
  user.addRigid(std::make_unique<btBoxShape>(btVector3(5, 5, btScalar(0.5))), 0.0,
                btVector3(0, 0, btScalar(-0.5)));  // ground, top at z = 0
  btSoftBody* cloth = btSoftBodyHelpers::CreatePatch(
      user.world.getWorldInfo(), btVector3(-1, -1, 2), btVector3(1, -1, 2), btVector3(-1, 1, 2),
      btVector3(1, 1, 2), 9, 9, 0, true);
  cloth->getCollisionShape()->setMargin(btScalar(0.02));
  cloth->setTotalMass(btScalar(0.5));
  user.world.addSoftBody(cloth);

  double lowest_mean_z = 2;
  for (int call = 0; call < 120; ++call) {
    user.world.stepSimulation(btScalar(1 / 60.), 10, btScalar(1 / 240.));
    double mean_z = 0;
    for (int i = 0; i < cloth->m_nodes.size(); ++i)
      mean_z += static_cast<double>(cloth->m_nodes[i].m_x.z());
    mean_z /= cloth->m_nodes.size();
    lowest_mean_z = std::min(lowest_mean_z, mean_z);
  }
  ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;
  EXPECT_EQ(user.fem.stepCount(), 480);
  double mean_z = 0, max_speed = 0;
  for (int i = 0; i < cloth->m_nodes.size(); ++i) {
    mean_z += static_cast<double>(cloth->m_nodes[i].m_x.z());
    max_speed = std::max(max_speed, static_cast<double>(cloth->m_nodes[i].m_v.length()));
  }
  mean_z /= cloth->m_nodes.size();
  EXPECT_LT(mean_z, 0.1) << "the cloth fell from z = 2 to the ground";
  EXPECT_GT(lowest_mean_z, -0.05) << "and did not pass through it";
  EXPECT_LT(max_speed, 0.5) << "it lies still";
  user.world.removeSoftBody(cloth);
  delete cloth;
}

btSoftBody* clothOver(btSoftBodyWorldInfo& info, double z) {
  btSoftBody* cloth = btSoftBodyHelpers::CreatePatch(
      info, btVector3(btScalar(-0.5), btScalar(-0.5), btScalar(z)),
      btVector3(btScalar(0.5), btScalar(-0.5), btScalar(z)),
      btVector3(btScalar(-0.5), btScalar(0.5), btScalar(z)),
      btVector3(btScalar(0.5), btScalar(0.5), btScalar(z)), 5, 5, 0, true);
  cloth->getCollisionShape()->setMargin(btScalar(0.02));
  return cloth;
}

TEST(UserWorld, BulletClothFallingOnAnFemBodyIsRefusedByNameNotPassedThrough) {
  for (UnsupportedContact policy : {UnsupportedContact::kError, UnsupportedContact::kWarn}) {
    UserWorld user;
    user.fem.setUnsupportedContact(policy);
    FemBody* slab =
        user.fem
            .addBody("slab", makeBoxTetMesh({-1, -1, 0}, {1, 1, 0.2}, 4, 4, 1).value(), Material{})
            .value();
    slab->carryNodes(
        "base", nodesWhere(*slab, [](const Eigen::Vector3d& p) { return p.z() < 1e-9; }),
        [](double) { return Frame{}; }, 0.0);
    btSoftBody* cloth = clothOver(user.world.getWorldInfo(), 0.6);
    user.world.addSoftBody(cloth);
    for (int call = 0; call < 60 && user.fem.status().ok; ++call)
      user.world.stepSimulation(btScalar(1 / 60.), 10, btScalar(1 / 240.));
    if (policy == UnsupportedContact::kError) {
      ASSERT_FALSE(user.fem.status().ok);
      EXPECT_NE(user.fem.status().message.find("FEM body 'slab'"), std::string::npos);
      EXPECT_NE(user.fem.status().message.find("do not collide with Bullet's soft bodies"),
                std::string::npos)
          << user.fem.status().message;
      // It was said when they met, not at the start: the cloth fell 0.4 m first (0.28 s).
      EXPECT_GT(user.fem.status().failed_step, 60);
    } else {
      EXPECT_TRUE(user.fem.status().ok) << user.fem.status().message;
      ASSERT_EQ(user.fem.warnings().size(), 1u);
      EXPECT_NE(user.fem.warnings()[0].find("pass through each other"), std::string::npos);
    }
    user.world.removeSoftBody(cloth);
    delete cloth;
  }
}

// The reported case: a Bullet cloth (1.2 x 1.2 m, 17 x 17 nodes 0.075 m apart, margin 0.02 m)
// dropped onto two coarse FEM blocks (0.3 m, 2 x 2 x 2 cells, 0.525 m apart), their bases held.
// Every block node lies half a cloth spacing off the cloth's nodes in x and in y (0.053 m away):
// cloth nodes land on the middle of the blocks' faces, far from every block node, so a test of
// nodes against nodes alone sees nothing and the cloth falls through.
struct ClothOverBlocks {
  UserWorld user;
  btSoftBody* cloth = nullptr;
  static constexpr double kTop = 0.3;  // m, the blocks' top faces

  ClothOverBlocks(double height, const btVector3& gravity) : user(gravity) {
    for (const auto& [name, x] :
         {std::pair<const char*, double>{"left", -0.4125}, {"right", 0.4125}}) {
      FemBody* block =
          user.fem
              .addBody(
                  name,
                  makeBoxTetMesh({x - 0.15, -0.1125, 0}, {x + 0.15, 0.1875, kTop}, 2, 2, 2).value(),
                  Material{})
              .value();
      block->carryNodes(
          "base", nodesWhere(*block, [](const Eigen::Vector3d& p) { return p.z() < 1e-9; }),
          [](double) { return Frame{}; }, 0.0);
    }
    const auto z = btScalar(kTop + height);
    const auto h = btScalar(0.6);
    cloth = btSoftBodyHelpers::CreatePatch(user.world.getWorldInfo(), btVector3(-h, -h, z),
                                           btVector3(h, -h, z), btVector3(-h, h, z),
                                           btVector3(h, h, z), 17, 17, 0, true);
    cloth->getCollisionShape()->setMargin(btScalar(0.02));
    cloth->setTotalMass(btScalar(1));
    user.world.addSoftBody(cloth);
  }
  ~ClothOverBlocks() {
    user.world.removeSoftBody(cloth);
    delete cloth;
  }
  double lowestClothZ() const {
    double z = 1e9;
    for (int i = 0; i < cloth->m_nodes.size(); ++i)
      z = std::min(z, static_cast<double>(cloth->m_nodes[i].m_x.z()));
    return z;
  }
  // Whether Bullet's broadphase pairs the cloth with the block (so the solver is asked).
  bool paired(const char* block) {
    return user.world.getPairCache()->findPair(
               cloth->getBroadphaseHandle(),
               user.fem.body(block)->softBody()->getBroadphaseHandle()) != nullptr;
  }
};

TEST(UserWorld, BulletClothDroppedOnCoarseFemBlocksIsReportedBeforeItPassesThrough) {
  for (UnsupportedContact policy : {UnsupportedContact::kError, UnsupportedContact::kWarn}) {
    // Dropped from 0.3 m above the blocks: a fall of 0.25 s, about 60 steps of 1/240 s.
    ClothOverBlocks scene(0.3, btVector3(0, 0, btScalar(-9.81)));
    scene.user.fem.setUnsupportedContact(policy);
    // One FEM step per call; the steps at which the cloth's lowest node came within 5 cm of the
    // blocks' top and reached it.
    std::int64_t near = 0, reached = 0;
    for (int step = 0; step < 240; ++step) {
      scene.user.world.stepSimulation(btScalar(1 / 240.), 0);
      const double lowest = scene.lowestClothZ();
      if (near == 0 && lowest <= ClothOverBlocks::kTop + 0.05) near = scene.user.fem.stepCount();
      if (reached == 0 && lowest <= ClothOverBlocks::kTop) reached = scene.user.fem.stepCount();
      if (policy == UnsupportedContact::kError && !scene.user.fem.status().ok) break;
    }
    if (policy == UnsupportedContact::kError) {
      ASSERT_FALSE(scene.user.fem.status().ok) << "the cloth fell through the blocks unreported";
      const std::string& message = scene.user.fem.status().message;
      EXPECT_NE(message.find("FEM body '"), std::string::npos) << message;
      EXPECT_NE(message.find("Bullet soft body"), std::string::npos) << message;
      // Said when they met: not while the cloth was still 5 cm above the blocks, and no later
      // than the step at which its lowest node reached their top.
      const std::int64_t failed = scene.user.fem.status().failed_step;
      EXPECT_GT(near, 0);
      EXPECT_GT(failed, near) << message;
      EXPECT_TRUE(reached == 0 || failed <= reached)
          << "reported at step " << failed << ", the cloth reached the top at step " << reached;
      std::cout << "[ reported  ] at step " << failed << " (5 cm above at step " << near
                << "): " << message << "\n";
    } else {
      EXPECT_TRUE(scene.user.fem.status().ok) << scene.user.fem.status().message;
      EXPECT_EQ(scene.user.fem.stepCount(), 240) << "the run goes on";
      EXPECT_LT(scene.lowestClothZ(), 0) << "the cloth passes through, as warned";
      ASSERT_EQ(scene.user.fem.warnings().size(), 2u) << "one warning for each block";
      int left = 0, right = 0;
      for (const std::string& w : scene.user.fem.warnings()) {
        left += w.find("FEM body 'left'") != std::string::npos;
        right += w.find("FEM body 'right'") != std::string::npos;
        EXPECT_NE(w.find("Bullet soft body"), std::string::npos) << w;
      }
      EXPECT_EQ(left, 1);
      EXPECT_EQ(right, 1);
    }
  }
}

TEST(UserWorld, BulletClothHoveringJustAboveFemBlocksIsNotReported) {
  // No gravity: the cloth stays 5 cm above the blocks, inside the broadphase's reach (the boxes
  // grow by the margins and Bullet's contact threshold) but 3 cm clear of both margins.
  ClothOverBlocks scene(0.05, btVector3(0, 0, 0));
  for (int step = 0; step < 100; ++step)
    scene.user.world.stepSimulation(btScalar(1 / 240.), 0);
  EXPECT_TRUE(scene.paired("left")) << "the broadphase must pair them for the test to mean much";
  EXPECT_TRUE(scene.paired("right"));
  EXPECT_TRUE(scene.user.fem.status().ok) << scene.user.fem.status().message;
  EXPECT_TRUE(scene.user.fem.warnings().empty()) << scene.user.fem.warnings().front();
  EXPECT_NEAR(scene.lowestClothZ(), ClothOverBlocks::kTop + 0.05, 1e-6);
}

TEST(UserWorld, FemBlockCornerPushedUpThroughATautBulletClothIsReported) {
  // The symmetric case: an FEM node (a cube's corner, pointing up) meets the middle of a cloth
  // face, 0.036 m and more from every cloth node. The cloth is held by its rim, no gravity.
  UserWorld user(btVector3(0, 0, 0));
  const btScalar z(0.5);
  btSoftBody* cloth = btSoftBodyHelpers::CreatePatch(
      user.world.getWorldInfo(), btVector3(btScalar(-0.5), btScalar(-0.5), z),
      btVector3(btScalar(0.5), btScalar(-0.5), z), btVector3(btScalar(-0.5), btScalar(0.5), z),
      btVector3(btScalar(0.5), btScalar(0.5), z), 10, 10, 0, true);
  cloth->getCollisionShape()->setMargin(btScalar(0.02));
  cloth->setTotalMass(btScalar(1));
  for (int i = 0; i < cloth->m_nodes.size(); ++i) {
    const btVector3& p = cloth->m_nodes[i].m_x;
    if (std::abs(p.x()) > btScalar(0.49) || std::abs(p.y()) > btScalar(0.49)) cloth->setMass(i, 0);
  }
  user.world.addSoftBody(cloth);

  // A 0.3 m cube turned corner-up, its top corner 0.3 m under the cloth, pushed up at 1 m/s.
  const Eigen::Quaterniond up = Eigen::Quaterniond::FromTwoVectors(
      Eigen::Vector3d(1, 1, 1).normalized(), Eigen::Vector3d::UnitZ());
  const Eigen::Vector3d corner = up * Eigen::Vector3d(0.15, 0.15, 0.15);
  const Eigen::Vector3d target(0.01, 0.02, 0.5 - 0.3);
  FemBody* cube =
      user.fem
          .addBody("cube",
                   makeBoxTetMesh({-0.15, -0.15, -0.15}, {0.15, 0.15, 0.15}, 2, 2, 2).value(),
                   Material{}, Frame{target - corner, up})
          .value();
  ASSERT_TRUE(cube->setVelocity(Eigen::Vector3d(0, 0, 1)).ok());
  int top = 0;
  for (int i = 0; i < cube->model().nodeCount(); ++i) {
    if (cube->state().position(i).z() > cube->state().position(top).z()) top = i;
  }
  // 80 steps: the corner ends 3 cm through the cloth, the cube's next nodes (8.7 cm below the
  // corner) still under it. The step at which the corner came within 5 cm of the cloth.
  std::int64_t near = 0;
  for (int step = 0; step < 80 && user.fem.status().ok; ++step) {
    user.world.stepSimulation(btScalar(1 / 240.), 0);
    if (near == 0 && cube->state().position(top).z() >= 0.45) near = user.fem.stepCount();
  }
  ASSERT_FALSE(user.fem.status().ok) << "the corner went through the cloth unreported";
  EXPECT_NE(user.fem.status().message.find("FEM body 'cube'"), std::string::npos)
      << user.fem.status().message;
  // Not before the corner came near; at the latest at step 72, when it crossed the cloth (0.3 m
  // at 1/240 m per step).
  EXPECT_GT(near, 0);
  EXPECT_GT(user.fem.status().failed_step, near) << user.fem.status().message;
  EXPECT_LE(user.fem.status().failed_step, 72) << user.fem.status().message;
  user.world.removeSoftBody(cloth);
  delete cloth;
}

// Two FEM balls, 0.5 m apart, then one thrown at the other: with contact between FEM bodies on
// (the default) they collide and bounce apart; with it off, the pair is refused by name.
void throwBallAtBall(UserWorld& user) {
  Material material;
  material.youngs_modulus = 1e6;
  user.fem.addBody("left", makeBallTetMesh({0, 0, 0}, 0.5, 2).value(), material).value();
  user.fem.addBody("right", makeBallTetMesh({1.5, 0, 0}, 0.5, 2).value(), material).value();
  // No gravity: they sit 0.5 m apart, their boxes apart too; then "right" is thrown at "left".
  user.world.setGravity(btVector3(0, 0, 0));
  for (int call = 0; call < 10; ++call)
    user.world.stepSimulation(btScalar(1 / 60.), 10, btScalar(1 / 240.));
  ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;
  EXPECT_TRUE(user.fem.body("right")->setVelocity(Eigen::Vector3d(-2, 0, 0)).ok());
  for (int call = 0; call < 60 && user.fem.status().ok; ++call)
    user.world.stepSimulation(btScalar(1 / 60.), 10, btScalar(1 / 240.));
}

TEST(UserWorld, TwoFemBodiesThatTouchCollideAndBounceApart) {
  UserWorld user;
  throwBallAtBall(user);
  ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;
  const FemBody& left = *user.fem.body("left");
  const FemBody& right = *user.fem.body("right");
  double left_x = 0, right_x = 0;
  for (int i = 0; i < left.model().nodeCount(); ++i)
    left_x += left.state().position(i).x() / left.model().nodeCount();
  for (int i = 0; i < right.model().nodeCount(); ++i)
    right_x += right.state().position(i).x() / right.model().nodeCount();
  // One second after the throw the balls are apart again, the right one still on the right.
  EXPECT_GT(right_x - left_x, 1.0);
  EXPECT_LT(left.state().velocity(0).x(), -0.5) << "the left ball was pushed away";
}

TEST(UserWorld, TwoFemBodiesThatTouchWithFemContactOffAreReported) {
  UserWorld user;
  ASSERT_TRUE(user.fem.setFemContact(std::nullopt).ok());
  throwBallAtBall(user);
  ASSERT_FALSE(user.fem.status().ok);
  EXPECT_NE(user.fem.status().message.find("contact between FEM bodies is off"), std::string::npos)
      << user.fem.status().message;
}

TEST(UserWorld, RigidBallDroppedOnAnFemSlabRestsOnItUnderSubsteps) {
  UserWorld user;
  Material foam;
  foam.youngs_modulus = 1e5;
  foam.mass_damping = 1;
  FemBody* slab =
      user.fem
          .addBody("slab", makeBoxTetMesh({-0.5, -0.5, 0}, {0.5, 0.5, 0.2}, 5, 5, 1).value(), foam)
          .value();
  slab->carryNodes(
      "base", nodesWhere(*slab, [](const Eigen::Vector3d& p) { return p.z() < 1e-9; }),
      [](double) { return Frame{}; }, 0.0);
  btRigidBody* ball =
      user.addRigid(std::make_unique<btSphereShape>(btScalar(0.1)), 0.5, btVector3(0, 0, 0.6));
  double lowest = 1;
  for (int call = 0; call < 120; ++call) {
    user.world.stepSimulation(btScalar(1 / 60.), 10, btScalar(1 / 240.));
    ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;
    lowest = std::min(lowest, static_cast<double>(ball->getWorldTransform().getOrigin().z()));
  }
  // It lands on the slab's top (z = 0.2) and stays there: its centre one radius above the
  // surface, less the dent a 0.5 kg ball makes in this foam (a few mm), never through it.
  const double z = static_cast<double>(ball->getWorldTransform().getOrigin().z());
  EXPECT_NEAR(z, 0.3, 0.01);
  EXPECT_GT(lowest, 0.28);
  // At rest; float Bullet's contact geometry (GJK at 1e-4 m) leaves it rocking a little more.
  EXPECT_LT(static_cast<double>(ball->getLinearVelocity().length()), kBulletIsDouble ? 0.05 : 0.15);
}

TEST(UserWorld, AttachRefusesAWorldBuiltWithBulletsSolver) {
  btSoftBodyRigidBodyCollisionConfiguration config;
  btCollisionDispatcher dispatcher(&config);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btSoftRigidDynamicsWorld world(&dispatcher, &broadphase, &solver, &config);
  Result<FemSoftBodySolver*> attached = attach(world);
  ASSERT_FALSE(attached.ok());
  EXPECT_NE(attached.error().message.find("torsion::FemSoftBodySolver"), std::string::npos);
}

TEST(UserWorld, OneSolverServesOneWorld) {
  UserWorld user;
  btSoftRigidDynamicsWorld other(&user.dispatcher, &user.broadphase, &user.solver, &user.config,
                                 &user.fem);
  Result<FemSoftBodySolver*> attached = attach(other);
  ASSERT_FALSE(attached.ok());
  EXPECT_NE(attached.error().message.find("already attached"), std::string::npos);
  EXPECT_TRUE(attach(user.world).ok()) << "attaching again to its own world is harmless";
}

TEST(UserWorld, FemBodiesFallInAMultibodyWorld) {
  btSoftBodyRigidBodyCollisionConfiguration config;
  btCollisionDispatcher dispatcher(&config);
  btDbvtBroadphase broadphase;
  btMultiBodyConstraintSolver solver;
  FemSoftBodySolver fem;
  {
    btSoftMultiBodyDynamicsWorld world(&dispatcher, &broadphase, &solver, &config, &fem);
    world.setGravity(btVector3(0, 0, btScalar(-9.81)));
    ASSERT_TRUE(attach(world).ok());
    Material material;
    material.youngs_modulus = 1e6;
    FemBody* ball =
        fem.addBody("ball", makeBallTetMesh({0, 0, 0}, 0.5, 2).value(), material).value();
    for (int call = 0; call < 60; ++call)
      world.stepSimulation(btScalar(1 / 60.), 10, btScalar(1 / 240.));
    ASSERT_TRUE(fem.status().ok) << fem.status().message;
    const double t = fem.time();
    const double n = static_cast<double>(fem.stepCount());
    // Backward Euler from rest: every node falls g dt^2 n (n + 1) / 2 (to the CG's tolerance).
    const double expected = 9.81 * (t / n) * (t / n) * n * (n + 1) / 2;
    EXPECT_NEAR(t, 1.0, 1.0 / 240 + 1e-9);
    EXPECT_NEAR(ball->state().position(0).z() - ball->model().mesh().restPositions()[0].z(),
                -expected, 1e-4 * expected);
  }
}

TEST(UserWorld, PerNodeExternalForcesActEveryStepUntilChanged) {
  UserWorld user(btVector3(0, 0, 0));
  Material material;
  material.youngs_modulus = 1e6;
  FemBody* ball =
      user.fem.addBody("ball", makeBallTetMesh({0, 0, 0}, 0.5, 2).value(), material).value();
  // A uniform force field: F_i = m_i a moves the body as a rigid whole at acceleration a.
  const Eigen::Vector3d a(1, 0, 0);
  Eigen::VectorXd forces(3 * ball->model().nodeCount());
  for (int i = 0; i < ball->model().nodeCount(); ++i)
    forces.segment<3>(3 * i) = ball->model().nodeMasses()[static_cast<size_t>(i)] * a;
  ASSERT_TRUE(ball->setExternalForces(forces).ok());
  for (int k = 0; k < 100; ++k)
    user.world.stepSimulation(btScalar(0.01), 0);
  ASSERT_TRUE(user.fem.status().ok);
  // a t after 1 s (applied once only, it would be 0.01 m/s), to the CG's tolerance.
  double momentum = 0, mass = 0;
  for (int i = 0; i < ball->model().nodeCount(); ++i) {
    const double m = ball->model().nodeMasses()[static_cast<size_t>(i)];
    momentum += m * ball->state().velocity(i).x();
    mass += m;
    EXPECT_NEAR(ball->state().velocity(i).x(), 1.0, 1e-4);
  }
  EXPECT_NEAR(momentum / mass, 1.0, 1e-4);  // once only would give 0.01
  EXPECT_FALSE(ball->setNodeForce(ball->model().nodeCount(), a).ok());
  EXPECT_FALSE(
      ball->setNodeForce(0, Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0, 0)).ok());
  EXPECT_FALSE(ball->setExternalForces(Eigen::VectorXd::Zero(5)).ok());
}

TEST(UserWorld, AnEmptyMeshIsRefusedNamingTheBody) {
  UserWorld user;
  Result<FemBody*> body = user.fem.addBody("empty", TetMesh{}, Material{});
  ASSERT_FALSE(body.ok()) << "an empty mesh would step silently as a body of nothing";
  EXPECT_NE(body.error().message.find("body 'empty'"), std::string::npos) << body.error().message;
  EXPECT_NE(body.error().message.find("no tets"), std::string::npos) << body.error().message;
  EXPECT_TRUE(user.fem.bodies().empty());
}

TEST(UserWorld, APoseWhoseQuaternionIsNotUnitIsRefusedNamingTheBody) {
  UserWorld user;
  const TetMesh mesh = makeBallTetMesh({0, 0, 0}, 0.5, 2).value();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const Eigen::Quaterniond& q :
       {Eigen::Quaterniond(0, 0, 0, 0), Eigen::Quaterniond(2, 0, 0, 0),
        Eigen::Quaterniond(0.9, 0, 0, 0), Eigen::Quaterniond(nan, 0, 0, 0)}) {
    Result<FemBody*> body = user.fem.addBody("b", mesh, Material{}, Frame{{0, 0, 1}, q});
    ASSERT_FALSE(body.ok()) << "quaternion (w, x, y, z) = (" << q.w() << ", " << q.x() << ", "
                            << q.y() << ", " << q.z() << ") was taken";
    EXPECT_NE(body.error().message.find("body 'b'"), std::string::npos) << body.error().message;
    EXPECT_NE(body.error().message.find("unit quaternion"), std::string::npos)
        << body.error().message;
  }
  Result<FemBody*> origin =
      user.fem.addBody("o", mesh, Material{}, Frame{{nan, 0, 0}, Eigen::Quaterniond::Identity()});
  ASSERT_FALSE(origin.ok());
  EXPECT_NE(origin.error().message.find("body 'o'"), std::string::npos);
  EXPECT_TRUE(user.fem.bodies().empty());

  // Round-off off unit length (a quaternion composed from several) is normalised, not refused.
  Result<FemBody*> body = user.fem.addBody("b", mesh, Material{},
                                           Frame{{0, 0, 1}, Eigen::Quaterniond(1 + 1e-9, 0, 0, 0)});
  ASSERT_TRUE(body.ok()) << body.error().message;
  for (int i = 0; i < mesh.nodeCount(); ++i) {
    const Eigen::Vector3d expected =
        mesh.restPositions()[static_cast<size_t>(i)] + Eigen::Vector3d(0, 0, 1);
    EXPECT_LT((body.value()->state().position(i) - expected).norm(), 1e-12);
  }
}

TEST(UserWorld, ValueOfAFailedResultThrowsTheErrorsMessage) {
  btSoftBodyRigidBodyCollisionConfiguration config;
  btCollisionDispatcher dispatcher(&config);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btSoftRigidDynamicsWorld world(&dispatcher, &broadphase, &solver, &config);
  std::string what;
  try {
    attach(world).value();
  } catch (const std::exception& e) {
    what = e.what();
  }
  EXPECT_NE(what.find("torsion::FemSoftBodySolver"), std::string::npos)
      << "what(): '" << what << "'";
}

// A rigid body that goes NaN (here set so; in practice an overflow Bullet integrates without
// complaint) while it rests on an FEM slab fails the solver's status, naming the rigid body, so
// a user who checks fem.status() after stepSimulation learns the world is no longer a number.
TEST(UserWorld, ANonFiniteRigidBodyOnAnFemSlabFailsTheSolversStatus) {
  UserWorld user;
  Material material;
  material.youngs_modulus = 1e6;
  FemBody* slab =
      user.fem.addBody("slab", makeBoxTetMesh({-1, -1, 0}, {1, 1, 0.2}, 6, 6, 2).value(), material)
          .value();
  slab->carryNodes(
      "base", nodesWhere(*slab, [](const Eigen::Vector3d& p) { return p.z() < 1e-9; }),
      [](double) { return Frame{}; }, user.fem.time());
  btRigidBody* box = user.addRigid(
      std::make_unique<btBoxShape>(btVector3(btScalar(0.1), btScalar(0.1), btScalar(0.1))), 1.0,
      btVector3(0, 0, btScalar(0.3)));
  for (int call = 0; call < 20; ++call)
    user.world.stepSimulation(btScalar(0.01), 0);
  ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;
  ASSERT_FALSE(slab->contacts().contacts().empty()) << "the box must rest on the slab";

  const double nan = std::numeric_limits<double>::quiet_NaN();
  box->setLinearVelocity(btVector3(0, 0, btScalar(nan)));
  user.world.stepSimulation(btScalar(0.01), 0);
  ASSERT_FALSE(user.fem.status().ok);
  EXPECT_EQ(user.fem.status().failed_step, 21);
  EXPECT_NE(user.fem.status().message.find("step 21: rigid body '#"), std::string::npos)
      << user.fem.status().message;
  EXPECT_NE(user.fem.status().message.find("not finite"), std::string::npos)
      << user.fem.status().message;
}

}  // namespace
}  // namespace torsion

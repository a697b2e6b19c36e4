// Removing an FEM body from a running world: the world forgets its btSoftBody, the body's memory
// goes with it, and the other bodies step on as before. Removing a rigid body: the FEM bodies
// forget it, an anchored one is refused.
#include <gtest/gtest.h>

#include <memory>

#include "torsion/bullet/fem_world.h"
#include "torsion/mesh/box_mesh.h"
#include "user_world.h"

namespace torsion {
namespace {

using testing::UserWorld;

// Mass-weighted mean vertical velocity: under gravity alone a free body's is exactly -g t (its
// internal forces sum to zero), whatever it does inside.
double meanVerticalVelocity(const FemBody& body) {
  const std::vector<double>& masses = body.model().nodeMasses();
  double momentum = 0, mass = 0;
  for (size_t i = 0; i < masses.size(); ++i) {
    momentum += masses[i] * body.state().velocities[static_cast<Eigen::Index>(3 * i + 2)];
    mass += masses[i];
  }
  return momentum / mass;
}

TEST(RemoveBody, TheWorldForgetsTheBodyItsMemoryIsFreedAndTheOthersStepOn) {
  UserWorld user;
  const TetMesh box = makeBoxTetMesh({0, 0, 0}, {1, 0.4, 0.4}, 4, 2, 2).value();
  FemBody* left = user.fem.addBody("left", box, Material{}).value();
  FemBody* right =
      user.fem.addBody("right", box, Material{}, Frame{{3, 0, 0}, Eigen::Quaterniond::Identity()})
          .value();
  const auto dt = static_cast<btScalar>(0.01);
  for (int k = 0; k < 10; ++k)
    user.world.stepSimulation(dt, 0);
  ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;

  // The model is shared by the body's stepper, system operator and contact solver: it is freed
  // only when all of them are.
  std::weak_ptr<const FemModel> left_model = left->checkpoint().model;
  ASSERT_FALSE(left_model.expired());
  user.fem.removeBody(left);
  EXPECT_TRUE(left_model.expired());
  EXPECT_EQ(user.fem.body("left"), nullptr);
  ASSERT_EQ(user.fem.bodies().size(), 1u);
  ASSERT_EQ(user.world.getSoftBodyArray().size(), 1);
  EXPECT_EQ(user.world.getSoftBodyArray()[0], right->softBody());

  // The remaining body goes on falling freely (ASan would catch a world stepping the freed one).
  for (int k = 0; k < 10; ++k)
    user.world.stepSimulation(dt, 0);
  ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;
  EXPECT_EQ(user.fem.stepCount(), 20);
  const double g = static_cast<double>(user.world.getGravity().z());
  EXPECT_NEAR(meanVerticalVelocity(*right), g * user.fem.time(), 1e-6);

  // The name is free again.
  EXPECT_TRUE(user.fem.addBody("left", box, Material{}).ok());
}

// A 20 kg box resting on a soft slab whose bottom is held, after 60 steps of 1/100 s.
struct BoxOnSlab {
  FemWorld world{WorldSettings{}};
  FemBody* slab = nullptr;
  btRigidBody* box = nullptr;

  BoxOnSlab() {
    const TetMesh mesh = makeBoxTetMesh({0, 0, 0}, {1, 1, 0.3}, 3, 3, 1).value();
    Material soft;
    soft.youngs_modulus = 2e4;
    soft.density = 100;
    slab = world.addBody("slab", mesh, soft).value();
    std::vector<int> bottom;
    for (int i = 0; i < slab->model().nodeCount(); ++i) {
      if (slab->state().position(i).z() < 1e-9) bottom.push_back(i);
    }
    slab->carryNodes(
        "bottom", bottom, [](double) { return Frame{}; }, 0);
    box = world.addRigidBody(std::make_unique<btBoxShape>(btVector3(0.3, 0.3, 0.1)), 20,
                             btTransform(btQuaternion::getIdentity(), btVector3(0.5, 0.5, 0.4)));
    for (int k = 0; k < 60; ++k)
      EXPECT_TRUE(world.step().ok);
  }
};

TEST(RemoveRigidBody, TheFemBodiesForgetItAndTheWorldStepsAndCheckpointsOn) {
  BoxOnSlab rig;
  const auto names_box = [&rig](const CarriedContacts& carried) {
    bool named = false;
    for (const CarriedContacts::Node& n : carried.nodes)
      named = named || n.object == rig.box;
    for (const CarriedContacts::Feature& f : carried.features)
      named = named || f.object == rig.box;
    return named;
  };
  ASSERT_TRUE(names_box(rig.slab->contacts().carriedContacts()));  // it rests on the slab
  // Mean height of the slab's top face (rest z = 0.3).
  const auto top_height = [&rig] {
    double sum = 0;
    int count = 0;
    for (int i = 0; i < rig.slab->model().nodeCount(); ++i) {
      if (rig.slab->model().mesh().restPositions()[static_cast<size_t>(i)].z() > 0.2) {
        sum += rig.slab->state().position(i).z();
        ++count;
      }
    }
    return sum / count;
  };
  const double pressed_top = top_height();

  ASSERT_TRUE(rig.world.removeRigidBody(rig.box).ok());
  EXPECT_TRUE(rig.world.rigidBodies().empty());
  EXPECT_EQ(rig.world.bulletWorld().getNumCollisionObjects(), 1);  // the slab's soft body alone
  EXPECT_FALSE(names_box(rig.slab->contacts().carriedContacts()));
  for (const RigidPartner& partner : rig.slab->contacts().partners())
    EXPECT_NE(partner.object, rig.box);
  // Removing it again is an error, not a double free.
  EXPECT_FALSE(rig.world.removeRigidBody(rig.box).ok());

  // Checkpoints of the world without it continue bit for bit; the slab rises, freed.
  const WorldCheckpoint saved = rig.world.checkpoint();
  for (int k = 0; k < 30; ++k)
    ASSERT_TRUE(rig.world.step().ok);
  const Eigen::VectorXd first = rig.slab->state().positions;
  ASSERT_TRUE(rig.world.restore(saved).ok());
  for (int k = 0; k < 30; ++k)
    ASSERT_TRUE(rig.world.step().ok);
  EXPECT_EQ(rig.slab->state().positions, first);
  EXPECT_GT(top_height(), pressed_top + 1e-4);
}

TEST(RemoveRigidBody, AnAnchoredBodyIsRefusedUntilItsAnchorsAreRemoved) {
  BoxOnSlab rig;
  std::vector<int> top;
  for (int i = 0; i < rig.slab->model().nodeCount(); ++i) {
    if (rig.slab->state().position(i).z() > 0.2) top.push_back(i);
  }
  const int anchor = rig.slab->anchorNodes(top, rig.box).value();
  const Status refused = rig.world.removeRigidBody(rig.box);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("FEM body 'slab' anchors nodes to it (anchor 0)"),
            std::string::npos)
      << refused.error().message;
  EXPECT_EQ(rig.world.rigidBodies().size(), 1u);
  EXPECT_TRUE(rig.world.step().ok);
  ASSERT_TRUE(rig.slab->removeAnchor(anchor).ok());
  EXPECT_TRUE(rig.world.removeRigidBody(rig.box).ok());
  EXPECT_TRUE(rig.world.step().ok);
}

}  // namespace
}  // namespace torsion

// Removing an FEM body from a running world: the world forgets its btSoftBody, the body's memory
// goes with it, and the other bodies step on as before.
#include <gtest/gtest.h>

#include <memory>

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

}  // namespace
}  // namespace torsion

// Checkpoints: going back to a moment and going on gives, bit for bit, what followed it.
#include <gtest/gtest.h>

#include "checkpoint_rigs.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion {
namespace {

struct Recorded {
  Eigen::VectorXd positions, velocities;
  Eigen::Vector3d hand_torque;
  btVector3 rigid_origin;
};

class TwistRig {
 public:
  TwistRig() : world_(test::checkpointWorldSettings()) {
    Material material;
    material.youngs_modulus = 1e5;
    body_ =
        world_.addBody("bar", makeBoxTetMesh({0, 0, 0}, {0.4, 0.4, 2}, 2, 2, 8).value(), material)
            .value();
    test::holdBase(*body_);
    hand_ = std::make_unique<Hand>(*body_);
    btTransform pose;
    pose.setIdentity();
    pose.setOrigin(btVector3(3, 0, 5));  // a rigid ball falling beside the bar
    rigid_ = world_.addRigidBody(std::make_unique<btSphereShape>(btScalar(0.2)), 1.0, pose);
  }

  // The hand grabs the top at step 0 and turns it about z at 1 rad/s.
  void step() {
    const double t = world_.time();
    Frame goal{Eigen::Vector3d(0.2, 0.2, 1.9),
               Eigen::Quaterniond(Eigen::AngleAxisd(t + 0.01, Eigen::Vector3d::UnitZ()))};
    if (!hand_->grabbed()) {
      Frame start{Eigen::Vector3d(0.2, 0.2, 1.9), Eigen::Quaterniond::Identity()};
      ASSERT_TRUE(hand_->grab(start, t).ok());
    }
    EXPECT_TRUE(hand_->moveTo(goal).ok());
    const WorldStepReport r = world_.step();
    ASSERT_TRUE(r.ok) << r.message;
  }

  Recorded record() const {
    return Recorded{body_->state().positions, body_->state().velocities, hand_->wrench().torque,
                    rigid_->getWorldTransform().getOrigin()};
  }

  FemWorld world_;
  FemBody* body_;
  std::unique_ptr<Hand> hand_;
  btRigidBody* rigid_;
};

TEST(Checkpoint, RestoredWorldContinuesBitForBit) {
  TwistRig rig;
  for (int k = 0; k < 30; ++k)
    rig.step();
  const WorldCheckpoint world = rig.world_.checkpoint();
  const HandCheckpoint hand = rig.hand_->checkpoint();
  const double t = rig.world_.time();

  std::vector<Recorded> first;
  for (int k = 0; k < 30; ++k) {
    rig.step();
    if (k == 10) {  // let go and grab again: the group list and the pursuit change
      rig.hand_->release();
    }
    first.push_back(rig.record());
  }
  ASSERT_GT(first.back().hand_torque.norm(), 1e-3) << "the bar must be twisted";

  ASSERT_TRUE(rig.world_.restore(world).ok());
  rig.hand_->restore(hand);
  EXPECT_EQ(rig.world_.time(), t);
  for (int k = 0; k < 30; ++k) {
    rig.step();
    if (k == 10) rig.hand_->release();
    const Recorded again = rig.record();
    EXPECT_EQ((again.positions - first[static_cast<size_t>(k)].positions).cwiseAbs().maxCoeff(),
              0.0)
        << "step " << k;
    EXPECT_EQ((again.velocities - first[static_cast<size_t>(k)].velocities).cwiseAbs().maxCoeff(),
              0.0);
    EXPECT_EQ(again.hand_torque, first[static_cast<size_t>(k)].hand_torque);
    EXPECT_EQ(again.rigid_origin, first[static_cast<size_t>(k)].rigid_origin);
  }
}

TEST(Checkpoint, RestoreRefusesAWorldWhoseRigidBodiesChanged) {
  TwistRig rig;
  rig.step();
  WorldCheckpoint checkpoint = rig.world_.checkpoint();
  rig.world_.addRigidBody(std::make_unique<btSphereShape>(btScalar(0.1)), 1.0,
                          btTransform::getIdentity());
  Status restored = rig.world_.restore(checkpoint);
  ASSERT_FALSE(restored.ok());
  EXPECT_NE(restored.error().message.find("rigid bodies"), std::string::npos);
}

}  // namespace
}  // namespace torsion

// Face contacts (face_contacts.h): rigid shapes smaller than the FEM mesh spacing rest on the
// surface instead of sinking between (or falling through) the nodes, within the stated tolerance,
// and exchange momentum exactly.

#include <gtest/gtest.h>

#include <iostream>

#include "contact_fixtures.h"
#include "torsion/contact/face_distance.h"
#include "torsion/contact/shape_distance.h"

namespace torsion::test {
namespace {

// Deepest penetration of the rigid shape into the body's surface (faces and nodes), m, >= 0.
double surfacePenetration(const FemBody& body, const btRigidBody& rigid) {
  double deepest = 0;
  const btCollisionShape& shape = *rigid.getCollisionShape();
  const btTransform& t = rigid.getWorldTransform();
  for (const Triangle& tri : body.model().mesh().surfaceTriangles()) {
    auto f = shapeToTriangle(shape, t, body.state().position(tri[0]), body.state().position(tri[1]),
                             body.state().position(tri[2]), 0.05);
    if (f) deepest = std::max(deepest, -f->distance);
  }
  return deepest;
}

// A slab 1 x 1 x 0.2 m of 4 x 4 x 1 cells (nodes 0.25 m apart), its base held.
FemBody* coarseSlab(FemWorld& world) {
  Material m = softMaterial(2e5, 100);
  FemBody* slab = addBox(world, "slab", {-0.5, -0.5, 0}, {0.5, 0.5, 0.2}, 4, 4, 1, m);
  if (!slab) return nullptr;  // addBox reported why
  std::vector<int> base;
  for (int i = 0; i < slab->model().nodeCount(); ++i) {
    if (slab->state().position(i).z() < 1e-9) base.push_back(i);
  }
  slab->carryNodes(
      "base", base, [](double) { return Frame{}; }, 0.0);
  return slab;
}

// A ball of radius 0.1 m over the middle of a cell of nodes 0.25 m apart: through the nodes'
// square (diagonal gap 0.35 m) it would fall right through with node contacts alone.
TEST(FaceContact, SmallBallRestsOnCoarseSlab) {
  FemWorld world(contactSettings(0.01));
  FemBody* slab = coarseSlab(world);
  ASSERT_NE(slab, nullptr);
  const double r = 0.1;
  btRigidBody* ball = world.addRigidBody(std::make_unique<btSphereShape>(r), 1.0,
                                         at({0.125, 0.125, 0.2 + r + 0.05}));
  ball->setFriction(0.6);
  double deepest = 0;
  for (int k = 0; k < 200; ++k) {
    ASSERT_TRUE(world.step().ok) << "step " << k;
    deepest = std::max(deepest, surfacePenetration(*slab, *ball));
  }
  const Eigen::Vector3d c = toEigen(ball->getCenterOfMassPosition());
  std::cout << "[figures] small ball on coarse slab: centre z " << c.z() << " m (rest height "
            << 0.2 + r << "), deepest penetration " << deepest << " m, face contacts "
            << slab->contacts().stats().face_active << "\n";
  // 0.1 mm: the face gap tolerance (10 um) plus what the linearisation misses while the ball
  // lands (0.5 m/s); against a fall-through of 0.3 m with node contacts alone.
  EXPECT_LT(deepest, 1e-4);
  // At rest on the surface: the slab (E = 200 kPa) sags well under a millimetre under 1 kg.
  EXPECT_NEAR(c.z(), 0.2 + r, 2e-3);
  EXPECT_LT(toEigen(ball->getLinearVelocity()).norm(), 1e-2);
  EXPECT_GT(slab->contacts().stats().face_active, 0);
}

// A capsule lying across the slab between two rows of nodes (0.25 m apart, the capsule 0.1 m
// thick) rests on the faces along its length.
TEST(FaceContact, CapsuleRestsAcrossFacesBetweenNodeRows) {
  FemWorld world(contactSettings(0.01));
  FemBody* slab = coarseSlab(world);
  ASSERT_NE(slab, nullptr);
  const double r = 0.05;
  btRigidBody* pin = world.addRigidBody(std::make_unique<btCapsuleShape>(r, 0.4), 0.5,
                                        at({0.125, 0.0, 0.2 + r + 0.02}));
  pin->setFriction(0.6);
  double deepest = 0;
  for (int k = 0; k < 150; ++k) {
    ASSERT_TRUE(world.step().ok) << "step " << k;
    deepest = std::max(deepest, surfacePenetration(*slab, *pin));
  }
  const Eigen::Vector3d c = toEigen(pin->getCenterOfMassPosition());
  std::cout << "[figures] capsule across faces: centre z " << c.z() << " m (rest height " << 0.2 + r
            << "), deepest penetration " << deepest << " m\n";
  EXPECT_LT(deepest, 1e-4);  // as for the ball
  EXPECT_NEAR(c.z(), 0.2 + r, 2e-3);
  EXPECT_LT(toEigen(pin->getLinearVelocity()).norm(), 1e-2);
}

// Without gravity, a rigid ball hits the middle of a free block's face (no node near): the
// momentum of the pair is conserved, the ball bounces off and the block is pushed.
TEST(FaceContact, MomentumExchangedThroughAFace) {
  WorldSettings s = contactSettings(0.01);
  s.gravity.setZero();
  FemWorld world(s);
  FemBody* block =
      addBox(world, "block", {0, -0.25, -0.25}, {0.2, 0.25, 0.25}, 1, 2, 2, softMaterial(1e5, 200));
  ASSERT_NE(block, nullptr);
  const double ball_mass = 2, r = 0.05;
  // Aimed at (0, 0.125, 0.125): the middle of a face of the block's -x side, 0.177 m from nodes.
  btRigidBody* ball =
      world.addRigidBody(std::make_unique<btSphereShape>(r), ball_mass, at({-0.2, 0.125, 0.125}));
  ball->setLinearVelocity(btVector3(1.5, 0, 0));
  ball->setFriction(0.0);
  auto p = [&]() -> Eigen::Vector3d {
    return momentum(*block) + ball_mass * toEigen(ball->getLinearVelocity());
  };
  const Eigen::Vector3d before = p();
  double deepest = 0;
  for (int k = 0; k < 40; ++k) {
    ASSERT_TRUE(world.step().ok) << "step " << k;
    deepest = std::max(deepest, surfacePenetration(*block, *ball));
  }
  const Eigen::Vector3d after = p();
  std::cout << "[figures] ball through a face: momentum " << before.transpose() << " -> "
            << after.transpose() << " N s, ball " << ball->getLinearVelocity().x() << " m/s, block "
            << momentum(*block).x() / block->model().totalMass() << " m/s, deepest " << deepest
            << " m\n";
  EXPECT_GT(momentum(*block).x(), 0.5 * before.x());  // most of it went across
  // Implicit and exact exchange: conserved to the solver tolerance (1 % is the bound).
  EXPECT_LT((after - before).norm(), 0.01 * before.norm());
  EXPECT_LT(deepest, 1e-3);  // a 1.5 m/s impact: 1 mm at most of linearisation error
}

}  // namespace
}  // namespace torsion::test

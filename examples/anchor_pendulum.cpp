// A soft FEM block hangs from a rigid pendulum bob by its top nodes (two-way anchors: the nodes
// move with the bob and pull on it, inside the FEM body's implicit solve). The bob swings on
// Bullet's point-to-point constraint under gravity; the program prints the swing and checks that
// the pair stays together and gains no energy.
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "torsion/bullet/fem_soft_body_solver.h"
#include "torsion/mesh/box_mesh.h"

int main() {
  btSoftBodyRigidBodyCollisionConfiguration config;
  btCollisionDispatcher dispatcher(&config);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  torsion::FemSoftBodySolver fem;  // before the world, destroyed after it
  auto world =
      std::make_unique<btSoftRigidDynamicsWorld>(&dispatcher, &broadphase, &solver, &config, &fem);
  const double g = 9.81;
  world->setGravity(btVector3(0, 0, btScalar(-g)));
  if (auto attached = torsion::attach(*world); !attached)
    return std::fprintf(stderr, "error: %s\n", attached.error().message.c_str()), 1;

  // The bob (1 kg) at the end of a 0.475 m rod from a fixed pivot at the origin, released from
  // rest at 45 degrees.
  const double length = 0.475, angle = M_PI / 4;
  btBoxShape bob_shape(btVector3(btScalar(0.05), btScalar(0.05), btScalar(0.025)));
  btVector3 inertia;
  bob_shape.calculateLocalInertia(1, inertia);
  btRigidBody bob(1, nullptr, &bob_shape, inertia);
  btTransform pose;
  pose.setIdentity();
  pose.setRotation(btQuaternion(btVector3(0, 1, 0), btScalar(angle)));
  pose.setOrigin(pose.getBasis() * btVector3(0, 0, btScalar(-length)));
  bob.setWorldTransform(pose);
  bob.setActivationState(DISABLE_DEACTIVATION);
  world->addRigidBody(&bob);
  btPoint2PointConstraint pivot(bob, btVector3(0, 0, btScalar(length)));
  world->addConstraint(&pivot);

  // A soft 10 cm block (1 kg) under the bob, turned with it; its top nodes anchored to the bob.
  torsion::Material rubber;
  rubber.youngs_modulus = 1e5;
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()));
  torsion::FemBody* block =
      fem.addBody(
             "block",
             torsion::makeBoxTetMesh({-0.05, -0.05, -0.6}, {0.05, 0.05, -0.5}, 3, 3, 3).value(),
             rubber, torsion::Frame{Eigen::Vector3d::Zero(), turn})
          .value();
  std::vector<int> top;
  for (int i = 0; i < block->model().nodeCount(); ++i) {
    const Eigen::Vector3d rest =
        turn.conjugate() * block->model().mesh().restPositions()[static_cast<size_t>(i)];
    if (rest.z() > -0.5 - 1e-9) top.push_back(i);
  }
  if (auto anchored = block->anchorNodes(top, &bob); !anchored)
    return std::fprintf(stderr, "error: %s\n", anchored.error().message.c_str()), 1;

  // Potential + kinetic energy of the pair (the block's elastic energy comes on top, >= 0).
  auto energy = [&] {
    double e = 0.5 * static_cast<double>(bob.getLinearVelocity().length2()) +
               g * static_cast<double>(bob.getCenterOfMassPosition().z());
    for (int i = 0; i < block->model().nodeCount(); ++i) {
      const double m = block->model().nodeMasses()[static_cast<size_t>(i)];
      e +=
          m * (0.5 * block->state().velocity(i).squaredNorm() + g * block->state().position(i).z());
    }
    return e;
  };
  const double start = energy();
  double highest = start;
  for (int k = 1; k <= 480; ++k) {
    world->stepSimulation(btScalar(1 / 240.), 0);
    if (!fem.status().ok)
      return std::fprintf(stderr, "error: %s\n", fem.status().message.c_str()), 3;
    highest = std::max(highest, energy());
    if (k % 60 == 0) {
      const btVector3 p = bob.getCenterOfMassPosition();
      std::printf("t = %.2f s: bob at x = %+.3f m, z = %+.3f m; energy %+.3f J (start %+.3f J)\n",
                  fem.time(), static_cast<double>(p.x()), static_cast<double>(p.z()), energy(),
                  start);
    }
  }
  world->removeConstraint(&pivot);
  world->removeRigidBody(&bob);
  world.reset();
  // Backward Euler and Bullet's constraint damp a little; they must never add energy.
  return highest <= start + 0.01 * std::abs(start) ? 0 : 4;
}

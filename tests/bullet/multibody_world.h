#pragma once
// A user's btSoftMultiBodyDynamicsWorld with Torsion's FemSoftBodySolver attached, and the
// Featherstone multibodies the tests build in it (a free box, a two-finger gripper). It owns
// everything it adds and removes it from the world before the world goes.

#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyConstraintSolver.h>
#include <BulletDynamics/Featherstone/btMultiBodyJointMotor.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftMultiBodyDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "torsion/bt_conversions.h"
#include "torsion/bullet/fem_soft_body_solver.h"

namespace torsion::testing {

struct MultibodyWorld {
  // Declaration order is destruction order reversed: the world goes before the FEM solver.
  btSoftBodyRigidBodyCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btMultiBodyConstraintSolver solver;
  FemSoftBodySolver fem;
  btSoftMultiBodyDynamicsWorld world{&dispatcher, &broadphase, &solver, &config, &fem};
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btRigidBody>> rigids;
  std::vector<std::unique_ptr<btMultiBody>> multibodies;
  std::vector<std::unique_ptr<btMultiBodyLinkCollider>> colliders;
  std::vector<std::unique_ptr<btMultiBodyJointMotor>> motors;

  explicit MultibodyWorld(const btVector3& gravity) {
    world.setGravity(gravity);
    world.getWorldInfo().m_gravity = gravity;
    EXPECT_TRUE(attach(world).ok());
  }
  ~MultibodyWorld() {
    for (auto& m : motors)
      world.removeMultiBodyConstraint(m.get());
    for (auto& c : colliders)
      world.removeCollisionObject(c.get());
    for (auto& m : multibodies)
      world.removeMultiBody(m.get());
    for (auto& r : rigids)
      world.removeRigidBody(r.get());
  }

  btRigidBody* addRigid(std::unique_ptr<btCollisionShape> shape, double mass,
                        const btVector3& origin) {
    btVector3 inertia(0, 0, 0);
    if (mass > 0) shape->calculateLocalInertia(mass, inertia);
    btRigidBody::btRigidBodyConstructionInfo info(mass, nullptr, shape.get(), inertia);
    info.m_startWorldTransform.setIdentity();
    info.m_startWorldTransform.setOrigin(origin);
    rigids.push_back(std::make_unique<btRigidBody>(info));
    rigids.back()->setActivationState(DISABLE_DEACTIVATION);
    world.addRigidBody(rigids.back().get());
    shapes.push_back(std::move(shape));
    return rigids.back().get();
  }

  /// A multibody, undamped and awake, added to the world; finish its links, then call
  /// addColliders.
  btMultiBody* addMultibody(int links, double base_mass, const btVector3& base_inertia,
                            bool fixed_base, const btVector3& base_position) {
    multibodies.push_back(
        std::make_unique<btMultiBody>(links, base_mass, base_inertia, fixed_base, false));
    btMultiBody* body = multibodies.back().get();
    body->setBasePos(base_position);
    body->setWorldToBaseRot(btQuaternion::getIdentity());
    body->setLinearDamping(0);
    body->setAngularDamping(0);
    return body;
  }

  /// After the links are set up: one collider per link (index -1 the base), null for none.
  void addColliders(btMultiBody* body, std::vector<std::unique_ptr<btCollisionShape>> link_shapes,
                    double friction) {
    body->finalizeMultiDof();
    world.addMultiBody(body);
    for (size_t s = 0; s < link_shapes.size(); ++s) {
      if (!link_shapes[s]) continue;
      const int link = static_cast<int>(s) - 1;
      colliders.push_back(std::make_unique<btMultiBodyLinkCollider>(body, link));
      btMultiBodyLinkCollider* collider = colliders.back().get();
      collider->setCollisionShape(link_shapes[s].get());
      collider->setFriction(friction);
      world.addCollisionObject(collider, btBroadphaseProxy::DefaultFilter,
                               btBroadphaseProxy::AllFilter);
      if (link < 0)
        body->setBaseCollider(collider);
      else
        body->getLink(link).m_collider = collider;
      shapes.push_back(std::move(link_shapes[s]));
    }
    btAlignedObjectArray<btQuaternion> world_to_local;
    btAlignedObjectArray<btVector3> local_origin;
    world_to_local.resize(body->getNumLinks() + 1);
    local_origin.resize(body->getNumLinks() + 1);
    body->forwardKinematics(world_to_local, local_origin);
    body->updateCollisionObjectWorldTransforms(world_to_local, local_origin);
  }

  /// A velocity motor on a one-dof joint that pushes with at most `max_force` (N) per step of
  /// length `dt` (Bullet bounds the motor's impulse per step).
  btMultiBodyJointMotor* addMotor(btMultiBody* body, int link, double velocity, double max_force,
                                  double dt) {
    motors.push_back(std::make_unique<btMultiBodyJointMotor>(body, link, velocity, max_force * dt));
    world.addMultiBodyConstraint(motors.back().get());
    return motors.back().get();
  }
};

/// World velocity of link `link`'s centre of mass (-1 the base); the link needs a collider.
inline btVector3 linkComVelocity(const btMultiBody& body, int link) {
  std::vector<btVector3> omega(static_cast<size_t>(body.getNumLinks() + 1));
  std::vector<btVector3> vel(omega.size());
  body.compTreeLinkVelocities(omega.data(), vel.data());  // each in its link's frame
  const btQuaternion local_to_world =
      link < 0 ? body.getWorldToBaseRot().inverse()
               : body.getLinkCollider(link)->getWorldTransform().getRotation();
  return quatRotate(local_to_world, vel[static_cast<size_t>(link + 1)]);
}

}  // namespace torsion::testing

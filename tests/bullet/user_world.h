#pragma once
// A Bullet world as a user builds it: their own collision configuration, dispatcher, broadphase,
// constraint solver and btSoftRigidDynamicsWorld, with Torsion's FemSoftBodySolver as the
// world's soft-body solver, attached. The tests step it with stepSimulation as users do.

#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "torsion/bullet/fem_soft_body_solver.h"

namespace torsion::testing {

struct UserWorld {
  // Declaration order is destruction order reversed: the world goes before the FEM solver.
  btSoftBodyRigidBodyCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  FemSoftBodySolver fem;
  btSoftRigidDynamicsWorld world{&dispatcher, &broadphase, &solver, &config, &fem};
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btRigidBody>> rigids;

  explicit UserWorld(const btVector3& gravity = btVector3(0, 0, btScalar(-9.81))) {
    world.setGravity(gravity);
    world.getWorldInfo().m_gravity = gravity;
    world.getWorldInfo().m_sparsesdf.Initialize();
    Result<FemSoftBodySolver*> attached = attach(world);
    EXPECT_TRUE(attached.ok()) << (attached.ok() ? "" : attached.error().message);
  }
  ~UserWorld() {
    for (auto& r : rigids)
      world.removeRigidBody(r.get());
  }

  btRigidBody* addRigid(std::unique_ptr<btCollisionShape> shape, double mass,
                        const btVector3& origin) {
    btVector3 inertia(0, 0, 0);
    if (mass > 0) shape->calculateLocalInertia(btScalar(mass), inertia);
    btTransform pose;
    pose.setIdentity();
    pose.setOrigin(origin);
    btRigidBody::btRigidBodyConstructionInfo info(btScalar(mass), nullptr, shape.get(), inertia);
    info.m_startWorldTransform = pose;
    rigids.push_back(std::make_unique<btRigidBody>(info));
    rigids.back()->setActivationState(DISABLE_DEACTIVATION);
    world.addRigidBody(rigids.back().get());
    shapes.push_back(std::move(shape));
    return rigids.back().get();
  }
};

}  // namespace torsion::testing

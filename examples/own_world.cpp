// Torsion in a Bullet world you build and step yourself: an FEM beam clamped at one end, a rigid
// ball dropped on it, and one of Bullet's own cloths falling beside it on the ground, stepped at
// 60 Hz with four substeps of 1/240 s. Prints the FEM time, the beam's tip and the ball.
#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include <cstdio>
#include <memory>

#include "torsion/bullet/fem_soft_body_solver.h"
#include "torsion/mesh/box_mesh.h"

int main() {
  // The world, as any Bullet program builds it; Torsion's solver is its soft-body solver.
  btSoftBodyRigidBodyCollisionConfiguration config;
  btCollisionDispatcher dispatcher(&config);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  torsion::FemSoftBodySolver fem;  // constructed before the world, destroyed after it
  auto world =
      std::make_unique<btSoftRigidDynamicsWorld>(&dispatcher, &broadphase, &solver, &config, &fem);
  const btVector3 gravity(0, 0, btScalar(-9.81));
  world->setGravity(gravity);
  world->getWorldInfo().m_gravity = gravity;
  world->getWorldInfo().m_sparsesdf.Initialize();
  if (auto attached = torsion::attach(*world); !attached) {
    std::fprintf(stderr, "error: %s\n", attached.error().message.c_str());
    return 1;
  }

  // An FEM beam, 2 m x 0.4 m x 0.4 m, clamped at x = 0, 1 m above the ground.
  torsion::Material rubber;
  rubber.youngs_modulus = 1e7;  // Pa: the beam sags about 0.15 m
  rubber.poisson_ratio = 0.45;
  auto mesh = torsion::makeBoxTetMesh({0, -0.2, 0.8}, {2, 0.2, 1.2}, 10, 2, 2);
  if (!mesh) return std::fprintf(stderr, "error: %s\n", mesh.error().message.c_str()), 1;
  torsion::FemBody* beam = fem.addBody("beam", mesh.value(), rubber).value();
  std::vector<int> clamped;
  int tip = 0;
  for (int i = 0; i < beam->model().nodeCount(); ++i) {
    const Eigen::Vector3d& p = beam->model().mesh().restPositions()[static_cast<size_t>(i)];
    if (p.x() < 1e-9) clamped.push_back(i);
    if (p.x() > 2 - 1e-9 && p.z() > 1.2 - 1e-9) tip = i;
  }
  beam->carryNodes(
      "clamp", clamped, [](double) { return torsion::Frame{}; }, fem.time());

  // Rigid bodies: the ground and a ball that lands on the beam's free half.
  btBoxShape ground_shape(btVector3(5, 5, btScalar(0.5)));
  btRigidBody ground(0, nullptr, &ground_shape);
  ground.getWorldTransform().setOrigin(btVector3(0, 0, btScalar(-0.5)));
  world->addRigidBody(&ground);
  btSphereShape ball_shape(btScalar(0.15));
  btVector3 inertia;
  ball_shape.calculateLocalInertia(2, inertia);
  btRigidBody ball(2, nullptr, &ball_shape, inertia);
  ball.getWorldTransform().setOrigin(btVector3(btScalar(1.6), 0, 2));
  world->addRigidBody(&ball);

  // One of Bullet's own cloths: Bullet's default solver steps it, beside the FEM beam.
  btSoftBody* cloth = btSoftBodyHelpers::CreatePatch(world->getWorldInfo(), btVector3(-2, -1, 1),
                                                     btVector3(-1, -1, 1), btVector3(-2, 1, 1),
                                                     btVector3(-1, 1, 1), 8, 8, 0, true);
  cloth->getCollisionShape()->setMargin(btScalar(0.02));
  world->addSoftBody(cloth);

  for (int frame = 1; frame <= 120; ++frame) {
    world->stepSimulation(btScalar(1 / 60.), 10, btScalar(1 / 240.));
    if (!fem.status().ok) {
      std::fprintf(stderr, "error: %s\n", fem.status().message.c_str());
      return 3;
    }
    if (frame % 30 == 0) {
      std::printf(
          "t = %.3f s (%lld FEM steps): beam tip z = %.4f m, ball z = %.4f m, cloth z = %.3f m\n",
          fem.time(), static_cast<long long>(fem.stepCount()), beam->state().position(tip).z(),
          static_cast<double>(ball.getWorldTransform().getOrigin().z()),
          static_cast<double>(cloth->m_nodes[0].m_x.z()));
    }
  }
  world->removeSoftBody(cloth);
  delete cloth;
  world->removeRigidBody(&ball);
  world->removeRigidBody(&ground);
  world.reset();  // the world goes before the solver
  return 0;
}

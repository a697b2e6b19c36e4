// Rigid bodies from a .bullet file (Bullet's own serialized worlds) beside an FEM body. The
// program first writes a small .bullet file (a ground and three boxes) as any Bullet program can,
// then loads it with btBulletWorldImporter into a world that has Torsion's solver, drops the boxes
// on an FEM slab and prints where they come to rest.
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <BulletWorldImporter/btBulletWorldImporter.h>
#include <btBulletDynamicsCommon.h>

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "torsion/bullet/fem_soft_body_solver.h"
#include "torsion/mesh/box_mesh.h"

namespace {

// A plain rigid-body world, serialized to `path`.
bool writeBulletFile(const std::string& path) {
  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher(&config);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &config);
  world.setGravity(btVector3(0, 0, btScalar(-9.81)));  // the file keeps it; the importer sets it
  btBoxShape ground_shape(btVector3(3, 3, btScalar(0.5)));
  btBoxShape box_shape(btVector3(btScalar(0.1), btScalar(0.1), btScalar(0.1)));
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  auto add = [&](btCollisionShape* shape, btScalar mass, const btVector3& at) {
    btVector3 inertia(0, 0, 0);
    if (mass > 0) shape->calculateLocalInertia(mass, inertia);
    bodies.push_back(std::make_unique<btRigidBody>(mass, nullptr, shape, inertia));
    bodies.back()->getWorldTransform().setOrigin(at);
    world.addRigidBody(bodies.back().get());
  };
  add(&ground_shape, 0, btVector3(0, 0, btScalar(-0.5)));
  for (int k = 0; k < 3; ++k)
    add(&box_shape, 1, btVector3(btScalar(-0.4 + 0.4 * k), 0, btScalar(0.8 + 0.3 * k)));
  btDefaultSerializer serializer;
  world.serialize(&serializer);
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) return false;
  const size_t size = static_cast<size_t>(serializer.getCurrentBufferSize());
  const bool ok = std::fwrite(serializer.getBufferPointer(), 1, size, file) == size;
  for (auto& b : bodies)
    world.removeRigidBody(b.get());
  return std::fclose(file) == 0 && ok;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : "boxes.bullet";
  if (!writeBulletFile(path))
    return std::fprintf(stderr, "error: cannot write %s\n", path.c_str()), 1;

  btSoftBodyRigidBodyCollisionConfiguration config;
  btCollisionDispatcher dispatcher(&config);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  torsion::FemSoftBodySolver fem;
  auto world =
      std::make_unique<btSoftRigidDynamicsWorld>(&dispatcher, &broadphase, &solver, &config, &fem);
  world->setGravity(btVector3(0, 0, btScalar(-9.81)));
  if (auto attached = torsion::attach(*world); !attached)
    return std::fprintf(stderr, "error: %s\n", attached.error().message.c_str()), 1;

  // The importer adds what the file holds to the world, and owns it.
  auto importer = std::make_unique<btBulletWorldImporter>(world.get());
  if (!importer->loadFile(path.c_str()))
    return std::fprintf(stderr, "error: %s: not a .bullet file Bullet can read\n", path.c_str()), 1;
  std::printf("%s: %d rigid bodies imported, gravity z = %.2f m/s^2\n", path.c_str(),
              importer->getNumRigidBodies(), static_cast<double>(world->getGravity().z()));

  // An FEM slab on the ground, under the boxes; its bottom is held.
  torsion::Material foam;
  foam.youngs_modulus = 5e4;
  auto mesh = torsion::makeBoxTetMesh({-1, -0.5, 0}, {1, 0.5, 0.3}, 10, 5, 2);
  torsion::FemBody* slab = fem.addBody("slab", mesh.value(), foam).value();
  std::vector<int> bottom;
  for (int i = 0; i < slab->model().nodeCount(); ++i) {
    if (slab->model().mesh().restPositions()[static_cast<size_t>(i)].z() < 1e-9)
      bottom.push_back(i);
  }
  slab->carryNodes(
      "bottom", bottom, [](double) { return torsion::Frame{}; }, fem.time());

  for (int frame = 0; frame < 120; ++frame) {
    world->stepSimulation(btScalar(1 / 60.), 10, btScalar(1 / 240.));
    if (!fem.status().ok)
      return std::fprintf(stderr, "error: %s\n", fem.status().message.c_str()), 3;
  }
  for (int k = 0; k < importer->getNumRigidBodies(); ++k) {
    const btCollisionObject* body = importer->getRigidBodyByIndex(k);
    if (body->isStaticObject()) continue;
    std::printf("box %d rests at z = %.4f m (slab top at 0.3 m, half size 0.1 m)\n", k,
                static_cast<double>(body->getWorldTransform().getOrigin().z()));
  }
  importer->deleteAllData();  // removes what it made from the world, then frees it
  world.reset();              // the world before the solver
  return 0;
}

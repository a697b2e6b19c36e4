#pragma once
// Small worlds for the contact tests: a world with a static ground plane, box and ball bodies.

#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <vector>

#include "torsion/bt_conversions.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/mesh/ball_mesh.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion::test {

/// A tolerance `tol` that holds with double Bullet, widened to what float Bullet can resolve on
/// coordinates of size `length` (m). Bullet keeps shapes and poses in btScalar and runs GJK in it:
/// with float (7 significant digits) a contact measured there is good to about 1e-7 m per metre,
/// twice that here for margin (docs/bullet-integration.md, "Bullet precision"). With double Bullet
/// this is `tol`, unchanged.
inline double atBulletPrecision(double tol, double length = 1.0) {
  return std::max(tol, 2 * kBulletEpsilon * length);
}

inline WorldSettings contactSettings(double dt = 0.01) {
  WorldSettings s;
  s.solver.time_step = dt;
  s.solver.threads = 1;
  s.solver.tolerance = 1e-6;
  s.solver.max_iterations = 1000;
  return s;
}

inline Material softMaterial(double E = 2e4, double density = 100) {
  Material m;
  m.youngs_modulus = E;
  m.poisson_ratio = 0.3;
  m.density = density;
  m.stiffness_damping = 0.01;
  return m;
}

inline btTransform at(const Eigen::Vector3d& p) {
  btTransform t;
  t.setIdentity();
  t.setOrigin(btVector3(p.x(), p.y(), p.z()));
  return t;
}

/// A static ground plane z = 0 with friction `mu`.
inline btRigidBody* addGround(FemWorld& world, double mu) {
  btRigidBody* g = world.addRigidBody(std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), 0),
                                      0, at({0, 0, 0}));
  g->setFriction(mu);
  return g;
}

/// Holds the nodes of `body` at z = 0 where they are (a slab's base on the ground).
inline void holdBase(FemBody& body) {
  std::vector<int> base;
  for (int i = 0; i < body.model().nodeCount(); ++i)
    if (body.state().position(i).z() < 1e-9) base.push_back(i);
  body.carryNodes(
      "base", base, [](double) { return Frame{}; }, 0.0);
}

inline FemBody* addBox(FemWorld& world, const std::string& name, const Eigen::Vector3d& lo,
                       const Eigen::Vector3d& hi, int nx, int ny, int nz, const Material& m) {
  Result<TetMesh> mesh = makeBoxTetMesh(lo, hi, nx, ny, nz);
  if (!mesh.ok()) {
    ADD_FAILURE() << mesh.error().message;
    return nullptr;
  }
  Result<FemBody*> body = world.addBody(name, mesh.value(), m);
  if (!body.ok()) {
    ADD_FAILURE() << body.error().message;
    return nullptr;
  }
  return body.value();
}

inline Eigen::Vector3d centreOfMass(const FemBody& body) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  double m = 0;
  for (int i = 0; i < body.model().nodeCount(); ++i) {
    c += body.model().nodeMasses()[static_cast<size_t>(i)] * body.state().position(i);
    m += body.model().nodeMasses()[static_cast<size_t>(i)];
  }
  return c / m;
}

inline Eigen::Vector3d momentum(const FemBody& body) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i < body.model().nodeCount(); ++i)
    p += body.model().nodeMasses()[static_cast<size_t>(i)] * body.state().velocity(i);
  return p;
}

inline double minZ(const FemBody& body) {
  double z = 1e300;
  for (int i = 0; i < body.model().nodeCount(); ++i)
    z = std::min(z, body.state().position(i).z());
  return z;
}

}  // namespace torsion::test

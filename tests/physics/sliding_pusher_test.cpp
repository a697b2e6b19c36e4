// A rigid box pushed across a soft FEM slab by a kinematic pusher at constant speed
// (docs/contact-pipeline.md, "Sliding over nodes"): once it slides steadily, the slab's friction on
// it is Coulomb's mu m g, and so is the force the pusher needs, whatever nodes and faces it passes
// over.

#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <vector>

#include "torsion/bt_conversions.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion::test {
// Named, not anonymous: its helpers share a unity batch with other files' (TORSION_UNITY_BUILD).
namespace sliding_pusher_test {

constexpr double kGravity = 9.81;
constexpr double kDt = 0.01;
constexpr double kRamp = 0.3;  ///< s, the pusher's speed ramps up over this

struct PushedBox {
  double slab_friction_n = 0;  ///< N, mean friction between the slab and the box, along the push
  double pusher_force_n = 0;   ///< N, mean normal force of Bullet's pusher-box contact
  double box_speed = 0;        ///< m/s, mean over the measured window
  int steps_failed = 0;
};

// Pushes a 2 kg box (0.2 x 0.3 x 0.1 m, friction mu) at `speed` along x across a 2 x 0.6 x 0.1 m
// slab of Young's modulus `E` (base held) for `seconds` after it settled for 0.2 s; the forces
// are averaged over the last half of the push (the box slides steadily by then).
PushedBox pushBox(double mu, double E, double speed, double seconds) {
  WorldSettings settings;
  settings.solver.time_step = kDt;
  settings.solver.threads = 1;
  settings.solver.tolerance = 1e-6;
  settings.solver.max_iterations = 1000;
  settings.gravity = Eigen::Vector3d(0, 0, -kGravity);
  FemWorld world(settings);
  Material m;
  m.youngs_modulus = E;
  m.poisson_ratio = 0.3;
  m.density = 100;
  m.stiffness_damping = 0.01;
  const double thickness = 0.1;
  PushedBox out;
  Result<TetMesh> mesh = makeBoxTetMesh({-1, -0.3, 0}, {1, 0.3, thickness}, 20, 6, 2);
  if (!mesh.ok()) {
    ADD_FAILURE() << mesh.error().message;
    return out;
  }
  Result<FemBody*> added = world.addBody("slab", mesh.value(), m, Frame{});
  if (!added.ok()) {
    ADD_FAILURE() << added.error().message;
    return out;
  }
  FemBody* slab = added.value();
  std::vector<int> base;
  for (int i = 0; i < slab->model().nodeCount(); ++i) {
    if (slab->state().position(i).z() < 1e-9) base.push_back(i);
  }
  slab->carryNodes(
      "base", base, [](double) { return Frame{}; }, 0.0);

  const double half_height = 0.05, box_x = -0.6, box_mass = 2;
  btTransform start;
  start.setIdentity();
  start.setOrigin(btVector3(box_x, 0, thickness + half_height + 1e-4));
  btRigidBody* box = world.addRigidBody(
      std::make_unique<btBoxShape>(btVector3(0.1, 0.15, half_height)), box_mass, start);
  box->setFriction(mu);
  // The pusher: a thin kinematic plate behind the box, clear of the slab, frictionless (it only
  // pushes), touching the box's rear face at the start; its speed ramps up over kRamp seconds
  // (a kinematic body that starts at full speed strikes the box, and Bullet's answer throws it).
  const double plate_half = 0.01;
  btTransform plate_pose;
  plate_pose.setIdentity();
  plate_pose.setOrigin(btVector3(box_x - 0.1 - plate_half, 0, thickness + half_height + 1e-4));
  btRigidBody* pusher = world.addRigidBody(
      std::make_unique<btBoxShape>(btVector3(plate_half, 0.12, 0.03)), 0, plate_pose);
  pusher->setCollisionFlags(pusher->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
  pusher->setActivationState(DISABLE_DEACTIVATION);
  pusher->setFriction(0);

  const int settle_steps = 20, push_steps = static_cast<int>(std::lround(seconds / kDt));
  int measured = 0;
  for (int k = 0; k < settle_steps + push_steps; ++k) {
    if (k >= settle_steps) {
      const double t = (k - settle_steps + 1) * kDt;
      plate_pose.getOrigin() += btVector3(toBtScalar(speed * std::min(1.0, t / kRamp) * kDt), 0, 0);
      pusher->getMotionState()->setWorldTransform(plate_pose);
    }
    const WorldStepReport r = world.step();
    if (!r.ok) {
      ++out.steps_failed;
      ADD_FAILURE() << "step " << k << ": " << r.message;
      break;
    }
    if (k < settle_steps + push_steps / 2) continue;
    // The slab's friction on the box, measured as its reaction: the impulse the box gave the
    // slab's nodes and faces, along the push (the partner's impulse is the slab's on the box).
    const RigidContactSolver& contacts = slab->contacts();
    Eigen::Vector3d on_slab = Eigen::Vector3d::Zero();
    for (const RigidPartner& partner : contacts.partners()) {
      if (partner.object == box) on_slab -= partner.impulse.head<3>();
    }
    out.slab_friction_n += on_slab.x() / kDt;
    // Bullet's contact between the pusher and the box.
    btDispatcher* dispatcher = world.bulletWorld().getDispatcher();
    double pushed = 0;
    for (int i = 0; i < dispatcher->getNumManifolds(); ++i) {
      const btPersistentManifold* manifold = dispatcher->getManifoldByIndexInternal(i);
      const bool pair = (manifold->getBody0() == pusher && manifold->getBody1() == box) ||
                        (manifold->getBody0() == box && manifold->getBody1() == pusher);
      if (!pair) continue;
      for (int p = 0; p < manifold->getNumContacts(); ++p)
        pushed += static_cast<double>(manifold->getContactPoint(p).getAppliedImpulse());
    }
    out.pusher_force_n += pushed / kDt;
    out.box_speed += static_cast<double>(box->getLinearVelocity().x());
    ++measured;
  }
  if (measured > 0) {
    out.slab_friction_n /= measured;
    out.pusher_force_n /= measured;
    out.box_speed /= measured;
  }
  return out;
}

// mu m g = 5.886 N for mu = 0.3, 2 kg.
TEST(SlidingPusher, PushingABoxAcrossASoftSlabTakesCoulombsForce) {
  const double mu = 0.3, speed = 0.2, box_mass = 2;
  const PushedBox p = pushBox(mu, 1e5, speed, 1.5);
  const double coulomb = mu * box_mass * kGravity;
  std::cout << "[figures] pushed box (soft slab, mu 0.3, 0.2 m/s): slab friction "
            << p.slab_friction_n << " N, pusher force " << p.pusher_force_n << " N, box speed "
            << p.box_speed << " m/s; mu m g = " << coulomb << " N ("
            << 100 * (p.slab_friction_n / coulomb - 1) << " %, "
            << 100 * (p.pusher_force_n / coulomb - 1) << " %)\n";
  EXPECT_EQ(p.steps_failed, 0);
  EXPECT_NEAR(p.box_speed, speed, 0.05 * speed) << "the box must move with the pusher";
  EXPECT_NEAR(p.slab_friction_n, coulomb, 0.05 * coulomb);
  EXPECT_NEAR(p.pusher_force_n, coulomb, 0.05 * coulomb);
}

}  // namespace sliding_pusher_test
}  // namespace torsion::test

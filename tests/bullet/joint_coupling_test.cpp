// Bullet's joints inside the FEM step (docs/contact-solve.md, "Joints in the island"): a rigid
// body with a btTypedConstraint that touches a FEM body is solved once, with its joints and its
// contacts together.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <utility>

#include "../contact/contact_fixtures.h"
#include "multibody_world.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion {
namespace {

using testing::MultibodyWorld;

constexpr double kGravity = 9.81;

// A 2 kg bob, a 0.1 m cube 0.3 m below a hinge about y at the origin, carrying a 1 kg bar
// (0.05 x 0.05 x 0.4 m) that hangs from its bottom face: the bar is FEM, anchored to the bob, or
// a rigid body welded to it (Bullet alone).
struct HingedPendulum {
  static constexpr double kBobMass = 2.0;
  static constexpr double kBarMass = 1.0;
  static constexpr double kBobDepth = 0.3;  // m, the bob's centre below the pivot
  static constexpr double kBarTop = -0.35;  // m
  static constexpr double kBarBottom = -0.75;
  static constexpr double kSpin = 3.0;  // rad/s about y at the start

  MultibodyWorld user{btVector3(0, 0, -kGravity)};
  btRigidBody* bob = nullptr;
  btRigidBody* rigid_bar = nullptr;  // Bullet alone
  FemBody* bar = nullptr;            // the FEM bar
  std::unique_ptr<btHingeConstraint> hinge;
  std::unique_ptr<btFixedConstraint> weld;

  explicit HingedPendulum(bool fem_bar) {
    bob = user.addRigid(std::make_unique<btBoxShape>(btVector3(0.05, 0.05, 0.05)), kBobMass,
                        btVector3(0, 0, -kBobDepth));
    bob->setDamping(0, 0);
    hinge =
        std::make_unique<btHingeConstraint>(*bob, btVector3(0, 0, kBobDepth), btVector3(0, 1, 0));
    user.world.addConstraint(hinge.get());
    const Eigen::Vector3d spin(0, kSpin, 0);
    bob->setAngularVelocity(btVector3(0, kSpin, 0));
    bob->setLinearVelocity(toBt(Eigen::Vector3d(spin.cross(Eigen::Vector3d(0, 0, -kBobDepth)))));
    const Eigen::Vector3d bar_centre(0, 0, 0.5 * (kBarTop + kBarBottom));
    if (fem_bar) {
      Material material;
      material.youngs_modulus = 1e6;
      material.poisson_ratio = 0.3;
      bar = user.fem
                .addBody(
                    "bar",
                    makeBoxTetMesh({-0.025, -0.025, kBarBottom}, {0.025, 0.025, kBarTop}, 1, 1, 8)
                        .value(),
                    material)
                .value();
      std::vector<int> top;
      for (int i = 0; i < bar->model().nodeCount(); ++i)
        if (bar->state().position(i).z() > kBarTop - 1e-9) top.push_back(i);
      EXPECT_TRUE(bar->anchorNodes(top, bob).ok());
      EXPECT_TRUE(bar->setRigidVelocity(spin.cross(bar_centre), spin).ok());
    } else {
      rigid_bar = user.addRigid(std::make_unique<btBoxShape>(btVector3(0.025, 0.025, 0.2)),
                                kBarMass, toBt(bar_centre));
      rigid_bar->setDamping(0, 0);
      weld = std::make_unique<btFixedConstraint>(
          *bob, *rigid_bar, btTransform(btMatrix3x3::getIdentity(), btVector3(0, 0, -0.05)),
          btTransform(btMatrix3x3::getIdentity(), btVector3(0, 0, 0.2)));
      user.world.addConstraint(weld.get(), true);
      rigid_bar->setAngularVelocity(btVector3(0, kSpin, 0));
      rigid_bar->setLinearVelocity(toBt(Eigen::Vector3d(spin.cross(bar_centre))));
    }
  }
  ~HingedPendulum() {
    if (weld) user.world.removeConstraint(weld.get());
    user.world.removeConstraint(hinge.get());
  }

  static double rigidEnergy(const btRigidBody& body) {
    const double m = 1.0 / static_cast<double>(body.getInvMass());
    const Eigen::Vector3d v = toEigen(body.getLinearVelocity());
    const Eigen::Vector3d w = toEigen(body.getAngularVelocity());
    const Eigen::Matrix3d inertia = toEigen(body.getInvInertiaTensorWorld()).inverse();
    return 0.5 * m * v.squaredNorm() + 0.5 * w.dot(inertia * w) +
           m * kGravity * static_cast<double>(body.getCenterOfMassPosition().z());
  }

  // Kinetic + gravity (+ elastic, at the step's start) energy, J.
  double energy() const {
    double e = rigidEnergy(*bob);
    if (rigid_bar != nullptr) return e + rigidEnergy(*rigid_bar);
    for (int i = 0; i < bar->model().nodeCount(); ++i) {
      const double m = bar->model().nodeMasses()[static_cast<std::size_t>(i)];
      e += 0.5 * m * bar->state().velocity(i).squaredNorm() +
           m * kGravity * bar->state().position(i).z();
    }
    return e + bar->lastReport().elastic_energy;
  }

  // How far the hinge's pivot on the bob has moved from the origin, m.
  double pivotStretch() const {
    return static_cast<double>(
        (bob->getCenterOfMassTransform() * btVector3(0, 0, kBobDepth)).length());
  }
};

struct Swing {
  double gain = 0;     // largest energy above the start's, relative to the swing's energy
  double stretch = 0;  // m, the pivot's largest stretch
  double widest = 0;   // m, the bob's largest distance from the vertical through the pivot
};

Swing swing(HingedPendulum& p, double dt, double seconds) {
  // The swing's energy: the start's above the pendulum hanging at rest.
  const double rest = -kGravity * (HingedPendulum::kBobMass * HingedPendulum::kBobDepth +
                                   HingedPendulum::kBarMass * 0.55);
  const double start = p.energy();
  Swing s;
  const int steps = static_cast<int>(std::lround(seconds / dt));
  for (int k = 0; k < steps; ++k) {
    p.user.world.stepSimulation(static_cast<btScalar>(dt), 0);
    EXPECT_TRUE(p.user.fem.status().ok) << p.user.fem.status().message;
    if (!p.user.fem.status().ok) break;
    s.gain = std::max(s.gain, (p.energy() - start) / (start - rest));
    s.stretch = std::max(s.stretch, p.pivotStretch());
    s.widest =
        std::max(s.widest, std::abs(static_cast<double>(p.bob->getCenterOfMassPosition().x())));
  }
  return s;
}

// The rigid pendulum in Bullet alone and the FEM one, each swung for 10 s at step `dt`.
std::pair<Swing, Swing> swingBoth(double dt) {
  HingedPendulum rigid(false);
  const Swing reference = swing(rigid, dt, 10);
  HingedPendulum soft(true);
  const Swing fem = swing(soft, dt, 10);
  std::printf(
      "dt %.4f s: Bullet alone: energy peak %+.2f %%, pivot %.3f mm; FEM bar: %+.2f %%, "
      "%.3f mm\n",
      dt, 100 * reference.gain, 1e3 * reference.stretch, 100 * fem.gain, 1e3 * fem.stretch);
  return {reference, fem};
}

// The pendulum swings for 10 s. Its energy is not conserved exactly by either solver: Bullet's
// symplectic Euler and its joint's error correction make it oscillate within a swing (peaks of
// +0.8 % at 1/240 s, +1.2 % at 1/60 s for the rigid bar) while damping makes it decay; the peak
// above the start is compared. Before Bullet's joints were rows of the island, the hinge was
// solved before the FEM step with the bob alone, the bar's pull came a step late: +7.5 % and a
// pivot stretched 4.6 mm at 1/240 s; at 1/60 s it blew up within 10 steps.
TEST(JointCoupling, AFemBarUnderAHingedBobGainsNoMoreEnergyThanBulletsRigidPendulum) {
  const auto [reference, fem] = swingBoth(1 / 240.);
  EXPECT_LE(fem.gain, reference.gain);
  EXPECT_LT(fem.stretch, 1e-3) << "the hinge's pivot holds";
  // The swing's energy lifts the pendulum by 37 deg: its bob 0.18 m out.
  EXPECT_GT(fem.widest, 0.15) << "it swings as far as its energy takes it";
}

// At Bullet's default step, 1/60 s: stable, and the pivot no looser than Bullet's own.
TEST(JointCoupling, AtBulletsDefaultStepTheHingedPendulumHoldsItsPivotAsBulletAlone) {
  const auto [reference, fem] = swingBoth(1 / 60.);
  EXPECT_LT(fem.stretch, 1.1 * reference.stretch);
  EXPECT_LT(fem.gain, 0.02) << "energy oscillates within a swing by about Bullet alone's";
}

// A rigid box on a soft slab pushed along x by a plate that a slider's velocity motor drives at
// 0.2 m/s with up to 20 N: Coulomb's friction (mu 0.5, 1 kg: 4.9 N) is well within the motor's
// force. The plate, its slider and the box are solved in the slab's island, with the box's
// friction on the slab: both move at the motor's speed, and the slider's feedback (written back
// by the island, as Bullet's solver writes it) reports the force that friction needs.
TEST(JointCoupling, AMotorDrivenPusherHoldsItsTargetSpeedAgainstFriction) {
  constexpr double kStep = 1 / 240., kSpeed = 0.2, kMu = 0.5;
  MultibodyWorld user(btVector3(0, 0, -kGravity));
  Material material;
  material.youngs_modulus = 1e5;
  material.density = 500;
  FemBody* slab =
      user.fem
          .addBody("slab", makeBoxTetMesh({-0.5, -0.2, 0}, {0.5, 0.2, 0.1}, 20, 8, 2).value(),
                   material)
          .value();
  test::holdBase(*slab);
  btRigidBody* box = user.addRigid(std::make_unique<btBoxShape>(btVector3(0.1, 0.1, 0.05)), 1.0,
                                   btVector3(-0.2, 0, 0.1 + 0.05 + 1e-4));
  box->setFriction(kMu);
  // The plate: clear of the slab (its bottom 2 cm above it), frictionless against the box.
  btRigidBody* plate = user.addRigid(std::make_unique<btBoxShape>(btVector3(0.01, 0.1, 0.03)), 1.0,
                                     btVector3(-0.2 - 0.1 - 0.01 - 1e-3, 0, 0.1 + 0.05));
  plate->setFriction(0);
  btTransform along_x;
  along_x.setIdentity();
  btSliderConstraint slider(*plate, along_x, true);
  slider.setLowerLinLimit(-10);
  slider.setUpperLinLimit(10);
  slider.setLowerAngLimit(0);
  slider.setUpperAngLimit(0);
  slider.setPoweredLinMotor(true);
  slider.setTargetLinMotorVelocity(btScalar(kSpeed));
  slider.setMaxLinMotorForce(20);
  user.world.addConstraint(&slider, true);
  btJointFeedback feedback;
  slider.setJointFeedback(&feedback);
  slider.enableFeedback(true);
  double plate_speed = 0, box_speed = 0, motor_force = 0;
  int samples = 0;
  const int steps = static_cast<int>(std::lround(2.5 / kStep));
  for (int k = 0; k < steps; ++k) {
    user.world.stepSimulation(btScalar(kStep), 0);
    ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;
    if (k * kStep < 1.0) continue;  // the plate reaches the box and both get going
    plate_speed += static_cast<double>(plate->getLinearVelocity().x());
    box_speed += static_cast<double>(box->getLinearVelocity().x());
    motor_force += static_cast<double>(feedback.m_appliedForceBodyB.x());
    ++samples;
  }
  user.world.removeConstraint(&slider);
  plate_speed /= samples;
  box_speed /= samples;
  motor_force /= samples;
  std::printf(
      "plate %.4f m/s, box %.4f m/s (motor target %.2f), slider force %.3f N (mu m g %.3f)\n",
      plate_speed, box_speed, kSpeed, motor_force, kMu * kGravity);
  EXPECT_NEAR(plate_speed, kSpeed, 0.03 * kSpeed);
  EXPECT_NEAR(box_speed, kSpeed, 0.03 * kSpeed);
  EXPECT_NEAR(motor_force, kMu * kGravity, 0.02 * kMu * kGravity);
}

}  // namespace
}  // namespace torsion

// FEM bodies against Featherstone multibody links, both ways (docs/contact.md, "Multibody
// links"): momentum exchanged with a free multibody, and a motor-driven gripper that picks up a
// soft block and holds it.
#include <gtest/gtest.h>

#include <cmath>

#include "multibody_world.h"
#include "torsion/contact/multibody_partner.h"
#include "torsion/mesh/ball_mesh.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion {
namespace {

using testing::MultibodyWorld;

Eigen::Vector3d femMomentum(const FemBody& body) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i < body.model().nodeCount(); ++i)
    p += body.model().nodeMasses()[static_cast<size_t>(i)] * body.state().velocity(i);
  return p;
}

Eigen::Vector3d femCentre(const FemBody& body) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  double mass = 0;
  for (int i = 0; i < body.model().nodeCount(); ++i) {
    const double m = body.model().nodeMasses()[static_cast<size_t>(i)];
    c += m * body.state().position(i);
    mass += m;
  }
  return c / mass;
}

TEST(MultibodyPartner, AFreeMultibodyBoxHasTheMassAndInertiaOfARigidBox) {
  MultibodyWorld user(btVector3(0, 0, 0));
  auto box = std::make_unique<btBoxShape>(btVector3(0.2, 0.1, 0.05));
  btVector3 inertia;
  box->calculateLocalInertia(2.0, inertia);
  btMultiBody* body = user.addMultibody(0, 2.0, inertia, false, btVector3(1, 2, 3));
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  shapes.push_back(std::move(box));
  user.addColliders(body, std::move(shapes), 0.5);
  body->setBaseOmega(btVector3(0, 0, 0.5));
  body->setBaseVel(btVector3(0.1, 0, 0));
  user.world.stepSimulation(1 / 240., 0);  // Bullet's forward dynamics caches M^-1

  RigidPartner p;
  p.com = toEigen(body->getBasePos());
  MultibodyLinks links;
  ASSERT_TRUE(links.describe(body->getBaseCollider(), p));
  EXPECT_TRUE(p.dynamic);
  const Eigen::Matrix3d R = toEigen(body->getBaseWorldTransform().getBasis());
  Matrix6d expected = Matrix6d::Zero();
  expected.topLeftCorner<3, 3>() = 2.0 * Eigen::Matrix3d::Identity();
  expected.bottomRightCorner<3, 3>() =
      R * Eigen::Vector3d(inertia.x(), inertia.y(), inertia.z()).asDiagonal() * R.transpose();
  // To the regularisation (a millionth of the box's own mass) and one step's turn (2e-3 rad): M^-1
  // is Bullet's, cached at the start of the step, R the end's.
  EXPECT_LT((p.mass_matrix - expected).norm(), 1e-4 * expected.norm()) << p.mass_matrix;
  Vector6d velocity;
  velocity << toEigen(body->getBaseVel()), toEigen(body->getBaseOmega());
  EXPECT_LT((p.entry_velocity - velocity).norm(), 1e-12);
}

TEST(MultibodyPartner, AFixedBasePrismaticLinkMovesOnlyAlongItsAxis) {
  MultibodyWorld user(btVector3(0, 0, 0));
  btMultiBody* body = user.addMultibody(1, 0, btVector3(0, 0, 0), true, btVector3(0, 0, 1));
  const btVector3 half(0.05, 0.05, 0.05);
  btVector3 inertia;
  btBoxShape(half).calculateLocalInertia(0.3, inertia);
  body->setupPrismatic(0, 0.3, inertia, -1, btQuaternion::getIdentity(), btVector3(0, 1, 0),
                       btVector3(0, 0, -0.2), btVector3(0, 0, 0), true);
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  shapes.push_back(nullptr);
  shapes.push_back(std::make_unique<btBoxShape>(half));
  user.addColliders(body, std::move(shapes), 0.5);
  body->setJointVel(0, 0.2);
  user.world.stepSimulation(1 / 240., 0);

  const btMultiBodyLinkCollider* collider = body->getLinkCollider(0);
  RigidPartner p;
  p.com = toEigen(collider->getWorldTransform().getOrigin());
  MultibodyLinks links;
  ASSERT_TRUE(links.describe(collider, p));
  EXPECT_TRUE(p.dynamic);
  // Velocity per unit impulse: 1/m along the joint's axis y, (almost) nothing elsewhere.
  EXPECT_NEAR(p.inverse_mass_matrix(1, 1), 1 / 0.3, 1e-5 / 0.3);
  EXPECT_LT(p.inverse_mass_matrix(0, 0), 1e-5 / 0.3);
  EXPECT_LT(p.inverse_mass_matrix(2, 2), 1e-5 / 0.3);
  EXPECT_NEAR(p.entry_velocity[1], 0.2, 1e-12);
  EXPECT_LT(p.entry_velocity.norm() - 0.2, 1e-12);
}

TEST(MultibodyContact, BallHittingAFreeMultibodyBoxConservesLinearMomentum) {
  MultibodyWorld user(btVector3(0, 0, 0));  // no external force on either body
  const double box_mass = 1.0;
  auto box = std::make_unique<btBoxShape>(btVector3(0.2, 0.2, 0.1));
  btVector3 inertia;
  box->calculateLocalInertia(box_mass, inertia);
  btMultiBody* body = user.addMultibody(0, box_mass, inertia, false, btVector3(0, 0, 0));
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  shapes.push_back(std::move(box));
  user.addColliders(body, std::move(shapes), 0.5);

  Material material;
  material.youngs_modulus = 2e5;
  material.density = 500;
  // Off the box's axis, so the hit also spins it (its angular response enters the solve).
  FemBody* ball =
      user.fem.addBody("ball", makeBallTetMesh({0.05, 0.03, 0.25}, 0.1, 3).value(), material)
          .value();
  EXPECT_TRUE((ball->setVelocity({0.3, 0, -1}).ok()));
  const Eigen::Vector3d before = femMomentum(*ball);
  double box_peak = 0;
  for (int k = 0; k < 240; ++k) {
    user.world.stepSimulation(1 / 240., 0);
    ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;
    box_peak = std::max(box_peak, std::abs(static_cast<double>(body->getBaseVel().z())));
  }
  const Eigen::Vector3d box_momentum = box_mass * toEigen(body->getBaseVel());
  const Eigen::Vector3d after = femMomentum(*ball) + box_momentum;
  // The box took a real share of the momentum (a one-way contact would leave it at rest).
  EXPECT_GT(std::abs(box_momentum.z()), 0.3 * std::abs(before.z()));
  EXPECT_GT(body->getBaseOmega().length(), 1e-3) << "the off-axis hit spins the box";
  EXPECT_LT((after - before).norm(), 0.01 * before.norm())
      << "before " << before.transpose() << ", after " << after.transpose();
  // The ball stays outside the box: its centre at least its radius above the box's top face
  // (to the contact's tolerance; the box has turned).
  const btVector3 local = body->getBaseWorldTransform().inverse() * toBt(femCentre(*ball));
  EXPECT_GT(local.z(), 0.1 + 0.1 - 0.005)
      << "ball centre in the box's frame " << local.x() << " " << local.y() << " " << local.z();
}

// A fixed-base gripper: a lift (prismatic along z) carrying two fingers (prismatic along x), all
// driven by velocity motors with bounded force, picks up a soft block from the ground.
struct Gripper {
  btMultiBody* body = nullptr;
  btMultiBodyJointMotor* lift = nullptr;
  btMultiBodyJointMotor* left = nullptr;   // link 1, at -x, closes along +x
  btMultiBodyJointMotor* right = nullptr;  // link 2, at +x, closes along -x
};

constexpr double kDt = 1 / 240.;
constexpr double kFingerGap = 0.065;    // m, each finger's centre from the axis, open
constexpr double kGripForce = 10;       // N, each finger motor's bound
constexpr double kClosingSpeed = 0.05;  // m/s

Gripper buildGripper(MultibodyWorld& user) {
  Gripper g;
  g.body = user.addMultibody(3, 0, btVector3(0, 0, 0), true, btVector3(0, 0, 0.25));
  const btVector3 bar_half(0.1, 0.03, 0.01), finger_half(0.01, 0.03, 0.04);
  const double bar_mass = 0.5, finger_mass = 0.1;
  btVector3 bar_inertia, finger_inertia;
  btBoxShape(bar_half).calculateLocalInertia(bar_mass, bar_inertia);
  btBoxShape(finger_half).calculateLocalInertia(finger_mass, finger_inertia);
  const btQuaternion same = btQuaternion::getIdentity();
  const btVector3 none(0, 0, 0);
  g.body->setupPrismatic(0, bar_mass, bar_inertia, -1, same, btVector3(0, 0, 1),
                         btVector3(0, 0, -0.1), none, true);
  // Fingers from z = 0.005 to 0.085 beside a block from 0 to 0.06 (the lift's centre at 0.15).
  g.body->setupPrismatic(1, finger_mass, finger_inertia, 0, same, btVector3(1, 0, 0),
                         btVector3(-kFingerGap, 0, -0.105), none, true);
  g.body->setupPrismatic(2, finger_mass, finger_inertia, 0, same, btVector3(1, 0, 0),
                         btVector3(kFingerGap, 0, -0.105), none, true);
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  shapes.push_back(nullptr);  // the base has no collider
  shapes.push_back(std::make_unique<btBoxShape>(bar_half));
  shapes.push_back(std::make_unique<btBoxShape>(finger_half));
  shapes.push_back(std::make_unique<btBoxShape>(finger_half));
  user.addColliders(g.body, std::move(shapes), 1.0);
  g.lift = user.addMotor(g.body, 0, 0, 200, kDt);
  g.left = user.addMotor(g.body, 1, 0, kGripForce, kDt);
  g.right = user.addMotor(g.body, 2, 0, kGripForce, kDt);
  return g;
}

Eigen::Vector3d fingersMidpoint(const Gripper& g) {
  return 0.5 * (toEigen(g.body->getLinkCollider(1)->getWorldTransform().getOrigin()) +
                toEigen(g.body->getLinkCollider(2)->getWorldTransform().getOrigin()));
}

TEST(MultibodyContact, MotorGripperLiftsASoftBlockAndHoldsItWithoutSlip) {
  MultibodyWorld user(btVector3(0, 0, -9.81));
  user.addRigid(std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), 0), 0, btVector3(0, 0, 0));
  Gripper g = buildGripper(user);
  Material material;
  material.youngs_modulus = 2e5;
  material.poisson_ratio = 0.3;
  FemBody* block =
      user.fem
          .addBody("block", makeBoxTetMesh({-0.03, -0.03, 0}, {0.03, 0.03, 0.06}, 4, 4, 4).value(),
                   material)
          .value();
  const double weight = 0.06 * 0.06 * 0.06 * material.density * 9.81;
  const Eigen::Vector3d start = femCentre(*block);

  // The lift is a servo: velocity target plus a position target along a ramp (Bullet's motor
  // corrects a fraction kp of the position error per step), so the load it carries does not make
  // it drift.
  double lift_target = 0, lift_speed = 0;
  long newton = 0;  // the contact solves' Newton iterations, summed over the steps run
  auto run = [&](double seconds) {
    const int steps = static_cast<int>(std::lround(seconds / kDt));
    for (int k = 0; k < steps; ++k) {
      lift_target += lift_speed * kDt;
      g.lift->setVelocityTarget(lift_speed);
      g.lift->setPositionTarget(lift_target, 0.2);
      user.world.stepSimulation(kDt, 0);
      ASSERT_TRUE(user.fem.status().ok) << user.fem.status().message;
      newton += block->contacts().stats().newton_iterations;
    }
  };
  // Close: each finger motor drives inward until the block stops it, then squeezes with its
  // bounded force.
  g.left->setVelocityTarget(kClosingSpeed);
  g.right->setVelocityTarget(-kClosingSpeed);
  run(1.0);
  // Squeeze: a velocity motor held back by a contact it does not see (it is solved before the FEM
  // step) pushes with min(max force, m v_target / dt); a target beyond max force dt / m makes the
  // motor's force bound the grip (docs/contact.md, "Multibody links").
  g.left->setVelocityTarget(1.0);
  g.right->setVelocityTarget(-1.0);
  run(0.25);
  const double width = (toEigen(g.body->getLinkCollider(2)->getWorldTransform().getOrigin()) -
                        toEigen(g.body->getLinkCollider(1)->getWorldTransform().getOrigin()))
                           .x() -
                       0.02;
  // The fingers closed the 2.5 cm gaps and pressed the block (10 N on 6 x 6 cm of E = 2e5 Pa
  // shortens it by about 1.4 %, 0.8 mm), without passing through it.
  EXPECT_LT(width, 0.06 - 0.0004);
  EXPECT_GT(width, 0.06 - 0.003);
  // Lift 5 cm.
  lift_speed = 0.05;
  run(1.0);
  lift_speed = 0;
  run(0.25);  // the lift stops; the block settles in the grip
  const Eigen::Vector3d held = femCentre(*block) - fingersMidpoint(g);
  EXPECT_GT(femCentre(*block).z() - start.z(), 0.04) << "the block went up with the gripper";
  // Hold 5 s against gravity.
  newton = 0;
  run(5.0);
  // The hold's contact solves: 70 rows, all sliding at each step's warm start and sticking at
  // its solution. 17-20 Newton iterations a step, up to three solves (the friction bounds
  // matched); 40-57 when the Newton model kept no curvature along a sliding row's slip
  // (sap_solver.h), one or two rows sticking per iteration.
  const double newton_per_step =
      static_cast<double>(newton) / static_cast<double>(std::lround(5.0 / kDt));
  std::printf("[figures] gripper hold: %.1f Newton iterations a step\n", newton_per_step);
  EXPECT_LT(newton_per_step, 30);
  const Eigen::Vector3d slip = femCentre(*block) - fingersMidpoint(g) - held;
  EXPECT_LT(slip.norm(), 1e-3) << "slip " << slip.transpose();
  EXPECT_GT(femCentre(*block).z() - start.z(), 0.04) << "still up after 5 s";
  // The contact carries the block's weight: the normal impulses over the last step balance it
  // through friction, i.e. the grip force is at least weight / (2 mu).
  const ContactStepStats& stats = block->contacts().stats();
  EXPECT_GT(stats.active, 0);
  EXPECT_GT(stats.normal_impulse / kDt, weight / 2);
}

}  // namespace
}  // namespace torsion

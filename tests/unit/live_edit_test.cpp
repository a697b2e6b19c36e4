// Live edits between steps (the viewer's E, nu, damping, dt and solver keys): FemBody::setMaterial
// and FemWorld::setSolverSettings change a running simulation without resetting its state.
#include <gtest/gtest.h>

#include <cmath>

#include "torsion/bt_conversions.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/bullet/hand.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion {
namespace live_edit_test {

constexpr double kLength = 4;

TetMesh beam() {
  return makeBoxTetMesh({0, 0, 0}, {kLength, 1, 1}, 8, 2, 2).value();
}

std::vector<int> endNodes(const FemBody& body, bool far_end) {
  std::vector<int> nodes;
  for (int i = 0; i < body.model().nodeCount(); ++i) {
    const double x = body.model().mesh().restPositions()[static_cast<size_t>(i)].x();
    if (far_end ? x > kLength - 1e-9 : x < 1e-9) nodes.push_back(i);
  }
  return nodes;
}

const Eigen::Vector3d kAxisPoint(kLength, 0.5, 0.5);

/// A beam clamped at x = 0 whose far end turns about x at `omega` for `turn_time` s, then holds.
struct TwistRig {
  std::unique_ptr<FemWorld> world;
  FemBody* body = nullptr;
  int end = -1;

  TwistRig(const WorldSettings& settings, const Material& material, double omega,
           double turn_time) {
    world = std::make_unique<FemWorld>(settings);
    body = world->addBody("beam", beam(), material).value();
    body->carryNodes(
        "clamp", endNodes(*body, false), [](double) { return Frame{}; }, 0.0);
    end = body->carryNodes(
        "end", endNodes(*body, true),
        [omega, turn_time](double t) {
          Frame f;
          f.origin = kAxisPoint;
          f.rotation = Eigen::AngleAxisd(omega * std::min(t, turn_time), Eigen::Vector3d::UnitX());
          return f;
        },
        0.0);
  }
  void run(int steps) {
    for (int k = 0; k < steps; ++k) {
      const WorldStepReport r = world->step();
      ASSERT_TRUE(r.ok) << r.message;
    }
  }
  double torque() const { return body->groupWrench(end, kAxisPoint).torque.x(); }
};

/// Brings `world` to rest under its current loads: steps of 1 s, which backward Euler turns
/// into a near-static solve (a mode of frequency w keeps 1 / sqrt(1 + w^2 dt^2) of its amplitude
/// per step: <= 1/5 for the slowest mode here, w ~ 5 rad/s, so 20 steps leave < 1e-13).
void settle(FemWorld& world) {
  SolverSettings s = world.settings().solver;
  s.time_step = 1.0;
  ASSERT_TRUE(world.setSolverSettings(s).ok());
  for (int k = 0; k < 20; ++k) {
    const WorldStepReport r = world.step();
    ASSERT_TRUE(r.ok) << r.message;
  }
}

WorldSettings quietWorld(double tolerance) {
  WorldSettings s;
  s.gravity.setZero();
  s.solver.tolerance = tolerance;
  s.solver.max_iterations = 2000;
  s.solver.threads = 1;
  return s;
}

Material dampedMaterial() {
  Material m;
  m.mass_damping = 20;  // 1/s: damps the start-up transient of the steady twist
  return m;
}

double maxDifference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).cwiseAbs().maxCoeff();
}

TEST(LiveEdit, StaticTwistTorqueScalesWithYoungsModulus) {
  // Ends held by displacements and no gravity: the equilibrium shape does not depend on E, so at
  // rest the torque is linear in E. Doubling E mid-run must double it at once, without moving
  // the body (a reset would drop the torque to zero and the twist with it).
  TwistRig rig(quietWorld(1e-10), Material{}, 0.5, 0.4);
  rig.run(40);  // 0.4 s: turned 0.2 rad
  settle(*rig.world);
  const double before = rig.torque();
  ASSERT_LT(before, 0);  // the beam resists the twist
  const Eigen::VectorXd positions = rig.body->state().positions;
  const double time = rig.world->time();

  Material stiffer;
  stiffer.youngs_modulus *= 2;
  ASSERT_TRUE(rig.body->setMaterial(stiffer).ok());
  EXPECT_EQ(rig.body->model().material().youngs_modulus, stiffer.youngs_modulus);
  // The wrench of the step already taken does not change under it.
  EXPECT_EQ(rig.torque(), before);

  rig.run(1);
  EXPECT_NEAR(rig.world->time(), time + 1.0, 1e-12);  // time goes on
  // The body stays where it was (the twist moves corners by 0.2 rad x 0.7 m = 0.14 m): the
  // equilibrium shape does not depend on E; 1e-9 m covers the CG tolerance.
  EXPECT_LT(maxDifference(rig.body->state().positions, positions), 1e-9);
  // Ratio 2 to the CG tolerance (1e-10 relative residual).
  EXPECT_NEAR(rig.torque() / before, 2.0, 1e-6);

  // Poisson's ratio changes the torsional stiffness through G = E / (2 (1 + nu)) and the
  // cross-section's warping; the body keeps its shape and the torque follows at once.
  Material softer_shear = stiffer;
  softer_shear.poisson_ratio = 0.45;
  const double before_nu = rig.torque();
  ASSERT_TRUE(rig.body->setMaterial(softer_shear).ok());
  settle(*rig.world);
  // nu moves the equilibrium a little (the section's warping and Poisson contraction): 1 mm.
  EXPECT_LT(maxDifference(rig.body->state().positions, positions), 1e-3);
  // G fell by 1.3 / 1.45 = 0.897; the beam is short and its ends are held, so the torque is
  // not pure St-Venant torsion: the ratio lies between that and 1.
  const double ratio = rig.torque() / before_nu;
  EXPECT_GT(ratio, 0.85);
  EXPECT_LT(ratio, 0.99);
}

TEST(LiveEdit, DensityChangeMovesMassAndWeight) {
  // A beam hanging from its clamped end, settled: the body pulls the clamp down by the weight of
  // its free nodes (the held nodes' own weight goes straight into the clamp, not through the
  // body). After doubling the density and settling again, by twice that.
  WorldSettings settings = quietWorld(1e-10);
  settings.gravity = Eigen::Vector3d(0, 0, -9.81);
  FemWorld world(settings);
  Material material = dampedMaterial();
  material.youngs_modulus = 1e7;  // stiff: small sag
  FemBody* body = world.addBody("beam", beam(), material).value();
  const std::vector<int> held = endNodes(*body, false);
  const int clamp = body->carryNodes(
      "clamp", held, [](double) { return Frame{}; }, 0.0);
  auto freeWeight = [&] {
    double m = body->model().totalMass();
    for (int i : held)
      m -= body->model().nodeMasses()[static_cast<size_t>(i)];
    return m * 9.81;
  };
  settle(world);
  const double mass = body->model().totalMass();
  EXPECT_NEAR(mass, 1000 * kLength, 1e-9);
  const double weight = freeWeight();
  // 1e-6 relative: the CG tolerance (1e-10), with margin.
  EXPECT_NEAR(body->groupWrench(clamp, Eigen::Vector3d::Zero()).force.z(), -weight, 1e-6 * weight);

  material.density *= 2;
  ASSERT_TRUE(body->setMaterial(material).ok());
  EXPECT_NEAR(body->model().totalMass(), 2 * mass, 1e-9);
  // Bullet's copy is the new inverse mass, rounded to btScalar (exact on double Bullet).
  EXPECT_EQ(body->softBody()->m_nodes[0].m_im, toBtScalar(1 / body->model().nodeMasses()[0]));
  EXPECT_NEAR(freeWeight(), 2 * weight, 1e-9 * weight);
  settle(world);
  EXPECT_NEAR(body->groupWrench(clamp, Eigen::Vector3d::Zero()).force.z(), -2 * weight,
              1e-6 * weight);
}

TEST(LiveEdit, TimeStepChangeKeepsTheMotionContinuous) {
  // The end turns steadily at 1 rad/s: after the transient every node moves at a nearly steady
  // velocity. Halving dt mid-run must keep positions and velocities where they were (a reset
  // would send the velocities to zero and the twist back to rest).
  TwistRig rig(quietWorld(1e-8), dampedMaterial(), 1.0, 1e9);
  rig.run(60);
  double largest_change = 0;  // velocity change per step before the edit
  for (int k = 0; k < 5; ++k) {
    const Eigen::VectorXd v = rig.body->state().velocities;
    rig.run(1);
    largest_change = std::max(largest_change, maxDifference(rig.body->state().velocities, v));
  }
  const Eigen::VectorXd x = rig.body->state().positions, v = rig.body->state().velocities;
  const double speed = v.cwiseAbs().maxCoeff();
  const double time = rig.world->time();

  SolverSettings finer = rig.world->settings().solver;
  finer.time_step = 0.005;
  ASSERT_TRUE(rig.world->setSolverSettings(finer).ok());
  rig.run(1);
  // The step as Bullet passes it (a float in a float Bullet).
  EXPECT_NEAR(rig.world->time(), time + static_cast<double>(btScalar(0.005)), 1e-12);
  // Nodes moved about speed x dt_new, not more (no jump); 1.5: velocities vary a little.
  EXPECT_LT(maxDifference(rig.body->state().positions, x), 1.5 * speed * 0.005);
  // Velocities change no more than in the steady steps before (2x margin for the dt change).
  EXPECT_LT(maxDifference(rig.body->state().velocities, v), 2 * largest_change + 1e-9);
  // The driven end lands exactly on its scripted frame at the new time.
  const CarriedNodes& end = *rig.body->groups()[static_cast<size_t>(rig.end)];
  const Frame f = end.frameAt(rig.world->time());
  for (size_t k = 0; k < end.nodes().size(); ++k)
    EXPECT_LT(
        (rig.body->state().position(end.nodes()[k]) - f.toWorld(end.localCoordinates()[k])).norm(),
        1e-12);
}

TEST(LiveEdit, SwitchingSolverMidRunGivesTheSameStep) {
  // Two identical runs; one switches from CG to CHOLMOD (then to Jacobi CG) between steps. Both
  // solve the same linear system, so the next states agree to the solvers' accuracy (CG at
  // 1e-10 relative residual; the system's condition number is ~1e3 here: 1e-9 m is generous).
  TwistRig a(quietWorld(1e-10), dampedMaterial(), 1.0, 1e9);
  TwistRig b(quietWorld(1e-10), dampedMaterial(), 1.0, 1e9);
  a.run(20);
  b.run(20);
  ASSERT_EQ(maxDifference(a.body->state().positions, b.body->state().positions), 0.0);
  SolverSettings direct = b.world->settings().solver;
  direct.linear_solver = LinearSolverKind::kCholmod;
  ASSERT_TRUE(b.world->setSolverSettings(direct).ok());
  EXPECT_EQ(b.body->stepper().settings().linear_solver, LinearSolverKind::kCholmod);
  a.run(5);
  b.run(5);
  EXPECT_LT(maxDifference(a.body->state().positions, b.body->state().positions), 1e-9);
  SolverSettings jacobi = direct;
  jacobi.linear_solver = LinearSolverKind::kConjugateGradient;
  jacobi.preconditioner = PreconditionerKind::kJacobi;
  ASSERT_TRUE(b.world->setSolverSettings(jacobi).ok());
  a.run(5);
  b.run(5);
  EXPECT_LT(maxDifference(a.body->state().positions, b.body->state().positions), 1e-9);
  EXPECT_NEAR(a.torque(), b.torque(), 1e-6 * std::abs(a.torque()));
}

TEST(LiveEdit, InvalidValuesAreRefusedAndChangeNothing) {
  TwistRig rig(quietWorld(1e-6), dampedMaterial(), 1.0, 1e9);
  rig.run(3);
  const Material kept = rig.body->model().material();

  Material bad = kept;
  bad.poisson_ratio = 0.5;
  Status s = rig.body->setMaterial(bad);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("body 'beam'"), std::string::npos) << s.error().message;
  EXPECT_NE(s.error().message.find("poisson_ratio"), std::string::npos) << s.error().message;
  bad = kept;
  bad.youngs_modulus = -1;
  s = rig.body->setMaterial(bad);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("youngs_modulus"), std::string::npos) << s.error().message;
  EXPECT_EQ(rig.body->model().material().youngs_modulus, kept.youngs_modulus);
  EXPECT_EQ(rig.body->model().material().poisson_ratio, kept.poisson_ratio);

  const SolverSettings solver = rig.world->settings().solver;
  SolverSettings bad_solver = solver;
  bad_solver.time_step = 0;
  s = rig.world->setSolverSettings(bad_solver);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("time_step"), std::string::npos) << s.error().message;
  // A step Bullet would skip (at or below its epsilon: 2.2e-16 s here, 1.2e-7 s with float
  // Bullet) is refused, not reported as steps in which nothing moved.
  for (const double tiny : {2.2e-16, 1e-300, 0.5 * kMinTimeStep}) {
    bad_solver.time_step = tiny;
    s = rig.world->setSolverSettings(bad_solver);
    ASSERT_FALSE(s.ok()) << tiny;
    EXPECT_NE(s.error().message.find("must be in [1e-06, 1] s"), std::string::npos)
        << s.error().message;
  }
  bad_solver = solver;
  bad_solver.tolerance = std::nan("");
  EXPECT_FALSE(rig.world->setSolverSettings(bad_solver).ok());
  bad_solver = solver;
  bad_solver.threads = 2;
  s = rig.world->setSolverSettings(bad_solver);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("threads"), std::string::npos) << s.error().message;
  EXPECT_EQ(rig.world->settings().solver.time_step, solver.time_step);
  EXPECT_EQ(rig.body->stepper().settings().time_step, solver.time_step);
  rig.run(1);  // and the world still steps
}

TEST(LiveEdit, HandSpeedLimitFollowsTheMaterial) {
  // The limit is a fraction of the shear wave speed sqrt(G / rho): E x 4 doubles it.
  WorldSettings settings = quietWorld(1e-6);
  FemWorld world(settings);
  FemBody* body = world.addBody("beam", beam(), Material{}).value();
  Hand hand(*body);
  const double before = hand.speedLimit();
  Material stiffer;
  stiffer.youngs_modulus *= 4;
  ASSERT_TRUE(body->setMaterial(stiffer).ok());
  hand.updateSpeedLimit();
  EXPECT_NEAR(hand.speedLimit(), 2 * before, 1e-12 * before);
}

}  // namespace live_edit_test
}  // namespace torsion

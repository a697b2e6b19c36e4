// Contact for hyperelastic bodies (docs/contact.md, "Hyperelastic bodies"): the step's Newton solve
// finds the free motion, and the island's convex solve takes the step's potential linearised there
// with the contact rows. The same physical facts as for corotated bodies, on the stable
// neo-Hookean and Mooney-Rivlin laws: no body passes through the ground or another body, a body at
// rest on the ground is carried by its weight, Coulomb's law on a slope, momentum handed over in an
// impact between two bodies and inside one body (self-contact), and at small strain the same rest
// as the corotated law.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "contact_fixtures.h"
#include "torsion/analysis/surface_intersections.h"

namespace torsion::test {
namespace hyperelastic_contact_test {

constexpr double kGravity = 9.81;
constexpr MaterialLaw kHyperelasticLaws[] = {MaterialLaw::kStableNeoHookean,
                                             MaterialLaw::kMooneyRivlin};

// Every step of every hyperelastic body ended with a converged Newton solve.
struct NewtonWatch {
  int steps = 0, unconverged = 0, most_iterations = 0;
  void see(const FemBody& body) {
    const NewtonReport& n = body.lastReport().newton;
    ++steps;
    if (!n.converged) ++unconverged;
    most_iterations = std::max(most_iterations, n.iterations);
  }
};

struct BallRun {
  double lowest = 1e300;   ///< m, the lowest node over the run
  double rest_height = 0;  ///< m, the centre of mass at the end
  double end_speed = 0;    ///< m/s, the fastest node at the end
  int active = 0;          ///< contacts at the end
  NewtonWatch newton;
};

// The corotated case's ball (ContactPhysics.DroppedBallRestsOnGround): 0.25 m, E 50 kPa,
// 500 kg/m^3, dropped from 0.75 m above the ground, 3 s at dt = 0.01.
BallRun dropBall(MaterialLaw law) {
  FemWorld world(contactSettings(0.01));
  addGround(world, 0.5);
  const double radius = 0.25;
  Material m = softMaterial(5e4, 500);
  m.mass_damping = 0.5;
  m.law = law;
  FemBody* ball = world.addBody("ball", makeBallTetMesh({0, 0, 1.0}, radius, 4).value(), m).value();
  BallRun run;
  for (int k = 0; k < 300; ++k) {
    const WorldStepReport r = world.step();
    EXPECT_TRUE(r.ok) << toString(law) << " step " << k << ": " << r.message;
    if (!r.ok) break;
    run.lowest = std::min(run.lowest, minZ(*ball));
    if (m.hyperelastic()) run.newton.see(*ball);
  }
  run.rest_height = centreOfMass(*ball).z();
  run.end_speed = ball->lastReport().max_speed;
  run.active = ball->contacts().stats().active;
  std::printf(
      "[figures] %s ball: deepest node %.3e m, centre at rest %.5f m, end speed %.2e m/s, "
      "contacts %d, Newton: most iterations %d, unconverged %d of %d steps\n",
      toString(law), run.lowest, run.rest_height, run.end_speed, run.active,
      run.newton.most_iterations, run.newton.unconverged, run.newton.steps);
  return run;
}

// Dropped, bounced and settled: never through the ground, at rest on it, every Newton solve
// converged; and squashed by its weight as much as the corotated ball. No node ends a step deeper
// than 1 % of the impact step's travel (sqrt(2 g 0.75 m) dt = 38 mm; measured 0.24 and 0.24 mm,
// the corotated ball 0.24 mm). The strain at rest is about rho g r / E = 2.5 %, where every law has
// the same small-strain moduli: their sags (r minus the resting centre's height) differ by terms
// of the strain's order, 5 % allowed (measured 1.5 and 1.8 %).
TEST(HyperelasticContact, ABallDroppedOnTheGroundRestsOnItAsTheCorotatedBallDoes) {
  const double radius = 0.25;
  const double impact_travel = std::sqrt(2 * kGravity * 0.75) * 0.01;
  const BallRun corotated = dropBall(MaterialLaw::kCorotated);
  const double corotated_sag = radius - corotated.rest_height;
  for (MaterialLaw law : kHyperelasticLaws) {
    const BallRun run = dropBall(law);
    EXPECT_GT(run.lowest, -0.01 * impact_travel) << toString(law);
    EXPECT_LT(run.end_speed, 0.02) << toString(law);
    EXPECT_GT(run.active, 0) << toString(law);
    EXPECT_EQ(run.newton.unconverged, 0) << toString(law);
    EXPECT_NEAR(radius - run.rest_height, corotated_sag, 0.05 * corotated_sag) << toString(law);
  }
}

// A block on a slope (gravity tilted by theta over flat ground) with friction mu: it stays put
// when tan(theta) < mu, and slides with the Coulomb acceleration g (sin - mu cos) when above
// (ContactPhysics.FrictionHoldsBelowAngleSlidesAbove, on a neo-Hookean block).
double slideDistance(double theta, double mu, double seconds, NewtonWatch& newton) {
  WorldSettings s = contactSettings(0.01);
  s.gravity = kGravity * Eigen::Vector3d(std::sin(theta), 0, -std::cos(theta));
  FemWorld world(s);
  addGround(world, mu);
  Material m = softMaterial(1e5, 500);
  m.law = MaterialLaw::kStableNeoHookean;
  FemBody* block = addBox(world, "block", {-0.1, -0.1, 0}, {0.1, 0.1, 0.2}, 2, 2, 2, m);
  if (!block) return std::nan("");  // addBox reported why
  const double x0 = centreOfMass(*block).x();
  const int steps = static_cast<int>(std::lround(seconds / s.solver.time_step));
  for (int k = 0; k < steps; ++k) {
    EXPECT_TRUE(world.step().ok) << "step " << k;
    newton.see(*block);
  }
  EXPECT_GT(minZ(*block), -1e-4);
  return centreOfMass(*block).x() - x0;
}

// The impact tests' world and blocks: no gravity, dt = 1 ms; neo-Hookean, E = 1 MPa.
WorldSettings impactSettings() {
  WorldSettings settings;
  settings.gravity.setZero();
  settings.solver.time_step = 1e-3;
  return settings;
}

Material impactMaterial() {
  Material material = softMaterial(1e6, 1000);
  material.stiffness_damping = 1e-3;
  material.law = MaterialLaw::kStableNeoHookean;
  return material;
}

TEST(HyperelasticContact, ABlockOnASlopeHoldsBelowTheFrictionAngleAndSlidesAsCoulombSaysAbove) {
  const double mu = 0.5;  // friction angle 26.6 degrees
  const double t = 1.0;
  NewtonWatch newton;
  const double below = slideDistance(20 * M_PI / 180, mu, t, newton);
  const double above_theta = 35 * M_PI / 180;
  const double above = slideDistance(above_theta, mu, t, newton);
  const double coulomb =
      0.5 * kGravity * (std::sin(above_theta) - mu * std::cos(above_theta)) * t * t;
  std::printf(
      "[figures] neo-Hookean block: 20 deg moved %.3e m; 35 deg moved %.4f m (Coulomb %.4f "
      "m); Newton unconverged %d of %d steps\n",
      below, above, coulomb, newton.unconverged, newton.steps);
  EXPECT_LT(std::abs(below), 2e-3);  // elastic creep of a soft block only
  // Measured 1.5 % over (the corotated block's test allows 15 %: its first steps settle the
  // block's contact).
  EXPECT_NEAR(above, coulomb, 0.05 * coulomb);
  EXPECT_EQ(newton.unconverged, 0);
}

// Two 0.1 m neo-Hookean cubes (3 x 3 x 3 cells, E = 1 MPa), no gravity, dt = 1 ms: one thrown at
// the other at 4 m/s (BodyContact.ASoftBlockThrownAtAnotherKeepsTheLinearMomentum... on the
// corotated law). Their contact rows couple both bodies' linearised steps in one island solve, so
// the momentum handed over is exact to the solve's tolerance.
TEST(HyperelasticContact, ANeoHookeanBlockThrownAtAnotherHandsOverItsMomentum) {
  FemWorld world(impactSettings());
  const Material material = impactMaterial();
  FemBody* struck =
      world.addBody("struck", makeBoxTetMesh({0, 0, 0}, {0.1, 0.1, 0.1}, 3, 3, 3).value(), material)
          .value();
  FemBody* thrown =
      world
          .addBody("thrown",
                   makeBoxTetMesh({0.12, 0.03, 0.01}, {0.22, 0.13, 0.11}, 3, 3, 3).value(),
                   material)
          .value();
  ASSERT_TRUE(thrown->setVelocity(Eigen::Vector3d(-4, 0, 0)).ok());
  const Eigen::Vector3d before = momentum(*struck) + momentum(*thrown);
  double worst = 0;
  int contact_steps = 0;
  NewtonWatch newton;
  for (int k = 0; k < 150; ++k) {
    const WorldStepReport r = world.step();
    ASSERT_TRUE(r.ok) << "step " << k << ": " << r.message;
    newton.see(*struck);
    newton.see(*thrown);
    worst =
        std::max(worst, (momentum(*struck) + momentum(*thrown) - before).norm() / before.norm());
    const FemContactStats& s = world.femSolver().femContact()->stats();
    if (s.active > 0) ++contact_steps;
    ASSERT_LT(s.max_end_penetration, 1e-3) << "step " << k;
    ASSERT_GT(centreOfMass(*thrown).x() - centreOfMass(*struck).x(), 0.095) << "step " << k;
  }
  std::printf(
      "[figures] neo-Hookean blocks: momentum %.5f N s, worst relative drift %.2e, struck "
      "%.4f N s, contact steps %d, Newton unconverged %d of %d\n",
      before.x(), worst, momentum(*struck).x(), contact_steps, newton.unconverged, newton.steps);
  EXPECT_GT(contact_steps, 0);
  EXPECT_LT(worst, 0.01);
  EXPECT_LT(momentum(*struck).x(), 0.5 * before.x()) << "the struck block took a good share";
  EXPECT_EQ(newton.unconverged, 0);
}

// Self-contact: two neo-Hookean cubes meshed as one body, one thrown at the other at 5 m/s
// (SelfContact.ABlockThrownAtAnother... on the corotated law): the exchange happens inside the
// body's own island solve, so its linear momentum is kept; no surface triangles cross at the end
// of the impact.
TEST(HyperelasticContact, ANeoHookeanBodyStruckByItselfKeepsItsMomentum) {
  const double side = 0.1;
  const TetMesh a =
      makeBoxTetMesh(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(side), 3, 3, 3).value();
  std::vector<Eigen::Vector3d> positions = a.restPositions();
  std::vector<Tet> tets = a.tets();
  const int second = a.nodeCount();
  for (const Eigen::Vector3d& x : a.restPositions())
    positions.push_back(x + Eigen::Vector3d(side + 0.02, 0.03, 0));
  for (Tet t : a.tets()) {
    for (int& n : t)
      n += second;
    tets.push_back(t);
  }
  const TetMesh mesh(std::move(positions), std::move(tets));
  FemWorld world(impactSettings());
  const Material material = impactMaterial();
  FemBody* body = world.addBody("blocks", mesh, material).value();
  ASSERT_TRUE(body->enableSelfContact(SelfContactSettings{}).ok());
  FemBodyCheckpoint start = body->checkpoint();
  for (int i = second; i < mesh.nodeCount(); ++i)
    start.state.velocities.segment<3>(3 * i) = Eigen::Vector3d(-5, 0, 0);
  body->restore(start);
  const Eigen::Vector3d before = momentum(*body);
  double worst = 0;
  int max_active = 0, crossing_steps = 0;
  NewtonWatch newton;
  for (int k = 0; k < 120; ++k) {
    const WorldStepReport r = world.step();
    ASSERT_TRUE(r.ok) << "step " << k << ": " << r.message;
    newton.see(*body);
    max_active = std::max(max_active, body->selfContact()->stats().active);
    worst = std::max(worst, (momentum(*body) - before).norm() / before.norm());
    if (!findSurfaceIntersections(mesh.surfaceTriangles(), body->state().positions).empty())
      ++crossing_steps;
  }
  Eigen::Vector3d struck = Eigen::Vector3d::Zero();
  for (int i = 0; i < second; ++i)
    struck += body->model().nodeMasses()[static_cast<size_t>(i)] * body->state().velocity(i);
  std::printf(
      "[figures] neo-Hookean self-contact: max active %d, worst relative momentum drift "
      "%.2e, struck block p_x %.4f of %.4f N s, crossing steps %d, Newton unconverged %d "
      "of %d\n",
      max_active, worst, struck.x(), before.x(), crossing_steps, newton.unconverged, newton.steps);
  EXPECT_GT(max_active, 0);
  EXPECT_LT(worst, 0.01);
  EXPECT_LT(struck.x(), 0.3 * before.x());  // moving the way it was struck (before.x() < 0)
  EXPECT_EQ(crossing_steps, 0);
  EXPECT_EQ(newton.unconverged, 0);
}

}  // namespace hyperelastic_contact_test
}  // namespace torsion::test

// Friction between FEM bodies (docs/contact.md, "Friction between FEM bodies"): a soft block on a
// soft incline sticks below the friction angle and slides above it as Coulomb's law says. The
// incline is a fixed slab under tilted gravity; the friction is implicit in the island's solve
// (k_t of surface_contact_set.h), bounded by mu lambda_n.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "torsion/bullet/fem_body.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kFriction = 0.5;

struct SlideResult {
  double distance = 0;  ///< m, the block's centre along the slope (down positive) after `time`
  double coulomb = 0;   ///< m, Coulomb's rigid-block prediction over the same time (0 sticking)
  /// The friction coefficient the block's acceleration over the second half says:
  /// (g sin(alpha) - a) / (g cos(alpha)).
  double effective_friction = 0;
  int unconverged = 0;
  double worst_penetration = 0, tolerance = 0;
};

double speedAlongSlope(const FemBody& body) {
  double p = 0;
  for (int i = 0; i < body.model().nodeCount(); ++i)
    p += body.model().nodeMasses()[static_cast<size_t>(i)] * body.state().velocity(i).x();
  return p / body.model().totalMass();
}

Eigen::Vector3d centreOf(const FemBody& body) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int i = 0; i < body.model().nodeCount(); ++i)
    c += body.model().nodeMasses()[static_cast<size_t>(i)] * body.state().position(i);
  return c / body.model().totalMass();
}

// A 0.1 m block (2 x 2 x 2 cells, E = 1 MPa) resting on a 0.6 x 0.4 x 0.1 m slab of 0.1 m cells
// (E = 1 MPa, base fixed), gravity tilted by `degrees` about y (down the slope: +x). The block
// settles under normal gravity for 0.2 s first, then the slope is measured over 0.5 s.
SlideResult slide(double degrees) {
  WorldSettings settings;
  settings.solver.time_step = 0.005;
  settings.gravity.setZero();
  FemWorld world(settings);
  BodyContactSettings contact;
  contact.friction = kFriction;
  EXPECT_TRUE(world.femSolver().setFemContact(contact).ok());
  Material material;
  material.youngs_modulus = 1e6;
  material.poisson_ratio = 0.3;
  material.density = 1000;
  material.mass_damping = 0;  // no drag on the sliding motion
  // As the scenes have it: with 1e-3 the stiff block chattered on its contacts while sliding
  // (contacts lifting off and landing again), and each landing's friction braked it.
  material.stiffness_damping = 0.01;
  FemBody* slab =
      world
          .addBody("slab", makeBoxTetMesh({-0.3, -0.2, 0}, {0.3, 0.2, 0.1}, 6, 4, 1).value(),
                   material)
          .value();
  std::vector<int> base;
  for (int i = 0; i < slab->model().nodeCount(); ++i)
    if (slab->state().position(i).z() < 1e-9) base.push_back(i);
  slab->carryNodes(
      "base", base, [](double) { return Frame{}; }, 0.0);
  FemBody* block =
      world
          .addBody("block",
                   makeBoxTetMesh({-0.13, -0.05, 0.1002}, {-0.03, 0.05, 0.2002}, 2, 2, 2).value(),
                   material)
          .value();
  const double g = 9.81, dt = settings.solver.time_step;
  const double alpha = degrees * kPi / 180;
  SlideResult result;
  auto run = [&](int steps, const Eigen::Vector3d& gravity) {
    for (int i = 0; i < block->model().nodeCount(); ++i)
      EXPECT_TRUE(
          block->setNodeForce(i, block->model().nodeMasses()[static_cast<size_t>(i)] * gravity)
              .ok());
    for (int k = 0; k < steps; ++k) {
      const WorldStepReport r = world.step();
      EXPECT_TRUE(r.ok) << r.message;
      const FemContactStats& s = world.femSolver().femContact()->stats();
      if (!s.converged) ++result.unconverged;
      result.worst_penetration = std::max(result.worst_penetration, s.max_end_penetration);
    }
  };
  run(40, Eigen::Vector3d(0, 0, -g));
  const double start = centreOf(*block).x();
  const double time = 0.5;
  const int half = static_cast<int>(std::lround(0.5 * time / dt));
  const Eigen::Vector3d tilted(g * std::sin(alpha), 0, -g * std::cos(alpha));
  run(half, tilted);
  const double speed_half = speedAlongSlope(*block);
  run(half, tilted);
  result.distance = centreOf(*block).x() - start;
  const double measured = (speedAlongSlope(*block) - speed_half) / (half * dt);
  result.effective_friction = (g * std::sin(alpha) - measured) / (g * std::cos(alpha));
  const double acceleration = g * (std::sin(alpha) - kFriction * std::cos(alpha));
  result.coulomb = acceleration > 0 ? 0.5 * acceleration * time * time : 0;
  result.tolerance = world.femSolver().femContact()->pair(slab, block)->gapTolerance();
  std::printf(
      "[figures] soft block on a soft incline at %.2f deg (friction angle %.2f deg): slid %.5f m "
      "in %.1f s, Coulomb %.5f m, effective friction %.4f (mu %.2f), unconverged steps %d, worst "
      "end penetration %.2e m (tolerance %.2e m)\n",
      degrees, std::atan(kFriction) * 180 / kPi, result.distance, time, result.coulomb,
      result.effective_friction, kFriction, result.unconverged, result.worst_penetration,
      result.tolerance);
  return result;
}

const double kFrictionAngle = std::atan(kFriction) * 180 / kPi;  // 26.57 degrees

TEST(SoftIncline, ASoftBlockOnASoftInclineSticksTwoDegreesBelowTheFrictionAngle) {
  const SlideResult r = slide(kFrictionAngle - 2);
  // Sticking: the block only shears on its elastic contact; what it would slide two degrees
  // above the friction angle in the same time is 48 mm.
  EXPECT_LT(std::abs(r.distance), 1e-3);
  EXPECT_LE(r.worst_penetration, r.tolerance);
  EXPECT_LE(r.unconverged, 5);
}

TEST(SoftIncline, ASoftBlockOnASoftInclineSlidesTwoDegreesAboveTheFrictionAngleAtCoulombsRate) {
  const SlideResult r = slide(kFrictionAngle + 2);
  // Sliding at Coulomb's rate: the friction the block's acceleration over the second 0.25 s says
  // is mu within 5 % (the friction angle within 0.8 degrees). How far it slid is less than
  // Coulomb's rigid block (the elastic contact shears for a while before it slips) but never more
  // (that would be friction below mu lambda_n).
  EXPECT_NEAR(r.effective_friction, kFriction, 0.05 * kFriction);
  EXPECT_GT(r.distance, 0.4 * r.coulomb);
  EXPECT_LT(r.distance, 1.02 * r.coulomb);
  EXPECT_LE(r.worst_penetration, r.tolerance);
  EXPECT_LE(r.unconverged, 5);
}

}  // namespace
}  // namespace torsion

// Friction between FEM bodies (docs/contact.md, "Friction between FEM bodies"): a soft block on a
// soft incline sticks below the friction angle and slides above it as Coulomb's law says. The
// incline is a fixed slab under tilted gravity; the friction is implicit in the island's solve
// (k_t of surface_contact_set.h), bounded by mu lambda_n.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "contact_fixtures.h"
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
  double creep = 0;  ///< m/s, the block's speed along the slope at the end
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

// A 0.1 m block (2 x 2 x 2 cells, E = 1 MPa) resting on a slab 0.4 m wide, 0.1 m thick and
// 2 `half_length` long, of 0.1 m cells (E = 1 MPa, base fixed), the block 0.1 m from its upper
// end; gravity tilted by `degrees` about y (down the slope: +x), friction `mu`. The block settles
// under normal gravity for 0.2 s first, then the slope is measured over `time`.
SlideResult slide(double degrees, double mu = kFriction, double time = 0.5,
                  double half_length = 0.3, ElementKind element = ElementKind::kTet4) {
  WorldSettings settings;
  settings.solver.time_step = 0.005;
  settings.gravity.setZero();
  FemWorld world(settings);
  BodyContactSettings contact;
  contact.friction = mu;
  EXPECT_TRUE(world.femSolver().setFemContact(contact).ok());
  Material material;
  material.youngs_modulus = 1e6;
  material.poisson_ratio = 0.3;
  material.density = 1000;
  material.mass_damping = 0;  // no drag on the sliding motion
  // As the scenes have it: with 1e-3 the stiff block chattered on its contacts while sliding
  // (contacts lifting off and landing again), and each landing's friction braked it.
  material.stiffness_damping = 0.01;
  FemBody* slab = world
                      .addBody("slab",
                               makeBoxTetMesh({-half_length, -0.2, 0}, {half_length, 0.2, 0.1},
                                              static_cast<int>(std::lround(20 * half_length)), 4, 1)
                                   .value(),
                               material, Frame{}, element)
                      .value();
  test::holdBase(*slab);
  FemBody* block = world
                       .addBody("block",
                                makeBoxTetMesh({0.17 - half_length, -0.05, 0.1002},
                                               {0.27 - half_length, 0.05, 0.2002}, 2, 2, 2)
                                    .value(),
                                material, Frame{}, element)
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
      if (std::getenv("TTRACE") && gravity.x() != 0 && k < 8)
        std::printf("  k %d v %.5f x %.6f N %.5f active %d stick %d\n", k, speedAlongSlope(*block),
                    centreOf(*block).x(), s.normal_impulse, s.active, s.sticking);
      result.worst_penetration = std::max(result.worst_penetration, s.max_end_penetration);
    }
  };
  run(40, Eigen::Vector3d(0, 0, -g));
  const double start = centreOf(*block).x();
  const int half = static_cast<int>(std::lround(0.5 * time / dt));
  const Eigen::Vector3d tilted(g * std::sin(alpha), 0, -g * std::cos(alpha));
  run(half, tilted);
  const double speed_half = speedAlongSlope(*block);
  run(half, tilted);
  result.distance = centreOf(*block).x() - start;
  const double measured = (speedAlongSlope(*block) - speed_half) / (half * dt);
  result.effective_friction = (g * std::sin(alpha) - measured) / (g * std::cos(alpha));
  result.creep = std::abs(speedAlongSlope(*block));
  const double acceleration = g * (std::sin(alpha) - mu * std::cos(alpha));
  result.coulomb = acceleration > 0 ? 0.5 * acceleration * time * time : 0;
  result.tolerance = world.femSolver().femContact()->pair(slab, block)->gapTolerance();
  std::printf(
      "[figures] soft block on a soft incline at %.2f deg (friction angle %.2f deg): slid %.5f m "
      "in %.1f s, Coulomb %.5f m, effective friction %.4f (mu %.2f), unconverged steps %d, worst "
      "end penetration %.2e m (tolerance %.2e m)\n",
      degrees, std::atan(mu) * 180 / kPi, result.distance, time, result.coulomb,
      result.effective_friction, mu, result.unconverged, result.worst_penetration,
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
  EXPECT_EQ(r.unconverged, 0);
}

TEST(SoftIncline, ASoftBlockOnASoftInclineSlidesTwoDegreesAboveTheFrictionAngleAtCoulombsRate) {
  const SlideResult r = slide(kFrictionAngle + 2);
  // Sliding at Coulomb's rate: the friction the block's acceleration over the second 0.25 s says
  // is mu within 1 % (measured: to 4 digits). How far it slid is Coulomb's rigid block's within
  // 5 %: more by the impulse of the first step, in which the soft block's contact is partly stuck
  // while its top already moves (the sudden tilt's transient: its centre reaches 0.004 m/s where a
  // rigid block reaches 0.0019 m/s), an offset that a 48 mm slide shows. (Before the pairs were
  // rows of one convex problem, nodes and edges at the block's leading face caught it: 52 %.)
  EXPECT_NEAR(r.effective_friction, kFriction, 0.01 * kFriction);
  EXPECT_NEAR(r.distance, r.coulomb, 0.05 * r.coulomb);
  EXPECT_LE(r.worst_penetration, r.tolerance);
  EXPECT_EQ(r.unconverged, 0);
}

// Coulomb's law at other angles and coefficients, frictionless included, on a slab long enough for
// 1 s of sliding (2 m): each distance within 3 % of Coulomb's rigid block, and 1 deg below the
// friction angle the block creeps below 0.1 mm/s.
TEST(SoftIncline, ASoftBlockSlidesCoulombsDistanceAtOtherAnglesAndCoefficients) {
  struct Case {
    double degrees, mu;
  };
  for (const Case c : {Case{20, 0.0}, Case{20, 0.15}, Case{25, 0.3}}) {
    const SlideResult r = slide(c.degrees, c.mu, 1.0, 1.0);
    EXPECT_NEAR(r.distance, r.coulomb, 0.03 * r.coulomb) << c.degrees << " deg, mu " << c.mu;
    EXPECT_LE(r.worst_penetration, r.tolerance);
    EXPECT_EQ(r.unconverged, 0);
  }
  const SlideResult below = slide(std::atan(0.3) * 180 / kPi - 1, 0.3, 1.0, 1.0);
  EXPECT_LT(below.creep, 1e-4) << "m/s";
  EXPECT_LT(std::abs(below.distance), 1e-3);
}

// The same on quadratic tets (block and slab tet10: mid-edge nodes on every face), mu 0.3 at
// 25 deg: measured +0.4 % of Coulomb's distance (tet4: +0.6 %).
TEST(SoftIncline, ASoftTet10BlockOnASoftTet10InclineSlidesCoulombsDistance) {
  const SlideResult r = slide(25, 0.3, 1.0, 1.0, ElementKind::kTet10);
  EXPECT_NEAR(r.distance, r.coulomb, 0.03 * r.coulomb);
  EXPECT_LE(r.worst_penetration, r.tolerance);
  EXPECT_EQ(r.unconverged, 0);
}

}  // namespace
}  // namespace torsion

// A rigid box sliding over an FEM slab (docs/contact.md, "Sliding over nodes"): gravity tilted by
// the slope angle a, the slab's base held. Coulomb's law gives the distance after t seconds,
// d = 0.5 g (sin a - mu cos a) t^2, whatever the slab's mesh spacing or stiffness: the box must
// feel only the normal force and its friction, not the rows of surface nodes it passes over.

#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <utility>

#include "torsion/bt_conversions.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/mesh/box_mesh.h"
#include "validation_output.h"

namespace torsion::test {
namespace {

constexpr double kGravity = 9.81;

struct Slope {
  double degrees = 20;
  double mu = 0.3;
  double youngs_modulus = 1e5;  ///< Pa
  int cells_along = 20;         ///< along the 2 m slope: node rows 2 / cells_along apart
  ElementKind element = ElementKind::kTet4;
};

double coulombDistance(const Slope& s, double t) {
  const double a = s.degrees * M_PI / 180;
  return std::max(0.0, 0.5 * kGravity * (std::sin(a) - s.mu * std::cos(a)) * t * t);
}

// Distance (m) the box's centre moves down the slope in `seconds`. The slab is 2 x 0.6 x 0.1 m;
// the box 0.2 x 0.3 x 0.1 m, 2 kg, starts 0.1 mm above it with its edges on node rows (across the
// slope, rows are 0.1 m apart and the box's sides lie between them).
double slideDistance(const Slope& s, double seconds) {
  const double a = s.degrees * M_PI / 180;
  WorldSettings settings;
  settings.solver.time_step = 0.01;
  settings.solver.threads = 1;
  settings.solver.tolerance = 1e-6;
  settings.solver.max_iterations = 1000;
  settings.gravity = kGravity * Eigen::Vector3d(std::sin(a), 0, -std::cos(a));
  FemWorld world(settings);
  Material m;
  m.youngs_modulus = s.youngs_modulus;
  m.poisson_ratio = 0.3;
  m.density = 100;
  m.stiffness_damping = 0.01;
  const double length = 2, width = 0.6, thickness = 0.1;
  Result<TetMesh> mesh = makeBoxTetMesh({-length / 2, -width / 2, 0},
                                        {length / 2, width / 2, thickness}, s.cells_along, 6, 2);
  if (!mesh.ok()) {
    ADD_FAILURE() << mesh.error().message;
    return std::nan("");
  }
  Result<FemBody*> added = world.addBody("slab", mesh.value(), m, Frame{}, s.element);
  if (!added.ok()) {
    ADD_FAILURE() << added.error().message;
    return std::nan("");
  }
  FemBody* slab = added.value();
  std::vector<int> base;
  for (int i = 0; i < slab->model().nodeCount(); ++i) {
    if (slab->state().position(i).z() < 1e-9) base.push_back(i);
  }
  slab->carryNodes(
      "base", base, [](double) { return Frame{}; }, 0.0);
  const double half_height = 0.05, x0 = -0.6;
  btTransform start;
  start.setIdentity();
  start.setOrigin(btVector3(x0, 0, thickness + half_height + 1e-4));
  btRigidBody* box = world.addRigidBody(
      std::make_unique<btBoxShape>(btVector3(0.1, 0.15, half_height)), 2.0, start);
  box->setFriction(s.mu);
  const int steps = static_cast<int>(std::lround(seconds / settings.solver.time_step));
  for (int k = 0; k < steps; ++k) {
    const WorldStepReport r = world.step();
    EXPECT_TRUE(r.ok) << "step " << k << ": " << r.message;
    if (!r.ok) break;
  }
  return static_cast<double>(box->getCenterOfMassPosition().x()) - x0;
}

void expectCoulomb(const Slope& s, double tolerance, const char* label) {
  const double t = 1.0;
  const double moved = slideDistance(s, t);
  const double coulomb = coulombDistance(s, t);
  std::cout << "[figures] sliding " << label << ": " << s.degrees << " deg, mu " << s.mu << ", E "
            << s.youngs_modulus << ", " << s.cells_along << " cells, "
            << (s.element == ElementKind::kTet10 ? "tet10" : "tet4") << ": moved " << moved
            << " m, Coulomb " << coulomb << " m (" << 100 * (moved / coulomb - 1) << " %)\n";
  if (auto csv = validationCsv(std::string("sliding_") + label + ".csv",
                               "degrees,mu,youngs_modulus,cells,moved_m,coulomb_m")) {
    *csv << s.degrees << "," << s.mu << "," << s.youngs_modulus << "," << s.cells_along << ","
         << moved << "," << coulomb << "\n";
  }
  EXPECT_NEAR(moved, coulomb, tolerance * coulomb);
}

// Without friction the box feels only the normal force: before the fix the nodes just ahead of
// its leading edge took its front face for a wall, and it moved 21 cm of 1.68 m, in jerks.
TEST(Sliding, FrictionlessBoxSlidesAsOnAPlaneOverSoftAndStiffSlabs) {
  for (double E : {1e5, 1e8}) {
    Slope s;
    s.degrees = 5;  // 0.43 m in 1 s: the box stays on the 2 m slab
    s.mu = 0;
    s.youngs_modulus = E;
    expectCoulomb(s, 0.05, E < 1e6 ? "frictionless_soft" : "frictionless_stiff");
  }
}

// Whatever the spacing of the node rows it passes: 0.2 m (the box spans one cell) to 0.05 m.
TEST(Sliding, FrictionlessBoxSlidesAsOnAPlaneOverCoarseAndFineSlabs) {
  for (int cells : {10, 40}) {
    Slope s;
    s.degrees = 5;
    s.mu = 0;
    s.cells_along = cells;
    expectCoulomb(s, 0.05, cells == 10 ? "frictionless_coarse" : "frictionless_fine");
  }
}

TEST(Sliding, FrictionlessBoxSlidesOverACoarseTet10Slab) {
  Slope s;
  s.degrees = 5;
  s.mu = 0;
  s.cells_along = 10;
  s.element = ElementKind::kTet10;
  expectCoulomb(s, 0.05, "frictionless_tet10");
}

// With friction, on a stiff slab, the box feels Coulomb's friction of its net normal force. Before
// the fix it moved 66 % of Coulomb's distance at 20 deg with mu = 0.3: face contacts at its edges
// ended steps stuck beyond Coulomb's cone or pulling, and a face and the node contacts at its
// corners split the load as a push and a pull whose push alone bounded the friction
// (docs/contact.md, "Sliding over nodes"). The distance magnifies a friction error by
// mu cos a / (sin a - mu cos a): 4.5 at 20 deg with mu = 0.3. Steeper slopes and mu = 0.1 at
// 20 deg are still short, and on a soft slab the box moves 31 % of Coulomb's distance
// (docs/validation.md, open); those are not asserted.
TEST(Sliding, BoxWithFrictionSlidesAsCoulombSaysOnAStiffSlab) {
  const std::pair<double, double> cases[] = {{10, 0.1}, {20, 0.3}};
  for (const auto& [degrees, mu] : cases) {
    Slope s;
    s.degrees = degrees;
    s.mu = mu;
    s.youngs_modulus = 1e8;
    expectCoulomb(s, 0.05, "friction_stiff");
  }
}

// The stick/slip threshold tan(a) = mu (16.7 deg for mu = 0.3), on a stiff slab: 1 deg below the
// box stays (creep within 2 mm in 1 s), 1 deg above it slides as Coulomb says (8.9 cm in 1 s).
TEST(Sliding, StiffSlabHoldsTheBoxBelowTheFrictionAngleAndLetsItSlideAbove) {
  Slope s;
  s.youngs_modulus = 1e8;
  const double friction_angle = std::atan(s.mu) * 180 / M_PI;
  s.degrees = friction_angle - 1;
  const double below = slideDistance(s, 1.0);
  s.degrees = friction_angle + 1;
  const double above = slideDistance(s, 1.0);
  const double coulomb = coulombDistance(s, 1.0);
  std::cout << "[figures] sliding threshold (stiff slab, mu 0.3): " << friction_angle - 1
            << " deg moved " << below << " m; " << friction_angle + 1 << " deg moved " << above
            << " m (Coulomb " << coulomb << " m)\n";
  EXPECT_LT(std::abs(below), 2e-3);
  EXPECT_NEAR(above, coulomb, 0.15 * coulomb);
}

}  // namespace
}  // namespace torsion::test

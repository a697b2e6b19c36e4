// A stack of FEM bodies on rigid ground (docs/contact.md, "Islands on rigid ground"): the bodies
// touching each other and the ground are solved in one island CG with the ground contacts as node
// constraints, so the stack carries its weight down to the ground with every step converged and
// no body sinking into another.
#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "torsion/bullet/fem_body.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion {
namespace {

Material soft(double youngs_modulus, double density) {
  Material m;
  m.youngs_modulus = youngs_modulus;
  m.poisson_ratio = 0.3;
  m.density = density;
  m.mass_damping = 1;
  m.stiffness_damping = 0.01;
  return m;
}

// m: how deep the surface nodes of `upper` are below the upward-facing surface triangles of
// `lower` they lie over (0 when none is below): the geometric overlap of two stacked bodies.
double overlap(const FemBody& upper, const FemBody& lower) {
  const TetMesh& mesh = lower.model().mesh();
  double deepest = 0;
  for (const Triangle& tri : mesh.surfaceTriangles()) {
    const Eigen::Vector3d a = lower.state().position(tri[0]);
    const Eigen::Vector3d b = lower.state().position(tri[1]);
    const Eigen::Vector3d c = lower.state().position(tri[2]);
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    if (n.z() < 0.9) continue;  // the top face only
    for (int i = 0; i < upper.model().nodeCount(); ++i) {
      const Eigen::Vector3d p = upper.state().position(i);
      // Barycentric coordinates of p's projection along z.
      const double d = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
      const double wb = ((p.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (p.y() - a.y())) / d;
      const double wc = ((b.x() - a.x()) * (p.y() - a.y()) - (p.x() - a.x()) * (b.y() - a.y())) / d;
      if (wb < 0 || wc < 0 || wb + wc > 1) continue;
      const double surface = a.z() + wb * (b.z() - a.z()) + wc * (c.z() - a.z());
      if (p.z() < surface + 0.05) deepest = std::max(deepest, surface - p.z());
    }
  }
  return deepest;
}

// The blocks of the scene soft_stack (block_162: 0.2 m, 3 x 3 x 3 cells, E = 100 kPa, 4 kg),
// stacked with its offsets on rigid ground and left to settle under gravity: 2 s at dt = 10 ms.
// Before the ground contacts joined the island's CG (block Gauss-Seidel between the bodies), most
// steps ended unconverged and the blocks sank millimetres into each other.
TEST(SoftStack, AStackOfSoftBodiesOnRigidGroundCarriesItsWeightWithEveryStepConverged) {
  WorldSettings settings;
  settings.solver.time_step = 0.01;
  settings.solver.tolerance = 1e-5;
  FemWorld world(settings);
  btRigidBody* ground = world.addRigidBody(
      std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), 0), 0, btTransform::getIdentity());
  ground->setFriction(0.5);
  std::vector<FemBody*> blocks;
  const double offsets[3][2] = {{0, 0}, {0.01, 0}, {-0.01, 0.01}};
  for (int k = 0; k < 3; ++k) {
    const double x = offsets[k][0], y = offsets[k][1], z = 0.0005 + 0.201 * k;
    blocks.push_back(
        world
            .addBody(
                "block" + std::to_string(k),
                makeBoxTetMesh({x - 0.1, y - 0.1, z}, {x + 0.1, y + 0.1, z + 0.2}, 3, 3, 3).value(),
                soft(1e5, 500))
            .value());
  }
  double mass = 0;
  for (const FemBody* block : blocks)
    mass += block->model().totalMass();
  const double g = 9.81, dt = 0.01;
  const int steps = 200, averaged = 20;
  int unconverged = 0;
  double worst_end = 0, worst_overlap = 0, ground_force = 0;
  for (int k = 0; k < steps; ++k) {
    const WorldStepReport r = world.step();
    ASSERT_TRUE(r.ok) << r.message;
    const FemContactStats& s = world.femSolver().femContact()->stats();
    bool converged = s.converged;
    double impulse = 0;
    for (const auto& body : world.bodies()) {
      converged = converged && body->contacts().stats().converged;
      impulse += body->contacts().stats().normal_impulse;
    }
    if (!converged) ++unconverged;
    worst_end = std::max(worst_end, s.max_end_penetration);
    worst_overlap =
        std::max({worst_overlap, overlap(*blocks[1], *blocks[0]), overlap(*blocks[2], *blocks[1])});
    if (k >= steps - averaged) ground_force += impulse / dt / averaged;
  }
  const double tolerance =
      world.femSolver().femContact()->pair(blocks[0], blocks[1])->gapTolerance();
  std::printf(
      "[figures] soft stack: m g = %.3f N, ground force %.3f N (%+.3f %%), unconverged steps %d "
      "of %d, worst end penetration %.2e m, worst overlap %.2e m (gap tolerance %.2e m)\n",
      mass * g, ground_force, 100 * (ground_force / (mass * g) - 1), unconverged, steps, worst_end,
      worst_overlap, tolerance);
  EXPECT_NEAR(ground_force, mass * g, 0.01 * mass * g);
  EXPECT_EQ(unconverged, 0);
  EXPECT_LE(worst_end, tolerance);
  // Geometric, after the step (the end gaps above are linearised): no node of a block below the
  // top face of the one under it by more than the tolerance.
  EXPECT_LE(worst_overlap, tolerance);
}

}  // namespace
}  // namespace torsion

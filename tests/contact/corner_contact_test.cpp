// A block pushed into the corner between the ground and a wall holds against both (convex solve,
// docs/contact-solve.md): the nodes of its edge in the corner touch both bodies. Each node keeps
// one contact, the deeper, and the face rows of the other body's features hold the node's
// triangles against it. The `auto` solve on the same block leaves 0.27 mm in the ground, 0.11 mm in
// the wall and nodes chattering at 3 cm/s after 1.5 s.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "contact_fixtures.h"

namespace torsion::test {
namespace {

struct CornerRun {
  double deepest_in_ground = 0;  ///< m, a node below z = 0, worst step after the first 0.2 s
  double deepest_in_wall = 0;    ///< m, a node beyond x = 0.1, the same
  double fastest_at_end = 0;     ///< m/s, the fastest node over the last 0.5 s
  int unconverged_steps = 0;
  bool ok = true;
};

CornerRun runCorner(ElementKind element, double youngs_modulus) {
  FemWorld world(contactSettings(0.01));
  const double tilt = 30 * 3.141592653589793 / 180;  // gravity leans this far towards the wall
  EXPECT_TRUE(world.setGravity({9.81 * std::sin(tilt), 0, -9.81 * std::cos(tilt)}).ok());
  addGround(world, 0.5);
  btRigidBody* wall = world.addRigidBody(std::make_unique<btBoxShape>(btVector3(0.1, 0.5, 0.5)),
                                         0.0, at({0.2, 0, 0.5}));
  wall->setFriction(0.5);
  Result<TetMesh> mesh = makeBoxTetMesh({-0.1, -0.1, 0}, {0.1, 0.1, 0.2}, 4, 4, 4);
  EXPECT_TRUE(mesh.ok());
  if (!mesh.ok()) return {};
  Result<FemBody*> added =
      world.addBody("block", mesh.value(), softMaterial(youngs_modulus, 1000), Frame{}, element);
  EXPECT_TRUE(added.ok());
  if (!added.ok()) return {};
  FemBody* block = added.value();
  block->contacts().settings().friction = 1.0;
  CornerRun run;
  const int steps = 200;
  for (int k = 0; k < steps; ++k) {
    const WorldStepReport r = world.step();
    if (!r.ok) {
      ADD_FAILURE() << "step " << k << ": " << r.message;
      run.ok = false;
      return run;
    }
    if (!block->contacts().stats().converged) ++run.unconverged_steps;
    for (int i = 0; k >= 20 && i < block->model().nodeCount(); ++i) {
      const Eigen::Vector3d x = block->state().position(i);
      run.deepest_in_ground = std::max(run.deepest_in_ground, -x.z());
      run.deepest_in_wall = std::max(run.deepest_in_wall, x.x() - 0.1);
      if (k >= steps - 50)
        run.fastest_at_end = std::max(run.fastest_at_end, block->state().velocity(i).norm());
    }
  }
  std::printf(
      "[corner, %s, E %.0e] deepest into the ground %.2e m, into the wall %.2e m; fastest node "
      "at the end %.2e m/s; unconverged %d\n",
      element == ElementKind::kTet4 ? "tet4" : "tet10", youngs_modulus, run.deepest_in_ground,
      run.deepest_in_wall, run.fastest_at_end, run.unconverged_steps);
  return run;
}

// Soft and stiff, tet4 and tet10: no node more than 20 um inside either body (the near-rigid
// compliance of the rows sinks a node by micrometres, "Defaults"), every node at rest to 1 mm/s.
TEST(CornerContact, ABlockPushedIntoACornerHoldsAgainstTheGroundAndTheWall) {
  for (const ElementKind element : {ElementKind::kTet4, ElementKind::kTet10}) {
    for (const double youngs_modulus : {1e5, 1e7}) {
      SCOPED_TRACE(testing::Message() << "E " << youngs_modulus << ", "
                                      << (element == ElementKind::kTet4 ? "tet4" : "tet10"));
      const CornerRun run = runCorner(element, youngs_modulus);
      ASSERT_TRUE(run.ok);
      EXPECT_EQ(run.unconverged_steps, 0);
      EXPECT_LT(run.deepest_in_ground, 2e-5);
      EXPECT_LT(run.deepest_in_wall, 2e-5);
      EXPECT_LT(run.fastest_at_end, 1e-3);
    }
  }
}

}  // namespace
}  // namespace torsion::test

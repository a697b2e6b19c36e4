// Self-contact (docs/contact.md, "Self-contact") between parts of one FEM body. Two soft blocks
// meshed as ONE body (two disjoint components) are the plainest case: every contact between them
// is self-contact and the whole exchange of momentum happens inside one implicit solve, so linear
// momentum must be kept to the solver's tolerance and angular momentum to the linearisation's.
// The results are the same for any thread count and whatever storage the step kept.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "torsion/analysis/surface_intersections.h"
#include "torsion/bullet/checkpoint_io.h"
#include "torsion/bullet/fem_body.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion {
namespace {

constexpr double kSide = 0.1;  // m, each block's edge

// Two cubes of side kSide, `gap` apart along x, the second shifted by `offset` along y, as one
// mesh. Nodes of the second start at second_first.
TetMesh twoBlocks(double gap, double offset, int cells, int& second_first) {
  const TetMesh a =
      makeBoxTetMesh(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(kSide), cells, cells, cells)
          .value();
  const Eigen::Vector3d shift(kSide + gap, offset, 0);
  std::vector<Eigen::Vector3d> positions = a.restPositions();
  std::vector<Tet> tets = a.tets();
  second_first = a.nodeCount();
  for (const Eigen::Vector3d& x : a.restPositions())
    positions.push_back(x + shift);
  for (Tet t : a.tets()) {
    for (int& n : t)
      n += second_first;
    tets.push_back(t);
  }
  return TetMesh(std::move(positions), std::move(tets));
}

// The impact scenes' world: no gravity, dt = 0.5 ms.
WorldSettings impactSettings() {
  WorldSettings settings;
  settings.gravity.setZero();
  settings.solver.time_step = 5e-4;
  return settings;
}

// The second block (nodes from `second` on) thrown at the first, at rest, at 15 m/s along -x.
void throwSecondBlock(FemBody& body, int second) {
  FemBodyCheckpoint start = body.checkpoint();
  start.state.velocities.setZero();
  for (int i = second; i < body.model().nodeCount(); ++i)
    start.state.velocities.segment<3>(3 * i) = Eigen::Vector3d(-15, 0, 0);
  body.restore(start);
}

struct Momenta {
  Eigen::Vector3d linear, angular;
};

Momenta momenta(const FemBody& body) {
  Momenta m{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  for (int i = 0; i < body.model().nodeCount(); ++i) {
    const double mass = body.model().nodeMasses()[static_cast<size_t>(i)];
    m.linear += mass * body.state().velocity(i);
    m.angular += mass * body.state().position(i).cross(body.state().velocity(i));
  }
  return m;
}

TEST(SelfContact, ABlockThrownAtAnotherAt15MetresPerSecondHandsItsMomentumOverExactly) {
  int second = 0;
  const TetMesh mesh = twoBlocks(0.02, 0.03, 3, second);
  FemWorld world(impactSettings());
  Material material;
  material.youngs_modulus = 1e6;
  material.stiffness_damping = 1e-3;
  FemBody* body = world.addBody("blocks", mesh, material).value();
  ASSERT_TRUE(body->enableSelfContact(SelfContactSettings{}).ok());
  throwSecondBlock(*body, second);

  const Momenta before = momenta(*body);
  int crossing_steps = 0, unconverged = 0, max_active = 0;
  double worst_linear = 0, worst_angular = 0;
  for (int k = 0; k < 200; ++k) {
    const WorldStepReport report = world.step();
    ASSERT_TRUE(report.ok) << "step " << k << ": " << report.message;
    const SelfContactStats& s = body->selfContact()->stats();
    if (!s.converged) ++unconverged;
    max_active = std::max(max_active, s.active);
    if (!findSurfaceIntersections(mesh.surfaceTriangles(), body->state().positions).empty())
      ++crossing_steps;
    const Momenta now = momenta(*body);
    worst_linear = std::max(worst_linear, (now.linear - before.linear).norm());
    worst_angular = std::max(worst_angular, (now.angular - before.angular).norm());
  }
  // The struck block took most of the momentum (equal masses: all of it in an elastic impact).
  Eigen::Vector3d struck = Eigen::Vector3d::Zero();
  for (int i = 0; i < second; ++i)
    struck += body->model().nodeMasses()[static_cast<size_t>(i)] * body->state().velocity(i);
  std::printf(
      "max active %d, unconverged %d, crossing steps %d, |dP| %g of %g, |dL| %g of %g, "
      "struck block p_x %g\n",
      max_active, unconverged, crossing_steps, worst_linear, before.linear.norm(), worst_angular,
      before.angular.norm(), struck.x());
  EXPECT_GT(max_active, 0);
  // Not asserted (docs/contact.md, "Limits"): at the blocks' rims a few steps may end with
  // crossing surface triangles and a contact solve may stop unconverged (reported).
  EXPECT_LT(worst_linear, 0.01 * before.linear.norm());
  EXPECT_LT(worst_angular, 0.02 * before.angular.norm());
  EXPECT_LT(struck.x(), -0.3 * before.linear.norm());  // moving the way it was struck
}

TEST(SelfContact, ABodyAtRestFeelsNoSelfContact) {
  // A slab resting on its clamped base under gravity: nothing touches, so with self-contact on
  // the motion is the same as without, to the last bit.
  const TetMesh mesh =
      makeBoxTetMesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(0.3, 0.1, 0.05), 6, 2, 2).value();
  std::vector<int> base;
  for (int i = 0; i < mesh.nodeCount(); ++i)
    if (mesh.restPositions()[static_cast<size_t>(i)].x() < 1e-9) base.push_back(i);
  Eigen::VectorXd result[2];
  for (int on = 0; on < 2; ++on) {
    WorldSettings settings;
    settings.solver.time_step = 1e-3;
    FemWorld world(settings);
    FemBody* body = world.addBody("slab", mesh, Material{}).value();
    body->carryNodes(
        "base", base, [](double) { return Frame{}; }, 0);
    if (on) {
      ASSERT_TRUE(body->enableSelfContact(SelfContactSettings{}).ok());
    }
    for (int k = 0; k < 100; ++k)
      ASSERT_TRUE(world.step().ok);
    if (on) {
      EXPECT_EQ(body->selfContact()->stats().active, 0);
    }
    result[on] = body->state().positions;
  }
  EXPECT_EQ((result[0] - result[1]).cwiseAbs().maxCoeff(), 0.0);
}

TEST(SelfContact, TheImpactEndsTheSameToTheLastBitOnOneAndOnTwoThreads) {
  // The candidate search runs in fixed blocks on the world's threads and adds their finds in
  // block order: the contacts, and so the motion, must not depend on the thread count.
  int second = 0;
  const TetMesh mesh = twoBlocks(0.02, 0.03, 3, second);
  Eigen::VectorXd result[2];
  int active = 0;
  for (int run = 0; run < 2; ++run) {
    WorldSettings settings = impactSettings();
    settings.solver.threads = run + 1;
    FemWorld world(settings);
    FemBody* body = world.addBody("blocks", mesh, Material{}).value();
    ASSERT_TRUE(body->enableSelfContact(SelfContactSettings{}).ok());
    throwSecondBlock(*body, second);
    for (int k = 0; k < 60; ++k) {
      ASSERT_TRUE(world.step().ok);
      active = std::max(active, body->selfContact()->stats().active);
    }
    result[run] = body->state().positions;
  }
  EXPECT_GT(active, 0);  // the blocks met: the search found and held contacts
  EXPECT_EQ((result[0] - result[1]).cwiseAbs().maxCoeff(), 0.0);
}

TEST(SelfContact, AWorldRestoredFreshGoesOnAsTheOneThatKeptItsIslandStorage) {
  // The island's storage (the SAP problem and solver, each body's island body and coarse space)
  // is kept from step to step; it must hold storage only. A new world restored to the moment of
  // contact (from the checkpoint's bytes) starts with none, and must go on to the last bit as the
  // world that stepped into it.
  int second = 0;
  const TetMesh mesh = twoBlocks(0.02, 0.03, 3, second);
  const WorldSettings settings = impactSettings();
  auto make = [&](FemWorld& world) {
    FemBody* body = world.addBody("blocks", mesh, Material{}).value();
    EXPECT_TRUE(body->enableSelfContact(SelfContactSettings{}).ok());
    return body;
  };
  FemWorld kept(settings);
  FemBody* body = make(kept);
  throwSecondBlock(*body, second);
  for (int k = 0; k < 6; ++k)
    ASSERT_TRUE(kept.step().ok);
  ASSERT_GT(body->selfContact()->stats().active, 0) << "the blocks must be in contact here";
  const std::string moment = writeCheckpoint(kept, kept.checkpoint(), {}, {}, {});
  int active = 0;
  for (int k = 0; k < 20; ++k) {
    ASSERT_TRUE(kept.step().ok);
    active = std::max(active, body->selfContact()->stats().active);
  }
  ASSERT_GT(active, 0);

  FemWorld fresh(settings);
  FemBody* again = make(fresh);
  Result<StoredCheckpoint> read = readCheckpoint(moment, fresh, {});
  ASSERT_TRUE(read.ok()) << read.error().message;
  ASSERT_TRUE(fresh.restore(read.value().world).ok());
  for (int k = 0; k < 20; ++k)
    ASSERT_TRUE(fresh.step().ok);
  EXPECT_EQ((again->state().positions - body->state().positions).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((again->state().velocities - body->state().velocities).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace torsion

// The body-level preconditioner of the SAP CG (island_body.h, fem_island_body.h): a stiff FEM
// slab (E = 1e8 Pa) preconditioned with its step's CHOLMOD factor solves to the same velocities as
// with block-Jacobi, within the solver's tolerance; with that exact inverse of A and the
// capacitance correction (sap_solver.h) a contact needs one CG iteration per Newton direction; the
// solve converges and repeats bit for bit.
#include <gtest/gtest.h>

#include <cstdio>

#include "sap_fem_scene.h"
#include "sap_test_support.h"
#include "torsion/solve/cholmod_solver.h"

namespace torsion::sap {
namespace {

// Block-Jacobi with the contact blocks (no body preconditioner); the step's factor with the
// capacitance correction (sap_solver.h).
enum class Precond { kBlockJacobi, kFactor };

struct Solved {
  Eigen::VectorXd v;
  SapReport report;
};

Solved solveScene(test::SlabScene& scene, Precond precond, const SapSolverSettings& settings = {}) {
  CholmodSolver factor;
  FemIslandBody slab(scene.system(), scene.constraints(), scene.momentum());
  if (precond != Precond::kBlockJacobi) {
    EXPECT_TRUE(factor.factorize(scene.system(), scene.constraints()));
    slab.usePreconditioner(factor);
  }
  const RigidBody box = scene.boxBody();
  const SapProblem problem = scene.problem(slab, box);
  SapSolver solver(settings);
  Solved out;
  out.report = solver.solve(problem, out.v);
  test::expectCoulombAndComplementarity(problem, out.report);
  return out;
}

// The two preconditioners' answers are compared solved tightly (eps_rel = 1e-10, far below the
// default 1e-6), where each stops within about H^-1 of its residual of the exact minimiser: their
// velocities then agree to 1e-7 of |v| (a factor 1000 of room over eps_rel for the conditioning of
// D H D on the slow, slab-wide modes) and the normal impulses to 1e-6, which a wrong
// preconditioned direction (a different minimiser) could not meet.
SapSolverSettings tight() {
  SapSolverSettings settings;
  settings.relative_tolerance = 1e-10;
  return settings;
}

void expectSameVelocities(const Solved& a, const Solved& b) {
  ASSERT_EQ(a.v.size(), b.v.size());
  const double difference = (a.v - b.v).norm();
  EXPECT_LE(difference, 1e-7 * a.v.norm()) << "|dv| " << difference << ", |v| " << a.v.norm();
  for (size_t i = 0; i < a.report.impulses.size(); ++i)
    EXPECT_NEAR(a.report.impulses[i](2), b.report.impulses[i](2),
                1e-6 * a.report.impulses[i](2) + 1e-12)
        << "row " << i;
}

// The slab on the ground (27 rows) with the box on top (4 rows of two terms). Every P0 is exact
// (the slab's factor, the box's mass), so the corrected P = H^-1: one CG iteration per direction
// (two allowed for rounding).
TEST(SapPrecond, FactorGivesTheBlockJacobiAnswer) {
  test::SlabScene scene{test::SlabSpec{}};
  const Solved jacobi = solveScene(scene, Precond::kBlockJacobi, tight());
  const Solved factor = solveScene(scene, Precond::kFactor, tight());
  expectSameVelocities(jacobi, factor);
  std::printf("slab %d nodes, %zu rows: Newton %d / %d, CG %d / %d (block-Jacobi / factor)\n",
              scene.nodeCount(), scene.rows().size(), jacobi.report.newton_iterations,
              factor.report.newton_iterations, jacobi.report.cg_iterations,
              factor.report.cg_iterations);
  EXPECT_LE(factor.report.cg_iterations, 2 * factor.report.newton_iterations);
}

// Prescribed dofs: the factor is of the free system S A S + (I - S). The slab's left end carried
// at 0.1 m/s along x; the answer again matches block-Jacobi's, the end at its speed.
TEST(SapPrecond, FactorRespectsPrescribedDofs) {
  test::SlabScene scene{test::SlabSpec{}};
  const Eigen::Vector3d carried(0.1, 0, 0);
  for (int i = 0; i < scene.nodeCount(); ++i)
    if (scene.system().model().mesh().restPositions()[static_cast<size_t>(i)].x() < 1e-9)
      scene.constraints().prescribeVelocity(i, carried);
  const Solved jacobi = solveScene(scene, Precond::kBlockJacobi, tight());
  const Solved factor = solveScene(scene, Precond::kFactor, tight());
  expectSameVelocities(jacobi, factor);
  EXPECT_EQ(factor.v.segment<3>(0), carried);
}

// One node on the ground, no box: H = A + j^T G j. The factor alone would leave A^-1 H = I +
// (rank <= 3), at most 4 distinct eigenvalues, so at most 4 CG iterations per direction; with the
// correction P = H^-1 exactly (W = j A^-1 j^T, 3 x 3), so 1 (2 allowed for rounding).
TEST(SapPrecond, ExactBodyInverseNeedsAHandfulOfCgIterationsPerContact) {
  test::SlabSpec spec;
  spec.box = false;
  spec.max_ground_rows = 1;
  test::SlabScene scene{spec};
  const Solved factor = solveScene(scene, Precond::kFactor);
  ASSERT_GT(factor.report.newton_iterations, 0);
  EXPECT_LE(factor.report.cg_iterations, 2 * factor.report.newton_iterations);
  const Solved jacobi = solveScene(scene, Precond::kBlockJacobi);
  expectSameVelocities(jacobi, factor);
  std::printf("one contact: CG %d in %d Newton (factor), %d in %d (block-Jacobi)\n",
              factor.report.cg_iterations, factor.report.newton_iterations,
              jacobi.report.cg_iterations, jacobi.report.newton_iterations);
}

// Above max_correction_rows the island ignores the factor: block-Jacobi's solve, bit for bit.
TEST(SapPrecond, AboveTheRowCapFallsBackToBlockJacobi) {
  test::SlabScene scene{test::SlabSpec{}};
  SapSolverSettings settings;
  settings.max_correction_rows = static_cast<int>(scene.rows().size()) - 1;
  const Solved jacobi = solveScene(scene, Precond::kBlockJacobi, settings);
  const Solved factor = solveScene(scene, Precond::kFactor, settings);
  EXPECT_EQ(jacobi.v, factor.v);
  EXPECT_EQ(jacobi.report.cg_iterations, factor.report.cg_iterations);
}

TEST(SapPrecond, FactorSolveIsDeterministic) {
  test::SlabScene scene{test::SlabSpec{}};
  const Solved first = solveScene(scene, Precond::kFactor);
  const Solved second = solveScene(scene, Precond::kFactor);
  EXPECT_EQ(first.v, second.v);
  EXPECT_EQ(first.report.cg_iterations, second.report.cg_iterations);
}

}  // namespace
}  // namespace torsion::sap

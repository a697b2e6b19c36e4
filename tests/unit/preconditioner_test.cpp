// CG preconditioners (SolverSettings::preconditioner): every kind converges to the direct
// solution; the lagged factorisations cut the iterations of a stiff twist; the refactorisation
// policy fires when iterations grow or the interval ends; results do not depend on the thread
// count.
#include <gtest/gtest.h>

#include "torsion/mesh/box_mesh.h"
#include "torsion/solve/cholmod_solver.h"
#include "torsion/solve/implicit_stepper.h"
#include "torsion/solve/projected_cg.h"

namespace torsion {
namespace {

std::shared_ptr<const FemModel> beam(double youngs_modulus, ElementKind element, int nx = 8,
                                     int ny = 2) {
  auto mesh = std::make_shared<TetMesh>(
      makeBoxTetMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(4, 1, 1), nx, ny, ny).value());
  Material material;
  material.youngs_modulus = youngs_modulus;
  return FemModel::create(mesh, material, element).value();
}

// The beam's end x = 0 held, its end x = 4 turned about the axis at 2 rad/s.
void twistConstraints(const FemModel& model, const FemState& state, double dt,
                      NodeConstraints& constraints) {
  constraints.reset(model.nodeCount());
  for (int i = 0; i < model.nodeCount(); ++i) {
    const double x = model.mesh().restPositions()[static_cast<size_t>(i)].x();
    if (x < 1e-9) constraints.prescribeVelocity(i, Eigen::Vector3d::Zero());
    if (x > 4 - 1e-9) {
      const Eigen::Vector3d p = state.position(i);
      const Eigen::Vector3d r = p - Eigen::Vector3d(p.x(), 0.5, 0.5);
      const Eigen::AngleAxisd turn(2.0 * dt, Eigen::Vector3d::UnitX());
      constraints.prescribeVelocity(i, (turn * r - r) / dt);
    }
  }
}

struct TwistRun {
  FemState state;
  double mean_iterations = 0;
  std::int64_t split_calls = 0;
};

TwistRun twist(std::shared_ptr<const FemModel> model, PreconditionerKind preconditioner, int steps,
               int threads = 1, double tolerance = 1e-4) {
  Parallel parallel(threads);
  SolverSettings settings;
  settings.preconditioner = preconditioner;
  settings.tolerance = tolerance;
  ImplicitStepper stepper(model, settings, parallel);
  TwistRun run{FemState::atRest(*model)};
  NodeConstraints constraints;
  const Eigen::VectorXd no_force = Eigen::VectorXd::Zero(3 * model->nodeCount());
  long iterations = 0;
  for (int k = 0; k < steps; ++k) {
    twistConstraints(*model, run.state, settings.time_step, constraints);
    const StepReport report = stepper.step(run.state, constraints, no_force);
    EXPECT_EQ(report.health, StepHealth::kOk) << report.message;
    iterations += report.solve.iterations;
  }
  run.mean_iterations = static_cast<double>(iterations) / steps;
  run.split_calls = parallel.splitCalls();
  return run;
}

const PreconditionerKind kAllKinds[] = {
    PreconditionerKind::kJacobi, PreconditionerKind::kBlockJacobi,
    PreconditionerKind::kLaggedCholesky, PreconditionerKind::kIncompleteCholesky,
    PreconditionerKind::kTwoLevel};

TEST(Preconditioners, EveryKindReachesTheDirectSolutionWithinTheCgTolerance) {
  for (ElementKind element : {ElementKind::kTet4, ElementKind::kTet10}) {
    SCOPED_TRACE(element == ElementKind::kTet4 ? "tet4" : "tet10");
    auto model = beam(1e6, element);
    // A twisted configuration: rotations far from identity, constraints on both ends.
    Parallel parallel(1);
    SolverSettings settings;
    ImplicitStepper stepper(model, settings, parallel);
    FemState state = FemState::atRest(*model);
    NodeConstraints constraints;
    const Eigen::VectorXd no_force = Eigen::VectorXd::Zero(3 * model->nodeCount());
    for (int k = 0; k < 20; ++k) {
      twistConstraints(*model, state, settings.time_step, constraints);
      ASSERT_EQ(stepper.step(state, constraints, no_force).health, StepHealth::kOk);
    }
    twistConstraints(*model, state, settings.time_step, constraints);
    const SystemOperator& op = stepper.system();
    Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(3 * model->nodeCount(), -1.0, 2.0);
    b = b.array().sin() * 10.0;

    CholmodSolver direct;
    Eigen::VectorXd reference = Eigen::VectorXd::Zero(b.size());
    ASSERT_TRUE(direct.solve(op, constraints, b, reference).converged);
    for (PreconditionerKind kind : kAllKinds) {
      SCOPED_TRACE(toString(kind));
      SolverSettings cg_settings;
      cg_settings.preconditioner = kind;
      cg_settings.tolerance = 1e-10;
      cg_settings.max_iterations = 5000;
      ProjectedCg cg;
      Eigen::VectorXd v = Eigen::VectorXd::Zero(b.size());
      const LinearSolveReport report = cg.solve(op, constraints, b, cg_settings, v);
      EXPECT_TRUE(report.converged);
      // |v - v*| <= cond(A) |r| / |A|: at a residual of 1e-10 the solutions agree far below
      // 1e-6 for this well-conditioned (mass-dominated) system.
      EXPECT_LT((v - reference).norm(), 1e-6 * reference.norm());
    }
  }
}

TEST(Preconditioners, LaggedFactorisationsNeedAtMostHalfTheBlockJacobiIterationsWhenStiff) {
  // E = 1e7 Pa at dt = 0.01 s: stiffness dominates the mass and block-Jacobi needs many
  // iterations (32 per step on the 8332-tet cylinder twist).
  auto tet4 = beam(1e7, ElementKind::kTet4);
  const double block_jacobi = twist(tet4, PreconditionerKind::kBlockJacobi, 30).mean_iterations;
  const double lagged = twist(tet4, PreconditionerKind::kLaggedCholesky, 30).mean_iterations;
  const double incomplete =
      twist(tet4, PreconditionerKind::kIncompleteCholesky, 30).mean_iterations;
  EXPECT_GT(block_jacobi, 8) << "the case must be stiff enough to matter";
  EXPECT_LE(lagged, 0.5 * block_jacobi);
  EXPECT_LT(incomplete, block_jacobi);

  auto tet10 = beam(1e7, ElementKind::kTet10);
  const double tet10_block_jacobi =
      twist(tet10, PreconditionerKind::kBlockJacobi, 30).mean_iterations;
  const double two_level = twist(tet10, PreconditionerKind::kTwoLevel, 30).mean_iterations;
  EXPECT_GT(tet10_block_jacobi, 8);
  EXPECT_LE(two_level, 0.5 * tet10_block_jacobi);
}

TEST(Preconditioners, LaggedCholeskyRefactorisesWhenIterationsGrowOrTheIntervalEnds) {
  auto soft = beam(1e5, ElementKind::kTet4);
  auto stiff = beam(1e7, ElementKind::kTet4);
  Parallel parallel(1);
  SystemOperator soft_system(soft, parallel), stiff_system(stiff, parallel);
  for (SystemOperator* op : {&soft_system, &stiff_system})
    op->setCoefficients(1, 1e-4 + 1e-4);
  NodeConstraints constraints(soft->nodeCount());
  for (int i = 0; i < soft->nodeCount(); ++i) {
    if (soft->mesh().restPositions()[static_cast<size_t>(i)].x() < 1e-9)
      constraints.prescribeVelocity(i, Eigen::Vector3d::Zero());
  }
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(3 * soft->nodeCount(), -1.0, 1.0);

  SolverSettings settings;
  settings.preconditioner = PreconditionerKind::kLaggedCholesky;
  settings.tolerance = 1e-8;
  settings.refactor_interval = 1000;
  settings.refactor_iterations = 3;
  ProjectedCg cg;
  auto solve = [&](const SystemOperator& op) {
    Eigen::VectorXd v = Eigen::VectorXd::Zero(b.size());
    return cg.solve(op, constraints, b, settings, v).iterations;
  };
  EXPECT_LE(solve(soft_system), 2);  // its own factor: the exact inverse
  EXPECT_LE(solve(soft_system), 2);
  EXPECT_EQ(cg.factorisations(), 1);
  // The soft system's factor for a 100x stiffer system: still a valid preconditioner, but the
  // iterations grow past the threshold...
  EXPECT_GT(solve(stiff_system), settings.refactor_iterations);
  EXPECT_EQ(cg.factorisations(), 1);
  // ...so the next solve refactorises, and needs as few iterations as the first.
  EXPECT_LE(solve(stiff_system), 2);
  EXPECT_EQ(cg.factorisations(), 2);

  // The interval: after refactor_interval solves with one factor, whatever the iterations.
  settings.refactor_interval = 2;
  solve(stiff_system);  // the second solve with factor 2
  EXPECT_EQ(cg.factorisations(), 2);
  solve(stiff_system);
  EXPECT_EQ(cg.factorisations(), 3);
}

TEST(Preconditioners, LaggedKindsGiveTheSameResultForAnyThreadCount) {
  // Big enough for the kernels to split over 2 threads (checked below).
  auto tet4 = beam(1e7, ElementKind::kTet4, 24, 6);
  auto tet10 = beam(1e7, ElementKind::kTet10, 16, 4);
  const std::pair<std::shared_ptr<const FemModel>, PreconditionerKind> cases[] = {
      {tet4, PreconditionerKind::kLaggedCholesky},
      {tet4, PreconditionerKind::kIncompleteCholesky},
      {tet10, PreconditionerKind::kTwoLevel}};
  for (const auto& [model, kind] : cases) {
    SCOPED_TRACE(toString(kind));
    const TwistRun one = twist(model, kind, 6, 1);
    const TwistRun two = twist(model, kind, 6, 2);
    EXPECT_GT(two.split_calls, 0) << "the 2-thread run must have split its loops";
    EXPECT_TRUE(one.state.positions == two.state.positions)
        << "max diff " << (one.state.positions - two.state.positions).cwiseAbs().maxCoeff();
  }
}

}  // namespace
}  // namespace torsion

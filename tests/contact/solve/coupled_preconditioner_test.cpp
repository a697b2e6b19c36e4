// The island CG's preconditioner with the contact couplings (coupled_preconditioner.h), checked
// on the facts it is built for, with dense matrices small enough to be exact:
//   - with A block-diagonal (point masses, a rigid body) it is the exact inverse of the Newton
//     Hessian: every eigenvalue of P H is 1, and each Newton direction costs one CG iteration;
//   - on a spring chain with stiff rows tying distant nodes (a rod touching itself), and an end
//     held still, the eigenvalues of P H lie within [min(alpha, 1), max(beta, 1)], alpha and beta
//     the extreme eigenvalues of D^-1 A (block-Jacobi on the chain alone): contacts however stiff
//     do not worsen the conditioning CG sees. Block-Jacobi with only the rows' diagonal blocks
//     (the preconditioner it replaced) is shown far outside those bounds on the same chain;
//   - on a slender FEM bar folded onto itself, the coarse correction (coarse_correction.h) only
//     adds: the smallest eigenvalue of P H does not fall, the largest rises by at most 1 (Z E^-1
//     Z^T H is an H-orthogonal projection), and the condition number falls by an order of
//     magnitude; the solve finds the same velocities in far fewer CG iterations.
#include "torsion/contact/solve/coupled_preconditioner.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <vector>

#include "sap_test_support.h"
#include "torsion/contact/solve/fem_island_body.h"
#include "torsion/solve/parallel.h"

namespace torsion::sap {
namespace {

constexpr double kDt = 1e-3;

// Columns of a linear map on the island's dofs, applied to each unit vector.
template <typename Map>
Eigen::MatrixXd denseOf(int dofs, Map&& apply) {
  Eigen::MatrixXd m(dofs, dofs);
  Eigen::VectorXd e, out;
  for (int c = 0; c < dofs; ++c) {
    e = Eigen::VectorXd::Unit(dofs, c);
    apply(e, out);
    m.col(c) = out;
  }
  return m;
}

// The eigenvalues of H x = lambda B x on the dofs `free` (B SPD there): with B = P^-1, those of
// the preconditioned operator P H.
Eigen::VectorXd pencilEigenvalues(const Eigen::MatrixXd& h, const Eigen::MatrixXd& b,
                                  const std::vector<int>& free) {
  const auto n = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd hf(n, n), bf(n, n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j) {
      hf(i, j) = h(free[static_cast<size_t>(i)], free[static_cast<size_t>(j)]);
      bf(i, j) = b(free[static_cast<size_t>(i)], free[static_cast<size_t>(j)]);
    }
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> pencil(hf, 0.5 * (bf + bf.transpose()));
  return pencil.eigenvalues();
}

// P^-1 on the dofs `free`, as a full-size matrix zero elsewhere.
Eigen::MatrixXd inverseOn(const Eigen::MatrixXd& p, const std::vector<int>& free) {
  const auto n = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd pf(n, n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j)
      pf(i, j) = p(free[static_cast<size_t>(i)], free[static_cast<size_t>(j)]);
  const Eigen::MatrixXd inverse = pf.inverse();
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(p.rows(), p.cols());
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j)
      out(free[static_cast<size_t>(i)], free[static_cast<size_t>(j)]) = inverse(i, j);
  return out;
}

// A row pressing node `a` of body 0 against node `b` along `normal`, penetrating 1 mm, with
// friction (mu 0.5, a lagged impulse): active at rest with G's normal and tangential parts.
ContactRow pairRow(int a, int b, const Eigen::Vector3d& normal) {
  ContactRow row;
  row.frame = contactFrame(normal);
  row.terms.push_back(nodeTerm(0, a, -1.0, row.frame));
  row.terms.push_back(nodeTerm(0, b, 1.0, row.frame));
  row.mu = 0.5;
  row.stiffness = 1e15;  // near-rigid: SAP's cap decides, G ~ 40 / w
  row.dissipation_time = kDt / 3.141592653589793;
  row.gap = -1e-3;
  row.lagged_normal_impulse = 1e-3;
  return row;
}

struct Operators {
  // H, P, and the inverse of block-Jacobi with the rows' diagonal blocks (H's diagonal blocks).
  Eigen::MatrixXd h, p, diagonal_blocks;
};

Operators operatorsAt(const SapProblem& problem, const Eigen::VectorXd& v) {
  SapEvaluation e;
  problem.evaluate(v, e);
  CoupledPreconditioner coupled;
  coupled.prepare(problem, e);
  EXPECT_GT(coupled.coupledDofs(), 0);
  Operators out;
  out.h = denseOf(problem.dofs(), [&](const Eigen::VectorXd& x, Eigen::VectorXd& y) {
    Eigen::VectorXd fx = x, ax;
    problem.filter(fx);
    problem.multiplyHessian(e, fx, ax, y);
  });
  out.p = denseOf(problem.dofs(), [&](const Eigen::VectorXd& x, Eigen::VectorXd& y) {
    Eigen::VectorXd fx = x;
    problem.filter(fx);
    coupled.apply(problem, fx, y);
  });
  // Block-Jacobi of H: its dense diagonal blocks inverted.
  Eigen::MatrixXd blocks = Eigen::MatrixXd::Zero(problem.dofs(), problem.dofs());
  for (int j = 0; j < problem.blockCount(); ++j) {
    const int o = problem.blockOffset(j);
    const auto n = problem.blockOfA(j).rows();
    blocks.block(o, o, n, n) = out.h.block(o, o, n, n);
  }
  out.diagonal_blocks = blocks;
  return out;
}

TEST(CoupledPreconditioner, IsTheExactInverseWhereAIsBlockDiagonal) {
  // Four point masses and a rigid box; rows between the masses and from two masses to the box.
  MatrixBody masses(test::massMatrix({1.0, 2.0, 0.5, 3.0}),
                    Eigen::VectorXd::LinSpaced(12, -1.0, 1.0));
  Eigen::VectorXd twist(6);
  twist << 0.1, 0, -0.2, 0.3, 0, 0.1;
  const Eigen::Matrix3d inertia = Eigen::Vector3d(0.2, 0.3, 0.4).asDiagonal();
  RigidBody box(2.0, inertia, twist);
  std::vector<ContactRow> rows = {pairRow(0, 1, Eigen::Vector3d::UnitZ()),
                                  pairRow(1, 2, Eigen::Vector3d(1, 1, 0).normalized()),
                                  pairRow(3, 0, Eigen::Vector3d::UnitX())};
  for (int node : {2, 3}) {
    ContactRow row = pairRow(node, node, Eigen::Vector3d::UnitZ());
    row.terms.pop_back();
    row.terms.push_back(rigidPointTerm(1, Eigen::Vector3d(0.1 * node, -0.1, 0.05), 1.0, row.frame));
    rows.push_back(row);
  }
  const SapProblem problem = SapProblem::create({&masses, &box}, rows, kDt).value();
  const Operators ops = operatorsAt(problem, Eigen::VectorXd::Zero(problem.dofs()));
  std::vector<int> all(static_cast<size_t>(problem.dofs()));
  for (int i = 0; i < problem.dofs(); ++i)
    all[static_cast<size_t>(i)] = i;
  const Eigen::VectorXd lambda = pencilEigenvalues(ops.h, inverseOn(ops.p, all), all);
  EXPECT_NEAR(lambda.minCoeff(), 1.0, 1e-9);
  EXPECT_NEAR(lambda.maxCoeff(), 1.0, 1e-9);
  // The solve: one CG iteration per Newton direction (two allowed for rounding).
  SapSolver solver;
  Eigen::VectorXd v;
  const SapReport report = solver.solve(problem, v);
  test::expectCoulombAndComplementarity(problem, report);
  EXPECT_LE(report.cg_iterations, 2 * report.newton_iterations);
}

// A chain of n nodes along x, springs of stiffness k between neighbours (all three directions),
// node 0 held still: A = M + dt^2 K.
Eigen::SparseMatrix<double> chainMatrix(int nodes, double mass, double stiffness) {
  std::vector<Eigen::Triplet<double>> t;
  const double k = kDt * kDt * stiffness;
  for (int i = 0; i < nodes; ++i)
    for (int d = 0; d < 3; ++d)
      t.emplace_back(3 * i + d, 3 * i + d, mass);
  for (int i = 0; i + 1 < nodes; ++i)
    for (int d = 0; d < 3; ++d) {
      const int a = 3 * i + d, b = 3 * (i + 1) + d;
      t.emplace_back(a, a, k);
      t.emplace_back(b, b, k);
      t.emplace_back(a, b, -k);
      t.emplace_back(b, a, -k);
    }
  Eigen::SparseMatrix<double> m(3 * nodes, 3 * nodes);
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

TEST(CoupledPreconditioner, KeepsTheChainsConditioningWhateverTheContacts) {
  constexpr int kNodes = 24;
  MatrixBody chain(chainMatrix(kNodes, 1e-3, 2e4), Eigen::VectorXd::Zero(3 * kNodes));
  for (int d = 0; d < 3; ++d)
    chain.prescribe(d, 0.0);
  // The chain folded on itself: nodes far apart along it pressed together.
  const std::vector<ContactRow> rows = {pairRow(3, 20, Eigen::Vector3d::UnitY()),
                                        pairRow(6, 17, Eigen::Vector3d(0, 1, 1).normalized()),
                                        pairRow(9, 14, Eigen::Vector3d::UnitZ())};
  const SapProblem problem = SapProblem::create({&chain}, rows, kDt).value();
  const Operators ops = operatorsAt(problem, Eigen::VectorXd::Zero(problem.dofs()));
  std::vector<int> free;
  for (int i = 3; i < problem.dofs(); ++i)
    free.push_back(i);
  // alpha, beta: D^-1 A on the chain alone (D its diagonal blocks).
  const Eigen::MatrixXd a = Eigen::MatrixXd(chainMatrix(kNodes, 1e-3, 2e4));
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(a.rows(), a.cols());
  for (int j = 0; j < kNodes; ++j)
    d.block<3, 3>(3 * j, 3 * j) = a.block<3, 3>(3 * j, 3 * j);
  const Eigen::VectorXd chain_lambda = pencilEigenvalues(a, d, free);
  const double alpha = chain_lambda.minCoeff(), beta = chain_lambda.maxCoeff();
  const Eigen::VectorXd lambda = pencilEigenvalues(ops.h, inverseOn(ops.p, free), free);
  EXPECT_GE(lambda.minCoeff(), std::min(alpha, 1.0) * (1 - 1e-9));
  EXPECT_LE(lambda.maxCoeff(), std::max(beta, 1.0) * (1 + 1e-9));
  // The rows are stiff: with only their diagonal blocks the conditioning is far worse.
  const Eigen::VectorXd diagonal_lambda = pencilEigenvalues(ops.h, ops.diagonal_blocks, free);
  const double coupled = lambda.maxCoeff() / lambda.minCoeff();
  const double diagonal_only = diagonal_lambda.maxCoeff() / diagonal_lambda.minCoeff();
  std::printf("chain: D^-1 A in [%.3g, %.3g]; P H condition %.3g, diagonal blocks only %.3g\n",
              alpha, beta, coupled, diagonal_only);
  EXPECT_GT(diagonal_only, 10 * coupled);
}

// A 2.4 m bar of 48 cubic cells (0.05 m, E 10 MPa), its end x = 0 held, folded on itself: rows
// press nodes a quarter and three quarters along it together. The same island with and without
// the bar's coarse space (its default: 32 aggregates).
TEST(CoupledPreconditioner, CoarseSpaceConditionsASlenderBarAsAShortOne) {
  constexpr int kCells = 48;
  constexpr double kStep = 1e-2;
  const std::shared_ptr<const FemModel> model = test::slenderBarModel(kCells);
  const TetMesh& mesh = model->mesh();
  const int n = model->nodeCount();
  Parallel parallel(1);
  SystemOperator system(model, parallel);
  system.setCoefficients(1.0, kStep * kStep);
  NodeConstraints constraints(n);
  Eigen::VectorXd x(3 * n), b(3 * n);
  std::vector<int> free;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = mesh.restPositions()[static_cast<size_t>(i)];
    x.segment<3>(3 * i) = p;
    b.segment<3>(3 * i) =
        kStep * model->nodeMasses()[static_cast<size_t>(i)] * Eigen::Vector3d(0, 0, -9.81);
    if (p.x() < 1e-9) {
      constraints.prescribeVelocity(i, Eigen::Vector3d::Zero());
    } else {
      for (int d = 0; d < 3; ++d)
        free.push_back(3 * i + d);
    }
  }
  // The node nearest a point of the bar.
  const auto nodeAt = [&](const Eigen::Vector3d& point) {
    int best = 0;
    for (int i = 1; i < n; ++i)
      if ((x.segment<3>(3 * i) - point).norm() < (x.segment<3>(3 * best) - point).norm()) best = i;
    return best;
  };
  std::vector<ContactRow> rows;
  for (double y : {0.0, 0.05})
    rows.push_back(
        pairRow(nodeAt({0.6, y, 0.05}), nodeAt({1.8, y, 0.05}), Eigen::Vector3d::UnitZ()));
  FemIslandBody plain(system, constraints, b), coarse(system, constraints, b);
  coarse.useCoarseSpace(x);
  ASSERT_NE(coarse.coarseSpace(), nullptr);
  const SapProblem plain_problem = SapProblem::create({&plain}, rows, kStep).value();
  const SapProblem coarse_problem = SapProblem::create({&coarse}, rows, kStep).value();
  const Eigen::VectorXd v0 = Eigen::VectorXd::Zero(3 * n);
  const Operators plain_ops = operatorsAt(plain_problem, v0);
  const Operators coarse_ops = operatorsAt(coarse_problem, v0);
  const Eigen::VectorXd plain_lambda =
      pencilEigenvalues(plain_ops.h, inverseOn(plain_ops.p, free), free);
  const Eigen::VectorXd coarse_lambda =
      pencilEigenvalues(coarse_ops.h, inverseOn(coarse_ops.p, free), free);
  EXPECT_GE(coarse_lambda.minCoeff(), plain_lambda.minCoeff() * (1 - 1e-9));
  EXPECT_LE(coarse_lambda.maxCoeff(), plain_lambda.maxCoeff() + 1 + 1e-9);
  const double plain_condition = plain_lambda.maxCoeff() / plain_lambda.minCoeff();
  const double coarse_condition = coarse_lambda.maxCoeff() / coarse_lambda.minCoeff();
  // The solves: the same minimiser, to the solver's tolerance.
  SapSolver solver;
  Eigen::VectorXd plain_v, coarse_v;
  const SapReport plain_report = solver.solve(plain_problem, plain_v);
  const SapReport coarse_report = solver.solve(coarse_problem, coarse_v);
  ASSERT_TRUE(plain_report.converged);
  ASSERT_TRUE(coarse_report.converged);
  test::expectCoulombAndComplementarity(coarse_problem, coarse_report);
  const double difference = (coarse_v - plain_v).norm() / plain_v.norm();
  std::printf(
      "slender bar: P H condition %.4g plain, %.4g with the coarse space; CG %d / %d over "
      "%d / %d Newton iterations; velocities differ by %.2g (relative)\n",
      plain_condition, coarse_condition, plain_report.cg_iterations, coarse_report.cg_iterations,
      plain_report.newton_iterations, coarse_report.newton_iterations, difference);
  EXPECT_LT(10 * coarse_condition, plain_condition);
  EXPECT_LT(2 * coarse_report.cg_iterations, plain_report.cg_iterations);
  EXPECT_LT(difference, 1e-4);
}

}  // namespace
}  // namespace torsion::sap

#include "torsion/contact/solve/convex_rows.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cstddef>

namespace torsion::sap {

namespace {

// A group's rows whose last normal impulses (their friction bounds) and this solve's differ by
// more than this factor either way are solved again with this solve's. At 2 a box landing while
// it slid lost +7 % more than mu times its normal impulses (its impact decays over three steps,
// each braked by the one before); at 1.1, -0.4 %. At rest and in steady sliding the two agree.
constexpr double kLaggedMismatch = 1.1;
constexpr int kMaxFrictionBoundRounds = 2;
// A group whose rows new to the solve (no lagged impulse: no friction) carried more than this
// share of its normal impulse is solved again with the impulses found, as a mismatch is. A box
// sliding over a slab meets new nodes and features at its leading edges every step; left without
// friction for their first step, they took up to 0.3 % off its friction, which the distance 1 deg
// above the friction angle magnifies 15.7 times: +8.7 % of Coulomb's on a soft tet10 slab, +5.3 %
// with this.
constexpr double kNewRowsShare = 0.01;

// Returns whether any bound changed (solveWithMatchedFrictionBounds).
bool matchFrictionBounds(SapProblem& problem, const std::vector<int>& row_group,
                         const SapReport& report) {
  if (row_group.empty()) return false;
  const auto groups =
      static_cast<std::size_t>(*std::max_element(row_group.begin(), row_group.end()) + 1);
  std::vector<double> lagged(groups, 0.0), solved(groups, 0.0), unbounded(groups, 0.0);
  for (int r = 0; r < problem.rowCount(); ++r) {
    const auto k = static_cast<std::size_t>(row_group[static_cast<std::size_t>(r)]);
    const double gamma_n = std::max(0.0, report.impulses[static_cast<std::size_t>(r)].z());
    lagged[k] += problem.row(r).lagged_normal_impulse;
    solved[k] += gamma_n;
    if (problem.row(r).lagged_normal_impulse == 0) unbounded[k] += gamma_n;
  }
  bool changed = false;
  for (int r = 0; r < problem.rowCount(); ++r) {
    const auto k = static_cast<std::size_t>(row_group[static_cast<std::size_t>(r)]);
    const ContactRow& row = problem.row(r);
    const bool mismatched = lagged[k] * kLaggedMismatch < solved[k] ||
                            lagged[k] > kLaggedMismatch * solved[k] ||
                            unbounded[k] > kNewRowsShare * solved[k];
    if (!mismatched || row.mu == 0 || row.kind != RowKind::kContact) continue;
    const double gamma_n = std::max(0.0, report.impulses[static_cast<std::size_t>(r)].z());
    if (gamma_n != row.lagged_normal_impulse) {
      problem.setLaggedNormalImpulse(r, gamma_n);  // >= 0 and finite
      changed = true;
    }
  }
  return changed;
}

}  // namespace

SapReport solveWithMatchedFrictionBounds(SapSolver& solver, SapProblem& problem,
                                         const std::vector<int>& row_group, Eigen::VectorXd& x) {
  SapReport report = solver.solve(problem, x);
  // Every round's iterations count: the statistics say what the step cost.
  int newton = report.newton_iterations;
  int cg = report.cg_iterations;
  for (int round = 0; round < kMaxFrictionBoundRounds && report.converged &&
                      matchFrictionBounds(problem, row_group, report);
       ++round) {
    report = solver.solve(problem, x);  // from the last solution
    newton += report.newton_iterations;
    cg += report.cg_iterations;
  }
  report.newton_iterations = newton;
  report.cg_iterations = cg;
  return report;
}

std::vector<Vector6d> solvedTwists(const SapProblem& problem, const SapReport& report,
                                   int first_body) {
  std::vector<Vector6d> twists;
  if (first_body >= problem.bodyCount()) return twists;
  Eigen::VectorXd row_impulses = Eigen::VectorXd::Zero(problem.dofs());
  for (int i = 0; i < problem.rowCount(); ++i)
    problem.addRowTranspose(i, report.impulses[static_cast<std::size_t>(i)], row_impulses);
  for (int b = first_body; b < problem.bodyCount(); ++b) {
    const int offset = problem.bodyOffset(b);
    const Vector6d momentum =
        problem.momentum().segment<6>(offset) + row_impulses.segment<6>(offset);
    twists.emplace_back(Matrix6d(problem.body(b).diagonalBlock(0)).llt().solve(momentum));
  }
  return twists;
}

}  // namespace torsion::sap

#pragma once
// Newton's method on the SAP cost of an island (sap_problem.h; Castro, Permenter, Han 2022: the
// paper's solver). Each iteration:
//
//   1. the gradient g = S (A v - b - J^T gamma) and the G blocks at v;
//   2. the Newton direction from S H S dv = -g, H = A + J^T G J, by preconditioned CG, matrix-free
//      (body products plus sum J_i^T G_i J_i), preconditioned (below),
//      started from dv = 0 and stopped at a relative residual eta_k = min(0.1, sqrt(r_k / r_0))
//      (inexact Newton, tightening as it converges; never tighter than the tolerance needs).
//      CG from zero on an SPD system returns a descent direction (g . dv < 0) after any number of
//      iterations; should rounding break that, the preconditioned gradient step replaces it.
//      After a step the line search cut short (alpha < 1/2), H takes each sliding row's
//      curvature along its slip as well (addSlipCurvature in sap_problem.h): the exact G has none
//      there, so from a warm start where rows slide that end the solve sticking, each exact
//      direction overshoots into the stick regions and is cut where the first rows meet them,
//      a few rows a step. H stays SPD, so every direction is still a descent direction;
//   3. an exact line search: alpha minimising the convex cost along dv, by safeguarded 1-D Newton
//      on ell'(alpha) with bisection (the Hessian is only piecewise continuous). ell' is
//      monotone, so the bracket always holds the minimiser, and the cost never increases.
//
// The preconditioner: block-Jacobi on A with the contact terms J^T G J kept whole
// (coupled_preconditioner.h: the blocks active rows act on factorised together), unless a body
// brings its own approximate inverse P_b of A_b (IslandBody::hasPreconditioner: a FEM body's step
// factor) and the island has at most max_correction_rows rows. Then,
// with P0 = blockdiag(P_b, the inverse of A's blocks for the other bodies), the contacts are
// folded in exactly by Woodbury's identity (the capacitance correction):
//
//     P = (P0^-1 + J^T G J)^-1 = P0 - Y (I + G W)^-1 G Y^T,   Y = P0 J^T,  W = J P0 J^T,
//
// Y and W made once per solve (3 applications of P0 per row: W is the Delassus operator when
// P0 = A^-1), I + G W (dense, 3 rows square) factorised per Newton iteration. With every P0 exact
// (a body's Cholesky factor, a rigid body's mass) P = H^-1: one CG iteration per direction.
// Both fold the contacts in whole: with only their diagonal blocks, the stiff, spread eigenvalues
// of J^T G J (G ~ 1/R up to 1e3 times A's blocks) cost up to rank + 1 CG iterations per
// direction (docs/contact-sap.md, "Cost").
//
// The cost is strictly convex and C1 with a piecewise-smooth gradient: Newton with exact line
// search converges from any start. It stops on the paper's optimality criterion,
//
//     |D g| <= eps_abs + eps_rel max(|D p|, |D j|),   D = diag(A)^{-1/2}, p = A v, j = J^T gamma
//
// (a momentum balance in units where every dof weighs alike). A solve that reaches its iteration
// cap, or can no longer make progress, reports converged = false with the reason: it is never
// silently accepted.
//
// Deterministic: rows, terms, bodies and blocks are visited in a fixed order and nothing is
// threaded, so the same input gives bit-identical output.

#include <Eigen/Core>
#include <Eigen/LU>
#include <string>
#include <vector>

#include "torsion/contact/solve/coupled_preconditioner.h"
#include "torsion/contact/solve/sap_problem.h"

namespace torsion::sap {

struct SapSolverSettings {
  /// eps_rel (the paper's default; an island of CG bodies alone uses theirs: island_step.cpp)
  double relative_tolerance = 1e-6;
  double absolute_tolerance = 1e-14;  ///< eps_abs, sqrt(kg) m/s
  int max_newton_iterations = 100;
  int max_cg_iterations = 1000;  ///< per Newton direction
  double max_forcing = 0.1;      ///< the CG's relative tolerance is at most this
  int max_line_search_iterations = 100;
  /// The capacitance correction (below) costs 3 applications of the body preconditioners per
  /// row; above this many rows the island is preconditioned by block-Jacobi with the contacts
  /// (coupled_preconditioner.h) for every body. 32: on a 1445-node slab one CHOLMOD solve costs
  /// about 1/60 of its factorisation, so 32 rows add at most about 1.6 factorisations
  /// (docs/contact-sap.md, "Cost").
  int max_correction_rows = 32;
};

struct SapReport {
  bool converged = false;
  /// Why an unconverged solve stopped ("iteration cap", "no progress", "non-finite residual");
  /// empty when converged.
  std::string message;
  int newton_iterations = 0;
  int cg_iterations = 0;           ///< summed over the Newton iterations
  int line_search_iterations = 0;  ///< summed
  double residual = 0;             ///< |D g| at the returned velocities
  double tolerance = 0;            ///< the criterion's right-hand side there
  double cost = 0;                 ///< ell(v), J
  /// Per row, at the returned velocities: gamma_i (N s, contact frame t1, t2, n), v_c,i (m/s)
  /// and its region of the projection.
  std::vector<Eigen::Vector3d> impulses;
  std::vector<Eigen::Vector3d> contact_velocities;
  std::vector<ContactState> states;
};

class SapSolver {
 public:
  explicit SapSolver(SapSolverSettings settings = {}) : settings_(settings) {}
  const SapSolverSettings& settings() const { return settings_; }
  /// For the next solves (a solver kept from step to step: its workspace is kept, nothing else).
  void setSettings(const SapSolverSettings& settings) { settings_ = settings; }

  /// Minimises the problem's cost. v: in, the warm start (the previous step's velocities), or
  /// empty for zero; out, the velocities (prescribed dofs at their values).
  SapReport solve(const SapProblem& problem, Eigen::VectorXd& v);

 private:
  // The CG solve of S H S dv = -g to relative tolerance eta; returns its iterations.
  int newtonDirection(const SapProblem& problem, double eta, Eigen::VectorXd& dv);
  // The sliding rows' slip curvature added to evaluation_'s G (the Newton model after a short
  // step).
  void addSlipCurvature(const SapProblem& problem);
  // The capacitance correction's Y and W, once per solve (a body brings its preconditioner).
  void prepareCorrection(const SapProblem& problem);
  // The preconditioner at evaluation_ (its blocks, or I + G W factorised).
  void preparePreconditioner(const SapProblem& problem);
  // z = P r.
  void precondition(const SapProblem& problem, const Eigen::VectorXd& r, Eigen::VectorXd& z);
  // The step length minimising the cost along dv from evaluation_.v (a_dv_ = A dv).
  double lineSearch(const SapProblem& problem, const Eigen::VectorXd& dv, int& iterations);
  // ell'(alpha) and ell''(alpha) along the line set up by lineSearch; noise: the size of the
  // terms summed into ell', for the rounding floor.
  void slopeAt(const SapProblem& problem, double alpha, double& slope, double& curvature,
               double& noise) const;
  void fillReport(const SapProblem& problem, SapReport& report) const;
  double scaledNorm(const SapProblem& problem, const Eigen::VectorXd& x) const;

  SapSolverSettings settings_;
  // Workspace, kept between solves.
  SapEvaluation evaluation_;
  std::vector<DiagonalBlock> preconditioner_;  // P0's blocks (the capacitance correction)
  CoupledPreconditioner coupled_;              // otherwise
  // The capacitance correction: P0 J^T, J P0 J^T, the LU of I + G W, scratch.
  Eigen::MatrixXd correction_y_, correction_w_, capacitance_matrix_;
  Eigen::PartialPivLU<Eigen::MatrixXd> capacitance_;
  Eigen::VectorXd row_values_;
  bool correction_ = false;  // this solve uses the capacitance correction
  Eigen::VectorXd residual_, z_, p_, q_, ap_;
  Eigen::VectorXd next_av_;  // A v at the next iterate
  // The line: dv . (A v - b), dv . A dv, v_c and J dv per row; A dv (the CG's sum of its A p).
  double line_linear_ = 0, line_quadratic_ = 0;
  Eigen::VectorXd a_dv_;
  std::vector<Eigen::Vector3d> line_vc_, line_dvc_;
};

}  // namespace torsion::sap

#pragma once
// Preconditioned conjugate gradients on the constrained system S A S y = S r (Baraff & Witkin
// 1998, "modified PCG"): prescribed velocity components never change, free ones are solved.

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "torsion/solve/node_constraints.h"
#include "torsion/solve/solver_settings.h"
#include "torsion/solve/system_operator.h"

namespace torsion {

class LaggedFactorPreconditioner;
class TwoLevelPreconditioner;

struct PcgScratch {
  Eigen::VectorXd z, p, q;  ///< workspace of pcgIterations (pcg_iterations.h)
};

struct LinearSolveReport {
  int iterations = 0;
  /// |S(b - A v)| / |S(b - A v_prescribed)|; a hyperelastic step's (the largest of its Newton
  /// solves) against the step's residual scale (SolverSettings::newton_tolerance).
  double relative_residual = 0;
  bool converged = false;
  /// The solver could not proceed (non-positive curvature, non-finite numbers, failed
  /// factorisation): the result is meaningless, unlike a merely unconverged one.
  bool breakdown = false;
  /// Why it broke down, when known: e.g. "the right-hand side is not finite". A static string.
  const char* breakdown_reason = nullptr;
};

/// Marks a report as broken down for a reason (a static string) and returns it.
inline LinearSolveReport brokenDown(LinearSolveReport report, const char* reason) {
  report.converged = false;
  report.breakdown = true;
  report.breakdown_reason = reason;
  return report;
}

/// Solves A v = b for the free components of v. On entry v holds the warm start; prescribed
/// components are imposed from `constraints` first. Workspace vectors are reused across calls, and
/// so are the lagged preconditioners' factorisations (SolverSettings::preconditioner): the solves
/// of one ProjectedCg must be of one body.
class ProjectedCg {
 public:
  ProjectedCg();
  ~ProjectedCg();
  ProjectedCg(const ProjectedCg&) = delete;
  ProjectedCg& operator=(const ProjectedCg&) = delete;
  // Movable, so solvers can be kept in a std::vector (one per body of an island); defined in the
  // .cpp, where the preconditioners' types are complete.
  ProjectedCg(ProjectedCg&&) noexcept;
  ProjectedCg& operator=(ProjectedCg&&) noexcept;

  LinearSolveReport solve(const SystemOperator& op, const NodeConstraints& constraints,
                          const Eigen::VectorXd& b, const SolverSettings& settings,
                          Eigen::VectorXd& v);

  /// Factorisations the lagged preconditioner in use has done so far (0 for the Jacobi kinds).
  long factorisations() const;

 private:
  void precondition(const NodeConstraints& constraints, PreconditionerKind kind,
                    const Eigen::VectorXd& r, Eigen::VectorXd& z) const;

  std::unique_ptr<LaggedFactorPreconditioner> lagged_;
  std::unique_ptr<TwoLevelPreconditioner> two_level_;
  std::vector<Eigen::Matrix3d> block_inverse_;
  Eigen::VectorXd r_, q_, prescribed_only_;
  std::vector<int> constrained_nodes_;  // the reference residual's nonzero nodes
  PcgScratch scratch_;
};

}  // namespace torsion

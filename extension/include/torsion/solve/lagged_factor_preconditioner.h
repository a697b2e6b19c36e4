#pragma once
// A factorisation of the whole constrained system A' = S A S + (I - S) (CholmodSolver::assemble)
// used as the CG preconditioner, z = S F^-1 S r, and kept across steps (RefactorPolicy): a full
// sparse Cholesky (CHOLMOD) or Eigen's IncompleteCholesky (limited fill, AMD order). Between
// refactorisations the factor belongs to an earlier step's rotations, constraints and dt; it is
// still symmetric positive definite, so CG converges to the current system's solution, in more
// iterations the further the system has moved.

#include <Eigen/Core>
#include <memory>

#include "torsion/solve/node_constraints.h"
#include "torsion/solve/refactor_policy.h"
#include "torsion/solve/solver_settings.h"
#include "torsion/solve/system_operator.h"

namespace torsion {

class LaggedFactorPreconditioner {
 public:
  /// kind: kLaggedCholesky or kIncompleteCholesky.
  explicit LaggedFactorPreconditioner(PreconditionerKind kind);
  ~LaggedFactorPreconditioner();
  LaggedFactorPreconditioner(const LaggedFactorPreconditioner&) = delete;
  LaggedFactorPreconditioner& operator=(const LaggedFactorPreconditioner&) = delete;

  PreconditionerKind kind() const { return kind_; }
  /// Before a solve: refactorises when the policy says so. False when there is no usable factor
  /// (the factorisation failed): the caller falls back to block-Jacobi for this solve.
  bool prepare(const SystemOperator& op, const NodeConstraints& constraints,
               const SolverSettings& settings);
  /// z = S F^-1 S r.
  void apply(const NodeConstraints& constraints, const Eigen::VectorXd& r,
             Eigen::VectorXd& z) const;
  /// After a solve: its CG iterations, for the policy.
  void solved(int iterations) { policy_.solved(iterations); }
  const RefactorPolicy& policy() const { return policy_; }

 private:
  struct Impl;
  PreconditionerKind kind_;
  std::unique_ptr<Impl> impl_;
  RefactorPolicy policy_;
};

}  // namespace torsion

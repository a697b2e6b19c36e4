#include "torsion/solve/lagged_factor_preconditioner.h"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/OrderingMethods>

#include "torsion/solve/cholmod_solver.h"

namespace torsion {

struct LaggedFactorPreconditioner::Impl {
  CholmodSolver assembler;  // assembles A' into a fixed pattern (its own factor stays unused)
  SparseCholesky cholesky;
  Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<int>> incomplete;
  bool incomplete_valid = false;
  mutable Eigen::VectorXd filtered;
  int size = -1;
};

LaggedFactorPreconditioner::LaggedFactorPreconditioner(PreconditionerKind kind)
    : kind_(kind), impl_(std::make_unique<Impl>()) {}
LaggedFactorPreconditioner::~LaggedFactorPreconditioner() = default;

bool LaggedFactorPreconditioner::prepare(const SystemOperator& op,
                                         const NodeConstraints& constraints,
                                         const SolverSettings& settings) {
  Impl& m = *impl_;
  const int size = 3 * op.model().nodeCount();
  if (size != m.size) policy_.invalidate();  // another model: the factor does not fit
  if (!policy_.due(settings)) return true;
  m.size = size;
  const Eigen::SparseMatrix<double>& A = m.assembler.assemble(op, constraints);
  bool ok = false;
  if (kind_ == PreconditionerKind::kIncompleteCholesky) {
    m.incomplete.compute(A);
    ok = m.incomplete_valid = m.incomplete.info() == Eigen::Success;
  } else {
    ok = m.cholesky.factorize(A);
  }
  if (ok) {
    policy_.factorised();
  } else {
    policy_.invalidate();
  }
  return ok;
}

void LaggedFactorPreconditioner::apply(const NodeConstraints& constraints, const Eigen::VectorXd& r,
                                       Eigen::VectorXd& z) const {
  Impl& m = *impl_;
  // r is already filtered by the CG (its residuals live on the free subspace).
  if (kind_ == PreconditionerKind::kIncompleteCholesky) {
    z = m.incomplete.solve(r);
  } else {
    m.cholesky.solve(r, z);
  }
  constraints.filter(z);
}

}  // namespace torsion

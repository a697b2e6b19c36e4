#include "torsion/solve/projected_cg.h"

#include <Eigen/LU>
#include <cmath>

#include "torsion/solve/lagged_factor_preconditioner.h"
#include "torsion/solve/pcg_iterations.h"
#include "torsion/solve/two_level_preconditioner.h"

namespace torsion {

ProjectedCg::ProjectedCg() = default;
ProjectedCg::~ProjectedCg() = default;
ProjectedCg::ProjectedCg(ProjectedCg&&) noexcept = default;
ProjectedCg& ProjectedCg::operator=(ProjectedCg&&) noexcept = default;

long ProjectedCg::factorisations() const {
  long count = 0;
  if (lagged_) count += lagged_->policy().factorisations();
  if (two_level_) count += two_level_->policy().factorisations();
  return count;
}

void ProjectedCg::precondition(const NodeConstraints& constraints, PreconditionerKind kind,
                               const Eigen::VectorXd& r, Eigen::VectorXd& z) const {
  const int n = constraints.nodeCount();
  z.resize(r.size());
  if (kind == PreconditionerKind::kBlockJacobi) {
    // The default, once per CG iteration: plain loops, the products associated as Eigen's
    // Matrix3d * Vector3d does (rows 0 and 1 left to right, row 2 as p0 + (p1 + p2)), so the
    // result is bit for bit the Eigen form below.
    const double* in = r.data();
    double* out = z.data();
    for (size_t i = 0; i < static_cast<size_t>(n); ++i) {
      const double* m = block_inverse_[i].data();
      const double* x = in + 3 * i;
      out[3 * i] = (m[0] * x[0] + m[3] * x[1]) + m[6] * x[2];
      out[3 * i + 1] = (m[1] * x[0] + m[4] * x[1]) + m[7] * x[2];
      out[3 * i + 2] = m[2] * x[0] + (m[5] * x[1] + m[8] * x[2]);
    }
    for (int i : constrained_nodes_)
      z.segment<3>(3 * i) = constraints.filterNode(i, Eigen::Vector3d(z.segment<3>(3 * i)));
    return;
  }
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix3d& inv = block_inverse_[static_cast<size_t>(i)];
    Eigen::Vector3d zi = kind == PreconditionerKind::kJacobi
                             ? Eigen::Vector3d(inv.diagonal().cwiseProduct(r.segment<3>(3 * i)))
                             : Eigen::Vector3d(inv * r.segment<3>(3 * i));
    z.segment<3>(3 * i) = constraints.isConstrained(i) ? constraints.filterNode(i, zi) : zi;
  }
}

LinearSolveReport ProjectedCg::solve(const SystemOperator& op, const NodeConstraints& constraints,
                                     const Eigen::VectorXd& b, const SolverSettings& settings,
                                     Eigen::VectorXd& v) {
  const int n = constraints.nodeCount();

  // Inverse diagonal (stored as a diagonal matrix) or inverse 3x3 node blocks: the
  // preconditioner, two_level's smoother, and the fallback of a failed factorisation.
  op.diagonalBlocks(block_inverse_);
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix3d& block = block_inverse_[static_cast<size_t>(i)];
    if (settings.preconditioner != PreconditionerKind::kJacobi) {
      block = block.inverse().eval();
    } else {
      // Through a temporary: assigning a diagonal wrapper zeroes the target before reading it.
      const Eigen::Vector3d inverse_diagonal = block.diagonal().cwiseInverse();
      block = inverse_diagonal.asDiagonal();
    }
  }

  // Reference: the right-hand side of the reduced system, S (b - A v_c) with v_c the prescribed
  // part alone.
  prescribed_only_.setZero(v.size());
  constraints.impose(prescribed_only_);
  constraints.constrainedNodes(constrained_nodes_);
  op.multiplyFromNodes(prescribed_only_, constrained_nodes_, q_);
  r_ = b - q_;
  constraints.filter(r_);
  const double reference = r_.norm();

  // Lagged preconditioners: refactorised when their policy says so; a failed factorisation
  // falls back to block-Jacobi for this solve. two_level needs quadratic elements (on tet4 the
  // corner nodes are all nodes: a lagged Cholesky of the whole system).
  PreconditionerKind kind = settings.preconditioner;
  if (kind == PreconditionerKind::kTwoLevel && op.model().elementKind() != ElementKind::kTet10)
    kind = PreconditionerKind::kLaggedCholesky;
  if (kind == PreconditionerKind::kLaggedCholesky ||
      kind == PreconditionerKind::kIncompleteCholesky) {
    if (!lagged_ || lagged_->kind() != kind)
      lagged_ = std::make_unique<LaggedFactorPreconditioner>(kind);
    if (!lagged_->prepare(op, constraints, settings)) kind = PreconditionerKind::kBlockJacobi;
  } else if (kind == PreconditionerKind::kTwoLevel) {
    if (!two_level_) two_level_ = std::make_unique<TwoLevelPreconditioner>();
    if (!two_level_->prepare(op, constraints, settings, block_inverse_))
      kind = PreconditionerKind::kBlockJacobi;
  }

  constraints.impose(v);
  // A start at zero (a Newton direction) has r = b: no product (A 0 is +-0, and b - +-0 is b).
  if (v.isZero(0.0)) {
    r_ = b;
  } else {
    op.multiply(v, q_);
    r_ = b - q_;
  }
  constraints.filter(r_);
  const LinearSolveReport report = pcgIterations(
      [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) {
        op.multiply(in, out);
        constraints.filter(out);
      },
      [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) {
        if (kind == PreconditionerKind::kLaggedCholesky ||
            kind == PreconditionerKind::kIncompleteCholesky) {
          lagged_->apply(constraints, in, out);
        } else if (kind == PreconditionerKind::kTwoLevel) {
          two_level_->apply(op, constraints, block_inverse_, in, out);
        } else {
          precondition(constraints, kind, in, out);
        }
      },
      reference, settings, v, r_, scratch_);
  if (kind == PreconditionerKind::kLaggedCholesky ||
      kind == PreconditionerKind::kIncompleteCholesky) {
    lagged_->solved(report.iterations);
  } else if (kind == PreconditionerKind::kTwoLevel) {
    two_level_->solved(report.iterations);
  }
  return report;
}

}  // namespace torsion

#include "torsion/solve/projected_cg.h"

#include <Eigen/LU>
#include <cmath>

#include "torsion/solve/pcg_iterations.h"

namespace torsion {

void ProjectedCg::precondition(const NodeConstraints& constraints, PreconditionerKind kind,
                               const Eigen::VectorXd& r, Eigen::VectorXd& z) const {
  const int n = constraints.nodeCount();
  z.resize(r.size());
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix3d& inv = block_inverse_[static_cast<size_t>(i)];
    Eigen::Vector3d zi = kind == PreconditionerKind::kBlockJacobi
                             ? Eigen::Vector3d(inv * r.segment<3>(3 * i))
                             : Eigen::Vector3d(inv.diagonal().cwiseProduct(r.segment<3>(3 * i)));
    z.segment<3>(3 * i) = constraints.isConstrained(i) ? constraints.filterNode(i, zi) : zi;
  }
}

LinearSolveReport ProjectedCg::solve(const SystemOperator& op, const NodeConstraints& constraints,
                                     const Eigen::VectorXd& b, const SolverSettings& settings,
                                     Eigen::VectorXd& v) {
  const int n = constraints.nodeCount();

  // Preconditioner: inverse diagonal (stored as a diagonal matrix) or inverse 3x3 node blocks.
  op.diagonalBlocks(block_inverse_);
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix3d& block = block_inverse_[static_cast<size_t>(i)];
    if (settings.preconditioner == PreconditionerKind::kBlockJacobi) {
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
  op.multiply(prescribed_only_, q_);
  r_ = b - q_;
  constraints.filter(r_);
  const double reference = r_.norm();

  constraints.impose(v);
  op.multiply(v, q_);
  r_ = b - q_;
  constraints.filter(r_);
  return pcgIterations(
      [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) {
        op.multiply(in, out);
        constraints.filter(out);
      },
      [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) {
        precondition(constraints, settings.preconditioner, in, out);
      },
      reference, settings, v, r_, scratch_);
}

}  // namespace torsion

#pragma once
// Two-level (p-multigrid) preconditioner for quadratic tets: one symmetric V(1,1) cycle per CG
// iteration,
//   z  = w D^-1 r                       pre-smoothing, block-Jacobi on all P2 nodes
//   z += P Ac^-1 P^T (r - A z)          coarse correction on the corner nodes
//   z += w D^-1 (r - A z)               post-smoothing
// with P the linear interpolation from corner nodes to all P2 nodes (a mid-edge node takes the
// mean of its edge's corners) and Ac = P^T A P, the Galerkin system on the corners: the linear
// (tet4) problem of the same mesh. Ac is factorised by CHOLMOD and kept across steps
// (RefactorPolicy, like LaggedFactorPreconditioner). The smoothing weight w = 4 / (3 rho), rho
// an estimate of the largest eigenvalue of D^-1 A from power iterations at each refactorisation,
// keeps the smoother convergent, so the cycle is symmetric positive definite (a valid CG
// preconditioner). Constraints: residuals and corrections are filtered by S, and the corner
// nodes' own constraints are applied to Ac as S Ac S + (I - S), as for the fine system.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <memory>
#include <vector>

#include "torsion/solve/node_constraints.h"
#include "torsion/solve/refactor_policy.h"
#include "torsion/solve/solver_settings.h"
#include "torsion/solve/system_operator.h"

namespace torsion {

class SparseCholesky;

class TwoLevelPreconditioner {
 public:
  TwoLevelPreconditioner();
  ~TwoLevelPreconditioner();
  TwoLevelPreconditioner(const TwoLevelPreconditioner&) = delete;
  TwoLevelPreconditioner& operator=(const TwoLevelPreconditioner&) = delete;

  /// Before a solve (tet10 models only): refactorises the coarse system when the policy says
  /// so. `block_inverse` are the filtered inverse diagonal blocks of this step's A (the
  /// smoother). False when the coarse factorisation failed (fall back to block-Jacobi).
  bool prepare(const SystemOperator& op, const NodeConstraints& constraints,
               const SolverSettings& settings, const std::vector<Eigen::Matrix3d>& block_inverse);
  /// z = one V(1,1) cycle applied to the filtered residual r.
  void apply(const SystemOperator& op, const NodeConstraints& constraints,
             const std::vector<Eigen::Matrix3d>& block_inverse, const Eigen::VectorXd& r,
             Eigen::VectorXd& z);
  void solved(int iterations) { policy_.solved(iterations); }
  const RefactorPolicy& policy() const { return policy_; }
  /// The smoothing weight in use.
  double smoothingWeight() const { return weight_; }

 private:
  void buildPattern(const SystemOperator& op);
  void assembleCoarse(const SystemOperator& op, const NodeConstraints& constraints);
  void estimateWeight(const SystemOperator& op, const NodeConstraints& constraints,
                      const std::vector<Eigen::Matrix3d>& block_inverse);
  void smooth(const NodeConstraints& constraints, const std::vector<Eigen::Matrix3d>& block_inverse,
              const Eigen::VectorXd& r, Eigen::VectorXd& z) const;
  void restrictToCorners(const Eigen::VectorXd& fine, Eigen::VectorXd& coarse) const;
  void prolongAdd(const Eigen::VectorXd& coarse, Eigen::VectorXd& fine) const;

  int fine_nodes_ = -1;
  int coarse_nodes_ = 0;
  // Mid-edge node m (>= coarse_nodes_): its corners edge_corners_[m - coarse_nodes_].
  std::vector<std::array<int, 2>> edge_corners_;
  // Coarse lower-triangle matrix with a fixed pattern; block k = (i >= j) has its 9 value indices
  // (row-major, -1 above the diagonal of a diagonal block).
  Eigen::SparseMatrix<double> coarse_;
  std::vector<std::pair<int, int>> coarse_blocks_;
  std::vector<std::array<int, 9>> coarse_values_;
  // What each fine upper-triangle slot adds to the coarse blocks: slot s contributes
  // weight * (transpose ? B^T : B) to block `block` for entries [slot_offsets_[s], ..[s + 1]).
  struct Contribution {
    int block;
    double weight;  // 1, 1/2 or 1/4
    bool transpose;
  };
  std::vector<int> slot_offsets_;
  std::vector<Contribution> contributions_;
  std::unique_ptr<SparseCholesky> factor_;
  RefactorPolicy policy_;
  double weight_ = 0.5;
  Eigen::VectorXd residual_, product_, coarse_rhs_, coarse_solution_;
};

}  // namespace torsion

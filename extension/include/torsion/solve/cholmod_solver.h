#pragma once
// Sparse direct solve of the constrained system with SuiteSparse CHOLMOD (through Eigen's
// CholmodSupport), or, in a build configured with TORSION_CHOLMOD=OFF (no GPL modules linked),
// with Eigen's own SimplicialLLT: the same factorisation, single-threaded, without supernodes.
// The matrix A = M' + c K takes the stiffness K the SystemOperator assembled for
// this step (its upper-triangle node blocks are this lower triangle, transposed; with nodal
// pressure the volumetric part is added from the operator's patches), in a fixed sparsity pattern
// made from the operator's (analysed once). Constraints are applied as A' = S A S + (I - S), which
// is SPD and leaves prescribed components at their prescribed values.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "torsion/solve/node_constraints.h"
#include "torsion/solve/projected_cg.h"
#include "torsion/solve/system_operator.h"

namespace torsion {

/// Cholesky factor of a symmetric positive definite sparse matrix given by its lower triangle
/// (column-major), with the same backend as CholmodSolver. The symbolic analysis is kept while
/// the pattern (size and number of stored entries) stays the same: refactorising a matrix of a
/// fixed pattern is numeric only. For preconditioners that keep a factor across steps.
class SparseCholesky {
 public:
  SparseCholesky();
  ~SparseCholesky();
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;

  /// False if the matrix is not positive definite (or not finite); the old factor is then gone.
  bool factorize(const Eigen::SparseMatrix<double>& lower);
  bool valid() const { return valid_; }
  /// x = A^-1 b with the last successful factor.
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const;
  /// X = A^-1 B, column by column of the dense B, in one pass of the factor.
  void solve(const Eigen::MatrixXd& B, Eigen::MatrixXd& X) const;
  /// Entries of the factor L (supernodal storage counts its padding), for cost reports.
  long factorEntries() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  bool valid_ = false;
};

class CholmodSolver {
 public:
  CholmodSolver();
  ~CholmodSolver();
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  /// Solves A v = b for the free components of v (prescribed ones imposed on entry).
  LinearSolveReport solve(const SystemOperator& op, const NodeConstraints& constraints,
                          const Eigen::VectorXd& b, Eigen::VectorXd& v);

  /// Assembles and factorises A' = S A S + (I - S) for the operator's current state and the
  /// constraints, without solving (solve() does this itself). False if A' is not finite or not
  /// positive definite; the old factor is then gone.
  bool factorize(const SystemOperator& op, const NodeConstraints& constraints);
  /// Whether the last solve() or factorize() left a factor.
  bool factorized() const;
  /// z = S A'^-1 S r with that factor: the exact inverse of A on the free dofs, for a
  /// preconditioner (a contact solve's, fem_island_body.h). Valid until the next solve() or
  /// factorize(), and only for the operator state and constraints it was made from.
  void applyInverse(const NodeConstraints& constraints, const Eigen::VectorXd& r,
                    Eigen::VectorXd& z) const;

  /// The factorisation this build uses: "CHOLMOD" or "Eigen SimplicialLLT".
  static const char* backend();

  /// Assembles the constrained matrix (lower triangle) for the current rotations; for tests.
  const Eigen::SparseMatrix<double>& assemble(const SystemOperator& op,
                                              const NodeConstraints& constraints);

 private:
  void buildPattern(const SystemOperator& op);

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace torsion

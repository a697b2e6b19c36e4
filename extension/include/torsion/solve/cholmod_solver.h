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

class CholmodSolver {
 public:
  CholmodSolver();
  ~CholmodSolver();
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  /// Solves A v = b for the free components of v (prescribed ones imposed on entry).
  LinearSolveReport solve(const SystemOperator& op, const NodeConstraints& constraints,
                          const Eigen::VectorXd& b, Eigen::VectorXd& v);

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

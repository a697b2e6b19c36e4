#pragma once
// The preconditioner of an island's Newton systems S H S dv = -g (sap_solver.h) when no body's
// own inverse is used: block-Jacobi on A, with the contact terms J^T G J kept whole,
//
//     P^-1 = S (D + J^T G J) S + I - S,   D = blockdiag(A) (3x3 per node, 6x6 per twist).
//
// Why the couplings: a stiff row ties the velocities of the blocks it acts on (a node and the
// face it presses on, far along the body; a node and a rigid body). Block-Jacobi with only the
// diagonal parts of J^T G J reads that as each block held on its own, and CG has to find the
// relative constraint itself: measured on the plectoneme with 42 active self-contact rows,
// 250-400 CG iterations per Newton direction against 68 for the rod's own solve. With them,
// alpha D <= A <= beta D gives min(alpha, 1) P^-1 <= H <= max(beta, 1) P^-1: the island's CG
// converges as the bodies' own block-Jacobi CG does, however stiff its contacts.
//
// Only the blocks an active row acts on (G != 0) are coupled: they are gathered into one sparse
// SPD matrix and factorised by Eigen's simplicial LDL^T with its AMD ordering (its pattern
// analysed again only when the active rows change); every other block is block-Jacobi's.
// A rigid body's 6x6 block links all its rows: it ends up last in the ordering, a dense border
// of 6 columns.
//
// To that the island's coarse correction is added (coarse_correction.h): the exact solve on the
// rigid modes of the aggregates of each rod, which block-Jacobi reaches only one neighbourhood
// per iteration (a slender rod's bending and twisting).
//
// Deterministic: rows, terms and blocks are visited in order; nothing is threaded.

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <vector>

#include "torsion/contact/solve/coarse_correction.h"
#include "torsion/contact/solve/sap_problem.h"

namespace torsion::sap {

class CoupledPreconditioner {
 public:
  /// Assembles and factorises P^-1 at the evaluation's G blocks.
  void prepare(const SapProblem& problem, const SapEvaluation& e);
  /// Forgets the last pattern (a new problem: its rows are others).
  void forget();
  /// z = P r (r, z: island dofs; z = S z).
  void apply(const SapProblem& problem, const Eigen::VectorXd& r, Eigen::VectorXd& z) const;
  /// The dofs of the coupled part at the last prepare (0: block-Jacobi alone).
  int coupledDofs() const { return static_cast<int>(local_r_.size()); }
  /// The coarse correction's dofs at the last prepare (0: none).
  int coarseDofs() const { return coarse_.dofs(); }

 private:
  // The blocks active rows act on, in block order, and their local dofs; the active rows.
  void gatherCoupledBlocks(const SapProblem& problem, const SapEvaluation& e);
  void assemble(const SapProblem& problem, const SapEvaluation& e);
  void packFreeInverses(const SapProblem& problem);

  // Block-Jacobi's blocks S (S A_jj S + I - S)^-1 S, packed, and the problem they are of.
  std::vector<double> packed_;
  const SapProblem* packed_for_ = nullptr;
  std::vector<int> local_of_block_;  // per island block: its first local dof, or -1
  std::vector<int> coupled_;         // the coupled blocks, ascending
  std::vector<int> active_rows_, last_active_rows_;
  std::vector<Eigen::Triplet<double>> triplets_;
  Eigen::SparseMatrix<double> matrix_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> factor_;
  bool factorised_ = false;  // the factor holds this evaluation's matrix
  CoarseCorrection coarse_;
  mutable Eigen::VectorXd local_r_, local_z_;
};

}  // namespace torsion::sap

#pragma once
// The island's coarse correction (coarse_space.h): the exact solve of the island's Newton system
// on the span of its FEM bodies' coarse spaces, added to block-Jacobi with the contacts
// (coupled_preconditioner.h):
//
//     z += Z E^-1 Z^T r,   E = Z^T H Z = blockdiag(Z_b^T A_b Z_b) + sum_i (J_i Z)^T G_i (J_i Z),
//
// Z = blockdiag(Z_b) over the bodies that have a coarse space (zero on the others' dofs: a rigid
// body's modes are block-Jacobi's own 6x6 block). The bodies' parts come once per step with their
// coarse spaces; the rows' part at each Newton iteration (G changes), with E's sparse Cholesky
// factorisation (at most kMaxAggregates x 6 dofs a body). E is sparse: an aggregate couples with
// the aggregates next to it and with those a row ties it to (a rod's coarse matrix is banded,
// plus its coil's contacts), and the pattern is analysed again only when the active rows change.
// Measured on the plectoneme (192 coarse dofs), the dense factorisation was half of the
// preconditioner's set-up. E must be the Galerkin matrix of the
// current Hessian: then Z E^-1 Z^T H is an H-orthogonal projection and adds at most 1 to the
// largest eigenvalue of P H. One kept from an earlier iteration was measured to raise the CG
// iterations where a row changes between stick and slide (G by orders of magnitude).
//
// Deterministic: bodies, rows and terms are visited in order; nothing is threaded.

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <vector>

#include "torsion/contact/solve/coarse_space.h"
#include "torsion/contact/solve/sap_problem.h"

namespace torsion::sap {

class CoarseCorrection {
 public:
  /// The problem's bodies with a coarse space (a new problem).
  void gather(const SapProblem& problem);
  /// E at the evaluation's G blocks, factorised. Without coarse dofs, or should E not factorise
  /// (a non-finite G), the correction is off until the next prepare.
  void prepare(const SapProblem& problem, const SapEvaluation& e);
  /// z += Z E^-1 Z^T r (r, z: island dofs).
  void applyAdd(const SapProblem& problem, const Eigen::VectorXd& r, Eigen::VectorXd& z) const;
  /// The coarse dofs in use (0: off).
  int dofs() const { return active_ ? static_cast<int>(coarse_r_.size()) : 0; }

 private:
  // Row i's J_i Z, one 3 x k piece per term on a body with a coarse space.
  struct Piece {
    int column = 0;
    Eigen::Matrix<double, 3, 6> block;
    int columns = 0;
  };
  void rowPieces(const SapProblem& problem, int row);

  std::vector<int> body_first_;  // per island body: its first coarse dof, or -1
  std::vector<Piece> pieces_;
  // The bodies' parts of E (their Galerkin matrices' non-zeros), fixed for the problem.
  std::vector<Eigen::Triplet<double>> body_triplets_;
  std::vector<Eigen::Triplet<double>> triplets_;
  Eigen::SparseMatrix<double> matrix_;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> factor_;
  bool active_ = false;
  bool analysed_ = false;  // factor_ holds the pattern of last_active_rows_ on this problem
  std::vector<int> active_rows_,
      last_active_rows_;  // the rows in contact at this, the last prepare
  mutable Eigen::VectorXd coarse_r_, coarse_z_;
};

}  // namespace torsion::sap

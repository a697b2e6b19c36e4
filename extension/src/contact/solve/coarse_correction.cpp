// The island's coarse correction (coarse_correction.h).
#include "torsion/contact/solve/coarse_correction.h"

#include <cstddef>

namespace torsion::sap {

void CoarseCorrection::gather(const SapProblem& problem) {
  body_first_.assign(static_cast<std::size_t>(problem.bodyCount()), -1);
  int dofs = 0;
  for (int b = 0; b < problem.bodyCount(); ++b) {
    const NodeCoarseSpace* space = problem.body(b).coarseSpace();
    if (space == nullptr || space->dofs() == 0) continue;
    body_first_[static_cast<std::size_t>(b)] = dofs;
    dofs += space->dofs();
  }
  coarse_r_.resize(dofs);
  coarse_z_.resize(dofs);
  active_ = false;
}

void CoarseCorrection::rowPieces(const SapProblem& problem, int row) {
  pieces_.clear();
  for (const ContactTerm& term : problem.row(row).terms) {
    const int first = body_first_[static_cast<std::size_t>(term.body)];
    if (first < 0) continue;
    const NodeCoarseSpace& space = *problem.body(term.body).coarseSpace();
    const int node = term.first_dof / 3;
    const int aggregate = space.aggregateOf(node);
    Piece piece;
    piece.column = first + space.firstColumn(aggregate);
    piece.columns = space.columns(aggregate);
    piece.block.noalias() = term.block * space.nodeBasis(node);
    pieces_.push_back(piece);
  }
}

void CoarseCorrection::prepare(const SapProblem& problem, const SapEvaluation& e) {
  const auto dofs = coarse_r_.size();
  if (dofs == 0) return;
  active_rows_.clear();
  for (int i = 0; i < problem.rowCount(); ++i)
    if (e.rows[static_cast<std::size_t>(i)].state != ContactState::kSeparated)
      active_rows_.push_back(i);
  active_ = false;
  matrix_.setZero(dofs, dofs);
  for (int b = 0; b < problem.bodyCount(); ++b) {
    const int first = body_first_[static_cast<std::size_t>(b)];
    if (first < 0) continue;
    const Eigen::MatrixXd& galerkin = problem.body(b).coarseSpace()->galerkin();
    matrix_.block(first, first, galerkin.rows(), galerkin.cols()) = galerkin;
  }
  for (int i : active_rows_) {
    const RowResponse& response = e.rows[static_cast<std::size_t>(i)];
    rowPieces(problem, i);
    for (const Piece& p : pieces_) {
      const Eigen::Matrix<double, 6, 3> left = p.block.transpose() * response.g;
      for (const Piece& q : pieces_)
        matrix_.block(p.column, q.column, p.columns, q.columns) +=
            (left * q.block).topLeftCorner(p.columns, q.columns);
    }
  }
  factor_.compute(matrix_);
  active_ = factor_.info() == Eigen::Success;
}

void CoarseCorrection::applyAdd(const SapProblem& problem, const Eigen::VectorXd& r,
                                Eigen::VectorXd& z) const {
  if (!active_) return;
  for (int b = 0; b < problem.bodyCount(); ++b) {
    const int first = body_first_[static_cast<std::size_t>(b)];
    if (first < 0) continue;
    const NodeCoarseSpace& space = *problem.body(b).coarseSpace();
    space.restrictTo(r.segment(problem.bodyOffset(b), problem.body(b).dofs()),
                     coarse_r_.segment(first, space.dofs()));
  }
  coarse_z_ = factor_.solve(coarse_r_);
  for (int b = 0; b < problem.bodyCount(); ++b) {
    const int first = body_first_[static_cast<std::size_t>(b)];
    if (first < 0) continue;
    const NodeCoarseSpace& space = *problem.body(b).coarseSpace();
    space.prolongAdd(coarse_z_.segment(first, space.dofs()),
                     z.segment(problem.bodyOffset(b), problem.body(b).dofs()));
  }
}

}  // namespace torsion::sap

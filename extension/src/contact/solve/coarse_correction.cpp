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
  analysed_ = false;
  body_triplets_.clear();
  for (int b = 0; b < problem.bodyCount(); ++b) {
    const int first = body_first_[static_cast<std::size_t>(b)];
    if (first < 0) continue;
    const Eigen::MatrixXd& galerkin = problem.body(b).coarseSpace()->galerkin();
    for (Eigen::Index c = 0; c < galerkin.cols(); ++c)
      for (Eigen::Index r = 0; r < galerkin.rows(); ++r)
        if (galerkin(r, c) != 0)
          body_triplets_.emplace_back(first + static_cast<int>(r), first + static_cast<int>(c),
                                      galerkin(r, c));
  }
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
  triplets_ = body_triplets_;
  for (int i : active_rows_) {
    const RowResponse& response = e.rows[static_cast<std::size_t>(i)];
    rowPieces(problem, i);
    for (const Piece& p : pieces_) {
      const Eigen::Matrix<double, 6, 3> left = p.block.transpose() * response.g;
      for (const Piece& q : pieces_) {
        const Eigen::Matrix<double, 6, 6> m = left * q.block;
        for (int c = 0; c < q.columns; ++c)
          for (int r = 0; r < p.columns; ++r)
            triplets_.emplace_back(p.column + r, q.column + c, m(r, c));
      }
    }
  }
  const auto n = static_cast<Eigen::Index>(dofs);
  matrix_.resize(n, n);
  matrix_.setFromTriplets(triplets_.begin(), triplets_.end());
  // The same active rows give the same pattern: only the values are factorised again.
  if (!(analysed_ && active_rows_ == last_active_rows_)) factor_.analyzePattern(matrix_);
  analysed_ = true;
  last_active_rows_ = active_rows_;
  factor_.factorize(matrix_);
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

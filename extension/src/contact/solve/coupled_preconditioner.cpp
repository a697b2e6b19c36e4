// Block-Jacobi with the contact couplings (coupled_preconditioner.h).
#include "torsion/contact/solve/coupled_preconditioner.h"

#include <cstddef>

namespace torsion::sap {

namespace {

// Adds the dense block m at local dofs (row, col) to the triplets.
void addBlock(std::vector<Eigen::Triplet<double>>& triplets, int row, int col,
              const DiagonalBlock& m) {
  for (Eigen::Index c = 0; c < m.cols(); ++c)
    for (Eigen::Index r = 0; r < m.rows(); ++r)
      triplets.emplace_back(row + static_cast<int>(r), col + static_cast<int>(c), m(r, c));
}

}  // namespace

void CoupledPreconditioner::gatherCoupledBlocks(const SapProblem& problem, const SapEvaluation& e) {
  local_of_block_.assign(static_cast<std::size_t>(problem.blockCount()), -1);
  active_rows_.clear();
  for (int i = 0; i < problem.rowCount(); ++i) {
    if (e.rows[static_cast<std::size_t>(i)].state == ContactState::kSeparated) continue;
    active_rows_.push_back(i);
    for (const ContactTerm& term : problem.row(i).terms)
      local_of_block_[static_cast<std::size_t>(problem.termBlock(term))] = 0;
  }
  coupled_.clear();
  int dofs = 0;
  for (int j = 0; j < problem.blockCount(); ++j) {
    auto& local = local_of_block_[static_cast<std::size_t>(j)];
    if (local < 0) continue;
    coupled_.push_back(j);
    local = dofs;
    dofs += static_cast<int>(problem.blockOfA(j).rows());
  }
  local_r_.resize(dofs);
  local_z_.resize(dofs);
}

void CoupledPreconditioner::assemble(const SapProblem& problem, const SapEvaluation& e) {
  triplets_.clear();
  for (int j : coupled_) {
    const DiagonalBlock& s = problem.blockProjector(j);
    const auto n = s.rows();
    const int local = local_of_block_[static_cast<std::size_t>(j)];
    addBlock(triplets_, local, local,
             s * problem.blockOfA(j) * s + (DiagonalBlock::Identity(n, n) - s));
  }
  // S_a B_a^T G B_b S_b for every ordered pair of a row's terms (the diagonal pairs included).
  for (int i : active_rows_) {
    const Eigen::Matrix3d& g = e.rows[static_cast<std::size_t>(i)].g;
    const std::vector<ContactTerm>& terms = problem.row(i).terms;
    for (const ContactTerm& a : terms) {
      const int block_a = problem.termBlock(a);
      const DiagonalBlock left = problem.blockProjector(block_a) * a.block.transpose() * g;
      for (const ContactTerm& b : terms) {
        const int block_b = problem.termBlock(b);
        addBlock(triplets_, local_of_block_[static_cast<std::size_t>(block_a)],
                 local_of_block_[static_cast<std::size_t>(block_b)],
                 left * b.block * problem.blockProjector(block_b));
      }
    }
  }
  matrix_.resize(static_cast<Eigen::Index>(local_r_.size()),
                 static_cast<Eigen::Index>(local_r_.size()));
  matrix_.setFromTriplets(triplets_.begin(), triplets_.end());
}

void CoupledPreconditioner::prepare(const SapProblem& problem, const SapEvaluation& e) {
  if (packed_for_ != &problem) {
    packFreeInverses(problem);
    coarse_.gather(problem);
  }
  coarse_.prepare(problem, e);
  gatherCoupledBlocks(problem, e);
  if (coupled_.empty()) {
    factorised_ = false;
    return;
  }
  // The same active rows give the same pattern: only the values are factorised again.
  const bool same_pattern = factorised_ && active_rows_ == last_active_rows_;
  assemble(problem, e);
  if (!same_pattern) factor_.analyzePattern(matrix_);
  factor_.factorize(matrix_);
  // SPD by construction (D SPD on the free dofs, G PSD); only a non-finite G fails here, and
  // then the solve stops on its non-finite residual: block-Jacobi alone until then.
  factorised_ = factor_.info() == Eigen::Success;
  last_active_rows_ = active_rows_;
  if (!factorised_) local_of_block_.assign(local_of_block_.size(), -1);
}

void CoupledPreconditioner::forget() {
  packed_for_ = nullptr;
  factorised_ = false;
  last_active_rows_.clear();
}

void CoupledPreconditioner::packFreeInverses(const SapProblem& problem) {
  // Packed column-major, n^2 values per block (DiagonalBlock keeps 36 for any block: on a rod of
  // 2.7k nodes the packed array is a quarter of the memory the apply streams through).
  packed_.clear();
  for (int j = 0; j < problem.blockCount(); ++j) {
    const DiagonalBlock& inverse = problem.freeInverse(j);
    packed_.insert(packed_.end(), inverse.data(), inverse.data() + inverse.size());
  }
  packed_for_ = &problem;
}

void CoupledPreconditioner::apply(const SapProblem& problem, const Eigen::VectorXd& r,
                                  Eigen::VectorXd& z) const {
  z.resize(problem.dofs());
  const double* inverse = packed_.data();
  for (int j = 0; j < problem.blockCount(); ++j) {
    const int o = problem.blockOffset(j);
    const int n =
        j + 1 < problem.blockCount() ? problem.blockOffset(j + 1) - o : problem.dofs() - o;
    const int local = local_of_block_[static_cast<std::size_t>(j)];
    if (local >= 0) {
      local_r_.segment(local, n) = r.segment(o, n);
    } else if (n == 3) {
      z.segment<3>(o).noalias() = Eigen::Map<const Eigen::Matrix3d>(inverse) * r.segment<3>(o);
    } else {
      z.segment(o, n).noalias() =
          Eigen::Map<const Eigen::MatrixXd>(inverse, n, n) * r.segment(o, n);
    }
    inverse += n * n;
  }
  if (factorised_) {
    local_z_ = factor_.solve(local_r_);
    for (int j : coupled_) {
      const DiagonalBlock& s = problem.blockProjector(j);
      const auto n = s.rows();
      z.segment(problem.blockOffset(j), n) =
          s * local_z_.segment(local_of_block_[static_cast<std::size_t>(j)], n);
    }
  }
  coarse_.applyAdd(problem, r, z);
}

}  // namespace torsion::sap

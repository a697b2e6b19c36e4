// W_soft = B^T B, B = L^-1 P U, from B's reach-limited columns and row panels
// (delassus_condensation.h).

#include "torsion/contact/delassus_condensation.h"

#include <algorithm>
#include <numeric>

namespace torsion {

void DelassusCondensation::lowerGram(const Eigen::SparseMatrix<double>& lower,
                                     const Eigen::VectorXi& permutation,
                                     const Eigen::SparseMatrix<double>& unit_impulses,
                                     Eigen::MatrixXd& delassus) {
  const Eigen::Index size = lower.rows();  // the factor's unknowns (3 per node)
  const int contact_rows = static_cast<int>(unit_impulses.cols() / 3);
  const int groups = (contact_rows + kGroupRows - 1) / kGroupRows;
  const Eigen::Index panel_count = (size + kPanelRows - 1) / kPanelRows;
  panels_.resize(static_cast<size_t>(panel_count));
  for (Panel& p : panels_) {  // (capacity kept from step to step)
    p.groups.clear();
    p.values.clear();
  }
  auto permuted = [&](Eigen::Index i) {
    return permutation.size() > 0 ? permutation[i] : static_cast<int>(i);
  };

  // The contact rows in the order of their first rows in P U: neighbours in it share most of
  // their reach.
  first_.assign(static_cast<size_t>(contact_rows), static_cast<int>(size));
  for (int s = 0; s < contact_rows; ++s) {
    for (int axis = 0; axis < 3; ++axis) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(unit_impulses, 3 * s + axis); it; ++it)
        first_[static_cast<size_t>(s)] =
            std::min(first_[static_cast<size_t>(s)], permuted(it.index()));
    }
  }
  order_.resize(static_cast<size_t>(contact_rows));
  std::iota(order_.begin(), order_.end(), 0);
  std::stable_sort(order_.begin(), order_.end(), [&](int a, int b) {
    return first_[static_cast<size_t>(a)] < first_[static_cast<size_t>(b)];
  });

  // P U, one group's columns at a time, then its forward substitution.
  work_.assign(static_cast<size_t>(kGroupColumns * size), 0.0);
  group_first_.assign(static_cast<size_t>(groups), static_cast<int>(size));
  for (int g = 0; g < groups; ++g) {
    for (int q = 0; q < kGroupRows; ++q) {
      const int position = kGroupRows * g + q;
      if (position >= contact_rows) break;
      const int s = order_[static_cast<size_t>(position)];
      group_first_[static_cast<size_t>(g)] =
          std::min(group_first_[static_cast<size_t>(g)], first_[static_cast<size_t>(s)]);
      for (int axis = 0; axis < 3; ++axis) {
        for (Eigen::SparseMatrix<double>::InnerIterator it(unit_impulses, 3 * s + axis); it; ++it)
          work_[static_cast<size_t>(kGroupColumns * permuted(it.index()) + 3 * q + axis)] =
              it.value();
      }
    }
    forwardSubstitute(lower, g);
  }

  // W_soft's lower triangle in order_'s order: per panel T^T T, added where its groups are.
  const Eigen::Index padded = static_cast<Eigen::Index>(kGroupColumns) * groups;
  ordered_.assign(static_cast<size_t>(padded * padded), 0.0);
  Eigen::Map<Eigen::MatrixXd> ordered(ordered_.data(), padded, padded);
  for (Eigen::Index b = 0; b < panel_count; ++b) {
    const Panel& p = panels_[static_cast<size_t>(b)];
    const int k = static_cast<int>(p.groups.size());
    if (k == 0) continue;
    const Eigen::Index rows = std::min<Eigen::Index>(kPanelRows, size - b * kPanelRows);
    const Eigen::Map<const Eigen::MatrixXd> panel(p.values.data(), rows, kGroupColumns * k);
    if (k == groups) {  // every group reaches it (near the tree's root): in place
      ordered.selfadjointView<Eigen::Lower>().rankUpdate(panel.transpose());
      continue;
    }
    const Eigen::Index columns = static_cast<Eigen::Index>(kGroupColumns) * k;
    gram_.assign(static_cast<size_t>(columns * columns), 0.0);
    Eigen::Map<Eigen::MatrixXd> gram(gram_.data(), columns, columns);
    gram.selfadjointView<Eigen::Lower>().rankUpdate(panel.transpose());
    for (int j = 0; j < k; ++j) {
      const Eigen::Index oj = kGroupColumns * p.groups[static_cast<size_t>(j)];
      for (int i = j; i < k; ++i) {  // groups increasing: i >= j lands in the lower triangle
        const Eigen::Index oi = kGroupColumns * p.groups[static_cast<size_t>(i)];
        ordered.block<kGroupColumns, kGroupColumns>(oi, oj) +=
            gram.block<kGroupColumns, kGroupColumns>(kGroupColumns * i, kGroupColumns * j);
      }
    }
  }
  // (A diagonal block above adds gram's zero strict upper part: ordered's stays 0.)

  // Back to the contact rows' own order, 3x3 blocks, lower triangle only.
  delassus.setZero(3 * contact_rows, 3 * contact_rows);
  for (int q = 0; q < contact_rows; ++q) {
    const Eigen::Index sq = 3 * order_[static_cast<size_t>(q)];
    for (int p = q; p < contact_rows; ++p) {
      const Eigen::Index sp = 3 * order_[static_cast<size_t>(p)];
      const auto block = ordered.block<3, 3>(3 * p, 3 * q);  // (p, q) in the lower triangle
      if (p == q) {
        delassus.block<3, 3>(sp, sq).triangularView<Eigen::Lower>() = block;
      } else if (sp > sq) {
        delassus.block<3, 3>(sp, sq) = block;
      } else {
        delassus.block<3, 3>(sq, sp) = block.transpose();
      }
    }
  }
}

void DelassusCondensation::forwardSubstitute(const Eigen::SparseMatrix<double>& lower, int group) {
  // L X = the group's columns of P U, in place in work_, from the first row they touch on; the
  // rows reached are moved into their panels (row k is final once column k is done, since L is
  // lower triangular) and cleared behind, so work_ is zero again at the end.
  const Eigen::Index size = lower.rows();
  Eigen::Index panel_open = -1;  // the panel this group's current rows go to
  double* chunk = nullptr;       // its rows x kGroupColumns block there
  Eigen::Index chunk_rows = 0;
  for (Eigen::Index k = group_first_[static_cast<size_t>(group)]; k < size; ++k) {
    double* x = &work_[static_cast<size_t>(kGroupColumns * k)];
    bool reached = false;
    for (int c = 0; c < kGroupColumns; ++c)
      reached = reached || x[c] != 0;
    if (!reached) continue;
    Eigen::SparseMatrix<double>::InnerIterator it(lower, k);
    while (it && it.index() < k)
      ++it;  // (the diagonal comes first in a Cholesky factor's L)
    const double inverse = 1 / it.value();
    for (int c = 0; c < kGroupColumns; ++c)
      x[c] *= inverse;
    for (++it; it; ++it) {
      double* y = &work_[static_cast<size_t>(kGroupColumns * it.index())];
      const double l = it.value();
      for (int c = 0; c < kGroupColumns; ++c)
        y[c] -= l * x[c];
    }
    const Eigen::Index panel = k / kPanelRows;
    if (panel != panel_open) {
      Panel& p = panels_[static_cast<size_t>(panel)];
      chunk_rows = std::min<Eigen::Index>(kPanelRows, size - panel * kPanelRows);
      const size_t at = p.values.size();
      p.values.resize(at + static_cast<size_t>(kGroupColumns * chunk_rows), 0.0);
      p.groups.push_back(group);
      chunk = p.values.data() + at;
      panel_open = panel;
    }
    const Eigen::Index r = k - panel * kPanelRows;
    for (int c = 0; c < kGroupColumns; ++c) {
      chunk[c * chunk_rows + r] = x[c];
      x[c] = 0;
    }
  }
}

}  // namespace torsion

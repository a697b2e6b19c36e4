#pragma once
// Node constraints applied to an assembled block matrix in place: A' = S A S + (I - S), block by
// block, with S_i node i's filter (I free, 0 fixed, I - n n^T on a plane). Shared by the CHOLMOD
// system (cholmod_solver.cpp) and the two-level preconditioner's coarse system.
#include <Eigen/Core>
#include <array>
#include <utility>
#include <vector>

#include "torsion/solve/node_constraints.h"

namespace torsion::detail {

/// blocks[k] = (i, j): the nodes of stored block k; slots[k]: where its 9 entries (row-major)
/// live in `values`, -1 where not stored (a diagonal block's upper triangle, read mirrored).
inline void applyConstraintsToBlocks(const NodeConstraints& constraints,
                                     const std::vector<std::pair<int, int>>& blocks,
                                     const std::vector<std::array<int, 9>>& slots, double* values) {
  if (constraints.constrainedCount() == 0) return;
  auto filter_matrix = [&](int node) {
    Eigen::Matrix3d S;
    for (int col = 0; col < 3; ++col)
      S.col(col) = constraints.filterNode(node, Eigen::Vector3d::Unit(col));
    return S;
  };
  for (size_t k = 0; k < blocks.size(); ++k) {
    const auto [i, j] = blocks[k];
    if (!constraints.isConstrained(i) && !constraints.isConstrained(j)) continue;
    const std::array<int, 9>& idx = slots[k];
    Eigen::Matrix3d block;
    for (int r = 0; r < 3; ++r) {
      for (int col = 0; col < 3; ++col) {
        const int at = idx[static_cast<size_t>(3 * r + col)] >= 0
                           ? idx[static_cast<size_t>(3 * r + col)]
                           : idx[static_cast<size_t>(3 * col + r)];
        block(r, col) = values[at];
      }
    }
    Eigen::Matrix3d filtered = filter_matrix(i) * block * filter_matrix(j);
    if (i == j) filtered += Eigen::Matrix3d::Identity() - filter_matrix(i);
    for (int r = 0; r < 3; ++r) {
      for (int col = 0; col < 3; ++col) {
        const int at = idx[static_cast<size_t>(3 * r + col)];
        if (at >= 0) values[at] = filtered(r, col);
      }
    }
  }
}

}  // namespace torsion::detail

#pragma once
// Part of the contact-space solve (rigid_contact_coulomb.cpp): the soft side of the
// Delassus operator, W_soft = U^T A^-1 U, for the contact rows' unit impulses U = S G^T (3n x 3m)
// and the step's matrix factored as P A P^T = L L^T:
//
//     W_soft = B^T B,   B = L^-1 P U.
//
// B is sparse in a way a general sparse product does not see: column j of B is nonzero only on
// the rows the forward substitution reaches from column j's first rows (the path up the
// elimination tree), so the columns share the rows near the tree's root (the top separators) and
// little else. Measured on the 8332-tet cylinder with a box on it: 3n = 6147, 3m up to 1122,
// B 18 % full. Both halves here follow that structure:
//
//  - the forward substitution runs on kGroupRows contact rows at a time (neighbours in the order
//    of their first rows in P U, whose paths up the tree nearly coincide: L is read once for
//    their 3 kGroupRows columns), on a dense work block, skipping the rows it does not reach, and
//    keeps what it reaches in row panels (blocks of kPanelRows consecutive rows of B, each with
//    the groups that reach it, dense within);
//  - the Gram matrix is the sum over panels of T^T T (T: a panel's rows, its groups' columns), a
//    dense symmetric rank-k update each, added where those contact rows are.
//
// The result is exactly B^T B up to rounding order: only products with a zero factor are skipped.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

namespace torsion {

class DelassusCondensation {
 public:
  /// Writes W_soft's lower triangle into `delassus` (3m x 3m, zeroed here; its strictly upper part
  /// is left zero). `lower` is L (column-major, diagonal included), `permutation` P's indices
  /// ((P x)[permutation[i]] = x[i]; empty: none), `unit_impulses` U; U's columns 3s, 3s+1, 3s+2 are
  /// contact row s's three axes.
  void lowerGram(const Eigen::SparseMatrix<double>& lower, const Eigen::VectorXi& permutation,
                 const Eigen::SparseMatrix<double>& unit_impulses, Eigen::MatrixXd& delassus);

  static constexpr int kPanelRows = 48;
  static constexpr int kGroupRows = 4;
  static constexpr int kGroupColumns = 3 * kGroupRows;

 private:
  struct Panel {
    std::vector<int> groups;     // the groups that reach it, increasing
    std::vector<double> values;  // its rows x kGroupColumns groups.size() block of B, column-major
  };
  void forwardSubstitute(const Eigen::SparseMatrix<double>& lower, int group);

  std::vector<Panel> panels_;
  std::vector<double> work_;      // n x kGroupColumns, row-major: one group's columns of B
  std::vector<int> first_;        // per contact row: its first nonzero row of P U
  std::vector<int> order_;        // contact rows by first_; group g is order_[kGroupRows g, ...)
  std::vector<int> group_first_;  // per group: its first nonzero row
  // Dense scratch of changing sizes, kept as buffers whose capacity stays from call to call (a
  // matrix reallocated per panel and per step cost a sixth of a contact-space step in page faults
  // on the 8332-tet cylinder):
  std::vector<double> gram_;     // one panel's T^T T
  std::vector<double> ordered_;  // W_soft's lower triangle in order_'s order (padded to groups)
};

}  // namespace torsion

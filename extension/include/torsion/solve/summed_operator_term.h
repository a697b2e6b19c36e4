#pragma once
// Two added operator terms as one (a body with self-contact inside an island of touching FEM
// bodies: its self-contact term and the pair contacts' term, contact/island_contact.h).

#include "torsion/solve/added_operator_term.h"

namespace torsion {

class SummedOperatorTerm final : public AddedOperatorTerm {
 public:
  /// Either may be nullptr (then it adds nothing); neither is owned.
  void set(const AddedOperatorTerm* first, const AddedOperatorTerm* second) {
    first_ = first;
    second_ = second;
  }
  void addProduct(const Eigen::VectorXd& y, Eigen::VectorXd& out) const override {
    if (first_ != nullptr) first_->addProduct(y, out);
    if (second_ != nullptr) second_->addProduct(y, out);
  }
  void addDiagonalBlocks(std::vector<Eigen::Matrix3d>& blocks) const override {
    if (first_ != nullptr) first_->addDiagonalBlocks(blocks);
    if (second_ != nullptr) second_->addDiagonalBlocks(blocks);
  }

 private:
  const AddedOperatorTerm* first_ = nullptr;
  const AddedOperatorTerm* second_ = nullptr;
};

}  // namespace torsion

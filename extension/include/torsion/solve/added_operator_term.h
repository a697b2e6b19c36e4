#pragma once
// A symmetric positive semi-definite term added to a body's system operator A for the solves of
// one step: the penalty part rho L^T P L of contact constraints solved by an augmented Lagrangian
// (contact/surface_contact_set.h). SystemOperator::multiply() and diagonalBlocks() include it, so
// every solver that works through the operator (ProjectedCg, the rigid-contact CG) sees the same
// augmented system without knowing about it; multiplyStiffness() does not (internal forces stay
// the body's own).

#include <Eigen/Core>
#include <vector>

namespace torsion {

class AddedOperatorTerm {
 public:
  virtual ~AddedOperatorTerm() = default;
  /// out += T y, with y and out over the body's 3n velocity components.
  virtual void addProduct(const Eigen::VectorXd& y, Eigen::VectorXd& out) const = 0;
  /// blocks[i] += T_ii, the term's 3x3 diagonal block of node i.
  virtual void addDiagonalBlocks(std::vector<Eigen::Matrix3d>& blocks) const = 0;
};

}  // namespace torsion

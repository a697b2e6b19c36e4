#include "torsion/contact/solve/island_body.h"

#include <algorithm>
#include <cassert>
#include <utility>

namespace torsion::sap {

DiagonalBlock IslandBody::freeProjector(int /*block*/) const {
  return DiagonalBlock::Identity(blockSize(), blockSize());
}

void IslandBody::applyPreconditioner(const Eigen::VectorXd& r, Eigen::VectorXd& z) const {
  z = r;
  filter(z);
}

MatrixBody::MatrixBody(const Eigen::SparseMatrix<double>& matrix, Eigen::VectorXd momentum)
    : matrix_(matrix), momentum_(std::move(momentum)) {
  assert(matrix_.rows() == matrix_.cols() && matrix_.rows() == momentum_.size());
  assert(momentum_.size() % 3 == 0);
  matrix_.makeCompressed();
}

void MatrixBody::prescribe(int dof, double value) {
  // Kept sorted so filter() and impose() walk the dofs in one fixed order.
  const auto at = std::lower_bound(prescribed_.begin(), prescribed_.end(), dof);
  const auto index = at - prescribed_.begin();
  if (at != prescribed_.end() && *at == dof) {
    values_[static_cast<size_t>(index)] = value;
    return;
  }
  prescribed_.insert(at, dof);
  values_.insert(values_.begin() + index, value);
}

void MatrixBody::multiply(const Eigen::VectorXd& x, Eigen::VectorXd& out) const {
  out.noalias() = matrix_ * x;
}

DiagonalBlock MatrixBody::diagonalBlock(int block) const {
  DiagonalBlock d = DiagonalBlock::Zero(3, 3);
  for (int c = 0; c < 3; ++c) {
    const int column = 3 * block + c;
    for (Eigen::SparseMatrix<double>::InnerIterator it(matrix_, column); it; ++it) {
      const auto row = it.row() - 3 * block;
      if (row >= 0 && row < 3) d(row, c) = it.value();
    }
  }
  return d;
}

void MatrixBody::filter(Eigen::VectorXd& x) const {
  for (int dof : prescribed_)
    x(dof) = 0;
}

void MatrixBody::impose(Eigen::VectorXd& v) const {
  for (size_t k = 0; k < prescribed_.size(); ++k)
    v(prescribed_[k]) = values_[k];
}

DiagonalBlock MatrixBody::freeProjector(int block) const {
  DiagonalBlock s = DiagonalBlock::Identity(3, 3);
  for (int dof : prescribed_)
    if (dof / 3 == block) s(dof % 3, dof % 3) = 0;
  return s;
}

RigidBody::RigidBody(double mass, const Eigen::Matrix3d& inertia, Eigen::VectorXd momentum)
    : mass_(mass), inertia_(inertia), momentum_(std::move(momentum)) {
  assert(momentum_.size() == 6 && mass_ > 0);
}

void RigidBody::multiply(const Eigen::VectorXd& x, Eigen::VectorXd& out) const {
  out.resize(6);
  out.head<3>() = mass_ * x.head<3>();
  out.tail<3>() = inertia_ * x.tail<3>();
}

DiagonalBlock RigidBody::diagonalBlock(int /*block*/) const {
  DiagonalBlock d = DiagonalBlock::Zero(6, 6);
  d.topLeftCorner<3, 3>() = mass_ * Eigen::Matrix3d::Identity();
  d.bottomRightCorner<3, 3>() = inertia_;
  return d;
}

LinkBody::LinkBody(const Eigen::Matrix<double, 6, 6>& effective_mass, Eigen::VectorXd momentum)
    : effective_mass_(effective_mass), momentum_(std::move(momentum)) {
  assert(momentum_.size() == 6);
}

void LinkBody::multiply(const Eigen::VectorXd& x, Eigen::VectorXd& out) const {
  out.noalias() = effective_mass_ * x;
}

DiagonalBlock LinkBody::diagonalBlock(int /*block*/) const {
  return effective_mass_;
}

}  // namespace torsion::sap

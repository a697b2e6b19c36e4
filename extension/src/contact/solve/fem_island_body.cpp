#include "torsion/contact/solve/fem_island_body.h"

#include <cassert>
#include <utility>

namespace torsion::sap {

FemIslandBody::FemIslandBody(const SystemOperator& system, const NodeConstraints& constraints,
                             Eigen::VectorXd momentum)
    : system_(system), constraints_(constraints), momentum_(std::move(momentum)) {
  assert(momentum_.size() == 3 * system_.model().nodeCount());
  assert(constraints_.nodeCount() == system_.model().nodeCount());
  system_.diagonalBlocks(blocks_);
}

void FemIslandBody::beginStep(const Eigen::VectorXd& momentum) {
  assert(momentum.size() == momentum_.size());
  momentum_ = momentum;
  system_.diagonalBlocks(blocks_);
  factor_ = nullptr;
  coarse_current_ = false;
}

void FemIslandBody::multiply(const Eigen::VectorXd& x, Eigen::VectorXd& out) const {
  out.resize(x.size());
  system_.multiply(x, out);
}

DiagonalBlock FemIslandBody::diagonalBlock(int node) const {
  return blocks_[static_cast<size_t>(node)];
}

DiagonalBlock FemIslandBody::freeProjector(int node) const {
  // S on one node: the filter applied to the unit vectors (identity, zero, or I - d d^T).
  if (constraints_.kind(node) == NodeConstraints::Kind::kFree) return DiagonalBlock::Identity(3, 3);
  DiagonalBlock s(3, 3);
  for (int k = 0; k < 3; ++k)
    s.col(k) = constraints_.filterNode(node, Eigen::Vector3d::Unit(k));
  return s;
}

void FemIslandBody::usePreconditioner(const CholmodSolver& factor) {
  assert(factor.factorized());
  factor_ = &factor;
}

void FemIslandBody::applyPreconditioner(const Eigen::VectorXd& r, Eigen::VectorXd& z) const {
  if (factor_ == nullptr) {
    IslandBody::applyPreconditioner(r, z);
    return;
  }
  factor_->applyInverse(constraints_, r, z);  // S A'^-1 S r
}

}  // namespace torsion::sap

namespace torsion::sap {

void FemIslandBody::useCoarseSpace(const Eigen::VectorXd& positions, int aggregates) {
  const FemModel& model = system_.model();
  const std::vector<Eigen::Vector3d>& rest = model.mesh().restPositions();
  const int count = aggregates > 0 ? aggregates : aggregateCountFor(rest);
  coarse_current_ = count > 0;  // a chunky body: block-Jacobi alone
  if (count == 0) return;
  if (coarse_ != nullptr && coarse_->aggregateCount() == count) {
    coarse_->update(system_, constraints_, positions);  // the same aggregates (of the rest shape)
    return;
  }
  coarse_ = std::make_unique<NodeCoarseSpace>(system_, constraints_, positions,
                                              bisectIntoAggregates(rest, count), count);
}

}  // namespace torsion::sap

#include "torsion/solve/node_constraints.h"

#include <cassert>

namespace torsion {

void NodeConstraints::reset(int node_count) {
  kind_.assign(static_cast<size_t>(node_count), Kind::kFree);
  direction_.assign(static_cast<size_t>(node_count), Eigen::Vector3d::Zero());
  velocity_.setZero(3 * node_count);
}

void NodeConstraints::prescribeVelocity(int node, const Eigen::Vector3d& velocity) {
  kind_[static_cast<size_t>(node)] = Kind::kFull;
  velocity_.segment<3>(3 * node) = velocity;
}

void NodeConstraints::prescribeDirection(int node, const Eigen::Vector3d& direction, double speed) {
  assert(std::abs(direction.norm() - 1.0) < 1e-9);
  if (kind_[static_cast<size_t>(node)] == Kind::kFull) return;
  kind_[static_cast<size_t>(node)] = Kind::kDirection;
  direction_[static_cast<size_t>(node)] = direction;
  velocity_.segment<3>(3 * node) = speed * direction;
}

NodeConstraints NodeConstraints::homogeneous() const {
  NodeConstraints zero = *this;
  zero.velocity_.setZero();
  return zero;
}

int NodeConstraints::constrainedCount() const {
  int count = 0;
  for (Kind k : kind_)
    count += (k != Kind::kFree);
  return count;
}

void NodeConstraints::constrainedNodes(std::vector<int>& nodes) const {
  nodes.clear();
  for (size_t i = 0; i < kind_.size(); ++i)
    if (kind_[i] != Kind::kFree) nodes.push_back(static_cast<int>(i));
}

Eigen::Vector3d NodeConstraints::filterNode(int node, const Eigen::Vector3d& v) const {
  switch (kind_[static_cast<size_t>(node)]) {
    case Kind::kFree:
      return v;
    case Kind::kFull:
      return Eigen::Vector3d::Zero();
    case Kind::kDirection: {
      const Eigen::Vector3d& n = direction_[static_cast<size_t>(node)];
      return v - n * n.dot(v);
    }
  }
  return v;
}

void NodeConstraints::filter(Eigen::VectorXd& vector) const {
  for (int i = 0; i < nodeCount(); ++i) {
    if (kind_[static_cast<size_t>(i)] != Kind::kFree) {
      vector.segment<3>(3 * i) = filterNode(i, vector.segment<3>(3 * i));
    }
  }
}

void NodeConstraints::impose(Eigen::VectorXd& velocity) const {
  for (int i = 0; i < nodeCount(); ++i) {
    if (kind_[static_cast<size_t>(i)] != Kind::kFree) {
      velocity.segment<3>(3 * i) =
          filterNode(i, velocity.segment<3>(3 * i)) + velocity_.segment<3>(3 * i);
    }
  }
}

}  // namespace torsion

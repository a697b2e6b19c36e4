#pragma once
// Projective constraints on nodes (Baraff & Witkin 1998, "Large Steps in Cloth Simulation", sec.
// 5.3; SOFA's projective constraints): a constrained node's velocity over the coming step is
// prescribed, and the implicit solve only moves the free degrees of freedom. Fixed nodes, nodes
// carried by a hand or a scripted motion, and (later) contacts all write here; one mechanism.
//
// A node is free, fully prescribed (all three components), or prescribed along one unit
// direction only (a contact normal; it stays free in the tangent plane). Prescribing a position
// x_target at the end of the step is prescribing the velocity (x_target - x) / dt.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace torsion {

class NodeConstraints {
 public:
  enum class Kind : std::uint8_t { kFree, kFull, kDirection };

  explicit NodeConstraints(int node_count = 0) { reset(node_count); }

  /// Frees every node.
  void reset(int node_count);
  int nodeCount() const { return static_cast<int>(kind_.size()); }

  /// All three velocity components of `node` over the step are `velocity`.
  void prescribeVelocity(int node, const Eigen::Vector3d& velocity);
  /// The velocity component along unit `direction` is `speed`; the rest stays free. A node that
  /// is already fully prescribed keeps its full prescription (a hand wins over a contact).
  void prescribeDirection(int node, const Eigen::Vector3d& direction, double speed);

  Kind kind(int node) const { return kind_[static_cast<size_t>(node)]; }
  bool isConstrained(int node) const { return kind(node) != Kind::kFree; }
  int constrainedCount() const;
  /// The constrained nodes, ascending, into `nodes` (cleared first; its capacity is kept).
  void constrainedNodes(std::vector<int>& nodes) const;

  /// The same constraints with every prescribed value zero (a Newton correction's: the iterate
  /// already meets the prescriptions).
  NodeConstraints homogeneous() const;
  /// Velocity with every prescribed component set to its prescribed value and free components
  /// taken from `free_velocity` (3n).
  void impose(Eigen::VectorXd& velocity) const;
  /// The filter S: zeroes every prescribed component of `vector` (3n), in place.
  void filter(Eigen::VectorXd& vector) const;
  /// Filter on one node's 3-vector.
  Eigen::Vector3d filterNode(int node, const Eigen::Vector3d& v) const;

 private:
  std::vector<Kind> kind_;
  std::vector<Eigen::Vector3d> direction_;  // unit, for kDirection
  Eigen::VectorXd velocity_;                // 3n; for kDirection, speed * direction
};

}  // namespace torsion

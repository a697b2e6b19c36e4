#pragma once
// The coarse space of a FEM body in the island's CG (coupled_preconditioner.h): the rigid motions
// of pieces of the body.
//
// The body's nodes are split into aggregates of nearby nodes by recursive coordinate bisection of
// the rest shape (aggregates stay pieces of the body however it is bent). Each aggregate a brings
// the six rigid modes of its nodes about its centroid c_a in the step's current shape,
//
//     Z_n = S_n [I, -[x_n - c_a]x]      (node n of aggregate a; S_n its free-dof projector),
//
// reduced to an orthonormal basis of their span: an aggregate whose nodes are held brings fewer
// modes, or none. Their span holds the body's slow modes (a rod's bending and twisting, a plate's
// bending), the ones block-Jacobi resolves only one node's neighbourhood per CG iteration: its
// condition number grows as the square of the body's length in elements, so the CG of a slender rod
// takes as many iterations as the rod is long. Adding the exact solve on that span,
//
//     P^-1 = P_coupled + Z E^-1 Z^T,   E = Z^T H Z  (the Galerkin system of the island's Hessian),
//
// is two-level additive Schwarz with a coarse space of aggregates' rigid modes (Toselli, Widlund,
// "Domain Decomposition Methods", 2005, ch. 2-3; Vanek, Mandel, Brezina, "Algebraic multigrid by
// smoothed aggregation for second and fourth order elliptic problems", Computing 56, 1996, for the
// rigid modes of aggregates): SPD, so CG stays CG.
//
// This body's part of E, Z^T A Z, is made here once per step from the operator's assembled blocks;
// the contacts' part, (J Z)^T G (J Z), by the island at each Newton iteration
// (coarse_correction.h).

#include <Eigen/Core>
#include <vector>

#include "torsion/solve/node_constraints.h"
#include "torsion/solve/system_operator.h"

namespace torsion::sap {

/// Only a body at least this slender, a rod (the longest side of its rest bounding box over the
/// second longest), gets a coarse space. Block-Jacobi's CG iterations grow with a rod's length in
/// elements, and its slow modes, bending and twisting, are the aggregates' rigid motions: measured,
/// rods of slenderness 15 to 21 (the Greenhill rod, the plectoneme) halve their CG iterations.
/// Elsewhere they are not the slow modes: the 8332-tet cylinder (slenderness 5) resting on the
/// ground took 50 CG iterations a step with a coarse space instead of 34, and slabs held at their
/// base under a resting sphere 1.3 to 1.6 times the time.
inline constexpr double kMinSlenderness = 8;
/// One aggregate per this many nodes at least ...
inline constexpr int kNodesPerAggregate = 64;
/// ... and at most this many aggregates: E is dense, factorised at every Newton iteration.
inline constexpr int kMaxAggregates = 32;

/// The aggregate count for a body's rest shape: 0 (no coarse space) below kMinSlenderness, else
/// the larger of nodes / kNodesPerAggregate and the slenderness (an aggregate is then a slice
/// about as long as the rod is thick), rounded up, at most kMaxAggregates.
int aggregateCountFor(const std::vector<Eigen::Vector3d>& rest_points);

/// Node i's aggregate (0 .. count - 1) for `count` aggregates of nearly equal size: the points are
/// split along the longest side of their bounding box at the ratio of the two halves' counts, and
/// each half again (ties broken by index: the split depends on the points alone).
std::vector<int> bisectIntoAggregates(const std::vector<Eigen::Vector3d>& points, int count);

class NodeCoarseSpace {
 public:
  /// Z's rows of one node: 3 x (its aggregate's columns, at most 6).
  using NodeBasis = Eigen::Matrix<double, 3, 6>;

  /// `positions`: 3n, the step's current node positions; `aggregate_of`: per node, from
  /// bisectIntoAggregates. `constraints` is not owned and must outlive the space. Returns no coarse
  /// space (dofs() == 0) for a body with nodal pressure (its volumetric stiffness is not in the
  /// operator's blocks).
  NodeCoarseSpace(const SystemOperator& system, const NodeConstraints& constraints,
                  const Eigen::VectorXd& positions, const std::vector<int>& aggregate_of,
                  int aggregate_count);
  /// The space at another step: `positions` (3n) and the system's blocks then, the same
  /// aggregates, the storage reused.
  void update(const SystemOperator& system, const NodeConstraints& constraints,
              const Eigen::VectorXd& positions);

  int aggregateCount() const { return aggregate_count_; }
  /// The coarse dofs (columns of Z).
  int dofs() const { return first_column_.back(); }
  int aggregateOf(int node) const { return aggregate_of_[static_cast<std::size_t>(node)]; }
  int firstColumn(int aggregate) const {
    return first_column_[static_cast<std::size_t>(aggregate)];
  }
  int columns(int aggregate) const {
    return first_column_[static_cast<std::size_t>(aggregate) + 1] - firstColumn(aggregate);
  }
  /// Node n's rows of Z; only the first columns(aggregateOf(n)) are used (the rest are zero).
  const NodeBasis& nodeBasis(int node) const { return basis_[static_cast<std::size_t>(node)]; }
  /// out = Z^T x (x: 3n; out: dofs()).
  void restrictTo(const Eigen::Ref<const Eigen::VectorXd>& x,
                  Eigen::Ref<Eigen::VectorXd> out) const;
  /// x += Z y (y: dofs(); x: 3n).
  void prolongAdd(const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> x) const;
  /// Z^T A Z, dofs() square, A the operator's system at this step.
  const Eigen::MatrixXd& galerkin() const { return galerkin_; }

 private:
  void buildBasis(const NodeConstraints& constraints, const Eigen::VectorXd& positions,
                  int aggregate_count);
  void assembleGalerkin(const SystemOperator& system);

  std::vector<int> aggregate_of_;
  int aggregate_count_ = 0;
  std::vector<int> first_column_{0};  // per aggregate, then the total
  const NodeConstraints* constraints_ = nullptr;
  std::vector<NodeBasis> basis_;          // per node
  std::vector<Eigen::Vector3d> offsets_;  // per node: x_n - c_a
  // Per aggregate: V_a, the orthonormalising reduction of its six modes (its first columns(a)
  // columns; the rest zero).
  std::vector<Eigen::Matrix<double, 6, 6>> reduction_;
  Eigen::MatrixXd galerkin_;
  std::vector<Eigen::Matrix<double, 6, 6>> galerkin_sums_;  // assembleGalerkin's, per pair
  // restrictTo / prolongAdd scratch: per aggregate, a force and moment or a rigid motion.
  mutable std::vector<Eigen::Matrix<double, 6, 1>> moments_;
};

}  // namespace torsion::sap

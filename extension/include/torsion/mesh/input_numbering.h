#pragma once
// How a body's node and tet numbers map to those of the mesh it was given (its input), when the
// library renumbered that mesh for cache locality (node_ordering.h; FemWorld::addBody with
// NodeNumbering::kCacheFriendly). The solver, Bullet's btSoftBody and FemBody's own functions use
// the body's numbers; what a user reads or writes by number (the outputs of `torsion run`, the
// Python arrays and node lists) is translated here, so it stays in the input's numbering.
//
// Body tets are those of FemModel::mesh(): a tet10 body's 8 linear sub-tets per element, whose
// input numbers are those the same body built from the unrenumbered mesh would have (its mid-edge
// nodes, its sub-tets).

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "torsion/mesh/tet_mesh.h"

namespace torsion {

/// How a body numbers the nodes of the mesh it is made of: as the mesh does, or renumbered for
/// cache locality when that pays (cacheFriendlyRenumbering, node_ordering.h: 5-30 % of the step
/// on a mesh in a mesher's insertion order, docs/performance.md, "Node order").
enum class NodeNumbering { kAsGiven, kCacheFriendly };

class InputNumbering {
 public:
  /// The body kept its input's numbers.
  InputNumbering() = default;
  /// `input_node[b]`: the input number of body node b of `body_mesh`; `input_tet[t]` likewise
  /// for its tets (each a permutation).
  InputNumbering(std::vector<int> input_node, std::vector<int> input_tet, const TetMesh& body_mesh);

  /// True when body and input numbers agree.
  bool identity() const { return input_node_.empty(); }
  int inputNode(int body_node) const {
    return identity() ? body_node : input_node_[static_cast<size_t>(body_node)];
  }
  int bodyNode(int input_node) const {
    return identity() ? input_node : body_node_[static_cast<size_t>(input_node)];
  }
  int inputTet(int body_tet) const {
    return identity() ? body_tet : input_tet_[static_cast<size_t>(body_tet)];
  }
  int bodyTet(int input_tet) const {
    return identity() ? input_tet : body_tet_[static_cast<size_t>(input_tet)];
  }
  /// Elements of `tets_per_element` consecutive tets (1 for tet4, 8 for tet10), whose tets map
  /// together: the input number of body element e, and back.
  int inputElement(int element, int tets_per_element) const {
    return inputTet(tets_per_element * element) / tets_per_element;
  }
  int bodyElement(int input_element, int tets_per_element) const {
    return bodyTet(tets_per_element * input_element) / tets_per_element;
  }
  /// The body's mesh in the input's numbering; null when identity() (the body's own is that).
  const std::shared_ptr<const TetMesh>& inputMesh() const { return input_mesh_; }

  /// `width` values per body node (3n positions, n masses, ...) -> the same in input order.
  Eigen::VectorXd nodesToInput(const Eigen::VectorXd& per_body_node, int width = 3) const;
  /// `width` values per input node -> the same in body order.
  Eigen::VectorXd nodesToBody(const Eigen::VectorXd& per_input_node, int width = 3) const;
  /// One value per body tet -> the same in input tet order.
  std::vector<double> tetsToInput(const std::vector<double>& per_body_tet) const;

 private:
  std::vector<int> input_node_, body_node_, input_tet_, body_tet_;
  std::shared_ptr<const TetMesh> input_mesh_;
};

}  // namespace torsion

#include "torsion/mesh/input_numbering.h"

#include <cassert>

namespace torsion {

InputNumbering::InputNumbering(std::vector<int> input_node, std::vector<int> input_tet,
                               const TetMesh& body_mesh)
    : input_node_(std::move(input_node)), input_tet_(std::move(input_tet)) {
  assert(input_node_.size() == static_cast<size_t>(body_mesh.nodeCount()) &&
         input_tet_.size() == static_cast<size_t>(body_mesh.tetCount()));
  body_node_.assign(input_node_.size(), -1);
  std::vector<Eigen::Vector3d> rest(input_node_.size());
  for (size_t b = 0; b < input_node_.size(); ++b) {
    const size_t i = static_cast<size_t>(input_node_[b]);
    body_node_[i] = static_cast<int>(b);
    rest[i] = body_mesh.restPositions()[b];
  }
  std::vector<Tet> tets(input_tet_.size());
  body_tet_.assign(input_tet_.size(), -1);
  for (size_t t = 0; t < input_tet_.size(); ++t) {
    body_tet_[static_cast<size_t>(input_tet_[t])] = static_cast<int>(t);
    Tet& tet = tets[static_cast<size_t>(input_tet_[t])];
    for (size_t a = 0; a < 4; ++a)
      tet[a] = input_node_[static_cast<size_t>(body_mesh.tets()[t][a])];
  }
  input_mesh_ = std::make_shared<const TetMesh>(std::move(rest), std::move(tets));
}

Eigen::VectorXd InputNumbering::nodesToInput(const Eigen::VectorXd& per_body_node,
                                             int width) const {
  if (identity()) return per_body_node;
  Eigen::VectorXd out(per_body_node.size());
  for (size_t b = 0; b < input_node_.size(); ++b)
    out.segment(width * input_node_[b], width) =
        per_body_node.segment(width * static_cast<Eigen::Index>(b), width);
  return out;
}

Eigen::VectorXd InputNumbering::nodesToBody(const Eigen::VectorXd& per_input_node,
                                            int width) const {
  if (identity()) return per_input_node;
  Eigen::VectorXd out(per_input_node.size());
  for (size_t b = 0; b < input_node_.size(); ++b)
    out.segment(width * static_cast<Eigen::Index>(b), width) =
        per_input_node.segment(width * input_node_[b], width);
  return out;
}

std::vector<double> InputNumbering::tetsToInput(const std::vector<double>& per_body_tet) const {
  if (identity()) return per_body_tet;
  std::vector<double> out(per_body_tet.size());
  for (size_t t = 0; t < input_tet_.size(); ++t)
    out[static_cast<size_t>(input_tet_[t])] = per_body_tet[t];
  return out;
}

}  // namespace torsion

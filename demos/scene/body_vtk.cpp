#include "body_vtk.h"

#include <vector>

#include "torsion/mesh/mesh_fields.h"
#include "torsion/mesh/vtk_format.h"

namespace torsion::scene {

std::string bodyVtkText(const FemBody& body, const Eigen::VectorXd& positions) {
  const InputNumbering& numbering = body.inputNumbering();
  const TetMesh& mesh = body.inputMesh();
  const Eigen::VectorXd input_positions = numbering.nodesToInput(positions);
  std::vector<Eigen::Vector3d> x(static_cast<size_t>(mesh.nodeCount()));
  MeshField displacement{"displacement", 3, {}};
  displacement.values.reserve(static_cast<size_t>(3 * mesh.nodeCount()));
  for (int i = 0; i < mesh.nodeCount(); ++i) {
    x[static_cast<size_t>(i)] = input_positions.segment<3>(3 * i);
    const Eigen::Vector3d u =
        x[static_cast<size_t>(i)] - mesh.restPositions()[static_cast<size_t>(i)];
    displacement.values.insert(displacement.values.end(), {u.x(), u.y(), u.z()});
  }
  MeshFields fields;
  fields.node_fields.push_back(std::move(displacement));
  return formatVtk(mesh, x, fields, body.name());
}

}  // namespace torsion::scene

#include "torsion/mesh/vtk_format.h"

namespace torsion {

Result<RawTetMesh> parseVtk(std::string_view /*text*/, std::string_view file) {
  return Error{std::string(file) + ": VTK reader not implemented yet"};
}

std::string formatVtk(const TetMesh& /*mesh*/, const std::vector<Eigen::Vector3d>& /*positions*/,
                      const MeshFields& /*fields*/, std::string_view /*title*/) {
  return {};
}

}  // namespace torsion

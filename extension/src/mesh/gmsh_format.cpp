#include "torsion/mesh/gmsh_format.h"

namespace torsion {

Result<RawTetMesh> parseGmsh(std::string_view /*text*/, std::string_view file) {
  return Error{std::string(file) + ": Gmsh reader not implemented yet"};
}

std::string formatGmsh41(const TetMesh& /*mesh*/) { return {}; }

}  // namespace torsion

#pragma once
// What a mesh reader produces: positions and tets exactly as the file gave them (indices already
// shifted to 0-based), plus where each tet came from so validation can name the line.
// Readers check syntax and index ranges; geometry (repeated vertices, zero volume, inversion) is
// checked once for every format by buildTetMesh (tet_mesh_builder.h).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "torsion/mesh/tet_mesh.h"

namespace torsion {

/// Where one element was read from.
struct ElementOrigin {
  int line = 0;  ///< 1-based line in RawTetMesh::element_file (0: unknown)
  long id = 0;   ///< the element's number as written in the file
};

struct RawTetMesh {
  std::vector<Eigen::Vector3d> positions;
  std::vector<Tet> tets;               ///< 0-based node indices, each < positions.size()
  std::vector<ElementOrigin> origins;  ///< one per tet
  std::string element_file;            ///< file name used in messages about tets
  std::vector<std::string> notes;      ///< reader remarks for the user (e.g. skipped cell types)
};

}  // namespace torsion

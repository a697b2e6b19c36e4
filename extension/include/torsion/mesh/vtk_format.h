#pragma once
// Legacy VTK (https://vtk.org/wp-content/uploads/2015/04/file-formats.pdf), ASCII
// UNSTRUCTURED_GRID. Reads both cell layouts: "CELLS n size" + "k i0 .. ik-1" rows (versions up to
// 5.0) and "CELLS n+1 m" + OFFSETS/CONNECTIVITY arrays (5.1). Tets are cell type 10; other cell
// types are skipped and named in RawTetMesh::notes. Binary files are refused.

#include <string>
#include <string_view>
#include <vector>

#include "torsion/mesh/mesh_fields.h"
#include "torsion/mesh/raw_tet_mesh.h"
#include "torsion/mesh/tet_mesh.h"
#include "torsion/result.h"

namespace torsion {

Result<RawTetMesh> parseVtk(std::string_view text, std::string_view file);

/// Legacy VTK 4.2 ASCII text of the mesh at `positions` (one per node; pass restPositions() for
/// the rest shape), with optional POINT_DATA / CELL_DATA fields. Opens in ParaView.
/// Fields whose size does not match are a programming error (asserted).
std::string formatVtk(const TetMesh& mesh, const std::vector<Eigen::Vector3d>& positions,
                      const MeshFields& fields = {}, std::string_view title = "torsion mesh");

}  // namespace torsion

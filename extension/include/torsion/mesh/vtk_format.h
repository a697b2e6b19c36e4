#pragma once
// Legacy VTK (https://vtk.org/wp-content/uploads/2015/04/file-formats.pdf), ASCII
// UNSTRUCTURED_GRID. Reads both cell layouts: "CELLS n size" + "k i0 .. ik-1" rows (versions up to
// 5.0) and "CELLS n+1 m" + OFFSETS/CONNECTIVITY arrays (5.1); the layout is told by the OFFSETS
// keyword, not by the version. Numbers are free format across lines; keywords are
// case-insensitive. POINTS (any numeric type) must come before CELLS, CELLS before CELL_TYPES.
// Tets are cell type 10 (4 points each); other cell types are skipped and named in
// RawTetMesh::notes. FIELD data and METADATA blocks before or inside the grid are skipped; parsing
// stops at POINT_DATA, CELL_DATA or FIELD after the grid. Binary files and datasets other than
// UNSTRUCTURED_GRID are refused. Tet origins: the line where the cell's row (or its connectivity)
// starts, and the cell's index among all cells.

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
/// the rest shape), with optional POINT_DATA / CELL_DATA fields (SCALARS for 1 component, VECTORS
/// for 3). Numbers are written with %.17g, so they read back bit for bit. Opens in ParaView.
/// Fields whose size does not match are a programming error (asserted). Whitespace in field names
/// becomes '_'. Non-finite values are written as nan/inf, which VTK's ASCII reader cannot parse.
std::string formatVtk(const TetMesh& mesh, const std::vector<Eigen::Vector3d>& positions,
                      const MeshFields& fields = {}, std::string_view title = "torsion mesh");

}  // namespace torsion

#pragma once
// Gmsh .msh ASCII, versions 2.2 and 4.1 (https://gmsh.info/doc/texinfo/gmsh.html#MSH-file-format).
// Tets are element type 4; other element types are skipped (and counted in RawTetMesh::notes).
// Node tags may be non-sequential and sparse; they are renumbered densely in order of appearance.
// Binary files, other versions and unknown sections before $Nodes are errors or skipped as
// documented in the implementation.

#include <string>
#include <string_view>

#include "torsion/mesh/raw_tet_mesh.h"
#include "torsion/mesh/tet_mesh.h"
#include "torsion/result.h"

namespace torsion {

Result<RawTetMesh> parseGmsh(std::string_view text, std::string_view file);

/// Gmsh 4.1 ASCII: one volume entity, nodes tagged 1..n, tets tagged 1..m.
std::string formatGmsh41(const TetMesh& mesh);

}  // namespace torsion

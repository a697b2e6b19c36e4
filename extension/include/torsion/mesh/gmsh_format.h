#pragma once
// Gmsh .msh ASCII, versions 2.2 and 4.1 (https://gmsh.info/doc/texinfo/gmsh.html#MSH-file-format).
// Tets are element type 4; other element types (points, lines, triangles, quadrangles, prisms,
// ...) are skipped and counted in RawTetMesh::notes; higher-order tets (types 11, 29-31) are
// skipped with a note that they are not supported. A file with no type-4 tet is an error.
// Node tags may be non-sequential and sparse; they are renumbered densely in order of appearance.
// Sections other than $MeshFormat, $Nodes and $Elements ($PhysicalNames, $Entities, $NodeData,
// ...) are skipped up to their $End line. Refused: versions other than 2.2 and 4.1, binary files
// (file-type 1), data-size other than 8, MSH 1 files ($NOD/$ELM), and any malformed content
// (counts that do not match, truncated or non-numeric fields, unknown or duplicate node tags).
// Errors read "file:line: fault".

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

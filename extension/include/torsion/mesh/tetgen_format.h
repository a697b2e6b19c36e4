#pragma once
// TetGen .node/.ele files (https://wias-berlin.de/software/tetgen/fformats.html).
// .node: "<#points> <dim=3> <#attributes> <#boundary markers 0|1>", then
//        "<index> <x> <y> <z> [attributes] [marker]" per point. '#' starts a comment.
// .ele:  "<#tets> <nodes per tet=4> <#attributes>", then "<index> <n0> <n1> <n2> <n3>
// [attributes]". Indices are 0- or 1-based, decided by the first point's index as TetGen does; they
// must then be consecutive. Quadratic (10-node) tets are refused.

#include <string>
#include <string_view>

#include "torsion/mesh/raw_tet_mesh.h"
#include "torsion/mesh/tet_mesh.h"
#include "torsion/result.h"

namespace torsion {

Result<RawTetMesh> parseTetGen(std::string_view node_text, std::string_view node_file,
                               std::string_view ele_text, std::string_view ele_file);

struct TetGenText {
  std::string node;
  std::string ele;
};
/// 0-based .node/.ele text, coordinates with round-trip precision.
TetGenText formatTetGen(const TetMesh& mesh);

}  // namespace torsion

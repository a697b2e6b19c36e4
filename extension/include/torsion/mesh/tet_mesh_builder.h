#pragma once
// Geometry validation shared by every reader: RawTetMesh -> TetMesh, or an Error naming the file,
// line and tet.

#include <string>
#include <vector>

#include "torsion/mesh/raw_tet_mesh.h"
#include "torsion/mesh/tet_mesh.h"
#include "torsion/result.h"

namespace torsion {

struct MeshLoadOptions {
  /// Inverted rest tets (negative volume) are reoriented by swapping two vertices and reported
  /// as a warning; set this to refuse them instead.
  bool refuse_inverted = false;
  /// A tet is degenerate when |6V| <= degenerate_tolerance * (longest edge)^3. For a regular tet
  /// that ratio is 0.707, so 1e-10 only catches tets that are flat to round-off.
  double degenerate_tolerance = 1e-10;
};

struct LoadedMesh {
  TetMesh mesh;
  int reoriented_tets = 0;            ///< inverted rest tets that were flipped
  std::vector<std::string> warnings;  ///< for the user, one line each, with file:line
};

/// Validates a raw mesh and builds the TetMesh. Errors: no nodes, no tets, a tet with a repeated
/// vertex, a degenerate (zero-volume) tet, an inverted tet when refused, a non-finite coordinate,
/// an index out of range.
Result<LoadedMesh> buildTetMesh(RawTetMesh raw, const MeshLoadOptions& options = {});

}  // namespace torsion

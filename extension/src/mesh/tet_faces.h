#pragma once
// The faces of a set of tets, sorted so that copies of one face are adjacent (private helper shared
// by TetMesh's surface extraction and buildTetMesh's manifold check).

#include <array>
#include <vector>

#include "torsion/mesh/tet_mesh.h"

namespace torsion::detail {

// Faces of a positively oriented tet, each wound so its normal points out of the tet.
inline constexpr int kOutwardFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

struct FaceRecord {
  std::array<int, 3> key;  ///< sorted node indices
  int tet;
  int local_face;  ///< row of kOutwardFaces
};

/// All 4 * tets.size() faces, sorted by key (then tet), so equal faces are consecutive.
std::vector<FaceRecord> sortedFaces(const std::vector<Tet>& tets);

}  // namespace torsion::detail

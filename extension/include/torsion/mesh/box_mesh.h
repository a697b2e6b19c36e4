#pragma once
// A structured tet mesh of a box: nx x ny x nz cells, each split into 6 tets around its main
// diagonal (Kuhn subdivision, conforming across cells). For beams, slabs and blocks in tests and
// scenes, where a reference solution wants a regular mesh.

#include <Eigen/Core>

#include "torsion/mesh/tet_mesh.h"
#include "torsion/result.h"

namespace torsion {

/// Fails when a cell count is < 1 or the box is empty.
Result<TetMesh> makeBoxTetMesh(const Eigen::Vector3d& min_corner, const Eigen::Vector3d& max_corner,
                               int nx, int ny, int nz);

}  // namespace torsion

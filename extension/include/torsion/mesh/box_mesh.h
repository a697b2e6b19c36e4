#pragma once
// A structured tet mesh of a box: nx x ny x nz cells, each split into 6 tets around one of its
// diagonals (Kuhn subdivision), for beams, slabs and blocks in tests and scenes, where a reference
// solution wants a regular mesh.
//
// The diagonal alternates in a mirror pattern: each cell's runs from its corner whose grid indices
// are all even to the opposite corner, so neighbouring cells are mirror images across their shared
// face. Every face of the grid is then cut along the diagonal through its even node, from both
// sides alike (conforming), and the mesh is mirror-symmetric about the box's mid-plane normal to
// any axis with an even cell count (with an odd count the middle layer of cells, whose split has
// no mirror symmetry of its own, breaks it). Splitting every cell the same way instead leans every
// tet the same way: a beam loaded symmetrically then also bends sideways (3.5 % of its vertical
// deflection on the 60 x 6 x 6-cell cantilever of tests/physics).

#include <Eigen/Core>

#include "torsion/mesh/tet_mesh.h"
#include "torsion/result.h"

namespace torsion {

/// Fails when a cell count is < 1 or the box is empty.
Result<TetMesh> makeBoxTetMesh(const Eigen::Vector3d& min_corner, const Eigen::Vector3d& max_corner,
                               int nx, int ny, int nz);

}  // namespace torsion

#pragma once
// A structured tet mesh of a ball, for contact scenes and tests: the box mesh of [-1, 1]^3 with
// `cells` cells per side, each node pulled onto the ball by p -> R p |p|_inf / |p|_2 (+ centre).
// Crude near the cube's corners, but conforming, positively oriented and symmetric.

#include <Eigen/Core>

#include "torsion/mesh/tet_mesh.h"
#include "torsion/result.h"

namespace torsion {

/// Fails when cells < 2, radius <= 0, or a tet comes out inverted or flat.
Result<TetMesh> makeBallTetMesh(const Eigen::Vector3d& center, double radius, int cells);

}  // namespace torsion

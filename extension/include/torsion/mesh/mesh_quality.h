#pragma once
// Element quality of a mesh, for `torsion mesh info` and for deciding whether a mesh is fit to
// simulate (slivers make the stiffness matrix ill-conditioned and the CG slow).

#include <vector>

#include "torsion/mesh/tet_mesh.h"

namespace torsion {

struct MeshQuality {
  double min_dihedral_deg = 0;  ///< smallest dihedral angle over all tets (regular tet: 70.53)
  double max_dihedral_deg = 0;  ///< largest dihedral angle over all tets
  /// Aspect ratio: longest edge / (2 sqrt(6) inradius); 1 for a regular tet, large for slivers.
  double max_aspect_ratio = 0;
  double mean_aspect_ratio = 0;
  int inverted_tets = 0;  ///< tets with non-positive volume at the given positions
};

/// Quality at the given positions (rest or deformed; one per node).
MeshQuality measureQuality(const TetMesh& mesh, const std::vector<Eigen::Vector3d>& positions);

/// Dihedral angles (radians) of one tet at its six edges.
std::array<double, 6> dihedralAngles(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                     const Eigen::Vector3d& c, const Eigen::Vector3d& d);

}  // namespace torsion

#include "torsion/mesh/ball_mesh.h"

#include <string>

#include "torsion/mesh/box_mesh.h"

namespace torsion {

Result<TetMesh> makeBallTetMesh(const Eigen::Vector3d& center, double radius, int cells) {
  if (cells < 2) return Error{"ball mesh: cells must be >= 2"};
  if (!(radius > 0)) return Error{"ball mesh: radius must be > 0"};
  Result<TetMesh> cube = makeBoxTetMesh(Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(1),
                                        cells, cells, cells);
  if (!cube) return cube.error();
  std::vector<Eigen::Vector3d> positions = cube.value().restPositions();
  for (Eigen::Vector3d& p : positions) {
    const double l2 = p.norm();
    if (l2 > 0) p *= p.cwiseAbs().maxCoeff() / l2;
    p = center + radius * p;
  }
  const std::vector<Tet>& tets = cube.value().tets();
  for (size_t t = 0; t < tets.size(); ++t) {
    const Tet& tet = tets[t];
    const double v6 = sixSignedVolume(
        positions[static_cast<size_t>(tet[0])], positions[static_cast<size_t>(tet[1])],
        positions[static_cast<size_t>(tet[2])], positions[static_cast<size_t>(tet[3])]);
    if (!(v6 > 1e-12 * radius * radius * radius))
      return Error{"ball mesh: tet " + std::to_string(t) + " is flat or inverted (use more cells)"};
  }
  return TetMesh(std::move(positions), tets);
}

}  // namespace torsion

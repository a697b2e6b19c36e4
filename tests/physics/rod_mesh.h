#pragma once
// A round rod on a structured mesh, for the twist-buckling tests: the box mesh of
// across x across x along cells (box_mesh.h) over the square [-1, 1]^2 x [0, length], each
// section's square mapped onto the disc of radius `radius` by the elliptical grid map
//   (u, v) -> radius (u sqrt(1 - v^2 / 2), v sqrt(1 - u^2 / 2)).
// The map keeps the square's symmetries, so the section's second moment is the same about every
// axis (I = J_p / 2, J_p its polar moment), as Greenhill's analysis wants; its boundary is a
// polygon with 4 x across corners on the circle.

#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "torsion/mesh/box_mesh.h"

namespace torsion::test {

inline TetMesh roundRodMesh(double radius, double length, int across, int along) {
  const TetMesh box = makeBoxTetMesh(Eigen::Vector3d(-1, -1, 0), Eigen::Vector3d(1, 1, length),
                                     across, across, along)
                          .value();
  std::vector<Eigen::Vector3d> mapped = box.restPositions();
  for (Eigen::Vector3d& p : mapped) {
    const double u = p.x(), v = p.y();
    p.x() = radius * u * std::sqrt(1 - v * v / 2);
    p.y() = radius * v * std::sqrt(1 - u * u / 2);
  }
  return TetMesh(mapped, box.tets());
}

}  // namespace torsion::test

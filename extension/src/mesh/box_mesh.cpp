#include "torsion/mesh/box_mesh.h"

#include <algorithm>
#include <array>

namespace torsion {

Result<TetMesh> makeBoxTetMesh(const Eigen::Vector3d& min_corner, const Eigen::Vector3d& max_corner,
                               int nx, int ny, int nz) {
  if (nx < 1 || ny < 1 || nz < 1) return Error{"box mesh: every cell count must be >= 1"};
  if (!((max_corner - min_corner).minCoeff() > 0))
    return Error{"box mesh: max corner must exceed min corner"};
  auto node = [&](int i, int j, int k) { return (k * (ny + 1) + j) * (nx + 1) + i; };

  std::vector<Eigen::Vector3d> positions;
  positions.reserve(static_cast<size_t>((nx + 1) * (ny + 1) * (nz + 1)));
  for (int k = 0; k <= nz; ++k) {
    for (int j = 0; j <= ny; ++j) {
      for (int i = 0; i <= nx; ++i) {
        const Eigen::Vector3d f(double(i) / nx, double(j) / ny, double(k) / nz);
        positions.push_back(min_corner + f.cwiseProduct(max_corner - min_corner));
      }
    }
  }

  std::vector<Tet> tets;
  tets.reserve(static_cast<size_t>(6 * nx * ny * nz));
  std::array<int, 3> axes = {0, 1, 2};
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        // One tet per path from corner (0,0,0) to (1,1,1) along the axes in some order.
        std::sort(axes.begin(), axes.end());
        do {
          std::array<int, 3> c = {i, j, k};
          Tet tet;
          tet[0] = node(c[0], c[1], c[2]);
          for (size_t s = 0; s < 3; ++s) {
            ++c[static_cast<size_t>(axes[s])];
            tet[s + 1] = node(c[0], c[1], c[2]);
          }
          const auto& x = positions;
          if (sixSignedVolume(x[static_cast<size_t>(tet[0])], x[static_cast<size_t>(tet[1])],
                              x[static_cast<size_t>(tet[2])], x[static_cast<size_t>(tet[3])]) < 0) {
            std::swap(tet[2], tet[3]);
          }
          tets.push_back(tet);
        } while (std::next_permutation(axes.begin(), axes.end()));
      }
    }
  }
  return TetMesh(std::move(positions), std::move(tets));
}

}  // namespace torsion

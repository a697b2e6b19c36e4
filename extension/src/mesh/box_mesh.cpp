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
        positions.emplace_back(min_corner + f.cwiseProduct(max_corner - min_corner));
      }
    }
  }

  std::vector<Tet> tets;
  tets.reserve(static_cast<size_t>(6 * nx * ny * nz));
  std::array<int, 3> axes = {0, 1, 2};
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        // The cell's diagonal runs from its even corner (every grid index even) to the opposite
        // one: along an axis the corner is the lower one in even cells, the upper one in odd
        // cells. One tet per path along that diagonal, stepping the axes in some order.
        const std::array<int, 3> start = {i + i % 2, j + j % 2, k + k % 2};
        const std::array<int, 3> step = {i % 2 ? -1 : 1, j % 2 ? -1 : 1, k % 2 ? -1 : 1};
        std::sort(axes.begin(), axes.end());
        do {
          std::array<int, 3> c = start;
          Tet tet;
          tet[0] = node(c[0], c[1], c[2]);
          for (size_t s = 0; s < 3; ++s) {
            const size_t axis = static_cast<size_t>(axes[s]);
            c[axis] += step[axis];
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

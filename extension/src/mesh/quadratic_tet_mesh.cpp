#include "torsion/mesh/quadratic_tet_mesh.h"

#include <algorithm>
#include <limits>
#include <utility>

namespace torsion {

namespace {

// Local index (4..9) of the mid-edge node between corners a and b.
int edgeNode(int a, int b) {
  if (a > b) std::swap(a, b);
  for (int e = 0; e < 6; ++e) {
    if (kTet10Edges[static_cast<size_t>(e)][0] == a && kTet10Edges[static_cast<size_t>(e)][1] == b)
      return 4 + e;
  }
  return -1;
}

Tet oriented(Tet tet, const std::vector<Eigen::Vector3d>& x) {
  const auto p = [&](int k) -> const Eigen::Vector3d& {
    return x[static_cast<size_t>(tet[static_cast<size_t>(k)])];
  };
  if (sixSignedVolume(p(0), p(1), p(2), p(3)) < 0) std::swap(tet[2], tet[3]);
  return tet;
}

}  // namespace

std::array<Tet, 8> splitQuadraticTet(const Tet10& element,
                                     const std::vector<Eigen::Vector3d>& positions) {
  const auto node = [&](int local) { return element[static_cast<size_t>(local)]; };
  const auto mid = [&](int a, int b) { return node(edgeNode(a, b)); };
  std::array<Tet, 8> sub;
  // The corner tets: the element scaled by 1/2 about each corner (same orientation).
  for (int c = 0; c < 4; ++c) {
    Tet t;
    for (int k = 0; k < 4; ++k)
      t[static_cast<size_t>(k)] = k == c ? node(c) : mid(c, k);
    sub[static_cast<size_t>(c)] = oriented(t, positions);
  }
  // The inner octahedron over the six mid-edge nodes, split along its shortest diagonal (the
  // diagonals join the midpoints of opposite edges: 01-23, 02-13, 03-12) into 4 tets around it.
  // Around diagonal (i j)-(k l) the other four mid-edge nodes form the cycle
  // (i k), (i l), (j l), (j k): consecutive ones share a corner.
  const std::array<std::array<int, 4>, 3> diagonals = {{{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2}}};
  int best = 0;
  double best_length = std::numeric_limits<double>::infinity();
  for (int d = 0; d < 3; ++d) {
    const auto& [i, j, k, l] = diagonals[static_cast<size_t>(d)];
    const double length =
        (positions[static_cast<size_t>(mid(i, j))] - positions[static_cast<size_t>(mid(k, l))])
            .squaredNorm();
    if (length < best_length * (1 - 1e-12)) {  // ties keep the first: deterministic
      best = d;
      best_length = length;
    }
  }
  const auto& [i, j, k, l] = diagonals[static_cast<size_t>(best)];
  const std::array<int, 4> ring = {mid(i, k), mid(i, l), mid(j, l), mid(j, k)};
  for (int r = 0; r < 4; ++r) {
    sub[static_cast<size_t>(4 + r)] = oriented({mid(i, j), mid(k, l), ring[static_cast<size_t>(r)],
                                                ring[static_cast<size_t>((r + 1) % 4)]},
                                               positions);
  }
  return sub;
}

QuadraticTetMesh buildQuadraticTetMesh(const TetMesh& linear) {
  // Unique edges in ascending (low, high) order; the mid-edge node of edge k is nodeCount + k.
  std::vector<std::pair<int, int>> edges;
  edges.reserve(linear.tets().size() * 6);
  for (const Tet& tet : linear.tets()) {
    for (const auto& [a, b] : kTet10Edges) {
      const int p = tet[static_cast<size_t>(a)], q = tet[static_cast<size_t>(b)];
      edges.emplace_back(std::min(p, q), std::max(p, q));
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());

  std::vector<Eigen::Vector3d> positions = linear.restPositions();
  positions.reserve(positions.size() + edges.size());
  for (const auto& [p, q] : edges) {
    positions.emplace_back(0.5 * (linear.restPositions()[static_cast<size_t>(p)] +
                                  linear.restPositions()[static_cast<size_t>(q)]));
  }

  QuadraticTetMesh result;
  result.elements.reserve(linear.tets().size());
  std::vector<Tet> sub_tets;
  sub_tets.reserve(8 * linear.tets().size());
  for (const Tet& tet : linear.tets()) {
    Tet10 element;
    for (size_t a = 0; a < 4; ++a)
      element[a] = tet[a];
    for (size_t e = 0; e < 6; ++e) {
      const int p = tet[static_cast<size_t>(kTet10Edges[e][0])];
      const int q = tet[static_cast<size_t>(kTet10Edges[e][1])];
      const auto it = std::lower_bound(edges.begin(), edges.end(),
                                       std::make_pair(std::min(p, q), std::max(p, q)));
      element[4 + e] = linear.nodeCount() + static_cast<int>(it - edges.begin());
    }
    for (const Tet& sub : splitQuadraticTet(element, positions))
      sub_tets.push_back(sub);
    result.elements.push_back(element);
  }
  result.refined = std::make_shared<const TetMesh>(std::move(positions), std::move(sub_tets));
  return result;
}

}  // namespace torsion

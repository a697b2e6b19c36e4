#pragma once
// The quadratic (10-node, P2) version of a linear tet mesh, for ElementKind::kTet10 bodies.
//
// Corner nodes keep their indices; one node per mesh edge is appended at the edge midpoint (edges
// numbered in ascending (low, high) order, so the numbering is deterministic), and no boundary
// snapping is done: the P2 geometry is exactly the linear one, so volumes and the meshed section
// are unchanged. Element node order: corners 0-3, then the edges 01, 02, 03, 12, 13, 23.
//
// Every surface-based module (hand-plane selection, contact, rendering, VTK output, Bullet faces)
// works on a plain TetMesh over all P2 nodes: `refined` splits each element into 8 linear
// sub-tets (4 at the corners, 4 around the shortest diagonal of the inner octahedron), so its
// boundary is each boundary face split into 4 triangles over the P2 surface nodes, with
// adjacency, surface nodes and node incidence derived as for any TetMesh. Sub-tets
// 8 e .. 8 e + 7 belong to element e. The solver never uses the sub-tets: its elements are
// `elements`.

#include <array>
#include <memory>
#include <vector>

#include "torsion/mesh/tet_mesh.h"

namespace torsion {

/// Corners 0-3, then the mid-edge nodes of edges 01, 02, 03, 12, 13, 23.
using Tet10 = std::array<int, 10>;
/// The corner pair of each mid-edge node (local indices 4..9).
inline constexpr std::array<std::array<int, 2>, 6> kTet10Edges = {
    {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};

struct QuadraticTetMesh {
  std::shared_ptr<const TetMesh> refined;  ///< all P2 nodes; 8 linear sub-tets per element
  std::vector<Tet10> elements;             ///< one per tet of the linear mesh, same order
};

/// Builds the P2 mesh of a linear mesh (valid, positively oriented, as TetMesh guarantees).
QuadraticTetMesh buildQuadraticTetMesh(const TetMesh& linear);

/// The 8 positively oriented linear sub-tets of one P2 element (node indices of `element`),
/// the inner octahedron split along its shortest diagonal at the given node positions.
std::array<Tet, 8> splitQuadraticTet(const Tet10& element,
                                     const std::vector<Eigen::Vector3d>& positions);

}  // namespace torsion

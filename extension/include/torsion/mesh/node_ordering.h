#pragma once
// A cache-friendly numbering of a tet mesh's nodes: reverse Cuthill-McKee (Cuthill and McKee,
// "Reducing the bandwidth of sparse symmetric matrices", 1969; reversed as George, 1971), from a
// pseudo-peripheral start node (Gibbs, Poole and Stockmeyer, 1976). Nodes that share a tet get
// nearby numbers, so a step's passes over tets and over block rows of K read positions,
// velocities and blocks that are already in cache. Tetgen numbers the nodes it inserts in
// insertion order: on the 31279-tet cylinder the nodes of one tet lie 3491 numbers apart on
// average (of 6971), and the step costs 25-30 % more CPU time than in this order
// (docs/performance.md, "Node order").
//
// It is applied where a mesh is made (`torsion mesh cylinder`, `torsion mesh tetrahedralize`),
// and to a body made from a mesh in another order when it pays (FemWorld::addBody with
// NodeNumbering::kCacheFriendly, the default of scene files and Python): the body then keeps how
// its numbers map to the mesh's (input_numbering.h).

#include <optional>
#include <vector>

#include "torsion/mesh/tet_mesh.h"

namespace torsion {

/// order[new] = old: the reverse Cuthill-McKee order of the node graph (nodes adjacent when they
/// share a tet). Each connected component is numbered from a pseudo-peripheral node, neighbours
/// by ascending degree (ties by old index), so the order is deterministic. Nodes in no tet come
/// last, in their old order.
std::vector<int> reverseCuthillMcKeeOrder(const TetMesh& mesh);

/// The same mesh with node order[i] renumbered i (order as returned above: a permutation of the
/// node indices) and the tets sorted by their smallest new node index, then their largest (each
/// tet's own node order, hence its orientation, kept).
TetMesh renumberNodes(const TetMesh& mesh, const std::vector<int>& order);

/// A renumbered mesh and, per new node and per new tet, its number in the mesh it came from.
struct RenumberedMesh {
  TetMesh mesh;
  std::vector<int> old_node;
  std::vector<int> old_tet;
};
/// renumberNodes(), with the old numbers.
RenumberedMesh renumberedMesh(const TetMesh& mesh, const std::vector<int>& order);

/// The mesh in reverse Cuthill-McKee order with the old numbers, when that brings the nodes of
/// its tets at least twice as close on average (meanTetIndexSpan halves); else nothing (a mesh
/// already in a local order, as every mesh Torsion writes, is left as it is).
std::optional<RenumberedMesh> cacheFriendlyRenumbering(const TetMesh& mesh);

/// The mesh in reverse Cuthill-McKee order (renumberNodes(mesh, reverseCuthillMcKeeOrder(mesh))).
TetMesh inCacheFriendlyOrder(const TetMesh& mesh);

/// Mean over the tets of (largest - smallest node index): what the ordering makes small.
double meanTetIndexSpan(const TetMesh& mesh);

}  // namespace torsion

#include "torsion/mesh/node_ordering.h"

#include <algorithm>
#include <cassert>
#include <numeric>

namespace torsion {

namespace {

// Node -> the nodes it shares a tet with, ascending.
CompressedRows nodeNeighbours(const TetMesh& mesh) {
  const int n = mesh.nodeCount();
  std::vector<std::vector<int>> lists(static_cast<size_t>(n));
  for (const Tet& tet : mesh.tets())
    for (int a : tet)
      for (int b : tet)
        if (a != b) lists[static_cast<size_t>(a)].push_back(b);
  CompressedRows rows;
  rows.offsets.assign(1, 0);
  for (std::vector<int>& list : lists) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    rows.items.insert(rows.items.end(), list.begin(), list.end());
    rows.offsets.push_back(static_cast<int>(rows.items.size()));
  }
  return rows;
}

int degree(const CompressedRows& graph, int node) {
  return graph.rowEnd(node) - graph.rowBegin(node);
}

// Breadth-first levels from `start` over the unnumbered component: the nodes in visiting order
// (neighbours by ascending degree, then index) and the last level's first node of least degree.
struct Sweep {
  std::vector<int> visited;
  int depth = 0;
  int far_node = -1;
};

Sweep breadthFirst(const CompressedRows& graph, int start, std::vector<int>& level_of) {
  Sweep sweep;
  sweep.visited.push_back(start);
  level_of[static_cast<size_t>(start)] = 0;
  std::vector<int> next;
  for (size_t head = 0; head < sweep.visited.size(); ++head) {
    const int node = sweep.visited[head];
    next.clear();
    for (int k = graph.rowBegin(node); k < graph.rowEnd(node); ++k) {
      const int neighbour = graph.items[static_cast<size_t>(k)];
      if (level_of[static_cast<size_t>(neighbour)] < 0) {
        level_of[static_cast<size_t>(neighbour)] = level_of[static_cast<size_t>(node)] + 1;
        next.push_back(neighbour);
      }
    }
    std::sort(next.begin(), next.end(), [&](int a, int b) {
      return std::make_pair(degree(graph, a), a) < std::make_pair(degree(graph, b), b);
    });
    sweep.visited.insert(sweep.visited.end(), next.begin(), next.end());
  }
  sweep.depth = level_of[static_cast<size_t>(sweep.visited.back())];
  for (int node : sweep.visited) {
    if (level_of[static_cast<size_t>(node)] != sweep.depth) continue;
    if (sweep.far_node < 0 || degree(graph, node) < degree(graph, sweep.far_node))
      sweep.far_node = node;
  }
  return sweep;
}

}  // namespace

std::vector<int> reverseCuthillMcKeeOrder(const TetMesh& mesh) {
  const int n = mesh.nodeCount();
  const CompressedRows graph = nodeNeighbours(mesh);
  std::vector<int> level_of(static_cast<size_t>(n), -1);
  std::vector<int> order;
  order.reserve(static_cast<size_t>(n));
  std::vector<int> loose;  // nodes in no tet
  for (int seed = 0; seed < n; ++seed) {
    if (level_of[static_cast<size_t>(seed)] >= 0) continue;
    if (degree(graph, seed) == 0) {
      level_of[static_cast<size_t>(seed)] = 0;
      loose.push_back(seed);
      continue;
    }
    // Pseudo-peripheral start: walk to the far end of the level structure while it deepens.
    Sweep sweep = breadthFirst(graph, seed, level_of);
    for (int round = 0; round < 8; ++round) {
      for (int node : sweep.visited)
        level_of[static_cast<size_t>(node)] = -1;
      Sweep further = breadthFirst(graph, sweep.far_node, level_of);
      const bool deeper = further.depth > sweep.depth;
      sweep = std::move(further);
      if (!deeper) break;
    }
    order.insert(order.end(), sweep.visited.begin(), sweep.visited.end());
  }
  std::reverse(order.begin(), order.end());
  order.insert(order.end(), loose.begin(), loose.end());
  return order;
}

RenumberedMesh renumberedMesh(const TetMesh& mesh, const std::vector<int>& order) {
  const size_t n = static_cast<size_t>(mesh.nodeCount());
  assert(order.size() == n && "order must be a permutation of the nodes");
  std::vector<int> new_index(n, -1);
  std::vector<Eigen::Vector3d> positions(n);
  for (size_t i = 0; i < n; ++i) {
    const size_t old = static_cast<size_t>(order[i]);
    new_index[old] = static_cast<int>(i);
    positions[i] = mesh.restPositions()[old];
  }
  std::vector<Tet> renumbered;
  renumbered.reserve(mesh.tets().size());
  for (const Tet& tet : mesh.tets()) {
    Tet t;
    for (size_t a = 0; a < 4; ++a)
      t[a] = new_index[static_cast<size_t>(tet[a])];
    renumbered.push_back(t);
  }
  auto key = [&](int t) {
    const Tet& tet = renumbered[static_cast<size_t>(t)];
    return std::make_pair(*std::min_element(tet.begin(), tet.end()),
                          *std::max_element(tet.begin(), tet.end()));
  };
  RenumberedMesh result;
  result.old_node = order;
  result.old_tet.resize(renumbered.size());
  std::iota(result.old_tet.begin(), result.old_tet.end(), 0);
  std::stable_sort(result.old_tet.begin(), result.old_tet.end(),
                   [&](int a, int b) { return key(a) < key(b); });
  std::vector<Tet> tets;
  tets.reserve(renumbered.size());
  for (int old : result.old_tet)
    tets.push_back(renumbered[static_cast<size_t>(old)]);
  result.mesh = TetMesh(std::move(positions), std::move(tets));
  return result;
}

TetMesh renumberNodes(const TetMesh& mesh, const std::vector<int>& order) {
  return renumberedMesh(mesh, order).mesh;
}

std::optional<RenumberedMesh> cacheFriendlyRenumbering(const TetMesh& mesh) {
  RenumberedMesh renumbered = renumberedMesh(mesh, reverseCuthillMcKeeOrder(mesh));
  if (2 * meanTetIndexSpan(renumbered.mesh) > meanTetIndexSpan(mesh)) return std::nullopt;
  return renumbered;
}

TetMesh inCacheFriendlyOrder(const TetMesh& mesh) {
  return renumberNodes(mesh, reverseCuthillMcKeeOrder(mesh));
}

double meanTetIndexSpan(const TetMesh& mesh) {
  if (mesh.tets().empty()) return 0;
  double sum = 0;
  for (const Tet& tet : mesh.tets())
    sum += *std::max_element(tet.begin(), tet.end()) - *std::min_element(tet.begin(), tet.end());
  return sum / static_cast<double>(mesh.tets().size());
}

}  // namespace torsion

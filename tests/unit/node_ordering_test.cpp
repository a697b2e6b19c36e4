#include "torsion/mesh/node_ordering.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>

#include "torsion/mesh/mesh_io.h"

namespace torsion {
namespace {

// The 8311-tet cylinder with its nodes scattered as a mesher's insertion order leaves them (the
// committed asset is already in reverse Cuthill-McKee order): node i moves to i * 1031 mod n, a
// permutation since 1031 is prime and does not divide n = 2049.
TetMesh cylinder() {
  Result<LoadedMesh> loaded = readMesh(std::string(TORSION_ASSETS_DIR) + "/cylinder_8332.node");
  EXPECT_TRUE(loaded.ok()) << loaded.error().message;
  const TetMesh& mesh = loaded.value().mesh;
  const int n = mesh.nodeCount();
  std::vector<int> scatter(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i)
    scatter[static_cast<size_t>(i)] = static_cast<int>((static_cast<long>(i) * 1031) % n);
  return renumberNodes(mesh, scatter);
}

TEST(NodeOrdering, ReverseCuthillMcKeeIsAPermutationOfTheNodes) {
  const TetMesh mesh = cylinder();
  std::vector<int> order = reverseCuthillMcKeeOrder(mesh);
  ASSERT_EQ(static_cast<int>(order.size()), mesh.nodeCount());
  std::sort(order.begin(), order.end());
  std::vector<int> identity(order.size());
  std::iota(identity.begin(), identity.end(), 0);
  EXPECT_EQ(order, identity);
}

TEST(NodeOrdering, RenumberedMeshIsTheSameBodyWithNearbyNumbersInEachTet) {
  const TetMesh mesh = cylinder();
  const std::vector<int> order = reverseCuthillMcKeeOrder(mesh);
  const TetMesh renumbered = renumberNodes(mesh, order);
  ASSERT_EQ(renumbered.nodeCount(), mesh.nodeCount());
  ASSERT_EQ(renumbered.tetCount(), mesh.tetCount());
  for (int i = 0; i < mesh.nodeCount(); ++i)
    EXPECT_EQ(renumbered.restPositions()[static_cast<size_t>(i)],
              mesh.restPositions()[static_cast<size_t>(order[static_cast<size_t>(i)])]);
  // Every tet keeps its orientation and volume; the surface is the same size.
  double smallest = 1;
  for (int t = 0; t < renumbered.tetCount(); ++t)
    smallest = std::min(smallest, renumbered.restVolume(t));
  EXPECT_GT(smallest, 0.0);
  EXPECT_NEAR(renumbered.totalRestVolume(), mesh.totalRestVolume(), 1e-12 * mesh.totalRestVolume());
  EXPECT_EQ(renumbered.surfaceTriangleCount(), mesh.surfaceTriangleCount());
  // The scattered numbering puts a tet's nodes about half the mesh apart (tetgen's own put them
  // 1035 of 2049 apart on this mesh); the reverse Cuthill-McKee order puts them within a few
  // rings of the cylinder (about 80).
  EXPECT_GT(meanTetIndexSpan(mesh), 500.0);
  EXPECT_LT(meanTetIndexSpan(renumbered), 0.15 * meanTetIndexSpan(mesh));
}

TEST(NodeOrdering, OrderIsDeterministic) {
  const TetMesh mesh = cylinder();
  EXPECT_EQ(reverseCuthillMcKeeOrder(mesh), reverseCuthillMcKeeOrder(mesh));
  const TetMesh once = inCacheFriendlyOrder(mesh);
  EXPECT_EQ(inCacheFriendlyOrder(mesh).tets(), once.tets());
}

}  // namespace
}  // namespace torsion

#include "torsion/mesh/tet_mesh.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <set>

#include "test_meshes.h"
#include "torsion/mesh/tet_mesh_builder.h"
#include "torsion/mesh/tetgen_format.h"

namespace torsion {
namespace {

TetMesh cube() {
  Result<RawTetMesh> raw = parseTetGen(test::kCubeNode, "cube.node", test::kCubeEle, "cube.ele");
  if (!raw.ok()) {
    ADD_FAILURE() << raw.error().message;
    return TetMesh();
  }
  Result<LoadedMesh> loaded = buildTetMesh(std::move(raw).value());
  if (!loaded.ok()) {
    ADD_FAILURE() << loaded.error().message;
    return TetMesh();
  }
  return std::move(loaded).value().mesh;
}

TEST(TetMesh, CubeVolumeIsOne) {
  const TetMesh mesh = cube();
  EXPECT_EQ(mesh.nodeCount(), 8);
  EXPECT_EQ(mesh.tetCount(), 5);
  EXPECT_NEAR(mesh.totalRestVolume(), 1.0, 1e-14);
  for (int t = 0; t < mesh.tetCount(); ++t)
    EXPECT_GT(mesh.restVolume(t), 0);
}

TEST(TetMesh, CubeSurfaceIsTwelveOutwardTriangles) {
  const TetMesh mesh = cube();
  ASSERT_EQ(mesh.surfaceTriangleCount(), 12);  // 6 faces x 2 triangles
  const Eigen::Vector3d centre(0.5, 0.5, 0.5);
  double enclosed = 0;  // divergence theorem: sum over faces of (c . n) A / 3 = volume
  for (const Triangle& tri : mesh.surfaceTriangles()) {
    const auto& x = mesh.restPositions();
    const Eigen::Vector3d a = x[static_cast<size_t>(tri[0])], b = x[static_cast<size_t>(tri[1])],
                          c = x[static_cast<size_t>(tri[2])];
    const Eigen::Vector3d n = (b - a).cross(c - a);  // 2A * unit normal
    EXPECT_GT(n.dot((a + b + c) / 3.0 - centre), 0) << "triangle normal points inward";
    enclosed += a.dot(n) / 6.0;
  }
  EXPECT_NEAR(enclosed, 1.0, 1e-14);
}

TEST(TetMesh, ClosedSurfaceHasThreeNeighboursPerTriangle) {
  const TetMesh mesh = cube();
  const CompressedRows& adj = mesh.surfaceTriangleNeighbours();
  ASSERT_EQ(adj.rowCount(), mesh.surfaceTriangleCount());
  for (int t = 0; t < adj.rowCount(); ++t) {
    EXPECT_EQ(adj.rowEnd(t) - adj.rowBegin(t), 3) << "triangle " << t;
    for (int k = adj.rowBegin(t); k < adj.rowEnd(t); ++k) {
      const int other = adj.items[static_cast<size_t>(k)];
      // Neighbours share exactly two vertices.
      const Triangle& a = mesh.surfaceTriangles()[static_cast<size_t>(t)];
      const Triangle& b = mesh.surfaceTriangles()[static_cast<size_t>(other)];
      int shared = 0;
      for (int u : a)
        for (int v : b)
          shared += (u == v);
      EXPECT_EQ(shared, 2);
    }
  }
  EXPECT_EQ(mesh.surfaceNodes().size(), 8u);
}

TEST(TetMesh, NodeTetIncidenceListsEveryTetOnce) {
  const TetMesh mesh = cube();
  const CompressedRows& inc = mesh.nodeTets();
  ASSERT_EQ(inc.rowCount(), mesh.nodeCount());
  int total = 0;
  for (int n = 0; n < mesh.nodeCount(); ++n) {
    for (int k = inc.rowBegin(n); k < inc.rowEnd(n); ++k) {
      const Tet& tet = mesh.tets()[static_cast<size_t>(inc.items[static_cast<size_t>(k)])];
      EXPECT_NE(std::find(tet.begin(), tet.end(), n), tet.end());
      ++total;
    }
  }
  EXPECT_EQ(total, 4 * mesh.tetCount());
  // Node 1 (corner (1,0,0)) touches the corner tets 0, 1, 2 and the central tet 4.
  std::set<int> tets_of_1(inc.items.begin() + inc.rowBegin(1), inc.items.begin() + inc.rowEnd(1));
  EXPECT_EQ(tets_of_1, (std::set<int>{0, 1, 2, 4}));
}

TEST(TetMesh, BoundsOfCube) {
  const TetMesh mesh = cube();
  EXPECT_EQ(mesh.boundsMin(), Eigen::Vector3d(0, 0, 0));
  EXPECT_EQ(mesh.boundsMax(), Eigen::Vector3d(1, 1, 1));
}

}  // namespace
}  // namespace torsion

// Geometry faults are checked once for every format by buildTetMesh; these tests feed it through
// the TetGen reader, whose line numbers are easy to predict.
#include "torsion/mesh/tet_mesh_builder.h"

#include <gtest/gtest.h>

#include "error_matchers.h"
#include "torsion/mesh/tetgen_format.h"

namespace torsion {
namespace {

using test::failsWith;

const std::string kNodes =
    "5 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 1 1 0\n";  // node 4 is coplanar with 0,1,2

Result<LoadedMesh> build(const std::string& ele, MeshLoadOptions options = {}) {
  Result<RawTetMesh> raw = parseTetGen(kNodes, "m.node", ele, "m.ele");
  if (!raw) return raw.error();
  return buildTetMesh(std::move(raw).value(), options);
}

TEST(BuildTetMesh, RepeatedVertex) {
  EXPECT_TRUE(
      failsWith(build("1 4 0\n1 0 1 1 3\n"), {"m.ele:2: tet 1:", "vertex 1 appears twice"}));
}

TEST(BuildTetMesh, ZeroVolume) {
  EXPECT_TRUE(failsWith(build("2 4 0\n0 0 1 2 3\n1 0 1 2 4\n"),
                        {"m.ele:3: tet 1:", "zero volume", "coplanar"}));
}

TEST(BuildTetMesh, InvertedTetIsReorientedWithWarning) {
  Result<LoadedMesh> loaded = build("1 4 0\n0 0 2 1 3\n");
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  EXPECT_EQ(loaded.value().reoriented_tets, 1);
  EXPECT_GT(loaded.value().mesh.restVolume(0), 0);
  ASSERT_FALSE(loaded.value().warnings.empty());
  EXPECT_NE(loaded.value().warnings.front().find("1 inverted tet was reoriented (line 2)"),
            std::string::npos)
      << loaded.value().warnings.front();
}

TEST(BuildTetMesh, InvertedTetRefusedByOption) {
  MeshLoadOptions refuse;
  refuse.refuse_inverted = true;
  EXPECT_TRUE(failsWith(build("1 4 0\n0 0 2 1 3\n", refuse), {"m.ele:2: tet 0:", "inverted"}));
}

TEST(BuildTetMesh, UnusedNodesAreDroppedWithWarning) {
  Result<LoadedMesh> loaded = build("1 4 0\n0 0 1 2 3\n");
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  EXPECT_EQ(loaded.value().mesh.nodeCount(), 4);
  ASSERT_EQ(loaded.value().warnings.size(), 1u);
  EXPECT_NE(loaded.value().warnings[0].find("1 node is used by no tet"), std::string::npos);
}

TEST(BuildTetMesh, FaceSharedByThreeTetsIsRefused) {
  // Three different apexes on the face (0, 1, 2): two above it, one below; the two above overlap.
  const std::string nodes = "6 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 0 0 -1\n5 0.1 0.1 2\n";
  Result<RawTetMesh> raw =
      parseTetGen(nodes, "m.node", "3 4 0\n0 0 1 2 3\n1 0 2 1 4\n2 0 1 2 5\n", "m.ele");
  ASSERT_TRUE(raw.ok()) << raw.error().message;
  EXPECT_TRUE(failsWith(buildTetMesh(std::move(raw).value()),
                        {"m.ele:4: tet 2:", "already shared by tets", "overlap"}));
}

TEST(BuildTetMesh, TwoTetsOnOneSideOfTheirSharedFaceAreRefused) {
  // Both apexes above the face (0, 1, 2): each face is shared at most twice, yet the tets overlap.
  const std::string nodes = "5 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 0.1 0.1 2\n";
  Result<RawTetMesh> raw = parseTetGen(nodes, "m.node", "2 4 0\n0 0 1 2 3\n1 0 1 2 4\n", "m.ele");
  ASSERT_TRUE(raw.ok()) << raw.error().message;
  EXPECT_TRUE(failsWith(buildTetMesh(std::move(raw).value()),
                        {"m.ele:3: tet 1:", "same side of face (0, 1, 2) as tet 0", "overlap"}));
}

TEST(BuildTetMesh, FoldedMeshWithoutBoundaryIsRefused) {
  // Found by fuzz_tetgen: tet 0 plus four tets fanning from an apex outside it, every face shared
  // twice, so no boundary surface at all.
  const std::string nodes =
      "8 3\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 1 1 0\n4 0 4 1\n5 1 0 1\n6 0 1 5\n7 1 1 9\n";
  const std::string tets = "5 4 0\n0 0 1 2 4\n1 0 2 1 7\n2 0 1 4 7\n3 1 4 2 7\n4 0 2 4 7\n";
  Result<RawTetMesh> raw = parseTetGen(nodes, "m.node", tets, "m.ele");
  ASSERT_TRUE(raw.ok()) << raw.error().message;
  EXPECT_TRUE(failsWith(buildTetMesh(std::move(raw).value()), {"m.ele:", "overlap"}));
}

TEST(BuildTetMesh, DuplicateTetIsRefused) {
  EXPECT_TRUE(
      failsWith(build("2 4 0\n0 0 1 2 3\n1 3 1 2 0\n"), {"m.ele:3: tet 1:", "duplicates tet 0"}));
}

TEST(BuildTetMesh, EmptyMeshes) {
  RawTetMesh raw;
  raw.element_file = "x.vtk";
  EXPECT_TRUE(failsWith(buildTetMesh(raw), {"x.vtk: the mesh has no nodes"}));
  raw.positions.push_back(Eigen::Vector3d::Zero());
  EXPECT_TRUE(failsWith(buildTetMesh(raw), {"x.vtk: the mesh has no tetrahedra"}));
}

}  // namespace
}  // namespace torsion

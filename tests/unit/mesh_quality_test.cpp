#include "torsion/mesh/mesh_quality.h"

#include <gtest/gtest.h>

#include <cmath>

#include "test_meshes.h"
#include "torsion/mesh/tet_mesh_builder.h"
#include "torsion/mesh/tetgen_format.h"

namespace torsion {
namespace {

TEST(MeshQuality, RegularTetHasDihedral70_53AndAspectOne) {
  const double s = 1.0 / std::sqrt(2.0);
  const Eigen::Vector3d a(1, 0, -s), b(-1, 0, -s), c(0, 1, s), d(0, -1, s);
  const Tet tet = sixSignedVolume(a, b, c, d) > 0 ? Tet{0, 1, 2, 3} : Tet{0, 1, 3, 2};
  const TetMesh mesh({a, b, c, d}, {tet});
  const MeshQuality q = measureQuality(mesh, mesh.restPositions());
  const double expected = std::acos(1.0 / 3.0) * 180.0 / M_PI;  // 70.5288 deg
  EXPECT_NEAR(q.min_dihedral_deg, expected, 1e-9);
  EXPECT_NEAR(q.max_dihedral_deg, expected, 1e-9);
  EXPECT_NEAR(q.max_aspect_ratio, 1.0, 1e-12);
  EXPECT_EQ(q.inverted_tets, 0);
}

TEST(MeshQuality, CornerTetHasRightAngles) {
  // The corner tet of a cube: three right dihedral angles at the corner edges and three of
  // acos(1/sqrt(3))... = 54.74 deg at the slanted face.
  const auto angles = dihedralAngles({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1});
  int right = 0, slanted = 0;
  for (double a : angles) {
    const double deg = a * 180.0 / M_PI;
    if (std::abs(deg - 90.0) < 1e-9) ++right;
    if (std::abs(deg - std::acos(1.0 / std::sqrt(3.0)) * 180.0 / M_PI) < 1e-9) ++slanted;
  }
  EXPECT_EQ(right, 3);
  EXPECT_EQ(slanted, 3);
}

TEST(MeshQuality, CountsInvertedTetsAtDeformedPositions) {
  Result<RawTetMesh> raw = parseTetGen(test::kCubeNode, "c.node", test::kCubeEle, "c.ele");
  Result<LoadedMesh> loaded = buildTetMesh(std::move(raw).value());
  ASSERT_TRUE(loaded.ok());
  const TetMesh& mesh = loaded.value().mesh;
  std::vector<Eigen::Vector3d> x = mesh.restPositions();
  EXPECT_EQ(measureQuality(mesh, x).inverted_tets, 0);
  x[0] = Eigen::Vector3d(0.6, 0.6, 0.6);  // push corner 0 through the opposite face of tet 0
  EXPECT_EQ(measureQuality(mesh, x).inverted_tets, 1);
}

}  // namespace
}  // namespace torsion

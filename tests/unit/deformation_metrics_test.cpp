// Element strain and inverted-tet count (analysis/deformation_metrics.h), against deformations
// whose principal stretches are known in closed form.
#include "torsion/analysis/deformation_metrics.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <memory>

#include "torsion/mesh/box_mesh.h"

namespace torsion {
namespace {

TEST(ElementStrain, ZeroAtRestAndUnderRotationPrincipalStretchOtherwise) {
  EXPECT_NEAR(elementStrain(Eigen::Matrix3d::Identity()), 0, 1e-12);
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  EXPECT_NEAR(elementStrain(rotation), 0, 1e-9);
  // Stretched by 1.5 along x and squeezed to 0.8 along z, then rotated: the larger is 0.5.
  const Eigen::Matrix3d stretch = Eigen::Vector3d(1.5, 1, 0.8).asDiagonal();
  EXPECT_NEAR(elementStrain(rotation * stretch), 0.5, 1e-9);
  // Turned inside out (a reflection): the signed stretch -0.5 deviates by 1.5.
  const Eigen::Matrix3d inverted = Eigen::Vector3d(1, 1, -0.5).asDiagonal();
  EXPECT_NEAR(elementStrain(rotation * inverted), 1.5, 1e-9);
}

TEST(MeasureDeformation, CountsInvertedTetsAndFindsTheWorst) {
  Result<TetMesh> mesh = makeBoxTetMesh(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 2, 2, 2);
  ASSERT_TRUE(mesh.ok());
  Material material;
  auto model = FemModel::create(std::make_shared<const TetMesh>(mesh.value()), material);
  ASSERT_TRUE(model.ok());
  Eigen::VectorXd x(3 * mesh.value().nodeCount());
  for (int n = 0; n < mesh.value().nodeCount(); ++n)
    x.segment<3>(3 * n) = mesh.value().restPositions()[static_cast<size_t>(n)];

  DeformationMetrics rest = measureDeformation(*model.value(), x);
  EXPECT_NEAR(rest.max_strain, 0, 1e-12);
  EXPECT_EQ(rest.inverted_tets, 0);

  // Mirror the body through z = 0.5: every tet is inverted, each with signed stretch -1 (strain 2).
  for (int n = 0; n < mesh.value().nodeCount(); ++n)
    x(3 * n + 2) = 1 - x(3 * n + 2);
  DeformationMetrics mirrored = measureDeformation(*model.value(), x);
  EXPECT_EQ(mirrored.inverted_tets, mesh.value().tetCount());
  EXPECT_NEAR(mirrored.max_strain, 2, 1e-9);
  EXPECT_GE(mirrored.max_strain_tet, 0);
}

}  // namespace
}  // namespace torsion

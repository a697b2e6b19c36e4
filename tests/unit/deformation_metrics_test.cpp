// Element strain and inverted-tet count (analysis/deformation_metrics.h), against deformations
// whose principal stretches are known in closed form.
#include "torsion/analysis/deformation_metrics.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <limits>
#include <memory>
#include <random>

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

TEST(InvertedTetCounter, JudgesEveryTetAsDetFDoesDownToNearlyFlatTets) {
  // The triple-product shortcut must never disagree with !(det F > 0), however close to flat a
  // tet is or however the body is scaled: nodes pulled onto (and just across) a face's plane.
  Result<TetMesh> mesh = makeBoxTetMesh(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 3, 3, 3);
  ASSERT_TRUE(mesh.ok());
  auto model = FemModel::create(std::make_shared<const TetMesh>(mesh.value()), Material{});
  ASSERT_TRUE(model.ok());
  const FemModel& m = *model.value();
  const InvertedTetCounter counter(m);
  const int n = mesh.value().nodeCount();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-1, 1);
  std::uniform_int_distribution<int> pick_tet(0, mesh.value().tetCount() - 1);
  for (int trial = 0; trial < 400; ++trial) {
    Eigen::VectorXd x(3 * n);
    const double amplitude = trial % 4 == 0 ? 0.6 : 0.05;  // some runs with many inversions
    for (int i = 0; i < n; ++i) {
      x.segment<3>(3 * i) = mesh.value().restPositions()[static_cast<size_t>(i)] +
                            amplitude * Eigen::Vector3d(jitter(rng), jitter(rng), jitter(rng));
    }
    // A few tets made flat to within a few ulps: a node moved onto the plane of the other three.
    for (int k = 0; k < 5; ++k) {
      const Tet& tet = mesh.value().tets()[static_cast<size_t>(pick_tet(rng))];
      const Eigen::Vector3d a = x.segment<3>(3 * tet[0]), b = x.segment<3>(3 * tet[1]),
                            c = x.segment<3>(3 * tet[2]);
      const Eigen::Vector3d normal = (b - a).cross(c - a).normalized();
      Eigen::Vector3d d = x.segment<3>(3 * tet[3]);
      d -= (normal.dot(d - a) + 1e-16 * jitter(rng)) * normal;
      x.segment<3>(3 * tet[3]) = d;
    }
    const double scale = trial % 3 == 0 ? 1e-90 : (trial % 3 == 1 ? 1.0 : 1e90);
    x *= scale;
    EXPECT_EQ(counter.count(m, x), measureDeformation(m, x).inverted_tets) << "trial " << trial;
    EXPECT_EQ(countInvertedTets(m, x), measureDeformation(m, x).inverted_tets);
  }
  // Non-finite positions count as inverted, as det F does.
  Eigen::VectorXd x(3 * n);
  for (int i = 0; i < n; ++i)
    x.segment<3>(3 * i) = mesh.value().restPositions()[static_cast<size_t>(i)];
  x(0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(counter.count(m, x), measureDeformation(m, x).inverted_tets);
  EXPECT_GT(counter.count(m, x), 0);
}

}  // namespace
}  // namespace torsion

#include "torsion/fem/polar_rotation.h"

#include <gtest/gtest.h>

#include <random>

namespace torsion {
namespace {

bool isRotation(const Eigen::Matrix3d& R) {
  return (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-9 &&
         std::abs(R.determinant() - 1) < 1e-9;
}

TEST(PolarRotation, MatchesPolarDecompositionForRandomDeformations) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
    for (int i = 0; i < 9; ++i)
      F(i / 3, i % 3) += u(rng);
    const Eigen::Matrix3d rot =
        Eigen::Quaterniond(1, u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
    F = rot * F;
    if (F.determinant() <= 0.05) continue;
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  // cold start: the hard case
    const Eigen::Matrix3d R = extractRotation(F, q, 200, 1e-13);
    EXPECT_TRUE(isRotation(R));
    // The polar factor makes S = R^T F symmetric and equals the SVD solution.
    const Eigen::Matrix3d S = R.transpose() * F;
    EXPECT_LT((S - S.transpose()).norm(), 1e-7) << "trial " << trial;
    EXPECT_LT((R - rotationBySvd(F)).norm(), 1e-6) << "trial " << trial;
  }
}

TEST(PolarRotation, WarmStartConvergesFromPreviousRotation) {
  const Eigen::Matrix3d R0 =
      Eigen::AngleAxisd(1.0, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Matrix3d R1 =
      Eigen::AngleAxisd(1.02, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  Eigen::Quaterniond q(R0);
  const Eigen::Matrix3d R =
      extractRotation(R1 * Eigen::Vector3d(1.1, 0.9, 1.0).asDiagonal(), q, 50, 1e-12);
  EXPECT_LT((R - R1).norm(), 1e-8);
  EXPECT_LT((q.toRotationMatrix() - R1).norm(), 1e-8);  // the warm start is updated in place
}

TEST(PolarRotation, InvertedDeformationStillGivesProperRotation) {
  const Eigen::Matrix3d flip =
      Eigen::Vector3d(1, 1, -0.3).asDiagonal();  // tet pushed through a face
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitY()).toRotationMatrix();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  const Eigen::Matrix3d R = extractRotation(rot * flip, q);
  EXPECT_TRUE(isRotation(R));
  // The reflection goes onto the least-stretched axis: R is the rotation itself, and the
  // rotated-frame stretch along z is negative, which the elastic force will undo.
  EXPECT_LT((R - rot).norm(), 1e-9);
  EXPECT_LT((R.transpose() * rot * flip)(2, 2), 0);
}

TEST(PolarRotation, FlatTetGivesProperRotation) {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  const Eigen::Matrix3d R = extractRotation(Eigen::Vector3d(1, 1, 0).asDiagonal(), q);
  EXPECT_TRUE(isRotation(R));
}

}  // namespace
}  // namespace torsion

#include "torsion/fem/polar_rotation.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

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

// The signed SVD: rotations U and V, F rebuilt to rounding, the singular values descending in
// magnitude with det F's sign on the last, also where they repeat, cluster or vanish (the
// hyperelastic tangent's frame, fem/hyperelastic.h).
TEST(SignedSvd, RebuildsFWithRotationsAndSignedSingularValues) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::Matrix3d> Fs;
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
    for (int i = 0; i < 9; ++i)
      F(i / 3, i % 3) += 0.5 * u(rng);
    Fs.push_back(F);
  }
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Matrix3d R =
        Eigen::Quaterniond(1, u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
    const Eigen::Matrix3d Q =
        Eigen::Quaterniond(u(rng), 1, u(rng), u(rng)).normalized().toRotationMatrix();
    for (double d : {1e-3, 1e-8, 1e-14, 0.0}) {
      for (const Eigen::Vector3d& s :
           {Eigen::Vector3d(1, 1 + d, 1 - d), Eigen::Vector3d(1.3, 1.3 + d, 0.2),
            Eigen::Vector3d(1.3, 0.5, -0.5 + d), Eigen::Vector3d(1.3, d, -d),
            Eigen::Vector3d(d, d, d)})
        Fs.push_back(R * s.asDiagonal() * Q);
    }
  }
  for (const Eigen::Matrix3d& F : Fs) {
    const SignedSvd svd = signedSvd(F);
    EXPECT_TRUE(isRotation(svd.U) && isRotation(svd.V)) << F;
    EXPECT_LE((svd.U * svd.sigma.asDiagonal() * svd.V.transpose() - F).norm(),
              1e-14 * std::max(F.norm(), 1.0))
        << F;
    // Descending to rounding (equal singular values may come in either order).
    const double rounding = 1e-14 * std::max(F.norm(), 1.0);
    EXPECT_GE(svd.sigma(0) + rounding, svd.sigma(1));
    EXPECT_GE(svd.sigma(1) + rounding, std::abs(svd.sigma(2)));
    if (std::abs(F.determinant()) > 1e-12) {
      EXPECT_EQ(svd.sigma(2) < 0, F.determinant() < 0) << F;
    }
  }
}

}  // namespace
}  // namespace torsion

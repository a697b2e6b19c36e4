// The passive part of a local stiffness (device/passive_stiffness.h): what the loop predicts
// with between simulation steps stores energy and never makes it.

#include "torsion/device/passive_stiffness.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace torsion::device {
namespace {

// dpose^T K dpose, the work form of K over a small motion.
double quadratic(const double k[36], const double x[6]) {
  double sum = 0;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c)
      sum += x[r] * k[6 * r + c] * x[c];
  return sum;
}

TEST(PassiveStiffness, ARestoringSymmetricStiffnessIsKeptAsItIs) {
  // A coupled spring: diagonal -60 ... -1, two off-diagonal couplings, negative definite.
  double k[36] = {};
  for (int d = 0; d < 6; ++d)
    k[7 * d] = -60.0 / (d + 1);
  k[6 * 0 + 4] = k[6 * 4 + 0] = 3;
  k[6 * 1 + 3] = k[6 * 3 + 1] = -2;
  double out[36];
  passiveStiffness(k, out);
  for (int e = 0; e < 36; ++e)
    EXPECT_NEAR(out[e], k[e], 1e-12) << e;
  EXPECT_LT(largestSymmetricEigenvalue(k), 0);
}

TEST(PassiveStiffness, ACirculatoryPartAndAnOutwardSpringAreRemoved) {
  // -50 about z, a follower-load coupling between x and y rotation (antisymmetric, 20), and a
  // spring pushing outward along x (+5): the work over the loop x -> y -> back is not zero and
  // pushing along x gives energy.
  double k[36] = {};
  k[35] = -50;
  k[6 * 3 + 4] = 20;
  k[6 * 4 + 3] = -20;
  k[6 * 3 + 3] = k[6 * 4 + 4] = -1;
  k[0] = 5;
  EXPECT_GT(largestSymmetricEigenvalue(k), 4.9);
  double out[36];
  passiveStiffness(k, out);
  EXPECT_LE(largestSymmetricEigenvalue(out), 1e-12);
  EXPECT_NEAR(out[35], -50, 1e-12);
  EXPECT_NEAR(out[0], 0, 1e-12);
  EXPECT_NEAR(out[6 * 3 + 4], 0, 1e-12);
  EXPECT_NEAR(out[6 * 3 + 3], -1, 1e-12);
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c)
      EXPECT_EQ(out[6 * r + c], out[6 * c + r]);
  // Every motion stores energy (or none): a sample of directions.
  for (int s = 0; s < 50; ++s) {
    double x[6];
    for (int d = 0; d < 6; ++d)
      x[d] = std::sin(1.7 * s + 2.3 * d);
    EXPECT_LE(quadratic(out, x), 1e-12);
  }
}

TEST(PassiveStiffness, ANonFiniteStiffnessPredictsNothing) {
  double k[36] = {};
  k[35] = -50;
  k[7] = std::numeric_limits<double>::quiet_NaN();
  double out[36];
  passiveStiffness(k, out);
  for (double v : out)
    EXPECT_EQ(v, 0);
}

}  // namespace
}  // namespace torsion::device

// SurfaceContactSet's convergence test (surface_contact_set.h): judged within the gap tolerance,
// a contact released after a pull too small to move it by the tolerance leaves the set converged;
// a larger pull, or the default test (any change of state), does not.
#include "torsion/contact/surface_contact_set.h"

#include <gtest/gtest.h>

namespace torsion {
namespace {

constexpr double kDt = 1e-3;            // s
constexpr double kGapTolerance = 1e-4;  // m
constexpr double kActivation = 1e-5;    // m
constexpr double kPenaltyFactor = 8;    // rho = 8 x the contact's effective mass (0.75 kg): 6 kg

// One node above the middle of a triangle, four nodes of 1 kg, no friction: activated by a
// first solve that ends 50 um deep, then released by a second whose node moves away at `away`
// (m/s); returns whether that update counts as converged.
bool convergedAfterRelease(bool within_tolerance, double away) {
  SurfaceContactSet set;
  set.setConvergedWithinTolerance(within_tolerance);
  SurfaceContact c;
  c.nodes = {0, 1, 2, 3};
  c.beta = {1.0, -1.0 / 3, -1.0 / 3, -1.0 / 3};
  c.normal = Eigen::Vector3d::UnitZ();
  c.gap = 0;
  c.friction = 0;
  set.add(c);
  set.setPenalties(std::vector<Eigen::Matrix3d>(4, Eigen::Matrix3d::Identity()), kPenaltyFactor);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(12);
  v[2] = -0.05;  // 50 um deep at the end of the step: active, lambda_n = 6 kg x 0.05 m/s
  set.update(v, kDt, kActivation, kGapTolerance);
  EXPECT_EQ(set.contacts()[0].state, SurfaceContact::State::kSlide);
  v[2] = away;  // the solve pulled with 6 kg x (away - 0.05 m/s): released
  const bool converged = set.update(v, kDt, kActivation, kGapTolerance);
  EXPECT_EQ(set.contacts()[0].state, SurfaceContact::State::kInactive);
  return converged;
}

TEST(SurfaceContactSet, AReleaseAfterAPullThatMovesTheNodeLessThanTheToleranceIsConverged) {
  // Pull 6 kg x 2 mm/s = 0.012 N s; over 0.75 kg for 1 ms: 16 um, within 100 um.
  EXPECT_TRUE(convergedAfterRelease(true, 0.052));
  EXPECT_FALSE(convergedAfterRelease(false, 0.052));
}

TEST(SurfaceContactSet, AReleaseAfterAPullThatMovesTheNodeBeyondTheToleranceIsNotConverged) {
  // Pull 6 kg x 0.15 m/s = 0.9 N s; over 0.75 kg for 1 ms: 1.2 mm.
  EXPECT_FALSE(convergedAfterRelease(true, 0.2));
  EXPECT_FALSE(convergedAfterRelease(false, 0.2));
}

}  // namespace
}  // namespace torsion

#include "torsion/device/wrench_safety.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "torsion/device/pose_math.h"

namespace torsion::device {
namespace {

DeviceLimits limits() {
  DeviceLimits l;
  l.max_force = 10;
  l.max_torque = 1;
  return l;
}

TEST(WrenchSafety, WithinLimitsPassesUnchanged) {
  const Wrench w{{1, 2, 3}, {0.1, 0.2, 0.3}};
  const Wrench s = saturate(w, limits());
  EXPECT_EQ(s.force.y, 2);
  EXPECT_EQ(s.torque.z, 0.3);
}

TEST(WrenchSafety, SaturationKeepsDirectionAndCapsNorm) {
  const Wrench s = saturate({{30, 40, 0}, {0, 0, -5}}, limits());
  EXPECT_NEAR(std::hypot(s.force.x, s.force.y, s.force.z), 10.0, 1e-12);
  EXPECT_NEAR(s.force.x / s.force.y, 0.75, 1e-12);
  EXPECT_NEAR(s.torque.z, -1.0, 1e-12);
}

TEST(WrenchSafety, NonFiniteBecomesZero) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Wrench s = saturate({{1, nan, 0}, {0, 0, 0.5}}, limits());
  EXPECT_FALSE(isFinite(Wrench{{1, nan, 0}, {}}));
  EXPECT_EQ(s.force.x, 0);
  EXPECT_EQ(s.torque.z, 0);
  EXPECT_TRUE(isFinite(s));
}

// The device layer's one limiter (pose_math.h): force, torque and rate limits all go through it.
TEST(WrenchSafety, ClampNormCapsTheNormKeepsTheDirectionAndFailsToZero) {
  const Vec3 v{3, -4, 12};  // norm 13
  const Vec3 inside = clampNorm(v, 13);
  EXPECT_EQ(inside.x, 3);  // not longer: v itself
  EXPECT_EQ(inside.z, 12);
  const Vec3 capped = clampNorm(v, 6.5);
  EXPECT_NEAR(norm(capped), 6.5, 1e-14);
  EXPECT_NEAR(capped.y / capped.x, -4.0 / 3.0, 1e-14);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  // A limit that is not positive, or a vector that is not finite: zero, never v or NaN.
  for (const double limit : {0.0, -1.0, nan}) {
    const Vec3 z = clampNorm(v, limit);
    EXPECT_TRUE(z.x == 0 && z.y == 0 && z.z == 0) << limit;
  }
  for (const Vec3& bad : {Vec3{nan, 0, 0}, Vec3{0, inf, 0}, Vec3{0, 0, -inf}}) {
    const Vec3 z = clampNorm(bad, 10);
    EXPECT_TRUE(z.x == 0 && z.y == 0 && z.z == 0);
  }
  // Components near the double range whose norm overflows: zero rather than NaN.
  const Vec3 huge = clampNorm(Vec3{1e308, 1e308, 0}, 10);
  EXPECT_TRUE(isFinite(huge));
  EXPECT_LE(norm(huge), 10.0);
}

TEST(WrenchSafety, ApproachMovesAtMostAStepAndLandsExactlyOnItsTarget) {
  const Vec3 from{1, 2, 3}, to{1, 2, 13};
  const Vec3 moved = approach(from, to, 4);
  EXPECT_EQ(moved.x, 1);
  EXPECT_NEAR(moved.z, 7, 1e-14);
  const Vec3 landed = approach(from, to, 10 * (1 - 1e-12));  // within the rounding slack
  EXPECT_EQ(landed.z, 13);
  // Three steps of a third land on the target itself, not a rounding hair short.
  Vec3 x = from;
  for (int k = 0; k < 3; ++k)
    x = approach(x, to, 10.0 / 3.0);
  EXPECT_EQ(x.z, 13);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // A target that is not finite, or no step: stay.
  const Vec3 stay = approach(from, Vec3{nan, 0, 0}, 4);
  EXPECT_EQ(stay.x, 1);
  EXPECT_EQ(stay.z, 3);
  EXPECT_EQ(approach(from, to, 0).z, 3);
  EXPECT_EQ(approach(from, to, nan).z, 3);
}

}  // namespace
}  // namespace torsion::device
